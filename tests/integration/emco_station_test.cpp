// EM01, the EMCOTRONIC TM02 lathe station (issue 17): the real processes (program store, scheduler, the
// interpreter with the EMCO dialect, the axis servo on the lathe kind with the virtual clock) run a
// threading program (G85) and a grooving program (G86) through `cellctl`, as a route and as a pallet run,
// and the machine seconds the jobs report are checked against times worked out by hand from the programs
// and EM01's machine data (deploy/stations/EM01.toml); the monitor parameters of its [params] reach the
// runs; `cellctl tools load` takes the control's own tool data file.
#include <cmath>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cell/testing/cell_fixture.h"
#include "emco_thread_program.h"

using namespace cell::testing;
using nlohmann::json;

namespace {

// E69/E70 (manual ln 4497-4536: the groove Z-24..-32 to X26 with a 3 mm tool, 1.5 mm pecks) with a 1.0 s
// dwell (D4=10) instead of E70's 5.0 s, on turret position 3 at 800 rpm and 60 um/rev (G95, ln 4850).
const char* kGroove =
    "%\n"
    "N0010 T0303 G00 X50. Z10.\n"
    "N0020 G97 S800 M03 G95\n"
    "N0030 G00 X42. Z-24.\n"
    "N0040 G86 X26. Z-32. D3=1500 D4=10 D5=3000 F60\n"
    "N0050 G00 X50. Z10.\n"
    "N0060 M30\n";

class EmcoStation : public CellFixture {
 protected:
  EmcoStation() : CellFixture("cell-emco-station-") {}
  void SetUp() override { Up("EM01"); }
  void Put(const std::string& text, const std::string& name) {
    std::string path = cell_.data_dir() + "/" + name + ".emco";
    std::ofstream(path) << text;
    auto r = Ctl({"program", "put", path, "--name", name, "--dialect", "emco"});
    ASSERT_EQ(r.code, 0) << name << ": " << r.out << r.err;
  }
  // Waits for the job and returns its `job show` object.
  json Finish(const RunResult& started) {
    EXPECT_EQ(started.code, 0) << started.err;
    std::string job = started.out.substr(0, started.out.find('\n'));
    auto wait = Ctl({"job", "wait", job, "--timeout", "60"});
    EXPECT_EQ(wait.code, 0) << wait.out << wait.err;
    json shown = cell_.Json({"job", "show", job, "--json"});
    EXPECT_EQ(shown["state"], "COMPLETED") << shown.dump();
    EXPECT_EQ(shown["station"], "EM01") << shown.dump();
    return shown;
  }
};

// The thread as a route's operation and the groove as a pallet run: EM01 takes both like any station.
TEST_F(EmcoStation, ThreadingRouteAndGroovingPalletWithTheirCycleTimes) {
  Put(kEmcoThreadE59, "THREAD");
  Put(kGroove, "GROOVE");
  auto d = Ctl({"route", "define", "EMR", "--op", "EM01:THREAD"});
  ASSERT_EQ(d.code, 0) << d.out << d.err;
  json thread = Finish(Ctl({"route", "operate", "EMR", "--pallet", "7"}));
  ASSERT_TRUE(thread["cycle_s"].is_number()) << thread.dump();

  // By hand. EM01.toml: X rapid 8000 mm/min on the radius (133.3 mm/s), Z 10000 (166.7 mm/s), both
  // 2500 mm/s^2, jerk 50000 mm/s^3, in position 0.02 mm; turret 0.8 s + 0.25 s per position (from position
  // 1 at start-up); spindle 2000 rpm/s. The servo (docs/axis-servo.md "Planner", "Devices", "Lathes"): a
  // move takes its trapezoid time, 2 sqrt(d/a) when short or d/v + v/a, and then the jerk filter's moving
  // average of N Ts = ceil(2 A / (J Ts)) ms = 0.1 s settles; the move is done when that average is within
  // 0.02 mm of the end: after 0.1 - (6 x 0.1 x 0.02 / 2500)^(1/3) = 0.083 s behind a deceleration at A, after
  // 0.1 - sqrt(2 x 0.1 x 0.02 / v) = 0.029 s behind a feed of v = 0.8 mm/s, at most 0.1 s. A thread takes
  // its index wait (< 1 rev = 0.1 s) + length / (lead rpm/60) + v/a, then settles like a move.
  // The cycle (ln 3568-3917): S00 = 100 um minimum, S01 = 1 idle pass; cumulative radius depths
  // 0.6 sqrt(n) = 0.600 0.849 1.039 1.200, then 1.227 (D6), then the idle pass: 6 passes.
  //   T0202 (1 position)                          0.8 + 0.25                        = 1.050
  //   X0 Z0 -> X50 Z10 (X 25 mm radius leads)     25/133.3 + 133.3/2500             = 0.241
  //   spindle 0 -> 600 rpm                        600/2000                          = 0.300
  //   -> X31 Z2 (X 9.5 mm leads)                  9.5/133.3 + 0.0533                = 0.125
  //   6 infeeds in X of 1.100 1.349 1.539 1.700 1.727 1.727 mm: sum of 2 sqrt(d/2500) = 0.295
  //   6 passes of 44 mm at 2 mm x 10 rev/s        6 x (2.2 + 20/2450)               = 13.249
  //   6 retracts (as the infeeds)                                                    = 0.295
  //   6 returns of 44 mm in Z                     6 x (44/166.7 + 166.7/2500)       = 1.984
  //   -> X50 Z10, spindle stop at M30             0.125 + 0.300                     = 0.425
  //   sum 17.964 s; 20 rapids and 6 threads settle 26 x (0.083 .. 0.1) = 2.16 .. 2.60 s; index waits
  //   0 .. 0.6 s: 20.12 .. 21.16 s (+ 0.2 s for the servo's own in-position settling).
  double t = thread["cycle_s"].get<double>();
  EXPECT_GT(t, 20.12) << thread.dump();
  EXPECT_LT(t, 21.16 + 0.2) << thread.dump();

  auto s = Ctl({"pallet", "set", "8", "GROOVE"});
  ASSERT_EQ(s.code, 0) << s.err;
  json groove = Finish(Ctl({"pallet", "run", "8", "--station", "EM01"}));
  ASSERT_TRUE(groove["cycle_s"].is_number()) << groove.dump();
  // By hand (the rates above; the thread left the tool at X50 Z10 on turret position 2). The cycle
  // (ln 4406-4457, catalogue 6.3): the 8 mm groove takes 3 plunges of the 3 mm tool (right edge at Z-24,
  // -26.5, -29: equal steps of at most 3 - 0.1); each goes 8 mm deep in ceil(8/1.5) = 6 pecks of 1.333 mm,
  // retracting S02 = 0.5 mm between them; 60 um/rev at 800 rpm is 0.8 mm/s.
  //   T0303 (1 position), spindle 0 -> 800 and back to 0, 3 dwells D4 = 10   1.05 + 2 x 0.4 + 3 = 4.850
  //   X50 Z10 -> X42 Z-24 and back (Z 34 mm leads)  2 x (34/166.7 + 166.7/2500)       = 0.542
  //   18 feeds: 3 x (1.333 + 5 x 1.833 = 10.5 mm) at 0.8 mm/s                         = 39.375
  //   15 retracts of 0.5 mm                          15 x 2 sqrt(0.5/2500)              = 0.424
  //   3 rapids out of 8 mm in X                      3 x (8/133.3 + 0.0533)             = 0.340
  //   Z steps of 2.5, 2.5 and back 5 mm              2 x 2 sqrt(2.5/2500) + 2 sqrt(5/2500) = 0.216
  //   sum 45.747 s; 23 rapids settle 23 x (0.083 .. 0.1) = 1.91 .. 2.30 s, 18 feeds 18 x (0.029 .. 0.1) =
  //   0.52 .. 1.80 s: 48.18 .. 49.85 s (+ 0.3 s for the servo's own in-position settling).
  double g = groove["cycle_s"].get<double>();
  EXPECT_GT(g, 48.18) << groove.dump();
  EXPECT_LT(g, 49.85 + 0.3) << groove.dump();
}

// EM01's [params] reach every run: the monitor's software limit R03 (X+ 220 on the diameter, ln 5913-5938)
// stops a program before it moves there, with the manual's ALARM 440 (ln 6914), where the servo's own
// travel limit would only stop the machine at the end of the previous move.
TEST_F(EmcoStation, MonitorParametersOfTheStationConfigReachTheRun) {
  Put("%\nN0010 T0101 G00 X50. Z10.\nN0020 G00 X230.\nN0030 M30\n", "LIMIT");
  ASSERT_EQ(Ctl({"pallet", "set", "9", "LIMIT"}).code, 0);
  auto run = Ctl({"pallet", "run", "9", "--station", "EM01"});
  ASSERT_EQ(run.code, 0) << run.err;
  std::string job = run.out.substr(0, run.out.find('\n'));
  EXPECT_EQ(Ctl({"job", "wait", job, "--timeout", "60"}).code, 1);
  json shown = cell_.Json({"job", "show", job, "--json"});
  EXPECT_EQ(shown["state"], "FAILED") << shown.dump();
  ASSERT_TRUE(shown["reason"].is_string()) << shown.dump();
  EXPECT_NE(
      shown["reason"].get<std::string>().find("LIMIT:3:11: error: [440] TARGET LIMITS EXCEEDED (X230.000)"),
      std::string::npos)
      << shown.dump();
}

// `cellctl tools load EM01 FILE` takes the EMCO tool data file; `station tools` shows the lathe fields.
TEST_F(EmcoStation, ToolsLoadTakesTheControlsOwnFile) {
  std::string path = cell_.data_dir() + "/EM01.tools";
  std::ofstream(path) << "(EMCO tool data)\nT0606 X10.000 Z25.000 R0.800 L3\n";
  auto r = Ctl({"tools", "load", "EM01", path});
  ASSERT_EQ(r.code, 0) << r.out << r.err;
  json tools = cell_.Json({"station", "tools", "EM01", "--json"});
  ASSERT_TRUE(tools.is_array()) << tools.dump();
  json six;
  for (const auto& e : tools) {
    if (e["tool"] == "6") six = e;
  }
  ASSERT_TRUE(six.is_object()) << tools.dump();
  EXPECT_EQ(six["socket"], 6);
  EXPECT_NEAR(six["x_offset"].get<double>(), 20.0, 1e-9);  // the file's X is a radius
  EXPECT_NEAR(six["z_offset"].get<double>(), 25.0, 1e-9);
  EXPECT_NEAR(six["nose_radius"].get<double>(), 0.8, 1e-9);
  EXPECT_EQ(six["tip"], 3);
  // A malformed file is refused with the file, line and column.
  std::ofstream(path) << "T0606 X10.000 Q1\n";
  auto bad = Ctl({"tools", "load", "EM01", path});
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.err.find("EM01.tools:1:15: error: unexpected 'Q'"), std::string::npos) << bad.err;
}

}  // namespace
