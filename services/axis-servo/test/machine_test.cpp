// Machine-level behaviour: servo and plant, alarms, flow control, clocks, devices and the index axis
// (lathes: lathe_test.cpp).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "cell/error/error.h"
#include "cell/servo/machine.h"
#include "test_util.h"

namespace cell::servo {
namespace {

using machine::AxisConfig;
using machine::DefaultMachineConfig;
using machine::LoadMachineConfig;
using machine::MachineConfig;
using testing::Find;
using testing::LimitChecker;
using testing::Line;
using testing::Rapid;
using testing::RunChecked;
using testing::SpindleOn;

Machine Kt(ClockKind clock = ClockKind::kVirtual) {
  return Machine(DefaultMachineConfig("hmc"), clock);
}

TEST(Servo, FollowingErrorNonZeroWhileAcceleratingAndBounded) {
  Machine m = Kt();
  m.Push(Line(1, 300, 0, 0, 9000, true));
  double max_accel_fe = 0, max_fe = 0, cruise_fe = 1e9;
  double prev_v = 0;
  while (m.Step()) {
    const double v = (m.commanded()[kX]);
    (void)v;
    const AxisState s = m.State();
    const double fe = std::abs(s.following_error[kX]);
    max_fe = std::max(max_fe, fe);
    const double vel = s.velocity[kX] / 60.0;
    const double acc = (vel - prev_v) / m.period();
    prev_v = vel;
    if (std::abs(acc) > 0.5 * m.config().axes[kX].max_acceleration) max_accel_fe = std::max(max_accel_fe, fe);
  }
  EXPECT_GT(max_accel_fe, 1e-4);                                       // physically non-zero
  EXPECT_LT(max_fe, 0.2 * m.config().axes[kX].following_error_limit);  // and bounded
  EXPECT_LT(std::abs(m.following_error()[kX]), 1e-4);                  // settles at rest
  (void)cruise_fe;
}

TEST(Servo, DiffOverAlarmWhenTheDriveCannotFollow) {
  MachineConfig c = DefaultMachineConfig("hmc");
  c.axes[kX].drive.max_torque = 1.0;  // far too weak for the configured acceleration
  Machine m(c, ClockKind::kVirtual);
  m.Push(Line(1, 300, 0, 0, 9000, true));
  m.Push(Line(2, 0, 0, 0, 9000, true));
  auto ev = m.RunUntilIdle(30);
  (void)ev;
  auto events = m.TakeEvents();
  EXPECT_EQ(m.alarm().code, AlarmCode::kFollowingError);
  EXPECT_NE(m.alarm().text.find("DIFF over X"), std::string::npos) << m.alarm().text;
  EXPECT_EQ(m.execution(), Execution::kStopped);
  EXPECT_NE(Find(events, EventKind::kAlarm, 1), nullptr);
  EXPECT_NE(Find(events, EventKind::kFlushed, 2), nullptr);
  EXPECT_THROW(m.Push(Line(3, 0, 0, 0, 100)), Error);
  m.Reset();
  EXPECT_EQ(m.alarm().code, AlarmCode::kNone);
  EXPECT_NO_THROW(m.Push(Line(3, 0, 0, 0, 100)));
}

// TakeEvents(into) gives the events TakeEvents() gives, in order, and keeps the caller's buffer for the
// next ones: a loop that takes events with two buffers allocates nothing once they have grown (issue 38).
TEST(Machine, TakeEventsIntoABufferSameEventsAndReusesIt) {
  Machine a = Kt(), b = Kt();
  for (std::uint64_t id = 1; id <= 6; ++id) {
    a.Push(Line(id, 10.0 * id, 5, 0, 3000));
    b.Push(Line(id, 10.0 * id, 5, 0, 3000));
  }
  std::vector<Event> by_value, into, buf;
  while (a.Step()) {
    ASSERT_TRUE(b.Step());
    ASSERT_EQ(a.HasEvents(), b.HasEvents());
    if (!a.HasEvents()) continue;
    for (const Event& e : a.TakeEvents()) by_value.push_back(e);
    b.TakeEvents(buf);
    for (const Event& e : buf) into.push_back(e);
  }
  ASSERT_EQ(by_value.size(), 12u);  // started and completed, six blocks
  ASSERT_EQ(into.size(), by_value.size());
  for (std::size_t i = 0; i < into.size(); ++i) {
    EXPECT_EQ(into[i].kind, by_value[i].kind) << i;
    EXPECT_EQ(into[i].segment_id, by_value[i].segment_id) << i;
    EXPECT_EQ(into[i].machine_time, by_value[i].machine_time) << i;
  }
  // The buffer handed in is where the next events go.
  std::vector<Event> spare;
  spare.reserve(16);
  const Event* storage = spare.data();
  b.TakeEvents(spare);  // hands `spare`'s storage to the machine
  b.Push(Line(7, 0, 0, 0, 3000));
  while (!b.HasEvents()) ASSERT_TRUE(b.Step());
  std::vector<Event> got;
  b.TakeEvents(got);
  EXPECT_EQ(got.data(), storage);
  EXPECT_EQ(got.front().segment_id, 7u);
}

TEST(Machine, SoftLimitAlarmBeforeMotion) {
  Machine m = Kt();
  m.Push(Rapid(1, 100, 100, 100));
  m.Push(Line(2, 900, 100, 100, 3000));  // X max is 800
  m.Push(Line(3, 100, 200, 100, 3000));
  m.RunUntilIdle(30);
  auto ev = m.TakeEvents();
  EXPECT_EQ(m.alarm().code, AlarmCode::kSoftLimit);
  EXPECT_NE(m.alarm().text.find("X+"), std::string::npos) << m.alarm().text;
  EXPECT_NE(Find(ev, EventKind::kCompleted, 1), nullptr);
  EXPECT_EQ(Find(ev, EventKind::kStarted, 2), nullptr);  // no motion of the bad segment
  EXPECT_NE(Find(ev, EventKind::kFlushed, 3), nullptr);
  EXPECT_NEAR(m.actual()[kX], 100, 1e-3);
  // An arc whose bulge leaves the travel: the check covers the arc's extent, not only its end point.
  m.Reset();
  m.Push(testing::Arc(4, 100, 300, 100, 100, 200, true, 2000));  // bulges to x = 200
  m.Push(testing::Arc(5, 100, 100, 100, 100, 200, true, 2000));  // bulges to x = 0, inside -5
  m.RunUntilIdle(60);
  EXPECT_EQ(m.alarm().code, AlarmCode::kNone) << m.alarm().text;
  m.Push(testing::Arc(6, 100, 500, 100, 100, 300, false, 2000));  // r 200 cw from (100,100): x to -100
  m.RunUntilIdle(60);
  EXPECT_EQ(m.alarm().code, AlarmCode::kSoftLimit);
  EXPECT_NE(m.alarm().text.find("X-"), std::string::npos) << m.alarm().text;
}

TEST(Machine, FlowControlUnderSlowConsumer) {
  MachineConfig c = DefaultMachineConfig("hmc");
  c.queue_capacity = 4;
  Machine m(c, ClockKind::kVirtual);
  LimitChecker check(m);
  EXPECT_EQ(m.credits(), 4u);
  std::uint64_t next = 1, completed = 0;
  const std::uint64_t total = 40;
  std::size_t max_queued = 0;
  // The producer is fast but only sends on credit; every segment is long compared with the queue.
  auto produce = [&] {
    while (m.credits() > 0 && next <= total) {
      const double x = (next % 2) ? 200 : 100;
      m.Push(Line(next, x, 10.0 * next, 50, 6000));
      ++next;
    }
    max_queued = std::max(max_queued, m.capacity() - m.credits());
  };
  produce();
  EXPECT_THROW(m.Push(Line(99, 0, 0, 0, 100)), Error);  // no credit left
  {
    Machine v(c, ClockKind::kVirtual);
    EXPECT_THROW(v.Push(Line(1, std::nan(""), 0, 0, 100)), Error);
    EXPECT_THROW(v.Push(Line(1, 0, 0, 0, -5)), Error);
    EXPECT_EQ(v.credits(), 4u);
  }
  std::uint64_t expect_id = 1;
  std::vector<Event> ev = RunChecked(m, check, 600, [&] {
    produce();
    for (const auto& e : m.TakeEvents()) {
      if (e.kind == EventKind::kCompleted) {
        EXPECT_EQ(e.segment_id, expect_id) << "completions in order";
        ++expect_id;
        ++completed;
      }
    }
  });
  EXPECT_EQ(completed, total);
  EXPECT_LE(max_queued, 4u);
  EXPECT_EQ(m.credits(), 4u);
  check.ExpectWithinLimits();

  // A starved consumer: segments arrive slower than the machine runs them; it slows down safely.
  Machine s(c, ClockKind::kVirtual);
  LimitChecker check2(s);
  int sent = 0;
  for (int tick = 0; tick < 20000; ++tick) {
    if (tick % 150 == 0 && sent < 30 && s.credits() > 0) {
      ++sent;
      s.Push(Line(sent, 100 + 10 * sent, 100 + ((sent % 2) ? 5 : 0), 50, 9000));
    }
    if (s.Step()) check2.Sample();
  }
  check2.ExpectWithinLimits();
  EXPECT_EQ(s.credits(), 4u);
  EXPECT_NEAR(s.actual()[kX], 400, 1e-3);
}

TEST(Machine, AbortFlushesAndStops) {
  Machine m = Kt();
  LimitChecker check(m);
  m.Push(Line(1, 500, 0, 0, 9000));
  m.Push(Line(2, 500, 500, 0, 9000));
  for (int i = 0; i < 500; ++i) {
    m.Step();
    check.Sample();
  }
  m.Abort();
  auto ev = RunChecked(m, check, 30);
  EXPECT_NE(Find(ev, EventKind::kFlushed, 1), nullptr);
  EXPECT_NE(Find(ev, EventKind::kFlushed, 2), nullptr);
  EXPECT_EQ(m.credits(), m.capacity());
  EXPECT_EQ(m.execution(), Execution::kReady);
  EXPECT_LT(m.actual()[kX], 499);
  check.ExpectWithinLimits();
}

TEST(Clock, VirtualAndRealAgreeOnCycleTime) {
  auto program = [](Machine& m) {
    m.Push(Rapid(1, 20, 10, 0));
    m.Push(Line(2, 40, 30, 0, 3000));
    m.Push(Line(3, 60, 10, 0, 3000));
    Segment d;
    d.id = 4;
    d.kind = SegmentKind::kDwell;
    d.dwell_s = 0.1;
    m.Push(d);
    m.Push(Line(5, 20, 10, 0, 4000, true));
  };
  double cycle[2];
  double wall = 0;
  for (int k = 0; k < 2; ++k) {
    Machine m = Kt(k == 0 ? ClockKind::kVirtual : ClockKind::kReal);
    program(m);
    const auto w0 = std::chrono::steady_clock::now();
    double first = -1, last = -1;
    for (int i = 0; i < 5000 && last < 0; ++i) {
      m.Step();
      for (const auto& e : m.TakeEvents()) {
        if (e.kind == EventKind::kStarted && first < 0) first = e.machine_time;
        if (e.kind == EventKind::kCompleted && e.segment_id == 5) last = e.machine_time;
      }
    }
    ASSERT_GE(last, 0);
    cycle[k] = last - first + m.period();
    if (k == 1) wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
  }
  EXPECT_NEAR(cycle[1], cycle[0], 0.01 * cycle[0]);
  // The real clock really paces: never faster than machine time. Slower happens when the host stalls the
  // loop (7.4 s wall for 3.2 s of machine time was seen in a loaded 2-core CI run): a property of the host's
  // load, not of the servo, so no upper bound here.
  EXPECT_GE(wall, 0.97 * cycle[1]);
  EXPECT_GT(cycle[0], 0.5);
}

// A resting machine on the real clock (idle, spindle stopped) may be left unstepped: CatchUp() then runs the
// periods due, so machine time keeps pace with the wall clock, and none counts as late (issue 43: an idle
// servo no longer wakes 1000 times a second).
TEST(Clock, RestingOnTheRealClockCatchesUpWithoutOverruns) {
  Machine m = Kt(ClockKind::kReal);
  EXPECT_TRUE(m.Resting());
  m.Step();
  // That first step may start late on a loaded host (not CatchUp's overrun), and leave the machine behind
  // the wall clock: catch up first so the measured interval starts level with it (a CI run saw +15 ms).
  m.CatchUp();
  const std::uint64_t late = m.overruns();
  const double t0 = m.machine_time();
  const auto w0 = std::chrono::steady_clock::now();
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  const std::uint64_t ran = m.CatchUp();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
  // A host that stalls this thread past 100 ms makes the machine re-anchor (NextDeadline: a stall, counted),
  // which is not what this checks; a full CI run once saw the first step counted late.
  if (wall < 0.1) {
    EXPECT_GE(ran, 25u);                             // ~30 periods of 1 ms were due
    EXPECT_NEAR(m.machine_time() - t0, wall, 0.01);  // with the wall clock, within 10 ms
    EXPECT_EQ(m.overruns(), late);                   // none of the periods caught up counts as late
  }
  m.Push(Line(1, 10, 0, 0, 3000));
  EXPECT_FALSE(m.Resting());  // work queued: stepped period by period again
  Machine v = Kt(ClockKind::kVirtual);
  EXPECT_FALSE(v.Resting());  // the virtual clock stands still instead
  EXPECT_EQ(v.CatchUp(), 0u);
}

TEST(Devices, ToolChangeFromMagazine) {
  Machine m = Kt();
  m.SetToolTable(tooltable::ToolTable({{.tool = "1001", .socket = 1}, {.tool = "1002", .socket = 5}}));
  Segment t;
  t.id = 1;
  t.kind = SegmentKind::kToolChange;
  t.tool = "1002";
  m.Push(t);
  m.RunUntilIdle();
  auto ev = m.TakeEvents();
  const Event* done = Find(ev, EventKind::kCompleted, 1);
  ASSERT_NE(done, nullptr);
  const double expect = m.config().tool_change_time + 4 * m.config().magazine_index_time;
  EXPECT_NEAR(done->machine_time, expect, 2 * m.period());
  EXPECT_EQ(m.State().tool, "1002");
  // A tool that is not in the magazine is an alarm.
  t.id = 2;
  t.tool = "4711";
  m.Push(t);
  m.RunUntilIdle();
  EXPECT_EQ(m.alarm().code, AlarmCode::kToolNotInMagazine);
  EXPECT_NE(m.alarm().text.find("4711"), std::string::npos);
  EXPECT_EQ(m.State().tool, "1002");
}

// Alternate tools (issue 15): the control names the socket of the data set it chose; the machine takes that
// one, not the first socket holding the number, and a socket without the tool is alarm 600.
TEST(Devices, ToolChangeTakesTheAlternateTheControlChose) {
  Machine m = Kt();
  m.SetToolTable(tooltable::ToolTable({{.tool = "1001", .socket = 1}, {.tool = "1001", .socket = 9}}));
  Segment t;
  t.id = 1;
  t.kind = SegmentKind::kToolChange;
  t.tool = "1001";
  t.tool_socket = 9;
  m.Push(t);
  m.RunUntilIdle();
  auto ev = m.TakeEvents();
  const Event* done = Find(ev, EventKind::kCompleted, 1);
  ASSERT_NE(done, nullptr);
  // From socket 1 (where the magazine stands at power-up) to socket 9: 8 steps.
  EXPECT_NEAR(done->machine_time, m.config().tool_change_time + 8 * m.config().magazine_index_time,
              2 * m.period());
  // The same number from the other socket is another tool: a real change (socket 1 is one step back).
  t.id = 2;
  t.tool_socket = 1;
  m.Push(t);
  const double before = m.machine_time();
  m.RunUntilIdle();
  ev = m.TakeEvents();
  done = Find(ev, EventKind::kCompleted, 2);
  ASSERT_NE(done, nullptr);
  EXPECT_GT(done->machine_time - before, m.config().tool_change_time);
  t.id = 3;
  t.tool_socket = 4;
  m.Push(t);
  m.RunUntilIdle();
  EXPECT_EQ(m.alarm().code, AlarmCode::kToolNotInMagazine);
}

// The state a pallet arrives in is the power-up state (docs/predict.md judgement call 4): ToArrival's
// segments take the machine back to it from wherever a program left it, and a second run of the same program
// from there takes what the first took.
TEST(Devices, ToArrivalBringsTheMachineBackToItsPowerUpState) {
  Machine m = Kt();
  m.SetToolTable(tooltable::ToolTable({{.tool = "1001", .socket = 1}, {.tool = "1002", .socket = 5}}));
  EXPECT_TRUE(m.ToArrival().empty());  // at power-up it is there
  auto program = [&](std::uint64_t id) {
    Segment t;
    t.id = id;
    t.kind = SegmentKind::kToolChange;
    t.tool = "1002";
    Segment on = SpindleOn(id + 1, 2000);
    Segment cool;
    cool.id = id + 2;
    cool.kind = SegmentKind::kCoolant;
    cool.coolant = CoolantMode::kFlood;
    for (const Segment& s :
         {t, on, cool, Rapid(id + 3, 300, 200, 100), Line(id + 4, 350, 200, 100, 600, true)})
      m.Push(s);
    const double t0 = m.machine_time();
    m.RunUntilIdle();
    return m.machine_time() - t0;
  };
  const double first = program(1);
  std::uint64_t id = 10;
  for (Segment s : m.ToArrival()) {
    s.id = ++id;
    m.Push(s);
  }
  m.RunUntilIdle();
  ASSERT_EQ(m.alarm().code, AlarmCode::kNone);
  const AxisState at = m.State();
  EXPECT_LT(m.actual().norm(), 1e-6);
  EXPECT_EQ(at.tool, "");
  EXPECT_EQ(at.spindle_rpm, 0);
  EXPECT_EQ(at.coolant, CoolantMode::kOff);
  EXPECT_TRUE(m.ToArrival().empty());
  // The magazine stands at socket 1 again: the second run indexes 4 steps to socket 5 as the first did.
  EXPECT_NEAR(program(20), first, 2 * m.period());
}

// Tool life is charged with cutting time: machine seconds of feed moves with the spindle turning, per tool
// and socket; rapids, and feed moves with the spindle stopped, do not count.
TEST(Devices, CuttingTimeCountsFeedMovesWithTheSpindleTurning) {
  Machine m = Kt();
  m.SetToolTable(tooltable::ToolTable({{.tool = "1001", .socket = 3}}));
  Segment t;
  t.id = 1;
  t.kind = SegmentKind::kToolChange;
  t.tool = "1001";
  m.Push(t);
  Segment on = SpindleOn(2, 1000);
  m.Push(on);
  m.Push(Rapid(3, 0, 0, 100));
  m.Push(Line(4, 100, 0, 100, 600, true));  // 100 mm at 600 mm/min: 10 s and the ramps
  Segment off = on;
  off.id = 5;
  off.spindle_dir = SpindleDirection::kStop;
  off.spindle_rpm = 0;
  m.Push(off);
  m.Push(Line(6, 0, 0, 100, 600, true));  // spindle stopped: not cutting
  std::vector<Event> ev;
  while (m.Step())
    for (auto& e : m.TakeEvents()) ev.push_back(e);
  const double line =
      Find(ev, EventKind::kCompleted, 4)->machine_time - Find(ev, EventKind::kStarted, 4)->machine_time;
  ASSERT_EQ(m.Cutting().size(), 1u);
  EXPECT_EQ(m.Cutting()[0].tool, "1001");
  EXPECT_EQ(m.Cutting()[0].socket, 3);
  EXPECT_GT(m.Cutting()[0].cutting_s, 10.0);
  // The move's own time, within the look-ahead filter's few periods and the in-position settle.
  EXPECT_NEAR(m.Cutting()[0].cutting_s, line, 0.1);
  m.ResetCutting();
  EXPECT_TRUE(m.Cutting().empty());
}

// G38 (KT-APL ln 1583-1593): the check of the spindle tool at the post takes a revolution and reports the
// tool whole (contact) unless the machine's model has it broken: the station file's [magazine] broken or
// the operator's word (ServoControl.broken_sockets).
TEST(Devices, G38ToolCheckFindsTheBrokenToolsOfTheModel) {
  MachineConfig cfg = DefaultMachineConfig("hmc");
  cfg.broken_sockets = {7};
  Machine m(cfg, ClockKind::kVirtual);
  m.SetToolTable(tooltable::ToolTable({{.tool = "1001", .socket = 3}, {.tool = "1002", .socket = 7}}));
  std::uint64_t id = 0;
  auto check = [&](const std::string& tool) {
    Segment t;
    t.id = ++id;
    t.kind = SegmentKind::kToolChange;
    t.tool = tool;
    m.Push(t);
    Segment g;
    g.id = ++id;
    g.kind = SegmentKind::kProbe;
    g.tool_check = true;
    g.axes = 0;
    m.Push(g);
    m.RunUntilIdle();
    const auto ev = m.TakeEvents();
    const Event* done = Find(ev, EventKind::kCompleted, id);
    EXPECT_NE(done, nullptr);
    EXPECT_EQ(m.alarm().code, AlarmCode::kNone) << m.alarm().text;
    return done && done->probe.contact;
  };
  EXPECT_TRUE(check("1001"));
  EXPECT_FALSE(check("1002"));  // configured broken
  m.SetBrokenSockets({3});
  EXPECT_FALSE(check("1001"));  // commanded broken
  m.SetBrokenSockets({});
  EXPECT_TRUE(check("1001"));
}

TEST(Devices, SpindleCoolantPalletTimes) {
  Machine m = Kt();
  m.SetPallets(3, 7);
  Segment s = SpindleOn(1, 2000);
  m.Push(s);
  Segment c;
  c.id = 2;
  c.kind = SegmentKind::kCoolant;
  c.coolant = CoolantMode::kFlood;
  m.Push(c);
  Segment p;
  p.id = 3;
  p.kind = SegmentKind::kPalletChange;
  p.pallet = 7;
  m.Push(p);
  double mid_rpm = -1;
  std::vector<Event> ev;
  while (m.Step()) {
    if (mid_rpm < 0 && m.machine_time() >= 0.5) mid_rpm = m.State().spindle_rpm;
    for (auto& e : m.TakeEvents()) ev.push_back(e);
  }
  const double ramp = 2000 / m.config().spindle_accel_rpm_s;
  EXPECT_NEAR(Find(ev, EventKind::kCompleted, 1)->machine_time, ramp, 2 * m.period());
  EXPECT_NEAR(mid_rpm, 0.5 * m.config().spindle_accel_rpm_s, 5);
  EXPECT_NEAR(Find(ev, EventKind::kCompleted, 2)->machine_time, ramp + m.config().coolant_time,
              3 * m.period());
  EXPECT_NEAR(Find(ev, EventKind::kCompleted, 3)->machine_time,
              ramp + m.config().coolant_time + m.config().pallet_change_time, 4 * m.period());
  const AxisState st = m.State();
  EXPECT_EQ(st.spindle_rpm, 2000);
  EXPECT_EQ(st.coolant, CoolantMode::kFlood);
  EXPECT_EQ(st.pallet_on_table, 7);
  EXPECT_EQ(st.pallet_on_shuttle, 3);
}

TEST(Devices, BIndexTableUnclampsMovesClamps) {
  Machine m = Kt();
  const AxisConfig& b = m.config().axes[kB];
  Segment s = Rapid(1, 0, 0, 0);
  s.end[kB] = 90;
  s.axes = 0x17;
  m.Push(s);
  LimitChecker check(m);
  auto ev = RunChecked(m, check, 60);
  const Event* done = Find(ev, EventKind::kCompleted, 1);
  ASSERT_NE(done, nullptr);
  EXPECT_NEAR(m.actual()[kB], 90, 1e-3);
  const double V = b.rapid / 60, A = b.max_acceleration;
  const double move = 90 / V + V / A;  // lower bound of the rotation itself
  EXPECT_GT(done->machine_time, b.unclamp_time + b.clamp_time + move);
  EXPECT_LT(done->machine_time, b.unclamp_time + b.clamp_time + move * 1.3);
  check.ExpectWithinLimits();
  // From 90 to 270 is 180 either way; 270 -> 0 turns +90 through 360 (shortest way), not -270.
  s.id = 3;
  s.end[kB] = 270;
  m.Push(s);
  m.RunUntilIdle();
  s.id = 4;
  s.end[kB] = 0;
  m.Push(s);
  double max_b = 0;
  const double t0 = m.machine_time();
  while (m.Step()) max_b = std::max(max_b, m.actual()[kB]);
  EXPECT_GT(max_b, 359.0);
  EXPECT_NEAR(m.actual()[kB], 0, 1e-3);
  EXPECT_NEAR(m.State().actual[kB], 0, 1e-3);
  EXPECT_LT(m.machine_time() - t0, b.unclamp_time + b.clamp_time + 1.3 * move + 1.0);
  s.id = 2;
  s.end[kB] = 90.5;  // not on the 1-degree index
  m.Push(s);
  m.RunUntilIdle();
  EXPECT_EQ(m.alarm().code, AlarmCode::kInvalidSegment);
}

}  // namespace
}  // namespace cell::servo

