// Planner behaviour through the machine on the virtual clock: limits on every tick, exact stop vs blend,
// arc accuracy, feed hold and resume, optimal time on closed-form paths.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "cell/servo/machine.h"
#include "test_util.h"

namespace cell::servo {
namespace {

using machine::AxisConfig;
using machine::DefaultMachineConfig;
using testing::Arc;
using testing::Find;
using testing::LimitChecker;
using testing::Line;
using testing::Rapid;
using testing::RunChecked;

Machine Kt() {
  return Machine(DefaultMachineConfig("hmc"), ClockKind::kVirtual);
}

TEST(Planner, RandomContourRespectsAxisLimitsEveryTick) {
  Machine m = Kt();
  LimitChecker check(m);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(50, 450), feed(500, 12000), coin(0, 1);
  std::uint64_t id = 1;
  m.Push(Rapid(id++, 100, 100, 100));
  double x = 100, y = 100, z = 100;
  int pushed = 1;
  auto refill = [&] {
    while (m.credits() > 0 && pushed < 160) {
      double r = coin(rng);
      double nx = pos(rng), ny = pos(rng), nz = z + (coin(rng) - 0.5) * 20;
      if (r < 0.15) {
        // arc (possibly helical) around a centre offset from the current point
        double cx = x + (coin(rng) - 0.5) * 60, cy = y + (coin(rng) - 0.5) * 60;
        double R = std::hypot(x - cx, y - cy);
        double ang = coin(rng) * 2 * M_PI;
        nx = cx + R * std::cos(ang);
        ny = cy + R * std::sin(ang);
        m.Push(Arc(id++, nx, ny, nz, cx, cy, coin(rng) < 0.5, feed(rng)));
      } else if (r < 0.6) {
        // short segment: a small step, to exercise look-ahead
        nx = x + (coin(rng) - 0.5) * 4;
        ny = y + (coin(rng) - 0.5) * 4;
        m.Push(Line(id++, nx, ny, nz, feed(rng), coin(rng) < 0.1));
      } else if (r < 0.65) {
        m.Push(Rapid(id++, nx, ny, nz));
      } else {
        m.Push(Line(id++, nx, ny, nz, feed(rng), coin(rng) < 0.2));
      }
      x = nx, y = ny, z = nz;
      ++pushed;
    }
  };
  refill();
  auto ev = RunChecked(m, check, 600, refill);
  EXPECT_EQ(m.alarm().code, AlarmCode::kNone) << m.alarm().text;
  EXPECT_EQ(pushed, 160);
  int completed = 0;
  for (const auto& e : ev) completed += e.kind == EventKind::kCompleted;
  EXPECT_EQ(completed, 160);
  check.ExpectWithinLimits();
  EXPECT_GT(check.worst_a, 0.5);  // the checker sees real accelerations
  EXPECT_LT(check.max_fe, 0.1);
}

// Max distance of the actual XY(Z) position from a polyline.
double PolylineDistance(const Eigen::Vector3d& p, const std::vector<Eigen::Vector3d>& pts) {
  double best = 1e18;
  for (std::size_t i = 0; i + 1 < pts.size(); ++i)
    best = std::min(best, testing::DistToSegment(p, pts[i], pts[i + 1]));
  return best;
}

// A finely segmented curve (0.5 degree deflection per 2 mm block): exact stop halts at every vertex;
// blended blocks keep the speed up, stay within the path tolerance and finish much sooner.
TEST(Planner, ExactStopVersusBlendOnSegmentedCurve) {
  double times[2], min_vertex_speed[2], max_dev[2];
  for (int exact = 0; exact < 2; ++exact) {
    Machine m = Kt();
    std::vector<Eigen::Vector3d> pts{{100, 100, 100}};
    m.Push(Rapid(1, 100, 100, 100));
    m.RunUntilIdle();
    m.TakeEvents();
    LimitChecker check(m);
    double heading = 0;
    for (int i = 0; i < 40; ++i) {
      heading += 0.5 * M_PI / 180;
      Eigen::Vector3d q = pts.back() + 2.0 * Eigen::Vector3d(std::cos(heading), std::sin(heading), 0);
      pts.push_back(q);
      m.Push(Line(2 + i, q.x(), q.y(), q.z(), 3000, exact == 1));
    }
    const double t0 = m.machine_time();
    min_vertex_speed[exact] = 1e9;
    max_dev[exact] = 0;
    auto ev = RunChecked(m, check, 60, [&] {
      const Eigen::Vector3d c = m.commanded().head<3>();
      for (std::size_t i = 5; i + 5 < pts.size(); ++i)
        if ((c - pts[i]).norm() < 0.05)
          min_vertex_speed[exact] = std::min(min_vertex_speed[exact], m.planner().Speed());
      max_dev[exact] = std::max(max_dev[exact], PolylineDistance(m.actual().head<3>(), pts));
    });
    const Event* done = Find(ev, EventKind::kCompleted, 41);
    ASSERT_NE(done, nullptr);
    times[exact] = done->machine_time - t0;
    check.ExpectWithinLimits();
  }
  EXPECT_LT(min_vertex_speed[1], 1e-9);  // exact stop: the interpolator halts at each vertex
  EXPECT_GT(min_vertex_speed[0], 10.0);  // blended: passes the vertices above 10 mm/s (600 mm/min)
  EXPECT_LT(max_dev[0], Kt().config().path_tolerance);
  EXPECT_LT(max_dev[1], Kt().config().in_position);
  EXPECT_LT(times[0], 0.5 * times[1]);
}

// Exact stop at a 90-degree corner: the second block starts only inside the 0.025 mm window. In blend
// mode the corner is too sharp to round within the tolerance, so the planner stops there too.
TEST(Planner, SharpCorner) {
  for (int exact = 0; exact < 2; ++exact) {
    Machine m = Kt();
    m.Push(Rapid(1, 100, 100, 100));
    m.RunUntilIdle();
    m.TakeEvents();
    LimitChecker check(m);
    m.Push(Line(2, 200, 100, 100, 6000, exact == 1));
    m.Push(Line(3, 200, 200, 100, 6000));
    const Eigen::Vector3d corner(200, 100, 100);
    std::vector<Eigen::Vector3d> pts{{100, 100, 100}, corner, {200, 200, 100}};
    double dist_at_start3 = -1, max_dev = 0;
    const std::uint64_t limit = m.ticks() + 20000;
    while (m.ticks() < limit && m.Step()) {
      check.Sample();
      max_dev = std::max(max_dev, PolylineDistance(m.actual().head<3>(), pts));
      for (auto& e : m.TakeEvents())
        if (e.kind == EventKind::kStarted && e.segment_id == 3)
          dist_at_start3 = (m.actual().head<3>() - corner).norm();
    }
    check.ExpectWithinLimits();
    ASSERT_GE(dist_at_start3, 0);
    EXPECT_LE(dist_at_start3, m.config().in_position);
    EXPECT_LT(max_dev, exact ? m.config().in_position : m.config().path_tolerance);
    EXPECT_NEAR(m.actual()[kY], 200, 1e-3);
  }
}

TEST(Planner, CircleStaysWithinTolerance) {
  Machine m = Kt();
  m.Push(Rapid(1, 350, 300, 100));
  m.RunUntilIdle();
  LimitChecker check(m);
  const double R = 50, cx = 300, cy = 300;
  m.Push(Arc(2, 350, 300, 100, cx, cy, true, 4000, 1));  // two full turns
  double max_err = 0;
  auto ev = RunChecked(m, check, 60, [&] {
    const AxisVector a = m.actual();
    max_err = std::max(max_err, std::abs(std::hypot(a[kX] - cx, a[kY] - cy) - R));
  });
  ASSERT_NE(Find(ev, EventKind::kCompleted, 2), nullptr);
  check.ExpectWithinLimits();
  EXPECT_LT(max_err, m.config().path_tolerance);
  EXPECT_GT(max_err, 0.0);
}

TEST(Planner, HelixInZxPlaneEndsOnTarget) {
  Machine m = Kt();
  m.Push(Rapid(1, 300, 100, 200));
  m.RunUntilIdle();
  LimitChecker check(m);
  Segment s = Line(2, 300, 150, 200, 2000);  // ZX plane, y is the helix axis
  s.kind = SegmentKind::kArc;
  s.plane = {kZ, kX};
  s.center = {300, 0, 180};
  s.direction = ArcDirection::kCW;
  s.turns = 1;
  m.Push(s);
  double max_err = 0;
  auto ev = RunChecked(m, check, 120, [&] {
    const AxisVector a = m.actual();
    max_err = std::max(max_err, std::abs(std::hypot(a[kX] - 300, a[kZ] - 180) - 20));
  });
  ASSERT_NE(Find(ev, EventKind::kCompleted, 2), nullptr);
  check.ExpectWithinLimits();
  EXPECT_LT(max_err, m.config().path_tolerance);
  EXPECT_NEAR(m.actual()[kY], 150, 1e-3);
  EXPECT_NEAR(m.actual()[kZ], 200, 1e-3);
}

// DESIGN section 4: a plane is two axes in the program's order, the sense seen with the first axis right and
// the second up. (DPI,X,Z) G2 from the top of the circle to its right (+X) end is a quarter turn through
// X > cx, Z > cz; read as G18 (first Z) it would be three quarters through X < cx.
TEST(Planner, ArcInReversedPlaneTurnsInTheProgramsSense) {
  struct Case {
    ArcPlane plane;
    ArcDirection dir;
    double x0, y0, z0, x1, y1, z1;
  };
  // Centre (300, 200, 180) radius 20. First axis right, second up: start at 90 deg, end at 0 deg, cw.
  const Case cases[] = {
      {{kX, kZ}, ArcDirection::kCW, 300, 200, 200, 320, 200, 180},  // Balt (DPI,X,Z) G2
      {{kY, kX}, ArcDirection::kCW, 320, 200, 180, 300, 220, 180},  // Balt (DPI,Y,X) G2
      {{kZ, kY}, ArcDirection::kCW, 300, 220, 180, 300, 200, 200},  // (DPI,Z,Y) G2
  };
  for (const Case& c : cases) {
    Machine m = Kt();
    m.Push(Rapid(1, c.x0, c.y0, c.z0));
    m.RunUntilIdle();
    LimitChecker check(m);
    Segment s = Line(2, c.x1, c.y1, c.z1, 1000);
    s.kind = SegmentKind::kArc;
    s.plane = c.plane;
    s.center = {300, 200, 180};
    s.direction = c.dir;
    m.Push(s);
    const double centre[3] = {300, 200, 180};
    double lowest_first = 1e9, lowest_second = 1e9, max_err = 0;
    auto ev = RunChecked(m, check, 60, [&] {
      const AxisVector a = m.actual();
      const double u = a[c.plane.first] - centre[c.plane.first],
                   v = a[c.plane.second] - centre[c.plane.second];
      lowest_first = std::min(lowest_first, u);
      lowest_second = std::min(lowest_second, v);
      max_err = std::max(max_err, std::abs(std::hypot(u, v) - 20));
    });
    ASSERT_NE(Find(ev, EventKind::kCompleted, 2), nullptr);
    check.ExpectWithinLimits();
    // The quarter from 90 to 0 degrees stays in the first quadrant of (first, second).
    EXPECT_GT(lowest_first, -1e-3) << int(c.plane.first) << int(c.plane.second);
    EXPECT_GT(lowest_second, -1e-3) << int(c.plane.first) << int(c.plane.second);
    EXPECT_LT(max_err, m.config().path_tolerance);
    EXPECT_NEAR(m.actual()[kX], c.x1, 1e-3);
    EXPECT_NEAR(m.actual()[kY], c.y1, 1e-3);
    EXPECT_NEAR(m.actual()[kZ], c.z1, 1e-3);
  }
}

TEST(Planner, ArcOutsideTheLinearAxesIsRefused) {
  Machine m = Kt();
  PathElement e;
  std::string why;
  AxisVector a = AxisVector::Zero(), b = AxisVector::Zero();
  a[kX] = 10;
  b[kB] = 10;
  // Balt (DPI,B,Y) circles are refused by the dialect; a segment that names a rotary plane, or a co-axis
  // the station lacks (KT01 has no U-head), is refused here too, never turned in some other plane.
  EXPECT_FALSE(m.planner().MakeArc(a, b, {0, 0, 0}, {kB, kY}, ArcDirection::kCW, 0, e, why));
  EXPECT_NE(why.find("BY"), std::string::npos) << why;
  EXPECT_FALSE(m.planner().MakeArc(a, b, {0, 0, 0}, {kZ, kU}, ArcDirection::kCW, 0, e, why));
  EXPECT_NE(why.find("arc plane ZU: the station has no U axis"), std::string::npos) << why;
}

TEST(Planner, FeedHoldStopsOnPathAndResumes) {
  Machine m = Kt();
  m.Push(Rapid(1, 100, 100, 100));
  m.RunUntilIdle();
  m.TakeEvents();
  LimitChecker check(m);
  m.Push(Line(2, 400, 300, 100, 8000));
  for (int i = 0; i < 800; ++i) {
    m.Step();
    check.Sample();
  }
  m.FeedHold();
  RunChecked(m, check, 30);
  EXPECT_EQ(m.execution(), Execution::kFeedHold);
  EXPECT_EQ(m.planner().Speed(), 0.0);
  const AxisVector held = m.actual();
  EXPECT_LT(testing::DistToSegment(held.head<3>(), {100, 100, 100}, {400, 300, 100}), 1e-3);
  EXPECT_GT((held.head<3>() - Eigen::Vector3d(400, 300, 100)).norm(), 10.0);
  EXPECT_FALSE(m.Step());  // virtual clock: no activity, no machine time
  m.Resume();
  auto ev = RunChecked(m, check, 60);
  ASSERT_NE(Find(ev, EventKind::kCompleted, 2), nullptr);
  check.ExpectWithinLimits();
  EXPECT_NEAR(m.actual()[kX], 400, 1e-3);
}

TEST(Planner, FeedOverrideChangesTimeWithinLimits) {
  double t[2];
  for (int k = 0; k < 2; ++k) {
    Machine m = Kt();
    m.SetFeedOverride(k == 0 ? 1.0 : 0.5);
    LimitChecker check(m);
    m.Push(Line(1, 300, 0, 0, 6000, true));
    auto ev = RunChecked(m, check, 60);
    t[k] = Find(ev, EventKind::kCompleted, 1)->machine_time;
    check.ExpectWithinLimits();
  }
  EXPECT_NEAR(t[1] / t[0], 2.0, 0.1);
}

// Closed-form optimum for a rest-to-rest line with velocity V, acceleration A and jerk J limits when both
// V and A are reached: T = L/V + V/A + A/J.
TEST(Planner, LongLineWithinTwoPercentOfOptimum) {
  Machine m = Kt();
  const AxisConfig& x = m.config().axes[kX];
  const double V = 6000 / 60.0, A = x.max_acceleration, J = x.max_jerk, L = 600;
  m.Push(Line(1, L, 0, 0, 6000, true));
  auto ev = m.RunUntilIdle(60);
  (void)ev;
  auto events = m.TakeEvents();
  const Event* done = Find(events, EventKind::kCompleted, 1);
  ASSERT_NE(done, nullptr);
  const double optimum = L / V + V / A + A / J;
  EXPECT_GE(done->machine_time, optimum * 0.999);
  EXPECT_LE(done->machine_time, optimum * 1.02);
}

}  // namespace
}  // namespace cell::servo

