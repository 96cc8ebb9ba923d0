// What a program changes stays on the station (issue 12), with real processes: one pallet's program sets the
// KT-APL machine parameter L1500 (manual ln 8513-8525: machine parameters "are not deleted when a program
// ends") and loads tool 4001 with TLD (ln 3975-4097); the interpreter is killed with SIGKILL and the cell
// stopped and started again; `cellctl station vars` and `station tools` show both; the next pallet's program
// reads L1500 as its X and changes to tool 4001, whose 50 mm length offsets Z: the machine ends at X 7, Z 150
// (programmed Z100.), as the servo's axis state shows.
#include <signal.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <thread>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cell/bus/bus.h"
#include "cell/bus/topics.h"
#include "cell/idl/motion.h"
#include "cell/testing/local_cell.h"

using namespace cell::testing;
using nlohmann::json;

namespace {

class StationMemory : public ::testing::Test {
 protected:
  void SetUp() override { Up(); }
  void TearDown() override {
    if (cell_.is_up()) {
      EXPECT_EQ(cell_.Down().code, 0);
    }
  }
  void Up() {
    auto r = cell_.Up("KT01", "virtual");
    ASSERT_EQ(r.code, 0) << r.out << r.err;
  }
  RunResult Ctl(std::vector<std::string> args) { return cell_.Ctl(std::move(args)); }
  json CtlJson(std::vector<std::string> args) { return cell_.Json(std::move(args)); }
  void Put(const std::string& name, const std::string& text) {
    std::string path = cell_.data_dir() + "/" + name + ".ktapl";
    std::ofstream(path) << text;
    auto r = Ctl({"program", "put", path, "--name", name, "--dialect", "ktapl"});
    ASSERT_EQ(r.code, 0) << name << ": " << r.err;
  }
  void RunPallet(const std::string& pallet, const std::string& program) {
    ASSERT_EQ(Ctl({"pallet", "set", pallet, program}).code, 0);
    auto run = Ctl({"pallet", "run", pallet, "--station", "KT01"});
    ASSERT_EQ(run.code, 0) << run.err;
    auto wait = Ctl({"job", "wait", run.out.substr(0, run.out.find('\n')), "--timeout", "60"});
    ASSERT_EQ(wait.code, 0) << wait.out << wait.err;
    ASSERT_EQ(wait.out, "COMPLETED\n");
  }
  json Tool(const json& tools, const std::string& number) {
    for (const auto& t : tools)
      if (t["tool"] == number) return t;
    return nullptr;
  }

  LocalCell cell_{"cell-station-memory-"};
};

TEST_F(StationMemory, ParametersAndToolsSurviveARestartAndTheNextProgramUsesThem) {
  Put("SETL", "%\nG71\n(PAR,L1500=7.)\n(TLD,S6T4001P50.D10.L0130)\nG90 G01 X0 Y0 Z100. F0\nM30\n%\n");
  Put("USEL", "%\nG71\nT4001 M06\nG90 G01 XL1500 Y0 Z100. F0\nM30\n%\n");
  RunPallet("1", "SETL");

  // kill -9 the interpreter (what it committed must be there), then stop and start the whole cell.
  const auto pids = cell_.Pids();
  auto interp = pids.find("cell-interpreter/KT01");
  ASSERT_NE(interp, pids.end());
  ASSERT_EQ(kill(interp->second, SIGKILL), 0);
  ASSERT_EQ(cell_.Down().code, 0);
  Up();

  auto vars = CtlJson({"station", "vars", "KT01", "--json"});
  ASSERT_TRUE(vars.is_object()) << vars;
  EXPECT_EQ(vars["L1500"], 7) << vars;
  auto tools = CtlJson({"station", "tools", "KT01", "--json"});
  auto t4001 = Tool(tools, "4001");
  ASSERT_TRUE(t4001.is_object()) << tools;
  EXPECT_EQ(t4001["socket"], 6);
  EXPECT_DOUBLE_EQ(t4001["length"].get<double>(), 50.0);
  EXPECT_DOUBLE_EQ(t4001["diameter"].get<double>(), 10.0);
  EXPECT_EQ(t4001["life_left_min"], 90);
  EXPECT_TRUE(Tool(tools, "1001").is_object()) << tools;  // the config's initial tools are still there

  // The next pallet reads L1500 and uses 4001: its positions show both.
  cell::bus::Participant bus("station-memory-test");
  cell::bus::Reader<cell::AxisState> axes(bus, cell::bus::topics::kAxisState, cell::bus::QosKind::kTelemetry);
  RunPallet("2", "USEL");
  auto at = axes.WaitFor(
      [](const cell::AxisState& a) {
        return a.station() == "KT01" && std::abs(a.commanded()[0] - 7.0) < 1e-3 &&
               std::abs(a.commanded()[2] - 150.0) < 1e-3;
      },
      cell::bus::Millis(10000));
  ASSERT_TRUE(at.has_value()) << "KT01 never stood at X 7, Z 150";

  // The parameter display (DESIGN §6 `station vars --set`): machine parameters and schedule variables only.
  auto set = Ctl({"station", "vars", "KT01", "--set", "L1600=2.5", "--set", "V7=1", "--json"});
  ASSERT_EQ(set.code, 0) << set.err;
  auto now = json::parse(set.out);
  EXPECT_EQ(now["L1500"], 7);
  EXPECT_EQ(now["L1600"], 2.5);
  EXPECT_EQ(now["V7"], 1);
  auto bad = Ctl({"station", "vars", "KT01", "--set", "L3000=1"});
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.err.find("L1000..L2999"), std::string::npos) << bad.err;
}

}  // namespace
