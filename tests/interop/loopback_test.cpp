// Proves that no DDS packet leaves loopback by default. Both peers (Fast DDS and Cyclone) run
// inside a private network namespace that also has a multicast-capable, addressed veth
// interface, the kind both stacks use by default. The kernel's tx counter of that interface
// must not move during a full interop run. A positive control runs a Cyclone peer told to use
// the veth interface and shows the counter does catch DDS traffic, so the check can fail.
// Needs root (CI and the dev machines run as root); skips with the reason otherwise.
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "cell/testing/process.h"

using namespace cell::testing;

namespace {

int Sh(const std::string& cmd) {
  return std::system((cmd + " >/dev/null 2>&1").c_str());
}

class NetNs {
 public:
  NetNs() : name_("cellnet" + std::to_string(getpid())), veth_("cv" + std::to_string(getpid() % 100000)) {
    ok_ = Sh("ip netns add " + name_) == 0 &&
          Sh("ip link add " + veth_ + "a type veth peer name " + veth_ + "b") == 0 &&
          Sh("ip link set " + veth_ + "a netns " + name_) == 0 && Sh("ip link set " + veth_ + "b up") == 0 &&
          Sh(In("ip link set lo up")) == 0 &&
          // No IPv6 on the veth: its router/neighbour chatter would move the counter by itself.
          Sh(In("sysctl -w net.ipv6.conf." + veth_ + "a.disable_ipv6=1")) == 0 &&
          Sh(In("ip addr add 10.251." + std::to_string(getpid() % 250) + ".1/30 dev " + veth_ + "a")) == 0 &&
          Sh(In("ip link set " + veth_ + "a up multicast on")) == 0 &&
          Sh(In("ip route add 224.0.0.0/4 dev " + veth_ + "a")) == 0;
  }
  ~NetNs() {
    Sh("ip link del " + veth_ + "b");
    Sh("ip netns del " + name_);
  }
  bool ok() const { return ok_; }
  std::string In(const std::string& cmd) const { return "ip netns exec " + name_ + " " + cmd; }
  long TxPackets() const {
    std::string f = MakeTempDir("cell-tx-") + "/tx";
    if (std::system((In("cat /sys/class/net/" + veth_ + "a/statistics/tx_packets") + " > " + f).c_str()) != 0)
      return -1;
    std::ifstream in(f);
    long n = -1;
    in >> n;
    return n;
  }
  const std::string& veth() const { return veth_; }
  const std::string& name() const { return name_; }

 private:
  std::string name_, veth_;
  bool ok_ = false;
};

}  // namespace

TEST(Loopback, NoDdsPacketLeavesLoopbackByDefault) {
  if (geteuid() != 0) GTEST_SKIP() << "needs root for a private network namespace";
  NetNs ns;
  if (!ns.ok()) GTEST_SKIP() << "cannot create a network namespace with a veth pair here";
  std::string peer = CELL_INTEROP_PEER;
  std::string dir = MakeTempDir("cell-lo-");
  long before = ns.TxPackets();
  ASSERT_GE(before, 0);
  Process fast({"/usr/sbin/ip", "netns", "exec", ns.name(), peer, "fastdds"}, {}, dir + "/f.out",
               dir + "/f.err");
  Process cyc({"/usr/sbin/ip", "netns", "exec", ns.name(), peer, "cyclonedds"}, {}, dir + "/c.out",
              dir + "/c.err");
  auto a = fast.Wait(std::chrono::seconds(60));
  auto b = cyc.Wait(std::chrono::seconds(30));
  ASSERT_TRUE(a && b);
  ASSERT_EQ(*a, 0) << ReadFile(dir + "/f.out") << ReadFile(dir + "/f.err");
  ASSERT_EQ(*b, 0) << ReadFile(dir + "/c.out") << ReadFile(dir + "/c.err");
  EXPECT_EQ(ns.TxPackets() - before, 0) << "DDS traffic left loopback through " << ns.veth() << "a";

  // Positive control: a Cyclone participant configured for the veth interface is seen.
  long mid = ns.TxPackets();
  std::string xml = "<CycloneDDS><Domain Id=\"any\"><General><Interfaces><NetworkInterface name=\"" +
                    ns.veth() + "a\"/></Interfaces></General></Domain></CycloneDDS>";
  Process ctl({"/usr/sbin/ip", "netns", "exec", ns.name(), peer, "cyclonedds"},
              {{"CYCLONEDDS_URI", xml}, {"CELL_DOMAIN", "99"}}, dir + "/ctl.out", dir + "/ctl.err");
  bool seen = false;
  for (int i = 0; i < 400 && !seen; ++i) {  // up to ~4 s: SPDP announces go out at once
    seen = ns.TxPackets() > mid;
    if (!seen) usleep(10000);
  }
  EXPECT_TRUE(seen) << "control run sent nothing on the veth: the counter proves nothing";
}
