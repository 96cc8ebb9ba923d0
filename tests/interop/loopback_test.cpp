// Proves that no DDS packet leaves loopback by default. Both peers (Fast DDS and Cyclone) run
// inside a private network namespace that also has a multicast-capable, addressed veth
// interface, the kind both stacks use by default. The kernel's tx counter of that interface
// must not move during a full interop run. A positive control runs a Cyclone peer told to use
// the veth interface and shows the counter does catch DDS traffic, so the check can fail.
// Needs root (CI and the dev machines run as root); skips with the reason otherwise.
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "cell/testing/netns.h"
#include "cell/testing/process.h"

using namespace cell::testing;

TEST(Loopback, NoDdsPacketLeavesLoopbackByDefault) {
  VethNamespaces ns("lo", 1, true);  // veth end 0 in the namespace: addressed, multicast, a 224/4 route
  if (!ns.ok()) GTEST_SKIP() << "no private network namespace with a veth pair here: " << ns.why();
  std::string peer = CELL_INTEROP_PEER;
  ScopedTempDir tmp("cell-lo-");
  const std::string& dir = tmp.path();
  long before = ns.Counter(0, "tx_packets");
  ASSERT_GE(before, 0);
  Process fast(ns.In(0, {peer, "fastdds"}), {}, dir + "/f.out", dir + "/f.err");
  // A CYCLONEDDS_URI naming the veth must not widen the default either (the backend ignores it).
  const std::string veth_xml =
      "<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface name=\"" + ns.veth(0) +
      "\"/></Interfaces></General></Domain></CycloneDDS>";
  Process cyc(ns.In(0, {peer, "cyclonedds"}), {{"CYCLONEDDS_URI", veth_xml}}, dir + "/c.out", dir + "/c.err");
  auto a = fast.Wait(std::chrono::seconds(60));
  auto b = cyc.Wait(std::chrono::seconds(30));
  ASSERT_TRUE(a && b);
  ASSERT_EQ(*a, 0) << ReadFile(dir + "/f.out") << ReadFile(dir + "/f.err");
  ASSERT_EQ(*b, 0) << ReadFile(dir + "/c.out") << ReadFile(dir + "/c.err");
  EXPECT_EQ(ns.Counter(0, "tx_packets") - before, 0) << "DDS traffic left loopback through " << ns.veth(0);

  // Positive control: a Cyclone participant configured for the veth interface is seen.
  long mid = ns.Counter(0, "tx_packets");
  // (Through CELL_DDS_PROFILE: the backends ignore CYCLONEDDS_URI and FASTRTPS_DEFAULT_PROFILES_FILE.)
  std::ofstream(dir + "/veth.xml") << veth_xml;
  Process ctl(ns.In(0, {peer, "cyclonedds"}),
              {{"CELL_DDS_PROFILE", dir + "/veth.xml"}, {"CELL_DOMAIN", "99"}}, dir + "/ctl.out",
              dir + "/ctl.err");
  bool seen = false;
  auto deadline =
      std::chrono::steady_clock::now() + std::chrono::seconds(4);  // SPDP announces go out at once
  while (!seen && std::chrono::steady_clock::now() < deadline) {
    seen = ns.Counter(0, "tx_packets") > mid;
    if (!seen) usleep(10000);
  }
  EXPECT_TRUE(seen) << "control run sent nothing on the veth: the counter proves nothing";
}