namespace cell::servo {
namespace {

TEST(Planner, ArcInYzPlaneAndRapidOverride) {
  Machine m(DefaultMachineConfig("hmc"), ClockKind::kVirtual);
  m.Push(testing::Rapid(1, 300, 240, 300));
  m.RunUntilIdle();
  testing::LimitChecker check(m);
  Segment s = testing::Line(2, 300, 240, 300, 3000);
  s.kind = SegmentKind::kArc;
  s.plane = {kY, kZ};  // full circle around (y 200, z 300), radius 40
  s.center = {0, 200, 300};
  s.direction = ArcDirection::kCCW;
  m.Push(s);
  double max_err = 0, min_z = 1e9;
  auto ev = testing::RunChecked(m, check, 60, [&] {
    const AxisVector a = m.actual();
    max_err = std::max(max_err, std::abs(std::hypot(a[kY] - 200, a[kZ] - 300) - 40));
    min_z = std::min(min_z, a[kZ]);
    EXPECT_NEAR(a[kX], 300, 1e-3);
  });
  ASSERT_NE(testing::Find(ev, EventKind::kCompleted, 2), nullptr);
  check.ExpectWithinLimits();
  EXPECT_LT(max_err, m.config().path_tolerance);
  EXPECT_NEAR(min_z, 260, 0.05);  // really went round

  double t[2];
  for (int k = 0; k < 2; ++k) {
    Machine r(DefaultMachineConfig("hmc"), ClockKind::kVirtual);
    r.SetRapidOverride(k == 0 ? 1.0 : 0.25);
    testing::LimitChecker c2(r);
    r.Push(testing::Rapid(1, 600, 0, 0));
    auto e2 = testing::RunChecked(r, c2, 60);
    t[k] = testing::Find(e2, EventKind::kCompleted, 1)->machine_time;
    c2.ExpectWithinLimits();
  }
  EXPECT_GT(t[1] / t[0], 3.0);  // 600 mm at 25 % of 20 m/min
  EXPECT_LT(t[1] / t[0], 4.2);
}

}  // namespace
}  // namespace cell::servo