namespace cell::servo {
namespace {

TEST(Devices, FeedHoldPausesDwell) {
  Machine m(DefaultMachineConfig("hmc"), ClockKind::kVirtual);
  Segment d;
  d.id = 1;
  d.kind = SegmentKind::kDwell;
  d.dwell_s = 1.0;
  m.Push(d);
  for (int i = 0; i < 400; ++i) m.Step();
  m.FeedHold();
  EXPECT_FALSE(m.Step());  // virtual clock: a held dwell is no activity
  const double held_at = m.machine_time();
  m.Resume();
  std::vector<Event> ev;
  while (m.Step())
    for (auto& e : m.TakeEvents()) ev.push_back(e);
  const Event* done = testing::Find(ev, EventKind::kCompleted, 1);
  ASSERT_NE(done, nullptr);
  EXPECT_NEAR(held_at, 0.4, 1e-9);
  EXPECT_NEAR(done->machine_time, 1.0, 2 * m.period());
}

TEST(Config, PartModelsFromStationFile) {
  const auto dir = std::filesystem::temp_directory_path() / "axis_servo_parts_test";
  std::filesystem::create_directories(dir / "parts");
  {
    std::ofstream(dir / "parts" / "p1.toml") << "[[plane]]\npoint = [0, 0, 20]\nnormal = [0, 0, 1]\n";
    std::ifstream in(std::string(CELL_SOURCE_DIR) + "/deploy/stations/KT01.toml");
    std::stringstream ss;
    ss << in.rdbuf();
    std::string text = ss.str();
    const auto at = text.find("[probe]\n");
    ASSERT_NE(at, std::string::npos);
    text.insert(at + 8, "parts = [ { pallet = 1, file = \"parts/p1.toml\" } ]\n");
    std::ofstream(dir / "KT99.toml") << text;
  }
  MachineConfig c = LoadMachineConfig(dir / "KT99.toml");
  ASSERT_EQ(c.part_models.size(), 1u);
  Machine m(c, ClockKind::kVirtual);
  m.SetPallets(1, 0);
  Segment p;
  p.id = 1;
  p.kind = SegmentKind::kProbe;
  p.end = {0, 0, 0, 0, 0, 0};
  p.axes = 0x07;
  p.feed = 500;
  m.Push(testing::Rapid(0, 0, 0, 40));
  m.Push(p);
  m.RunUntilIdle();
  auto ev = m.TakeEvents();
  const Event* done = testing::Find(ev, EventKind::kCompleted, 1);
  ASSERT_NE(done, nullptr);
  EXPECT_TRUE(done->probe.contact);
  EXPECT_NEAR(done->probe.position[kZ], 20.0, 1e-4);  // the tip (probe length 0) rests on the face
  std::filesystem::remove_all(dir);
}

// ---- The U-head (KT-APL manual ch. 7, ln 7126-7433): a linear co-axis U beside X Y Z B.

// KT01's machine with a U axis: rapid 9.843 in/min = 250 mm/min (ln 7132), a programmed feed of at most
// 10 IPM (ln 7161; the servo clamps to the rapid rate, ln 7132: "in a circular move the velocity is limited
// to the rapid rate"); the acceleration and jerk keep the jerk filter's length.
MachineConfig UHead() {
  MachineConfig c = DefaultMachineConfig("hmc");
  AxisConfig& u = c.axes[kU];
  u = c.axes[kZ];
  u.min = -5;
  u.max = 60;
  u.max_velocity = 250;
  u.rapid = 250;
  return c;
}

Segment UMove(std::uint64_t id, SegmentKind kind, double z, double u, double feed = 0) {
  Segment s;
  s.id = id;
  s.kind = kind;
  s.end[kZ] = z;
  s.end[kU] = u;
  s.axes = 1u << kZ | 1u << kU;
  s.feed = feed;
  s.exact_stop = true;
  return s;
}

TEST(Servo, AMachineWithUMovesXYZAsOneWithout) {
  // The per-period arithmetic is six wide without U V W and nine wide with them: the same program moves
  // X Y Z bit for bit alike on KT01 and on KT01 with a U-head that stands still.
  Machine six(DefaultMachineConfig("hmc"), ClockKind::kVirtual), nine(UHead(), ClockKind::kVirtual);
  for (Machine* m : {&six, &nine}) {
    m->Push(Rapid(1, 100, 100, 100));
    m->Push(Line(2, 150, 120, 100, 3000));
    m->Push(testing::Arc(3, 170, 140, 110, 150, 140, true, 3000));
    m->Push(Line(4, 120, 160, 90, 6000, true));
  }
  int ticks = 0;
  while (true) {
    const bool a = six.Step(), b = nine.Step();
    ASSERT_EQ(a, b) << "tick " << ticks;
    if (!a) break;
    ++ticks;
    for (int i : {kX, kY, kZ}) {
      ASSERT_EQ(six.commanded()[i], nine.commanded()[i]) << "axis " << i << " tick " << ticks;
      ASSERT_EQ(six.actual()[i], nine.actual()[i]) << "axis " << i << " tick " << ticks;
    }
    ASSERT_EQ(nine.commanded()[kU], 0.0);
  }
  EXPECT_GT(ticks, 1000);
  EXPECT_EQ(nine.alarm().code, AlarmCode::kNone) << nine.alarm().text;
}

TEST(Servo, TheUHeadCutsATaperThreadAndArcsInTheZUPlane) {
  Machine m(UHead(), ClockKind::kVirtual);
  m.Push(UMove(1, SegmentKind::kRapid, 60, 5));
  Segment sp = SpindleOn(2, 300);
  m.Push(sp);
  m.RunUntilIdle();
  ASSERT_EQ(m.alarm().code, AlarmCode::kNone) << m.alarm().text;
  // G33 E2. Z50. U6. (ln 7247-7263): the lead along Z, the longer axis; U follows, 0.1 mm per mm of Z.
  Segment th = UMove(3, SegmentKind::kThread, 50, 6);
  th.thread_lead = 2;
  m.Push(th);
  m.Push(UMove(4, SegmentKind::kRapid, 60, 5));
  // G18 G21 G03 (ln 7140): the quarter circle about Z55 U5 from Z60 U5 to Z55 U10, counter-clockwise with
  // Z to the right and U up; U's centre in the slot of X.
  Segment arc = UMove(5, SegmentKind::kArc, 55, 10, 200);
  arc.center = {5, 0, 55};
  arc.plane = {kZ, kU};
  arc.direction = ArcDirection::kCCW;
  m.Push(arc);
  int on_thread = 0, on_arc = 0, middle = 0;
  double max_u_rate = 0, prev_u = 5;
  while (m.Step()) {
    const AxisVector c = m.commanded();
    max_u_rate = std::max(max_u_rate, std::abs(c[kU] - prev_u) / m.period() * 60);
    prev_u = c[kU];
    ASSERT_EQ(c[kX], 0.0);
    if (c[kZ] > 51 && c[kZ] < 59 && c[kU] < 6.05) {
      EXPECT_NEAR(c[kU], 5 + (60 - c[kZ]) / 10, 1e-3) << "Z " << c[kZ];
      ++on_thread;
    }
    const double r = std::hypot(c[kZ] - 55, c[kU] - 5);
    if (c[kU] > 6.05) {
      EXPECT_NEAR(r, 5, 0.02) << "Z " << c[kZ] << " U " << c[kU];
      EXPECT_GE(c[kZ], 55 - 0.02);
      ++on_arc;
      const double deg = std::atan2(c[kU] - 5, c[kZ] - 55) * 180 / M_PI;
      if (deg > 20 && deg < 70) ++middle;
    }
  }
  EXPECT_EQ(m.alarm().code, AlarmCode::kNone) << m.alarm().text;
  EXPECT_GT(on_thread, 500);  // 5 revolutions at 300 rpm: 1 s, and the rapid back along the same line
  EXPECT_GT(on_arc, 1000);    // 7.85 mm at 200 mm/min: 2.4 s
  EXPECT_GT(middle, 500);
  EXPECT_LE(max_u_rate, 250 * 1.01);
  EXPECT_NEAR(m.actual()[kZ], 55, 1e-3);
  EXPECT_NEAR(m.actual()[kU], 10, 1e-3);
}

}  // namespace
}  // namespace cell::servo
