// Arcs in every plane reach the machine as the program turns them (issue 35, domain 44): a Balt-System
// program on BS01 cuts quarter circles in (DPI,X,Z) and (DPI,Y,X), a KT-APL program on KT01 in G18 (Z,X) and
// G19 (Y,Z), with the real processes on the real clock. The servo's commanded positions, sampled at 50 Hz
// from AxisState while the arcs run, lie on each circle and inside the quadrant the manual's sense gives; an
// arc turned in another plane, or the other way round, leaves the circle or sweeps the other three
// quadrants. DESIGN section 4: `plane` is the two axes in the program's order, `dir` seen with the first
// axis right and the second up.
#include <cmath>
#include <fstream>
#include <mutex>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cell/bus/bus.h"
#include "cell/bus/topics.h"
#include "cell/idl/motion.h"
#include "cell/testing/cell_fixture.h"

using namespace cell::testing;
using nlohmann::json;

namespace {

constexpr int kX = 0, kY = 1, kZ = 2;

// Balt-System (manual ln 6578-6604 DPI; ln 2936-2956: I J are the plane's abscissa and ordinate, absolute in
// G90). N3: (X,Z) from the top of the circle about X100 Z80 (R20) clockwise to its right end, a quarter
// through X >= 100, Z >= 80 at Y100. N5: (Y,X) from the top of the circle about Y100 X100 (first axis Y to
// the right, X up) counter-clockwise to its left end: Y <= 100, X >= 100 at Z80.
const char* kBalt =
    "N1 G0 X100 Y100 Z100\n"
    "N2 (DPI,X,Z)\n"
    "N3 G2 X120 Z80 I100 J80 F1500\n"
    "N4 (DPI,Y,X)\n"
    "N5 G3 Y80 X100 I100 J100\n"
    "N6 (DPI,X,Y)\n"
    "N7 M30\n";

// KT-APL (G18 = Z,X and G19 = Y,Z; centre words absolute in G90, manual ln 1270-1330). N30: from the top of
// the circle about Z100 X80 (Z to the right, X up) clockwise to its right end: Z >= 100, X >= 80 at Y100.
// N40: from the top of the circle about Y100 Z100 (Y right, Z up) counter-clockwise to its left end:
// Y <= 100, Z >= 100 at X80.
const char* kKtapl =
    "%\n(NAM,ARCS)\nN10 G71 G90\nN20 G00 X100. Y100. Z100. F0\n"
    "N30 G18 G02 X80. Z120. I80. K100. F1500.\n"
    "N40 G19 G03 Y80. Z100. J100. K100.\n"
    "N50 G17\nN60 M30\n%\n";

// A quarter circle: centre and radius in (first, second), the normal axis's value, and the signs the
// quadrant's points keep along first and second.
struct Quarter {
  const char* name;
  int first, second, normal;
  double c1, c2, at, r;
  double sign1, sign2;
};

struct Samples {
  std::mutex mu;
  std::vector<std::array<double, 3>> points;
};

// The samples on the quarter's circle (in its plane, at its normal value): how many, how many lie outside
// its quadrant, and the largest angle from the quadrant's start reached (proof the middle was sampled).
void Check(const Quarter& q, const std::vector<std::array<double, 3>>& pts) {
  int on = 0, outside = 0, middle = 0;
  for (const auto& p : pts) {
    if (std::abs(p[static_cast<size_t>(q.normal)] - q.at) > 1e-3) continue;
    const double u = p[static_cast<size_t>(q.first)] - q.c1, v = p[static_cast<size_t>(q.second)] - q.c2;
    if (std::abs(std::hypot(u, v) - q.r) > 0.05) continue;
    ++on;
    if (u * q.sign1 < -0.05 || v * q.sign2 < -0.05) ++outside;
    const double deg = std::atan2(std::abs(v), std::abs(u)) * 180.0 / M_PI;
    if (u * q.sign1 > 0 && v * q.sign2 > 0 && deg > 20 && deg < 70) ++middle;
  }
  EXPECT_GE(on, 10) << q.name << ": too few samples on the circle";
  EXPECT_EQ(outside, 0) << q.name << ": the arc left its quadrant (another plane or the other sense)";
  EXPECT_GE(middle, 3) << q.name << ": no samples along the middle of the arc";
}

class ArcPlanes : public CellFixture {
 protected:
  ArcPlanes() : CellFixture("cell-arc-planes-") {}
  void SetUp() override { Up("KT01,BS01", "real"); }
  void Run(const std::string& name, const std::string& text, const std::string& ext,
           const std::string& dialect, const std::string& station, const std::string& pallet) {
    const std::string path = cell_.data_dir() + "/" + name + "." + ext;
    std::ofstream(path) << text;
    auto put = Ctl({"program", "put", path, "--name", name, "--dialect", dialect});
    ASSERT_EQ(put.code, 0) << put.err;
    ASSERT_EQ(Ctl({"pallet", "set", pallet, name}).code, 0);
    auto run = Ctl({"pallet", "run", pallet, "--station", station});
    ASSERT_EQ(run.code, 0) << run.err;
    const std::string job = run.out.substr(0, run.out.find('\n'));
    auto wait = Ctl({"job", "wait", job, "--timeout", "120"});
    ASSERT_EQ(wait.code, 0) << wait.out << wait.err << CtlJson({"job", "show", job, "--json"}).dump();
  }
};

TEST_F(ArcPlanes, BaltAndKtaplArcsTurnInTheProgramsPlaneAndSense) {
  cell::bus::Participant bus("arc-planes-test");
  Samples balt, kt;
  cell::bus::Reader<cell::AxisState> axes(
      bus, cell::bus::topics::kAxisState, cell::bus::QosKind::kTelemetry,
      [&](const cell::AxisState& a, const cell::bus::SampleInfo&) {
        Samples& s = a.station() == "BS01" ? balt : kt;
        std::lock_guard lk(s.mu);
        s.points.push_back({a.commanded()[0], a.commanded()[1], a.commanded()[2]});
      });
  Run("ARCSB", kBalt, "balt", "balt", "BS01", "1");
  Run("ARCSK", kKtapl, "ktapl", "ktapl", "KT01", "2");
  {
    std::lock_guard lk(balt.mu);
    Check({"BS01 (DPI,X,Z) G2", kX, kZ, kY, 100, 80, 100, 20, +1, +1}, balt.points);
    Check({"BS01 (DPI,Y,X) G3", kY, kX, kZ, 100, 100, 80, 20, -1, +1}, balt.points);
  }
  std::lock_guard lk(kt.mu);
  Check({"KT01 G18 G02", kZ, kX, kY, 100, 80, 100, 20, +1, +1}, kt.points);
  Check({"KT01 G19 G03", kY, kZ, kX, 100, 100, 80, 20, -1, +1}, kt.points);
}

}  // namespace
