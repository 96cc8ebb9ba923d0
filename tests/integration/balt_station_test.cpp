// BS01, the Balt-System mill (issue 19), with the real processes (program store, scheduler, the interpreter
// with the Balt-System dialect, the axis servo on the machining-centre kind with the virtual clock): a GTL
// profile is copied into memory MP2 with the control's own COP command, selected with SPG (its deletion is
// then refused), called from MP1 as (CLS,PROFIL/MP2) and run through `cellctl pallet run`; a G72 probing
// program measures a face and a boss of a part model; the probed values, kept in E parameters by the
// station, and the origins file the run rewrote on MP3 are checked against values worked out by hand.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cell/bus/bus.h"
#include "cell/bus/topics.h"
#include "cell/idl/motion.h"
#include "cell/testing/cell_fixture.h"
#include "cell/testing/process.h"

using namespace cell::testing;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

// The open GTL profile of manual ln 5078-5092 (Fig. 5.84): a line, an automatic radius r3, two circles taken
// with s2, the line again; compensated on the right (G42) with T1.1 (BS01.toml: K 4 mm, radius 2).
const char* kProfile =
    "l1 = X Y25,a\n"
    "p1 = X-20 Y25\n"
    "p2 = X90 Y25\n"
    "c1 = I30 J25 r-14\n"
    "c2 = I45 J25 r15\n"
    "F200\n"
    "G X-30 Y25\n"
    "G21 G42 p1\n"
    "l1\n"
    "r3\n"
    "c1 s2\n"
    "c2 s2\n"
    "l1\n"
    "G20 G40 p2\n"
    "G X-30\n";

// The main program: T1.1 (length 100, ln 2478-2482: added to Z), down to Z5, the profile from MP2, up.
const char* kMain =
    "N1 T1.1 M6 S2000 M3\n"
    "N2 G0 X-30 Y25 Z5\n"
    "(CLS,PROFIL/MP2)\n"
    "N3 G0 Z50\n"
    "N4 M30\n";

// G72 (ln 688-695, 3653-3683) with the probe T30.30 (length 100, ball 6 mm): the face below, then the
// boss's flank in X; results in E30 and E31; (RQO,1,ZE30) moves origin 1 by the measured Z (ln 5767-5794),
// which the run writes back into the origins file FILEOR on MP3.
const char* kProbe =
    "N1 T30.30 M6\n"
    "N2 (DPT,5,5,500)\n"
    "N3 G0 X50 Y50 Z50\n"
    "N4 G72 Z-20 E30\n"
    "N5 G0 X60 Y50 Z-10\n"
    "N6 G72 X20 E31\n"
    "N7 G0 Z50\n"
    "N8 (RQO,1,ZE30)\n"
    "N9 M30\n";

// The part (machine coordinates of the axes, which carry the tool length: the tip of the 100 mm probe is at
// axis Z = programmed Z + 100): a face at programmed Z-20.5, i.e. axis Z 79.5, and a boss of diameter 40.2
// on it around X0 Y50.
const char* kPart =
    "[[plane]]\npoint = [0, 0, 79.5]\nnormal = [0, 0, 1]\n"
    "[[boss]]\nbase = [0, 50, 79.5]\naxis = [0, 0, 1]\ndiameter = 40.2\nheight = 40\n";

class BaltStation : public CellFixture {
 protected:
  BaltStation() : CellFixture("cell-balt-station-") {}
  void SetUp() override {
    // The shipped stations, with a part model on BS01's table for every pallet the test uses.
    const fs::path etc = fs::path(cell_.data_dir()) / "etc";
    fs::create_directories(etc / "stations" / "parts");
    fs::copy(fs::path(SourceDir()) / "deploy" / "stations", etc / "stations",
             fs::copy_options::overwrite_existing | fs::copy_options::recursive);
    std::ofstream(etc / "stations" / "parts" / "BS01-part.toml") << kPart;
    std::ofstream(etc / "stations" / "BS01.toml", std::ios::app)
        << "parts = [ { pallet = 0, file = \"parts/BS01-part.toml\" }, { pallet = 1, file = "
           "\"parts/BS01-part.toml\" }, { pallet = 2, file = \"parts/BS01-part.toml\" } ]\n";
    cell_.SetEnv("CELL_CONFIG_DIR", etc.string());
    Up("BS01");
  }
  void Put(const std::string& text, const std::string& name, const std::string& node) {
    std::string path = cell_.data_dir() + "/" + name + ".balt";
    std::ofstream(path) << text;
    auto r = Ctl({"program", "put", path, "--name", name, "--dialect", "balt", "--node", node});
    ASSERT_EQ(r.code, 0) << name << ": " << r.out << r.err;
  }
  RunResult Memory(const std::string& command, bool yes = false) {
    std::vector<std::string> args = {"program", "memory", "BS01", command};
    if (yes) args.push_back("--yes");
    return Ctl(args);
  }
  void RunPallet(const std::string& pallet, const std::string& program) {
    ASSERT_EQ(Ctl({"pallet", "set", pallet, program}).code, 0);
    auto run = Ctl({"pallet", "run", pallet, "--station", "BS01"});
    ASSERT_EQ(run.code, 0) << run.err;
    const std::string job = run.out.substr(0, run.out.find('\n'));
    auto wait = Ctl({"job", "wait", job, "--timeout", "60"});
    json shown = cell_.Json({"job", "show", job, "--json"});
    ASSERT_EQ(wait.code, 0) << wait.out << wait.err << shown.dump();
    EXPECT_EQ(shown["station"], "BS01") << shown.dump();
  }
};

