// A cell that mixes DDS vendors (issue 20): the host services (program store, scheduler, inspection writer)
// on one stack and the stations (interpreter and axis servo of KT01 and KT02) on the other, each way round.
// Every process is its own real process started by `cellctl up`; the host's stack comes from CELL_DDS, the
// stations' from `dds` in their station files (a private copy of deploy/stations), so no process speaks the
// other vendor on another's behalf. `cellctl` itself alternates between the two stacks verb by verb.
//
// The same scenario runs first on an all-Fast-DDS cell; pallets must route, run and complete the same way,
// and `job show`, `job ls`, `station ls` and `station tools` must print the same JSON (wall-clock times
// aside), whichever stack `cellctl` is on.
#include <cctype>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cell/testing/local_cell.h"

using namespace cell::testing;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

const char* kStacks[] = {"fastdds", "cyclonedds"};

// "2026-11-24T04:36:40..." (ISO-8601 UTC, as cellctl prints times).
bool IsWallTime(const std::string& s) {
  if (s.size() < 19) return false;
  for (size_t i = 0; i < 19; ++i) {
    const char want = i == 4 || i == 7 ? '-' : i == 10 ? 'T' : i == 13 || i == 16 ? ':' : '0';
    if (want == '0' ? !std::isdigit(static_cast<unsigned char>(s[i])) : s[i] != want) return false;
  }
  return true;
}

// Wall-clock times differ from run to run; everything else must not.
json WithoutWallTimes(json j) {
  if (j.is_object() || j.is_array()) {
    for (auto& v : j) v = WithoutWallTimes(v);
  } else if (j.is_string() && IsWallTime(j.get<std::string>())) {
    j = "<time>";
  }
  return j;
}

class MixedVendors : public ::testing::Test {
 protected:
  // A copy of deploy/ whose station files say `dds = stack` (empty: the shipped files).
  static std::string ConfigDir(const std::string& data, const std::string& stack) {
    fs::path dir = fs::path(data) / "config";
    fs::create_directories(dir);
    fs::copy(fs::path(SourceDir()) / "deploy" / "stations", dir / "stations", fs::copy_options::recursive);
    if (stack.empty()) return dir.string();
    for (auto& e : fs::directory_iterator(dir / "stations")) {
      if (e.path().extension() != ".toml") continue;
      std::string text = ReadFile(e.path().string());
      auto at = text.find("[station]\n");
      EXPECT_NE(at, std::string::npos) << e.path();
      text.insert(at + 10, "dds = \"" + stack + "\"\n");
      std::ofstream(e.path()) << text;
    }
    return dir.string();
  }

  // `cellctl` on the given stack; a failing verb fails the test.
  static RunResult Ctl(const LocalCell& cell, const std::string& stack, std::vector<std::string> args) {
    std::map<std::string, std::string> env = cell.env();
    env["CELL_DDS"] = stack;
    std::string what = "cellctl (" + stack + ")";
    for (auto& a : args) what += " " + a;
    args.insert(args.begin(), BinDir() + "/cellctl");
    RunResult r = RunCommand(args, env);
    EXPECT_EQ(r.code, 0) << what << ": " << r.out << r.err;
    return r;
  }
  static json CtlJson(const LocalCell& cell, const std::string& stack, std::vector<std::string> args) {
    args.push_back("--json");
    auto r = Ctl(cell, stack, args);
    auto j = json::parse(r.out, nullptr, false);
    EXPECT_FALSE(j.is_discarded()) << r.out;
    return WithoutWallTimes(j);
  }

  // Each process of the cell says which stack it joined with ("ready on domain N with <stack>").
  static void ExpectStacks(const LocalCell& cell, const std::string& host, const std::string& stations) {
    for (auto& e : fs::directory_iterator(fs::path(cell.data_dir()) / "logs")) {
      const std::string unit = e.path().filename().string();
      const bool station = unit.find('@') != std::string::npos;
      const std::string want = "with " + (station ? stations : host);
      const std::string log = ReadFile(e.path().string());
      EXPECT_NE(log.find("ready on domain"), std::string::npos) << unit << ":\n" << log;
      EXPECT_NE(log.find(want), std::string::npos) << unit << " should run on " << want << ":\n" << log;
    }
  }