namespace cell::servo {
namespace {

// CAM output often repeats a point; a zero-length block must neither stop a blended path nor get lost.
TEST(Planner, DuplicatePointsDoNotStopBlending) {
  Machine m(DefaultMachineConfig("hmc"), ClockKind::kVirtual);
  m.Push(testing::Rapid(1, 100, 100, 100));
  m.RunUntilIdle();
  m.TakeEvents();
  testing::LimitChecker check(m);
  Eigen::Vector3d p(100, 100, 100);
  double heading = 0;
  std::uint64_t id = 2;
  for (int i = 0; i < 30; ++i) {
    heading += 0.5 * M_PI / 180;
    p += 2.0 * Eigen::Vector3d(std::cos(heading), std::sin(heading), 0);
    m.Push(testing::Line(id++, p.x(), p.y(), p.z(), 3000));
    if (i % 5 == 2) m.Push(testing::Line(id++, p.x(), p.y(), p.z(), 3000));  // duplicate
  }
  double min_speed = 1e9;
  int completed = 0;
  auto ev = testing::RunChecked(m, check, 60, [&] {
    if (m.planner().Position().x() > 110 && m.planner().Position().x() < 150)
      min_speed = std::min(min_speed, m.planner().Speed());
  });
  for (const auto& e : ev) completed += e.kind == EventKind::kCompleted;
  EXPECT_EQ(completed, static_cast<int>(id - 2));
  EXPECT_GT(min_speed, 10.0);
  check.ExpectWithinLimits();
}

}  // namespace
}  // namespace cell::servo