TEST_F(BaltStation, MemoriesSelectionGtlProfileAndProbingThroughCellctl) {
  // The profile reaches MP2 from the host with COP (ln 2064-2082), listed by DIR (ln 1740-1760).
  Put(kProfile, "PROFIL", "HOST");
  auto cop = Memory("COP,PROFIL/HOST,/MP2");
  ASSERT_EQ(cop.code, 0) << cop.out << cop.err;
  EXPECT_NE(cop.out.find("[FILMS2 03] COMMAND EXECUTED"), std::string::npos) << cop.out;
  auto dir = Memory("DIR/MP2");
  ASSERT_EQ(dir.code, 0) << dir.err;
  EXPECT_NE(dir.out.find("PROFIL    2"), std::string::npos) << dir.out;  // 141 bytes: 2 sectors of 128
  // A second COP onto it asks FILMS2 05 and changes nothing without the answer.
  auto again = Memory("COP,PROFIL/HOST,/MP2");
  EXPECT_EQ(again.code, 1);
  EXPECT_NE(again.err.find("[FILMS2 05] EXISTS DELETE??? (Y/N): PROFIL/MP2"), std::string::npos) << again.err;

  // SPG selects it; a selected program cannot be deleted (ln 1913, 2202-2203), neither by the control's DEL
  // nor by the store's own verb.
  ASSERT_EQ(Memory("SPG,PROFIL/MP2").code, 0);
  auto del = Memory("DEL,PROFIL/MP2");
  EXPECT_NE(del.code, 0);
  EXPECT_NE(del.err.find("[FILMS3 20] INVALID OPERATION: PROFIL is selected (SPG)"), std::string::npos)
      << del.err;
  auto rm = Ctl({"program", "rm", "PROFIL", "--node", "BS01/MP2"});
  EXPECT_NE(rm.code, 0);
  EXPECT_NE(rm.err.find("'PROFIL' in BS01/MP2 is selected for execution (SPG)"), std::string::npos) << rm.err;
  json listed = cell_.Json({"program", "ls", "--node", "BS01/MP2", "--json"});
  ASSERT_EQ(listed.size(), 1u) << listed.dump();
  EXPECT_EQ(listed[0]["selected"], true) << listed.dump();

  // MAIN (on the host, where the scheduler finds a pallet's programs; the station looks in MP1, then HOST)
  // calls the profile in MP2. By hand (the path is the corpus's gtl_open_profile, offset by the
  // 2 mm radius on the right of the travel; its last move is the uncompensated G X-30 at Y25): the machine
  // ends at X-30 Y25 and, after N3, Z 50 + 100 (T1.1's length) = 150.
  Put(kMain, "MAIN", "HOST");
  cell::bus::Participant bus("balt-station-test");
  cell::bus::Reader<cell::AxisState> axes(bus, cell::bus::topics::kAxisState, cell::bus::QosKind::kTelemetry);
  RunPallet("1", "MAIN");
  auto at = axes.WaitFor(
      [](const cell::AxisState& a) {
        return a.station() == "BS01" && std::abs(a.commanded()[0] + 30.0) < 1e-3 &&
               std::abs(a.commanded()[1] - 25.0) < 1e-3 && std::abs(a.commanded()[2] - 150.0) < 1e-3;
      },
      cell::bus::Millis(10000));
  EXPECT_TRUE(at.has_value()) << "BS01 never stood at X-30 Y25 Z150";

  // Probing. By hand: N4 measures along -Z from X50 Y50 (outside the boss, radius 20.1): the face at
  // programmed Z-20.5 (axis 79.5 less the probe's 100) is E30 = -20.500. N6 measures along -X at Z-10
  // (axis 90, inside the boss's 79.5..119.5) through the boss's axis line Y50: its flank at X+20.1 is
  // E31 = 20.100. The G72 results are compensated for the ball (ln 7058-7062): the dialect moves the
  // ball's contact point, so these are the surfaces themselves. Qa = Qs = 5 (DPT, ln 7018-7035) puts both
  // within reach (Z from -15 to -25, X from 25 to 15 for the ball's centre).
  Put(kProbe, "PROBE", "HOST");
  RunPallet("2", "PROBE");
  json vars = cell_.Json({"station", "vars", "BS01", "--json"});
  ASSERT_TRUE(vars["E30"].is_number()) << vars.dump();
  ASSERT_TRUE(vars["E31"].is_number()) << vars.dump();
  EXPECT_NEAR(vars["E30"].get<double>(), -20.5, 1e-3) << vars.dump();
  EXPECT_NEAR(vars["E31"].get<double>(), 20.1, 1e-3) << vars.dump();
  // RQO wrote origin 1 (Z by E30) into FILEOR on MP3, where the next run reads it.
  auto fileor = Ctl({"program", "get", "FILEOR", "--node", "BS01/MP3"});
  ASSERT_EQ(fileor.code, 0) << fileor.err;
  EXPECT_NE(fileor.out.find("Z-20.500"), std::string::npos) << fileor.out;

  // REL releases the selection; then DEL removes the profile (ln 2092-2098).
  ASSERT_EQ(Memory("REL").code, 0);
  auto del2 = Memory("DEL,PROFIL/MP2");
  EXPECT_EQ(del2.code, 0) << del2.err;
  EXPECT_EQ(cell_.Json({"program", "ls", "--node", "BS01/MP2", "--json"}).size(), 0u);
}

