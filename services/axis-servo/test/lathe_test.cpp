// The lathe station kind: X programmed as a diameter, feed per revolution, constant surface speed and
// spindle-synchronised threads (docs/axis-servo.md, "Lathes"). The built-in lathe (DefaultMachineConfig
// "lathe", like deploy/stations/OK01.toml): X and Z accelerate at 3000 mm/s², jerk 60000 mm/s³ (a jerk
// filter of 100 ticks), spindle max_rpm 3500, acceleration 1500 rpm/s, servo period 1 ms.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "cell/servo/machine.h"
#include "test_util.h"

namespace cell::servo {
namespace {

using machine::DefaultMachineConfig;
using testing::Find;

Machine Lathe() {
  return Machine(DefaultMachineConfig("lathe"), ClockKind::kVirtual);
}

// X as a diameter, Z.
Segment Move(std::uint64_t id, SegmentKind kind, double x, double z, double feed = 0,
             FeedMode mode = FeedMode::kPerMinute) {
  Segment s;
  s.id = id;
  s.kind = kind;
  s.end = {x, 0, z, 0, 0, 0};
  s.axes = 0x05;
  s.feed = feed;
  s.feed_mode = mode;
  return s;
}

Segment Rapid(std::uint64_t id, double x, double z) {
  return Move(id, SegmentKind::kRapid, x, z);
}

Segment Spindle(std::uint64_t id, double rpm, SpindleDirection dir = SpindleDirection::kCW) {
  Segment s;
  s.id = id;
  s.kind = SegmentKind::kSpindle;
  s.spindle_rpm = rpm;
  s.spindle_dir = dir;
  return s;
}

Segment Css(std::uint64_t id, double v, double limit, SpindleDirection dir = SpindleDirection::kCW) {
  Segment s = Spindle(id, 0, dir);
  s.css_surface_speed = v;
  s.spindle_max_rpm = limit;
  return s;
}

Segment Thread(std::uint64_t id, double x, double z, double lead, double change = 0, double angle = 0) {
  Segment s = Move(id, SegmentKind::kThread, x, z);
  s.thread_lead = lead;
  s.thread_lead_change = change;
  s.thread_start_angle = angle;
  return s;
}

// One servo tick as seen from outside.
struct Sample {
  double t = 0;
  double rev = 0;    // spindle revolutions turned (each test turns one way only)
  double angle = 0;  // degrees from the index mark
  double rpm = 0;
  double x = 0, z = 0;    // commanded after the jerk filter, X as a diameter
  double xi = 0, zi = 0;  // interpolated (before the filter), X as a diameter
  double path_feed = 0;   // mm/min
  std::uint64_t seg = 0;  // segment being interpolated
};

// Runs the machine until idle, sampling every tick.
std::vector<Sample> RunSampled(Machine& m, std::vector<Event>& ev, double max_s = 300) {
  std::vector<Sample> out;
  const std::uint64_t limit = m.ticks() + static_cast<std::uint64_t>(max_s / m.period());
  while (m.ticks() < limit && m.Step()) {
    const AxisState st = m.State();
    Sample s;
    s.t = st.machine_time;
    s.rev = std::abs(st.spindle_revolutions);
    s.angle = st.spindle_angle;
    s.rpm = st.spindle_rpm;
    s.x = st.commanded[kX];
    s.z = st.commanded[kZ];
    s.xi = 2 * m.interpolated()[kX];
    s.zi = m.interpolated()[kZ];
    s.path_feed = st.path_feed;
    s.seg = st.segment_id;
    out.push_back(s);
    for (auto& e : m.TakeEvents()) ev.push_back(e);
  }
  for (auto& e : m.TakeEvents()) ev.push_back(e);
  return out;
}

std::vector<Sample> Of(const std::vector<Sample>& all, std::uint64_t seg) {
  std::vector<Sample> out;
  for (const auto& s : all)
    if (s.seg == seg) out.push_back(s);
  return out;
}

// A coordinate at spindle revolution r (linear interpolation between ticks); NaN outside the samples.
double AtRev(const std::vector<Sample>& s, double r, double Sample::*f) {
  for (std::size_t i = 0; i + 1 < s.size(); ++i)
    if (s[i].rev <= r && r <= s[i + 1].rev && s[i + 1].rev > s[i].rev)
      return s[i].*f + (r - s[i].rev) / (s[i + 1].rev - s[i].rev) * (s[i + 1].*f - s[i].*f);
  return NAN;
}

// The spindle revolution at which a coordinate first reaches `v`; NaN if it never does.
double RevAt(const std::vector<Sample>& s, double v, double Sample::*f) {
  for (std::size_t i = 0; i + 1 < s.size(); ++i) {
    const double a = s[i].*f - v, b = s[i + 1].*f - v;
    if (a != b && (a <= 0) != (b <= 0)) return s[i].rev + a / (a - b) * (s[i + 1].rev - s[i].rev);
  }
  return NAN;
}

double Frac(double r) {
  return r - std::floor(r);
}

// ---- X as a diameter, feed per revolution.

TEST(Lathe, XIsProgrammedInDiameter) {
  Machine m = Lathe();
  m.Push(Move(1, SegmentKind::kLinear, 100, -50, 2000));
  // A per-revolution feed needs the spindle: 0.2 mm/rev at 1000 rpm = 200 mm/min.
  m.Push(Spindle(2, 1000));
  Segment f = Move(3, SegmentKind::kLinear, 100, -60, 0.2, FeedMode::kPerRevolution);
  f.exact_stop = true;
  m.Push(f);
  std::vector<Event> ev;
  RunSampled(m, ev);
  EXPECT_NEAR(m.actual()[kX], 50, 1e-3);         // radius inside the machine
  EXPECT_NEAR(m.State().actual[kX], 100, 2e-3);  // diameter outside
  const double t =
      Find(ev, EventKind::kCompleted, 3)->machine_time - Find(ev, EventKind::kStarted, 3)->machine_time;
  EXPECT_NEAR(t, 10.0 / (200.0 / 60), 0.2);
}

TEST(Lathe, FeedPerRevolutionWithTheSpindleStoppedIsAnAlarm) {
  Machine m = Lathe();
  m.Push(Move(1, SegmentKind::kLinear, 100, -10, 0.2, FeedMode::kPerRevolution));
  m.RunUntilIdle();
  EXPECT_EQ(m.alarm().code, AlarmCode::kInvalidSegment);
  EXPECT_NE(m.alarm().text.find("spindle stopped"), std::string::npos) << m.alarm().text;
}

TEST(Lathe, TurretIndexesWithTheSpindleTurning) {
  // A machining centre stops the spindle to change tools (Devices tests); a lathe's turret does not.
  Machine m = Lathe();
  m.Push(Spindle(1, 1200));
  Segment t;
  t.id = 2;
  t.kind = SegmentKind::kToolChange;
  t.tool = "2";
  m.SetToolTable(tooltable::ToolTable({{.tool = "1", .socket = 1}, {.tool = "2", .socket = 2}}));
  m.Push(t);
  std::vector<Event> ev;
  RunSampled(m, ev);
  ASSERT_NE(Find(ev, EventKind::kCompleted, 2), nullptr);
  EXPECT_EQ(m.State().tool, "2");
  EXPECT_EQ(m.State().spindle_rpm, 1200);
  const double t_change =
      Find(ev, EventKind::kCompleted, 2)->machine_time - Find(ev, EventKind::kStarted, 2)->machine_time;
  EXPECT_NEAR(t_change, m.config().tool_change_time + m.config().magazine_index_time, 2 * m.period());
}

// The live-tool (M-tool) spindle (Okuma M13/M14 SB=, M12; manual ln 1868-1871): its own speed, reached at
// its own acceleration, the work spindle untouched. The built-in lathe's live tool: 4000 rpm, 2000 rpm/s.
// M13 SB=400 from rest: 400 / 2000 = 0.2 s; M14 SB=1000 from +400: 1400 / 2000 = 0.7 s; M12: 0.5 s.
TEST(Lathe, TheLiveToolTurnsAtItsOwnSpeedAfterItsOwnRamp) {
  Machine m = Lathe();
  m.Push(Spindle(1, 1200));  // the work spindle, 1200 / 1500 = 0.8 s
  Segment live = Spindle(2, 400);
  live.live_tool = true;
  m.Push(live);
  live.id = 3;
  live.spindle_rpm = 1000;
  live.spindle_dir = SpindleDirection::kCCW;
  m.Push(live);
  live.id = 4;
  live.spindle_dir = SpindleDirection::kStop;
  m.Push(live);
  std::vector<Event> ev;
  RunSampled(m, ev);
  ASSERT_EQ(m.alarm().code, AlarmCode::kNone) << m.alarm().text;
  auto took = [&](std::uint64_t id) {
    return Find(ev, EventKind::kCompleted, id)->machine_time -
           Find(ev, EventKind::kStarted, id)->machine_time;
  };
  EXPECT_NEAR(took(1), 0.8, 2 * m.period());
  EXPECT_NEAR(took(2), 0.2, 2 * m.period());
  EXPECT_NEAR(took(3), 0.7, 2 * m.period());
  EXPECT_NEAR(took(4), 0.5, 2 * m.period());
  EXPECT_EQ(m.State().spindle_rpm, 1200);  // the work spindle kept its speed throughout
}

TEST(Lathe, ALiveToolOnAMachineWithoutOneOrAboveItsLimitIsAnAlarm) {
  Segment live = Spindle(1, 400);
  live.live_tool = true;
  Machine hmc(DefaultMachineConfig("hmc"), ClockKind::kVirtual);
  hmc.Push(live);
  hmc.RunUntilIdle();
  EXPECT_EQ(hmc.alarm().code, AlarmCode::kInvalidSegment);
  EXPECT_NE(hmc.alarm().text.find("no live-tool spindle"), std::string::npos) << hmc.alarm().text;
  Machine m = Lathe();
  live.spindle_rpm = 4500;  // above the built-in lathe's 4000
  m.Push(live);
  m.RunUntilIdle();
  EXPECT_EQ(m.alarm().code, AlarmCode::kInvalidSegment);
  EXPECT_NE(m.alarm().text.find("above live_tool_max_rpm 4000"), std::string::npos) << m.alarm().text;
}

// ---- Constant surface speed: rpm = min(limit, max_rpm, 1000 v / (pi D)).

double CssRpm(double v, double d) {
  return 1000 * v / (M_PI * d);
}

TEST(Lathe, ConstantSurfaceSpeedFollowsTheDiameterUpToTheLimits) {
  Machine m = Lathe();
  const double max_rpm = m.config().spindle_max_rpm;  // 3500
  m.Push(Rapid(1, 200, 2));
  m.Push(Css(2, 200, 0));  // 200 m/min, no programmed limit: the machine's 3500 rpm
  std::uint64_t id = 3;
  // At rest at each diameter the speed is exactly the formula's (the spindle has finished its ramp).
  for (double d : {200.0, 100.0, 50.0, 25.0}) {
    m.Push(Rapid(id++, d, 2));
    m.RunUntilIdle();
    EXPECT_NEAR(m.State().spindle_rpm, CssRpm(200, d), 1e-6) << "D " << d;
  }
  m.Push(Rapid(id++, 10, 2));  // 6366 rpm by the formula: the machine's max_rpm
  m.RunUntilIdle();
  EXPECT_NEAR(m.State().spindle_rpm, max_rpm, 1e-9);
  // A programmed limit (Okuma G50 S2000): clamps; at the centre (D = 0) the speed is the limit.
  m.Push(Css(id++, 200, 2000));
  m.Push(Rapid(id++, 50, 2));
  m.RunUntilIdle();
  EXPECT_NEAR(m.State().spindle_rpm, CssRpm(200, 50), 1e-6);  // 1273 < 2000
  m.Push(Rapid(id++, 20, 2));
  m.RunUntilIdle();
  EXPECT_NEAR(m.State().spindle_rpm, 2000, 1e-9);  // 3183 by the formula
  m.Push(Rapid(id++, 0, 2));
  m.RunUntilIdle();
  EXPECT_NEAR(m.State().spindle_rpm, 2000, 1e-9);
  // A limit above the machine's maximum: the machine's maximum.
  m.Push(Css(id++, 200, 9000));
  m.RunUntilIdle();
  EXPECT_NEAR(m.State().spindle_rpm, max_rpm, 1e-9);
  // Counter-clockwise: the same speed, negative.
  m.Push(Css(id++, 200, 0, SpindleDirection::kCCW));
  m.Push(Rapid(id++, 100, 2));
  m.RunUntilIdle();
  EXPECT_NEAR(m.State().spindle_rpm, -CssRpm(200, 100), 1e-6);
  // Off again (G97 S800): constant rpm wherever X goes.
  m.Push(Spindle(id++, 800));
  m.Push(Rapid(id++, 30, 2));
  m.Push(Rapid(id++, 180, 2));
  std::vector<Event> ev;
  for (const Sample& s : RunSampled(m, ev)) {
    if (s.seg == id - 1 || s.seg == id - 2) {
      EXPECT_EQ(s.rpm, 800);
    }
  }
  EXPECT_EQ(m.State().spindle_rpm, 800);
  EXPECT_EQ(m.alarm().code, AlarmCode::kNone) << m.alarm().text;
}

TEST(Lathe, ConstantSurfaceSpeedFacingCutFeedsPerActualRevolution) {
  // Facing from D 120 to D 8 at 0.15 mm/rev and 180 m/min, limit 3000 rpm: the speed rises with 1/D at
  // no more than the spindle's acceleration, reaches the limit at D = 19.1 mm, and the X feed is
  // 0.15 mm per actual revolution all the way.
  Machine m = Lathe();
  const double accel = m.config().spindle_accel_rpm_s, ts = m.period();
  m.Push(Rapid(1, 120, 0));
  m.Push(Css(2, 180, 3000));
  m.Push(Move(3, SegmentKind::kLinear, 8, 0, 0.15, FeedMode::kPerRevolution));
  std::vector<Event> ev;
  const std::vector<Sample> all = RunSampled(m, ev);
  ASSERT_EQ(m.alarm().code, AlarmCode::kNone) << m.alarm().text;
  const std::vector<Sample> cut = Of(all, 3);
  ASSERT_GT(cut.size(), 1000u);
  double worst_step = 0, worst_feed = 0, lag = 0;
  int checked = 0, ramping = 0;
  for (std::size_t i = 1; i < cut.size(); ++i) {
    const Sample& s = cut[i];
    const double step = s.rpm - cut[i - 1].rpm;
    worst_step = std::max(worst_step, std::abs(step));
    // The spindle heads for the speed of the diameter commanded one tick earlier: it is there, or on
    // its way at full acceleration.
    const double target = std::min(3000.0, CssRpm(180, cut[i - 1].x));
    EXPECT_LE(s.rpm, target + 1e-6) << "D " << s.x;  // never above the surface speed or the limit
    if (std::abs(s.rpm - target) > 1e-6) {
      EXPECT_NEAR(step, accel * ts, 1e-9) << "D " << s.x;
      ++ramping;
    }
    lag = std::max(lag, target - s.rpm);
    if (s.xi < 110 && s.xi > 12) {  // the interpolator is at feed, not ramping
      worst_feed = std::max(worst_feed, std::abs(s.path_feed - 0.15 * s.rpm) / (0.15 * s.rpm));
      ++checked;
    }
  }
  EXPECT_GT(checked, 500);
  EXPECT_LE(worst_step, accel * ts + 1e-9);  // the spindle's acceleration limit
  EXPECT_LT(worst_feed, 0.01);               // feed per actual revolution within 1 %
  // Near 3000 rpm the speed the diameter asks for rises faster than 1500 rpm/s (0.005 rpm³/57296 per
  // second at 0.15 mm/rev): there, and only there, the spindle lags, by at most a few per cent.
  EXPECT_GT(ramping, 0);
  EXPECT_LT(lag, 0.05 * 3000);
  EXPECT_NEAR(cut.back().rpm, 3000, 1e-9);  // at the limit near the centre
  // The cut takes as long as its revolutions at 0.15 mm each: 56 mm radial / 0.15 = 373 revolutions.
  const double revs = cut.back().rev - cut.front().rev;
  EXPECT_NEAR(revs, 56 / 0.15, 3);
}

TEST(Lathe, ConstantSurfaceSpeedNeedsALathe) {
  Machine m(DefaultMachineConfig("hmc"), ClockKind::kVirtual);
  m.Push(Css(1, 200, 0));
  m.RunUntilIdle();
  EXPECT_EQ(m.alarm().code, AlarmCode::kInvalidSegment);
  EXPECT_NE(m.alarm().text.find("constant surface speed needs a lathe"), std::string::npos);
}

// ---- Threads.

// Rapid to (x, z), the spindle at `rpm`, then `thread`: the samples of the thread.
std::vector<Sample> CutThread(Machine& m, double x, double z, double rpm, Segment thread,
                              SpindleDirection dir = SpindleDirection::kCW) {
  m.Push(Rapid(1, x, z));
  m.Push(Spindle(2, rpm, dir));
  thread.id = 3;
  m.Push(thread);
  std::vector<Event> ev;
  const std::vector<Sample> all = RunSampled(m, ev);
  EXPECT_EQ(m.alarm().code, AlarmCode::kNone) << m.alarm().text;
  return Of(all, 3);
}

// Checks that the commanded positions move `dx` (diameter) and `dz` per spindle revolution over n
// revolutions of the thread's steady part, starting where the commanded Z (or X) reaches `from`.
void ExpectTravelPerRevolution(const std::vector<Sample>& th, double Sample::*axis, double from, int n,
                               double dx, double dz, double tol = 1e-6) {
  const double r0 = RevAt(th, from, axis);
  ASSERT_FALSE(std::isnan(r0));
  for (int k = 0; k < n; ++k) {
    const double ddx = AtRev(th, r0 + k + 1, &Sample::x) - AtRev(th, r0 + k, &Sample::x);
    const double ddz = AtRev(th, r0 + k + 1, &Sample::z) - AtRev(th, r0 + k, &Sample::z);
    EXPECT_NEAR(ddx, dx, tol) << "revolution " << k;
    EXPECT_NEAR(ddz, dz, tol) << "revolution " << k;
  }
}

TEST(Lathe, StraightThreadTravelsOneLeadPerRevolutionFromTheStartAngle) {
  // M20x1.5 style: X 40 from Z 5 to Z -40, lead 1.5 mm at 600 rpm (900 mm/min), cut starting at 30°.
  Machine m = Lathe();
  const double lead = 1.5, rpm = 600, rps = rpm / 60, angle = 30;
  m.Push(Rapid(1, 40, 5));
  m.Push(Spindle(2, rpm));
  m.Push(Thread(3, 40, -40, lead, 0, angle));
  m.Push(Rapid(4, 46, -40));
  std::vector<Event> ev;
  const std::vector<Sample> all = RunSampled(m, ev);
  ASSERT_EQ(m.alarm().code, AlarmCode::kNone) << m.alarm().text;
  const std::vector<Sample> th = Of(all, 3);
  // Axial travel per revolution equals the lead, X stays (40 revolutions of the steady part).
  ExpectTravelPerRevolution(th, &Sample::z, -1, 25, 0, -lead);
  EXPECT_NEAR(m.State().commanded[kZ], -40, 1e-9);

  // The cut begins when the spindle passes the start angle: the first tick the interpolator moves.
  std::size_t first = 0;
  while (first < th.size() && th[first].zi == 5) ++first;
  ASSERT_LT(first, th.size());
  const double per_tick = 360 * rps * m.period();  // 3.6° per tick
  EXPECT_GT(th[first].angle, angle);
  EXPECT_LE(th[first].angle, angle + per_tick + 1e-9);

  // Phase: before the filter, Z = 5 - lead (R - ramp/2) after R revolutions from the pulse, where the
  // axis accelerates at the thread's path acceleration a = 0.98 x 3000 mm/s² (the planner's margin) over
  // ramp = rps v / a revolutions.
  const double v = lead * rps, a = 0.98 * m.config().axes[kZ].max_acceleration, ramp = rps * v / a;
  const Sample& started = th.front();  // the tick the thread began: it waits for the pulse from here
  const double pulse = started.rev + std::fmod(angle - started.angle + 360, 360) / 360;
  for (double r = 1; r < 25; r += 0.37) {
    const double zi = AtRev(th, pulse + r, &Sample::zi);
    EXPECT_NEAR(zi, 5 - lead * (r - ramp / 2), 1e-6) << "revolution " << r;
  }

  // Time: the synchronisation wait (less than a revolution), then length / (lead x rpm), plus the
  // acceleration lag (v/2a at each end) and the jerk filter's 0.1 s to be in position.
  const double t_start = Find(ev, EventKind::kStarted, 3)->machine_time;
  const double t_thread = Find(ev, EventKind::kCompleted, 3)->machine_time - t_start;
  const double wait = std::fmod(angle - started.angle + 360, 360) / 360 / rps;
  EXPECT_LT(wait, 1 / rps);
  const double ideal = wait + 45 / (lead * rpm / 60);
  const double filter = m.filter_length() * m.period();
  EXPECT_GE(t_thread, ideal);
  EXPECT_LE(t_thread, ideal + v / a + filter + 0.005);
}

// The state a pallet arrives in has the spindle at its index mark, as at power-up (docs/predict.md judgement
// call 4): ToArrival orients it, so a thread's wait for its start angle, and with it the run's time, is the
// same on every run whatever angle the run before stopped the spindle at (issue 40: Okuma threads 1.017-1.031
// and EMCO's 0.989 against their predictions, each run waiting a different fraction of a revolution).
TEST(Lathe, AThreadAfterThePalletsArrivalWaitsAsAfterPowerUp) {
  auto thread = [](Machine& m, std::uint64_t id) {
    m.Push(Rapid(id, 40, 5));
    m.Push(Spindle(id + 1, 600));
    m.Push(Thread(id + 2, 40, -40, 1.5, 0, 30));
    const double t0 = m.machine_time();
    m.RunUntilIdle();
    EXPECT_EQ(m.alarm().code, AlarmCode::kNone) << m.alarm().text;
    return m.machine_time() - t0;
  };
  Machine fresh = Lathe();
  const double at_power_up = thread(fresh, 1);

  Machine m = Lathe();
  Segment dwell;
  dwell.id = 2;
  dwell.kind = SegmentKind::kDwell;
  dwell.dwell_s = 0.337;
  m.Push(Spindle(1, 437));
  m.Push(dwell);
  m.Push(Spindle(3, 0, SpindleDirection::kStop));
  m.RunUntilIdle();
  ASSERT_GT(std::abs(m.State().spindle_angle - 180), 1)
      << "the spindle stopped at " << m.State().spindle_angle;
  ASSERT_GT(m.State().spindle_angle, 1);
  std::uint64_t id = 10;
  for (Segment s : m.ToArrival()) {
    s.id = ++id;
    m.Push(s);
  }
  m.RunUntilIdle();
  EXPECT_EQ(m.State().spindle_angle, 0.0);
  EXPECT_TRUE(m.ToArrival().empty());
  EXPECT_NEAR(thread(m, 20), at_power_up, 1.5 * m.period());
}

TEST(Lathe, AZeroLengthBlockBeforeAThreadDoesNotStartItEarly) {
  // A feed move to where the tool already is (common in generated programs) is a transparent marker to
  // the planner; the thread behind it still starts from rest at its start angle.
  Machine m = Lathe();
  m.Push(Rapid(1, 40, 5));
  m.Push(Spindle(2, 600));
  m.Push(Move(3, SegmentKind::kLinear, 40, 5, 300));
  m.Push(Thread(4, 40, -20, 1.5, 0, 200));
  std::vector<Event> ev;
  const std::vector<Sample> th = Of(RunSampled(m, ev), 4);
  ASSERT_EQ(m.alarm().code, AlarmCode::kNone) << m.alarm().text;
  std::size_t first = 0;
  while (first < th.size() && th[first].zi == 5) ++first;
  ASSERT_LT(first, th.size());
  EXPECT_GT(th[first].angle, 200);
  EXPECT_LE(th[first].angle, 200 + 3.6 + 1e-9);
  ExpectTravelPerRevolution(th, &Sample::z, 0, 10, 0, -1.5);
}

TEST(Lathe, EveryPassOfAThreadCutsTheSameGrooveAndStartsShiftIt) {
  // Three passes at 800 rpm, lead 2: pass 2 deeper, same start angle; pass 3 with the start angle 180°
  // (the second start of a two-start thread). Where the tool passes Z -20, the spindle angle is the same
  // on passes 1 and 2 and half a turn further on pass 3.
  Machine m = Lathe();
  m.Push(Rapid(1, 40, 4));
  m.Push(Spindle(2, 800));
  std::uint64_t id = 3;
  std::vector<std::uint64_t> passes;
  const double depth[] = {40, 39.6, 39.6}, start[] = {0, 0, 180};
  for (int p = 0; p < 3; ++p) {
    m.Push(Rapid(id++, depth[p], 4));
    passes.push_back(id);
    m.Push(Thread(id++, depth[p], -30, 2, 0, start[p]));
    m.Push(Rapid(id++, 46, -30));
    m.Push(Rapid(id++, 46, 4));
  }
  std::vector<Event> ev;
  const std::vector<Sample> all = RunSampled(m, ev);
  ASSERT_EQ(m.alarm().code, AlarmCode::kNone) << m.alarm().text;
  double phase[3];
  for (int p = 0; p < 3; ++p) {
    const double r = RevAt(Of(all, passes[p]), -20, &Sample::z);
    ASSERT_FALSE(std::isnan(r));
    phase[p] = Frac(r);
  }
  EXPECT_NEAR(phase[1], phase[0], 1e-6);
  EXPECT_NEAR(Frac(phase[2] - phase[0]), 0.5, 1e-6);
}

TEST(Lathe, FaceThreadLeadIsRadialTravelOnX) {
  // A face (scroll) thread, counter-clockwise: X 100 to X 20 (diameters) at Z 0, lead 2 mm of radius per
  // revolution at 300 rpm, start angle 90°. X has the larger travel: the lead is measured on it.
  Machine m = Lathe();
  const double lead = 2, rps = 5, angle = 90;
  const std::vector<Sample> th =
      CutThread(m, 100, 0, 300, Thread(3, 20, 0, lead, 0, angle), SpindleDirection::kCCW);
  ExpectTravelPerRevolution(th, &Sample::x, 90, 12, -2 * lead, 0);  // diameter: twice the radial lead
  // Turning backwards the spindle reaches 90° from above.
  std::size_t first = 0;
  while (first < th.size() && th[first].xi == 100) ++first;
  ASSERT_LT(first, th.size());
  EXPECT_LT(th[first].angle, angle);
  EXPECT_GE(th[first].angle, angle - 360 * rps * m.period() - 1e-9);
}

TEST(Lathe, TaperThreadLeadIsAlongTheMajorAxis) {
  // Gentle taper: Z travels 45, X 5 (radius): lead along Z, X follows in proportion.
  {
    Machine m = Lathe();
    const std::vector<Sample> th = CutThread(m, 40, 5, 500, Thread(3, 50, -40, 2));
    ExpectTravelPerRevolution(th, &Sample::z, -2, 15, 2 * 2 * 5.0 / 45, -2);
  }
  // Steep taper: X travels 50 (radius), Z 20: the lead is measured on X (Okuma G32, EMCO above 45°).
  {
    Machine m = Lathe();
    const std::vector<Sample> th = CutThread(m, 20, 0, 400, Thread(3, 120, -20, 3));
    ExpectTravelPerRevolution(th, &Sample::x, 35, 10, 2 * 3, -3 * 20.0 / 50);
  }
}

TEST(Lathe, VariableLeadThreadChangesItsLeadEveryRevolution) {
  // Okuma G34 (increasing) and G35 (decreasing): the lead changes by E every revolution, so the travel
  // of revolution k+1 differs from that of revolution k by E, and the lead after rho revolutions from the
  // start is L0 + E rho.
  for (double e : {0.05, -0.03}) {
    Machine m = Lathe();
    const double l0 = e > 0 ? 2.0 : 3.0;
    const std::vector<Sample> th = CutThread(m, 40, 5, 300, Thread(3, 40, -80, l0, e));
    const double r0 = RevAt(th, 0, &Sample::z);
    double prev = NAN;
    for (int k = 0; k < 20; ++k) {
      const double d = AtRev(th, r0 + k, &Sample::z) - AtRev(th, r0 + k + 1, &Sample::z);
      if (!std::isnan(prev)) {
        EXPECT_NEAR(d - prev, e, 1e-5) << "E " << e << " revolution " << k;
      }
      prev = d;
    }
    // The end lead: sqrt(L0² + 2 E travel) (travel = L0 rho + E rho²/2), seen over the last steady
    // revolutions before the deceleration.
    const double end_lead = std::sqrt(l0 * l0 + 2 * e * 85);
    const double r1 = RevAt(th, -75, &Sample::z);
    const double d1 = AtRev(th, r1 - 1, &Sample::z) - AtRev(th, r1, &Sample::z);
    EXPECT_NEAR(d1, end_lead, std::abs(e) * 4);  // within a few revolutions of the end
  }
}

TEST(Lathe, ChainedThreadsContinueWithoutWaiting) {
  // A straight thread running into a taper thread (Okuma G34/G35 chains, thread pull-out): the second
  // follows the spindle on from where the first ended, no stop and no index wait between them.
  Machine m = Lathe();
  m.Push(Rapid(1, 40, 5));
  m.Push(Spindle(2, 600));
  m.Push(Thread(3, 40, -20, 1.5, 0, 45));
  m.Push(Thread(4, 43, -22, 1.5, 0, 270));  // its start angle is ignored: it continues the chain
  m.Push(Rapid(5, 50, -22));
  std::vector<Event> ev;
  const std::vector<Sample> all = RunSampled(m, ev);
  ASSERT_EQ(m.alarm().code, AlarmCode::kNone) << m.alarm().text;
  const std::vector<Sample> th = Of(all, 4);
  ASSERT_FALSE(th.empty());
  // Around the junction the interpolator keeps the thread's pace (15 mm/s = 900 mm/min, then 1125 along
  // the taper).
  for (const Sample& s : all) {
    if (std::abs(s.t - th.front().t) < 0.05) {
      EXPECT_GT(s.path_feed, 800) << "t " << s.t;
    }
  }
  // The second thread: lead 1.5 along Z (|dZ| 2 > |dX| 1.5 as a radius).
  const double r0 = RevAt(th, -20.3, &Sample::zi);
  const double r1 = RevAt(th, -21.5, &Sample::zi);
  EXPECT_NEAR(r1 - r0, 1.2 / 1.5, 1e-6);
}

TEST(Lathe, ExactStopThreadsStopAndTheNextWaitsForItsStartAngle) {
  // Okuma G65 (droop control) on G31-G35: each thread ends in position, so a thread after it starts from
  // rest at its own start angle instead of continuing the chain.
  Machine m = Lathe();
  m.Push(Rapid(1, 40, 5));
  m.Push(Spindle(2, 600));
  Segment first = Thread(3, 40, -20, 1.5, 0, 45);
  first.exact_stop = true;
  m.Push(first);
  m.Push(Thread(4, 43, -22, 1.5, 0, 270));
  m.Push(Rapid(5, 50, -22));
  std::vector<Event> ev;
  const std::vector<Sample> all = RunSampled(m, ev);
  ASSERT_EQ(m.alarm().code, AlarmCode::kNone) << m.alarm().text;
  const std::vector<Sample> th = Of(all, 4);
  ASSERT_FALSE(th.empty());
  // The path stops at the junction: the second thread starts at rest.
  EXPECT_LT(th.front().path_feed, 1) << "t " << th.front().t;
  // It begins to move when the spindle passes 270 degrees (3.6 degrees per tick at 600 rpm).
  std::size_t moving = 0;
  while (moving < th.size() && th[moving].zi == -20) ++moving;
  ASSERT_LT(moving, th.size());
  EXPECT_GT(th[moving].angle, 270);
  EXPECT_LE(th[moving].angle, 270 + 3.6 + 1e-9);
}

TEST(Lathe, ThreadIgnoresFeedHoldAndOverrideUntilItsEnd) {
  // Feed hold during a thread is deferred to the end of the thread block; the feed override does not
  // change the lead (Okuma: feed override ignored, slide hold finishes the pass; EMCO: FEEDHOLD waits
  // until the end of the thread pass).
  Machine m = Lathe();
  m.SetFeedOverride(0.5);
  m.Push(Rapid(1, 40, 5));
  m.Push(Spindle(2, 600));
  m.Push(Thread(3, 40, -30, 1.5));
  m.Push(Rapid(4, 46, -30));
  std::vector<Event> ev;
  std::vector<Sample> th;
  bool held = false;
  while (m.Step()) {
    for (auto& e : m.TakeEvents()) ev.push_back(e);
    const AxisState st = m.State();
    if (st.segment_id == 3) {
      th.push_back({st.machine_time, std::abs(st.spindle_revolutions), st.spindle_angle, st.spindle_rpm,
                    st.commanded[kX], st.commanded[kZ], 0, 0, st.path_feed, 3});
      if (!held && st.commanded[kZ] < -10) {
        m.FeedHold();
        held = true;
      }
    }
  }
  ASSERT_TRUE(held);
  ASSERT_NE(Find(ev, EventKind::kCompleted, 3), nullptr);  // the thread ran to its end
  EXPECT_EQ(Find(ev, EventKind::kCompleted, 4), nullptr);  // the retract waits for the resume
  EXPECT_NEAR(m.State().commanded[kX], 40, 1e-9);
  EXPECT_EQ(m.execution(), Execution::kFeedHold);
  ExpectTravelPerRevolution(th, &Sample::z, -5, 14, 0, -1.5);  // across the hold, at 50 % override
  m.Resume();
  RunSampled(m, ev);
  EXPECT_NE(Find(ev, EventKind::kCompleted, 4), nullptr);
}

TEST(Lathe, AbortStopsAThread) {
  Machine m = Lathe();
  m.Push(Rapid(1, 40, 5));
  m.Push(Spindle(2, 600));
  m.Push(Thread(3, 40, -60, 1.5));
  while (m.Step())
    if (m.State().commanded[kZ] < -10) break;
  m.Abort();
  std::vector<Event> ev;
  RunSampled(m, ev, 5);
  EXPECT_TRUE(m.Idle());
  EXPECT_NE(Find(ev, EventKind::kFlushed, 3), nullptr);
  EXPECT_GT(m.State().commanded[kZ], -12);  // decelerated at once, far from the end
}

TEST(Lathe, InvalidThreadsAreAlarms) {
  auto alarm_of = [](std::vector<Segment> segs) {
    Machine m = Lathe();
    for (const auto& s : segs) m.Push(s);
    m.RunUntilIdle();
    EXPECT_EQ(m.alarm().code, AlarmCode::kInvalidSegment);
    return m.alarm().text;
  };
  // No spindle: nothing to synchronise with.
  EXPECT_NE(alarm_of({Rapid(1, 40, 5), Thread(2, 40, -20, 1.5)}).find("thread with the spindle stopped"),
            std::string::npos);
  // Lead x rpm above the axis's max_velocity (Okuma: N·P below the maximum feedrate): 5 mm x 3000 rpm =
  // 15000 mm/min on Z, max 10000.
  EXPECT_NE(alarm_of({Spindle(1, 3000), Thread(2, 40, -20, 5)}).find("above max_velocity"),
            std::string::npos);
  // A decreasing lead that would reach zero before the end.
  EXPECT_NE(alarm_of({Spindle(1, 300), Rapid(2, 40, 5), Thread(3, 40, -80, 1, -0.05)}).find("reaches zero"),
            std::string::npos);
  EXPECT_NE(alarm_of({Spindle(1, 300), Rapid(2, 40, 5), Thread(3, 40, -20, 0)}).find("lead is zero"),
            std::string::npos);
}

// ---- The C-axis joint (Okuma M110/M109, manual ln 1983-1984, 2057-2069), on OK01's station file: X, Z and
// C, spindle 1500 rpm/s, c_joint_time 1 s, C at 7200 deg/min.

Machine Ok01() {
  return Machine(machine::LoadMachineConfig(std::string(CELL_SOURCE_DIR) + "/deploy/stations/OK01.toml"),
                 ClockKind::kVirtual);
}

Segment Joint(std::uint64_t id, bool join) {
  return Spindle(id, 0, join ? SpindleDirection::kAxis : SpindleDirection::kStop);
}

Segment CMove(std::uint64_t id, double c) {
  Segment s;
  s.id = id;
  s.kind = SegmentKind::kRapid;
  s.end[kC] = c;
  s.axes = 1u << kC;
  return s;
}

// The arrival's segments run as the station sends them (ids from 10).
void RunArrival(Machine& m, std::vector<Segment> arrival) {
  std::uint64_t id = 10;
  for (Segment& s : arrival) {
    s.id = id++;
    m.Push(s);
  }
  m.RunUntilIdle();
}

double Took(const std::vector<Event>& ev, std::uint64_t id) {
  return Find(ev, EventKind::kCompleted, id)->machine_time - Find(ev, EventKind::kStarted, id)->machine_time;
}

// M03 S900, M110 (the spindle stops: 900 / 1500 = 0.6 s, then the joint: 1 s), C90, M109 (1 s): C moves
// joined, and after the release a C move is the servo's alarm, not executed (C stays at 90, commanded and
// actual).
TEST(Lathe, CMovesOnlyWhileJoinedAndTheJointTakesTheStationsTime) {
  Machine m = Ok01();
  ASSERT_EQ(m.config().c_joint_time, 1.0);
  m.Push(Spindle(1, 900));
  m.Push(Joint(2, true));
  m.Push(CMove(3, 90));
  m.Push(Joint(4, false));
  m.Push(CMove(5, 180));
  std::vector<Event> ev;
  RunSampled(m, ev);
  EXPECT_NEAR(Took(ev, 2), 0.6 + 1.0, 2 * m.period());
  EXPECT_NEAR(Took(ev, 4), 1.0, 2 * m.period());
  ASSERT_NE(Find(ev, EventKind::kCompleted, 3), nullptr);
  EXPECT_EQ(m.alarm().code, AlarmCode::kInvalidSegment);
  EXPECT_NE(m.alarm().text.find("segment 5: C 180.0000 while the C axis is not joined (M110)"),
            std::string::npos)
      << m.alarm().text;
  EXPECT_EQ(Find(ev, EventKind::kStarted, 5), nullptr);
  EXPECT_NEAR(m.State().commanded[kC], 90, 1e-6);
  EXPECT_NEAR(m.State().actual[kC], 90, 1e-3);
  EXPECT_FALSE(m.State().c_joined);
  EXPECT_EQ(m.State().spindle_rpm, 0);
}

// From power-up C is released: the first C move is the alarm, nothing moves.
TEST(Lathe, ACMoveWithoutTheJointIsAnAlarmOfTheServo) {
  Machine m = Ok01();
  EXPECT_FALSE(m.State().c_joined);
  m.Push(CMove(1, 45));
  std::vector<Event> ev;
  RunSampled(m, ev);
  EXPECT_EQ(m.alarm().code, AlarmCode::kInvalidSegment);
  EXPECT_EQ(Find(ev, EventKind::kStarted, 1), nullptr);
  EXPECT_EQ(m.State().actual[kC], 0);
  // The built-in lathe has no C axis: its spindle cannot be joined.
  Machine plain = Lathe();
  plain.Push(Joint(1, true));
  plain.RunUntilIdle();
  EXPECT_NE(plain.alarm().text.find("cannot be joined as a C axis"), std::string::npos) << plain.alarm().text;
}

// While joined the spindle is an axis: M03, M04 and M19 are alarms (the manual stops the spindle before
// M110 and returns it with M109 before turning, ln 2042-2053, 2079-2140).
TEST(Lathe, TheSpindleCannotTurnOrOrientWhileCIsJoined) {
  for (SpindleDirection d : {SpindleDirection::kCW, SpindleDirection::kCCW, SpindleDirection::kOrient}) {
    Machine m = Ok01();
    m.Push(Joint(1, true));
    m.Push(Spindle(2, 500, d));
    std::vector<Event> ev;
    RunSampled(m, ev);
    EXPECT_EQ(m.alarm().code, AlarmCode::kInvalidSegment);
    EXPECT_NE(m.alarm().text.find("segment 2: the spindle is joined as the C axis (M110)"), std::string::npos)
        << m.alarm().text;
    EXPECT_EQ(m.State().spindle_rpm, 0);
    EXPECT_TRUE(m.State().c_joined);  // the alarm does not release it (M110 survives a reset, ln 2059)
    m.Reset();
    EXPECT_TRUE(m.State().c_joined);
  }
}

// The state a pallet arrives in has C released at 0: joined, the machine goes there and releases; released
// off 0, it joins to get there.
TEST(Lathe, TheArrivalStateReleasesCAtZero) {
  for (bool release_first : {false, true}) {
    Machine m = Ok01();
    m.Push(Joint(1, true));
    m.Push(CMove(2, 270));
    if (release_first) m.Push(Joint(3, false));
    m.RunUntilIdle();
    ASSERT_EQ(m.alarm().code, AlarmCode::kNone) << m.alarm().text;
    std::vector<Segment> arrival = m.ToArrival();
    RunArrival(m, arrival);
    ASSERT_EQ(m.alarm().code, AlarmCode::kNone) << m.alarm().text;
    EXPECT_FALSE(m.State().c_joined);
    EXPECT_NEAR(m.State().actual[kC], 0, 1e-3);
    EXPECT_TRUE(m.ToArrival().empty());
    // (join,) C to 0, release, orient: the spindle stands at its index mark as at power-up.
    EXPECT_EQ(arrival.size(), release_first ? 4u : 3u);
  }
}

// A turning spindle released with C off 0: the join stops it, so the arrival orients it once, at the end.
TEST(Lathe, TheArrivalOrientsATurningSpindleOnceAfterCReachesZero) {
  Machine m = Ok01();
  m.Push(Joint(1, true));
  m.Push(CMove(2, 90));
  m.Push(Joint(3, false));
  m.Push(Spindle(4, 500, SpindleDirection::kCW));
  m.RunUntilIdle();
  ASSERT_EQ(m.alarm().code, AlarmCode::kNone) << m.alarm().text;
  std::vector<Segment> arrival = m.ToArrival();
  ASSERT_EQ(arrival.size(), 4u);  // join, C to 0, release, orient
  EXPECT_EQ(arrival.front().spindle_dir, SpindleDirection::kAxis);
  EXPECT_EQ(arrival.back().spindle_dir, SpindleDirection::kOrient);
  RunArrival(m, arrival);
  ASSERT_EQ(m.alarm().code, AlarmCode::kNone) << m.alarm().text;
  EXPECT_TRUE(m.ToArrival().empty());
}

// The live tool's speed is in the machine's state, beside the work spindle's (the service publishes both on
// cell/motion/axes).
TEST(Lathe, TheStateCarriesTheLiveToolsSpeed) {
  Machine m = Ok01();
  Segment live = Spindle(1, 400, SpindleDirection::kCCW);
  live.live_tool = true;
  m.Push(live);
  m.RunUntilIdle();
  EXPECT_EQ(m.State().live_tool_rpm, -400);
  EXPECT_EQ(m.State().spindle_rpm, 0);
}

}  // namespace
}  // namespace cell::servo