  // The scenario, with verbs alternating between the two stacks; returns what the query verbs print (each
  // asked on both stacks, which must agree).
  static json RunScenario(const LocalCell& cell) {
    int turn = 0;
    auto next = [&] { return std::string(kStacks[turn++ % 2]); };
    const std::string pump = cell.data_dir() + "/pump.apl", valve = cell.data_dir() + "/valve.apl";
    // KT-APL heading (NAM, UTL, UCY) as the manual lays it out; UTL 1001,1002: KT01 and KT02 both hold them;
    // UTL 2001: of the two, only KT02 (deploy/stations).
    std::ofstream(pump)
        << "%\n(NAM,PUMP341)\n(UTL,1001,1002)\n(UCY,90)\nN10 G71 G90 G01\nN20 T1001 M06\n"
           "N30 X0 Y0 Z100. F0\nN40 X100. Y50. Z0 F1000.\nN50 G02 X150. Y100. I100. J100. F500.\n"
           "N60 G00 X0 Y0 Z100. F0\nN70 M30\n%\n";
    std::ofstream(valve)
        << "%\n(NAM,VALVE12)\n(UTL,2001)\n(UCY,60)\nN10 G71 G90 G01\nN20 T2001 M06\n"
           "N30 X20. Y20. Z50. F0\nN40 Z0 F800.\nN50 X120. F1200.\nN60 Y80.\nN70 G00 Z50. F0\n"
           "N80 M30\n%\n";
    Ctl(cell, next(), {"program", "put", pump});
    Ctl(cell, next(), {"program", "put", valve});
    Ctl(cell, next(), {"route", "define", "R1", "--op", "KT01,KT02:PUMP341"});
    Ctl(cell, next(), {"route", "define", "R2", "--op", "KT01,KT02:VALVE12"});
    Ctl(cell, next(), {"pallet", "set", "6", "PUMP341"});
    std::vector<std::string> jobs;
    // One pallet at a time, so that every OPERATE sees the same backlogs (zero) in every run.
    auto finish = [&](RunResult r) {
      jobs.push_back(r.out.substr(0, r.out.find('\n')));
      auto w = Ctl(cell, next(), {"job", "wait", jobs.back(), "--timeout", "60"});
      EXPECT_EQ(w.out, "COMPLETED\n");
    };
    finish(Ctl(cell, next(), {"route", "operate", "R1", "--pallet", "3"}));  // tie: KT01, listed first
    finish(Ctl(cell, next(), {"route", "operate", "R2", "--pallet", "4"}));  // tool 2001: KT02
    finish(Ctl(cell, next(), {"pallet", "run", "6", "--station", "KT02"}));  // direct, as an operator
    json out;
    auto ask = [&](const std::string& key, const std::vector<std::string>& args) {
      json f = CtlJson(cell, "fastdds", args), c = CtlJson(cell, "cyclonedds", args);
      EXPECT_EQ(f, c) << key << ": cellctl on Fast DDS and on Cyclone disagree";
      out[key] = f;
    };
    for (auto& id : jobs) ask("job show " + id, {"job", "show", id});
    ask("job ls", {"job", "ls"});
    ask("station ls", {"station", "ls"});
    ask("station tools KT01", {"station", "tools", "KT01"});
    ask("station tools KT02", {"station", "tools", "KT02"});
    return out;
  }

  // Runs the scenario on a cell whose host is on `host` and whose stations are on `stations`.
  static json Cell(const std::string& host, const std::string& stations) {
    LocalCell cell("cell-mixed-");
    cell.SetEnv("CELL_DDS", host);
    cell.SetEnv("CELL_CONFIG_DIR", ConfigDir(cell.data_dir(), stations == host ? "" : stations));
    auto up = cell.Up("KT01,KT02", "virtual");
    EXPECT_EQ(up.code, 0) << up.out << up.err;
    if (up.code != 0) return nullptr;
    ExpectStacks(cell, host, stations);
    json out = RunScenario(cell);
    auto down = cell.Down();
    EXPECT_EQ(down.code, 0) << down.err;
    return out;
  }

  static void SetUpTestSuite() { baseline_ = new json(Cell("fastdds", "fastdds")); }
  static void TearDownTestSuite() {
    delete baseline_;
    baseline_ = nullptr;
  }
  static void ExpectSameAsBaseline(const json& got) {
    ASSERT_FALSE(baseline_->is_null()) << "the all-Fast-DDS run failed";
    ASSERT_FALSE(got.is_null());
    for (auto& [key, value] : baseline_->items()) EXPECT_EQ(got.value(key, json()), value) << key;
    // The scenario itself did what it should (so that "the same" means "right").
    EXPECT_EQ((*baseline_)["job show 1"]["station"], "KT01");
    EXPECT_EQ((*baseline_)["job show 2"]["station"], "KT02");
    EXPECT_EQ((*baseline_)["job show 3"]["station"], "KT02");
    for (auto& job : (*baseline_)["job ls"]) EXPECT_EQ(job["state"], "COMPLETED") << job;
  }
  static json* baseline_;
};

json* MixedVendors::baseline_ = nullptr;

TEST_F(MixedVendors, FastDdsHostWithCycloneStations) {
  ExpectSameAsBaseline(Cell("fastdds", "cyclonedds"));
}

TEST_F(MixedVendors, CycloneHostWithFastDdsStations) {
  ExpectSameAsBaseline(Cell("cyclonedds", "fastdds"));
}

}  // namespace