// The operator's way (issue 35 item 4): a program in memory MP4, selected with SPG, runs on `cellctl station
// start BS01` (ln 8873-8888); with nothing selected START is FILMS4 54 (ln 10079-10080). A pallet map and a
// route name the same program as BS01/MP4:SEL, which the scheduler reads there and sends to BS01 only.
// By hand: no tool is called, so the axes stand where the program says, X11 Y22 Z33, then X44.
TEST_F(BaltStation, SelectedProgramRunsOnStartAndMapsNameAMemory) {
  auto none = Ctl({"station", "start", "BS01"});
  EXPECT_NE(none.code, 0);
  EXPECT_NE(none.err.find("[FILMS4 54] NO PROGRAM HAS BEEN SELECTED"), std::string::npos) << none.err;
  Put("%:SEL\nN1 G0 X11 Y22 Z33\nN2 M30\n", "SEL", "BS01/MP4");
  ASSERT_EQ(Memory("SPG,SEL/MP4").code, 0);
  cell::bus::Participant bus("balt-station-test");
  cell::bus::Reader<cell::AxisState> axes(bus, cell::bus::topics::kAxisState, cell::bus::QosKind::kTelemetry);
  auto stands_at = [&](double x) {
    return axes.WaitFor(
        [x](const cell::AxisState& a) {
          return a.station() == "BS01" && std::abs(a.commanded()[0] - x) < 1e-3 &&
                 std::abs(a.commanded()[1] - 22.0) < 1e-3 && std::abs(a.commanded()[2] - 33.0) < 1e-3;
        },
        cell::bus::Millis(10000));
  };
  auto start = Ctl({"station", "start", "BS01"});
  ASSERT_EQ(start.code, 0) << start.err;
  EXPECT_TRUE(stands_at(11.0).has_value()) << "START did not run the selected program";

  // The same memory in a map and a route; another station may not be sent it.
  Put("%:SEL2\nN1 G0 X44 Y22 Z33\nN2 M30\n", "SEL2", "BS01/MP4");
  RunPallet("3", "BS01/MP4:SEL2");
  EXPECT_TRUE(stands_at(44.0).has_value()) << "the map's BS01/MP4:SEL2 did not run";
  auto route = Ctl({"route", "define", "R", "--op", "BS01:\"BS01/MP4:SEL2\""});
  EXPECT_EQ(route.code, 0) << route.err;
  auto other = Ctl({"route", "define", "R2", "--op", "KT01:\"BS01/MP4:SEL2\""});
  EXPECT_NE(other.code, 0);
  EXPECT_NE(other.err.find("is in BS01's memory: only BS01 runs it, not KT01"), std::string::npos)
      << other.err;
}

}  // namespace
