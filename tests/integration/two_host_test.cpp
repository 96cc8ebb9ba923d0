// A cell across two hosts (issue 20): two network namespaces joined by a veth pair stand for the cell host
// (program store, scheduler, inspection writer, dashboard, cellctl) and a station host (interpreter and axis
// servo of KT01 and KT02). Every process runs on the shipped LAN profile of its stack (CELL_DDS_PROFILE=lan
// or lan-multicast, deploy/dds/), the two hosts on different stacks. Pallets run end to end, their run
// records reach the host's inspection writer, and the kernel's packet counters of both veth ends show the
// traffic really crossed the link (the built-in loopback profile could never do that:
// tests/interop/loopback_test).
//
// Needs root for the namespaces; elsewhere it says why and is reported skipped (never passed).
#include <signal.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <thread>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cell/testing/netns.h"
#include "cell/testing/process.h"

using namespace cell::testing;
using nlohmann::json;

namespace {

struct Layout {
  const char* host_stack;     // program store, scheduler, inspection writer, cellctl
  const char* station_stack;  // interpreters and axis servos
  const char* profile;        // CELL_DDS_PROFILE of every process
};

class TwoHosts : public ::testing::TestWithParam<Layout> {
 protected:
  // The processes stop before the namespaces and the veth go (net_ is destroyed after TearDown): Cyclone
  // wakes its receive threads at shutdown with a packet to its own address, which needs the interface.
  void TearDown() override {
    for (auto& p : procs_) p->Signal(SIGTERM);
    for (auto& p : procs_)
      if (!p->Wait(std::chrono::seconds(10)))
        ADD_FAILURE() << "a process did not stop within 10 s of SIGTERM";
    procs_.clear();  // kills what is left
  }

  void Start(const VethNamespaces& net, int host, const std::map<std::string, std::string>& env,
             std::vector<std::string> argv) {
    std::string name = argv[0] + (argv.size() > 2 ? "-" + argv[2] : "");
    argv[0] = BinDir() + "/" + argv[0];
    logs_.push_back(dir_ + "/" + name + ".log");
    procs_.push_back(std::make_unique<Process>(net.In(host, argv), env, logs_.back(), logs_.back()));
  }

  RunResult Ctl(const VethNamespaces& net, const std::map<std::string, std::string>& env,
                std::vector<std::string> args) {
    args.insert(args.begin(), BinDir() + "/cellctl");
    return RunCommand(net.In(0, args), env);
  }