namespace cell::servo {
namespace {

// Line, tangent semicircle, line (a slot): blended without stopping, within the path tolerance.
TEST(Planner, TangentLineArcLineBlends) {
  Machine m(DefaultMachineConfig("hmc"), ClockKind::kVirtual);
  m.Push(testing::Rapid(1, 100, 100, 100));
  m.RunUntilIdle();
  m.TakeEvents();
  testing::LimitChecker check(m);
  m.Push(testing::Line(2, 200, 100, 100, 3000));
  m.Push(testing::Arc(3, 200, 140, 100, 200, 120, true, 3000));
  m.Push(testing::Line(4, 100, 140, 100, 3000));
  double min_speed = 1e9, max_dev = 0;
  auto ev = testing::RunChecked(m, check, 60, [&] {
    const AxisVector p = m.planner().Position();
    if (p.x() > 150) min_speed = std::min(min_speed, m.planner().Speed());
    const Eigen::Vector3d a = m.actual().head<3>();
    double d = std::min(testing::DistToSegment(a, {100, 100, 100}, {200, 100, 100}),
                        testing::DistToSegment(a, {200, 140, 100}, {100, 140, 100}));
    if (a.x() >= 200) d = std::min(d, std::abs(std::hypot(a.x() - 200, a.y() - 120) - 20));
    max_dev = std::max(max_dev, d);
  });
  ASSERT_NE(testing::Find(ev, EventKind::kCompleted, 4), nullptr);
  check.ExpectWithinLimits();
  EXPECT_GT(min_speed, 10.0);  // no stop at the tangent junctions
  EXPECT_LT(max_dev, m.config().path_tolerance);
}

}  // namespace
}  // namespace cell::servo