  std::unique_ptr<VethNamespaces> net_;
  std::string dir_;
  std::vector<std::string> logs_;
  std::vector<std::unique_ptr<Process>> procs_;
};

TEST_P(TwoHosts, PalletsRunEndToEndAcrossTheVeth) {
  const Layout l = GetParam();
  const bool multicast = std::string(l.profile) == "lan-multicast";
  net_ = std::make_unique<VethNamespaces>("2h", 2, multicast);
  const VethNamespaces& net = *net_;
  if (!net.ok()) GTEST_SKIP() << "two network namespaces joined by a veth pair are needed: " << net.why();
  dir_ = MakeTempDir("cell-2h-");
  std::filesystem::create_directories(dir_ + "/host");
  std::filesystem::create_directories(dir_ + "/station");
  const std::string config = SourceDir() + "/deploy";  // both hosts ship the same station files and profiles
  const std::map<std::string, std::string> host_env = {
      {"CELL_DDS", l.host_stack},           {"CELL_DDS_PROFILE", l.profile},
      {"CELL_LAN_ADDRESS", net.Address(0)}, {"CELL_CONFIG_DIR", config},
      {"CELL_DATA_DIR", dir_ + "/host"},    {"CELL_HTTP", "127.0.0.1:0"}};  // the dashboard's port
  const std::map<std::string, std::string> station_env = {{"CELL_DDS", l.station_stack},
                                                          {"CELL_DDS_PROFILE", l.profile},
                                                          {"CELL_LAN_ADDRESS", net.Address(1)},
                                                          {"CELL_LAN_PEER", net.Address(0)},
                                                          {"CELL_CONFIG_DIR", config},
                                                          {"CELL_DATA_DIR", dir_ + "/station"},
                                                          {"CELL_CLOCK", "virtual"}};
  const long tx0 = net.Counter(0, "tx_packets"), rx0 = net.Counter(0, "rx_packets");
  const long tx1 = net.Counter(1, "tx_packets");
  ASSERT_GE(tx0, 0);
  ASSERT_GE(tx1, 0);

  const auto t0 = std::chrono::steady_clock::now();
  auto secs = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  for (const char* svc : {"cell-program-store", "cell-scheduler", "cell-inspection-writer", "cell-dashboard"})
    Start(net, 0, host_env, {svc});
  const size_t host_processes = procs_.size();
  for (const char* st : {"KT01", "KT02"}) {
    Start(net, 1, station_env, {"cell-interpreter", "--station", st});
    Start(net, 1, station_env, {"cell-axis-servo", "--station", st});
  }
  // Every process joined its stack on its LAN address ("ready on domain N with <stack>").
  for (size_t i = 0; i < logs_.size(); ++i) {
    const std::string want = "with " + std::string(i < host_processes ? l.host_stack : l.station_stack);
    auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (ReadFile(logs_[i]).find(want) == std::string::npos && procs_[i]->Running() &&
           std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    ASSERT_NE(ReadFile(logs_[i]).find(want), std::string::npos) << logs_[i] << ":\n" << ReadFile(logs_[i]);
  }

  const double ready_s = secs();
  // The host sees both stations online (their heartbeats crossed the link).
  json ls;
  // Stations by id (deploy/stations lists others too, offline here).
  auto online_of = [&](const char* id) {
    if (ls.is_array())
      for (auto& row : ls)
        if (row["id"] == id) return row["online"] == true;
    return false;
  };
  auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  for (bool online = false; !online && std::chrono::steady_clock::now() < deadline;) {
    auto r = Ctl(net, host_env, {"station", "ls", "--json"});
    ls = json::parse(r.out, nullptr, false);
    online = online_of("KT01") && online_of("KT02");
    if (!online) std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
  ASSERT_TRUE(online_of("KT01")) << ls.dump();
  ASSERT_TRUE(online_of("KT02")) << ls.dump();

  const double online_s = secs();
  // Program put (host), routes to each station, two pallets run to completion on the station host.
  const std::string prog = dir_ + "/pump.apl";
  std::ofstream(prog)
      << "%\n(NAM,PUMP341)\n(UTL,1001,1002)\n(UCY,90)\nN10 G71 G90 G01\nN20 T1001 M06\n"
         "N30 X0 Y0 Z100. F0\nN40 X100. Y50. Z0 F1000.\nN50 G02 X150. Y100. I100. J100. F500.\n"
         "N60 G00 X0 Y0 Z100. F0\nN70 M30\n%\n";
  auto put = Ctl(net, host_env, {"program", "put", prog});
  ASSERT_EQ(put.code, 0) << put.err;
  ASSERT_EQ(Ctl(net, host_env, {"route", "define", "R1", "--op", "KT01:PUMP341"}).code, 0);
  ASSERT_EQ(Ctl(net, host_env, {"route", "define", "R2", "--op", "KT02:PUMP341"}).code, 0);
  std::vector<std::string> jobs;
  for (auto [route, pallet] : {std::pair{"R1", "3"}, std::pair{"R2", "4"}}) {
    auto op = Ctl(net, host_env, {"route", "operate", route, "--pallet", pallet});
    ASSERT_EQ(op.code, 0) << op.err;
    jobs.push_back(op.out.substr(0, op.out.find('\n')));
  }
  for (size_t i = 0; i < jobs.size(); ++i) {
    auto w = Ctl(net, host_env, {"job", "wait", jobs[i], "--timeout", "60"});
    EXPECT_EQ(w.out, "COMPLETED\n") << w.err;
    auto shown = json::parse(Ctl(net, host_env, {"job", "show", jobs[i], "--json"}).out, nullptr, false);
    EXPECT_EQ(shown.value("station", ""), i == 0 ? "KT01" : "KT02") << shown.dump();
    EXPECT_GT(shown.value("cycle_s", 0.0),
              6.0 + 28.27);  // tool change 6 s + the 270-degree arc (skeleton test)
  }
  // The stations' run records reached the host's inspection writer.
  auto records = json::parse(Ctl(net, host_env, {"inspect", "ls", "--json"}).out, nullptr, false);
  ASSERT_TRUE(records.is_array()) << records.dump();
  int runs = 0;
  for (auto& r : records) runs += r.value("kind", "") == "run";
  EXPECT_EQ(runs, 2) << records.dump();

  // The traffic went over the veth, both ways: discovery, heartbeats, segments, credits, records.
  const long sent = net.Counter(0, "tx_packets") - tx0, got = net.Counter(0, "rx_packets") - rx0;
  const long sent_by_stations = net.Counter(1, "tx_packets") - tx1;
  EXPECT_GT(sent, 100) << "host -> station packets on " << net.veth(0);
  EXPECT_GT(got, 100) << "station -> host packets on " << net.veth(0);
  EXPECT_GT(sent_by_stations, 100) << "station -> host packets on " << net.veth(1);
  std::printf(
      "veth %s: host sent %ld packets, received %ld (profile %s, host %s, stations %s); processes ready "
      "after %.1f s, stations online after %.1f s, pallets done after %.1f s\n",
      net.veth(0).c_str(), sent, got, l.profile, l.host_stack, l.station_stack, ready_s, online_s, secs());
  std::error_code ec;
  if (!HasFailure()) std::filesystem::remove_all(dir_, ec);
}

// Both stacks on both profiles: a Fast DDS host with Cyclone stations on unicast discovery, and a Cyclone
// host with Fast DDS stations on multicast discovery.
INSTANTIATE_TEST_SUITE_P(Layouts, TwoHosts,
                         ::testing::Values(Layout{"fastdds", "cyclonedds", "lan"},
                                           Layout{"cyclonedds", "fastdds", "lan-multicast"}),
                         [](const ::testing::TestParamInfo<Layout>& info) {
                           return std::string(info.param.host_stack == std::string("fastdds")
                                                  ? "FastHost"
                                                  : "CycloneHost") +
                                  (std::string(info.param.profile) == "lan" ? "Unicast" : "Multicast");
                         });

}  // namespace
