// Probe simulation: contact geometry against planes, bores, bosses and spheres; no contact at the end of
// travel; part-model file errors.
#include <gtest/gtest.h>

#include "cell/error/error.h"
#include "cell/servo/machine.h"
#include "test_util.h"

namespace cell::servo {
namespace {

using machine::DefaultMachineConfig;
using machine::MachineConfig;
using testing::Find;
using testing::Rapid;

// The shared test part: common/partmodel/testdata/block.toml.
const std::string kBlock = std::string(CELL_SOURCE_DIR) + "/common/partmodel/testdata/block.toml";

struct Hit {
  bool contact;
  AxisVector pos;
  AxisVector final_pos;
};

Hit Probe(const AxisVector& from, const AxisVector& to, double feed = 600) {
  Machine m(DefaultMachineConfig("hmc"), ClockKind::kVirtual);
  m.SetPartModel(1, partmodel::LoadPartModel(kBlock));
  m.SetPallets(1, 0);
  m.Push(Rapid(1, from[0], from[1], from[2]));
  Segment p;
  p.id = 2;
  p.kind = SegmentKind::kProbe;
  p.end = {to[0], to[1], to[2], 0, 0, 0};
  p.axes = 0x07;
  p.feed = feed;
  m.Push(p);
  m.RunUntilIdle(120);
  auto ev = m.TakeEvents();
  const Event* done = Find(ev, EventKind::kCompleted, 2);
  EXPECT_NE(done, nullptr);
  if (!done) return {false, AxisVector::Zero(), AxisVector::Zero()};
  return {done->probe.contact, done->probe.position, m.actual()};
}

AxisVector P(double x, double y, double z) {
  AxisVector v = AxisVector::Zero();
  v << x, y, z, 0, 0, 0;
  return v;
}

TEST(Probe, PlaneTripsWhereTheTipRestsOnTheFace) {
  Hit h = Probe(P(100, 100, 100), P(100, 100, 0));
  ASSERT_TRUE(h.contact);
  EXPECT_NEAR(h.pos[kZ], 50.0, 1e-4);  // Z is the ball's tip (probe_length 0): it rests on the face
  EXPECT_NEAR(h.pos[kX], 100.0, 1e-4);
  // Stops shortly after the trip, far from the programmed end.
  EXPECT_LT(h.final_pos[kZ], 50.0);
  EXPECT_GT(h.final_pos[kZ], 49.0);
}

TEST(Probe, BoreWallBossAndSphere) {
  Hit bore = Probe(P(200, 200, 40), P(240, 200, 40));
  ASSERT_TRUE(bore.contact);
  EXPECT_NEAR(bore.pos[kX], 217.0, 1e-4);
  Hit boss = Probe(P(340, 300, 60), P(290, 300, 60));
  ASSERT_TRUE(boss.contact);
  EXPECT_NEAR(boss.pos[kX], 318.0, 1e-4);
  Hit sphere = Probe(P(400, 100, 100), P(400, 100, 55));
  ASSERT_TRUE(sphere.contact);
  EXPECT_NEAR(sphere.pos[kZ], 70.0, 1e-4);  // the tip on the sphere's top (60 + 10)
  // Diagonal approach to the sphere: contact where the ball's centre (3 above the tip) is 13 from c.
  Hit diag = Probe(P(430, 100, 90), P(400, 100, 60));
  ASSERT_TRUE(diag.contact);
  EXPECT_NEAR((diag.pos.head<3>() + Eigen::Vector3d(0, 0, 3) - Eigen::Vector3d(400, 100, 60)).norm(), 13.0,
              1e-4);
}

TEST(Probe, NoContactReportsEndOfTravel) {
  Hit h = Probe(P(100, 400, 100), P(100, 400, 60));
  EXPECT_FALSE(h.contact);
  EXPECT_NEAR(h.pos[kZ], 60.0, 1e-9);
  EXPECT_NEAR(h.final_pos[kZ], 60.0, 1e-3);
}

TEST(Probe, NoPartModelMeansNoContact) {
  Machine m(DefaultMachineConfig("hmc"), ClockKind::kVirtual);
  Segment p;
  p.id = 1;
  p.kind = SegmentKind::kProbe;
  p.end = {0, 0, 10, 0, 0, 0};
  p.axes = 0x07;
  p.feed = 500;
  m.Push(p);
  m.RunUntilIdle();
  auto ev = m.TakeEvents();
  ASSERT_NE(Find(ev, EventKind::kCompleted, 1), nullptr);
  EXPECT_FALSE(Find(ev, EventKind::kCompleted, 1)->probe.contact);
}

// G22 down onto the face, then G23 back up and G22 again: the break latches where the ball leaves the face
// (centre 3 mm above z = 50, the same point the make latched), and a G22 that starts touching is "already".
Segment ProbeSeg(std::uint64_t id, double z, bool brk, double feed = 600) {
  Segment p;
  p.id = id;
  p.kind = SegmentKind::kProbe;
  p.end = {100, 100, z, 0, 0, 0};
  p.axes = 0x07;
  p.feed = feed;
  p.probe_break = brk;
  return p;
}

TEST(Probe, BreakLatchesWhereContactIsLostAndAlreadyMeansNoMotion) {
  Machine m(DefaultMachineConfig("hmc"), ClockKind::kVirtual);
  m.SetPartModel(1, partmodel::LoadPartModel(kBlock));
  m.SetPallets(1, 0);
  m.Push(Rapid(1, 100, 100, 100));
  m.Push(ProbeSeg(2, 0, false));
  m.RunUntilIdle(120);
  auto ev = m.TakeEvents();
  ASSERT_NE(Find(ev, EventKind::kCompleted, 2), nullptr);
  EXPECT_TRUE(Find(ev, EventKind::kCompleted, 2)->probe.contact);
  // Overtravel: the slide stops below the trip point (the stylus deflects).
  const double stopped = m.actual()[kZ];
  EXPECT_LT(stopped, 50.0);

  m.Push(ProbeSeg(3, 0, false));  // G22 while touching: already, nothing moves
  m.RunUntilIdle(120);
  ev = m.TakeEvents();
  const Event* again = Find(ev, EventKind::kCompleted, 3);
  ASSERT_NE(again, nullptr);
  EXPECT_TRUE(again->probe.already);
  EXPECT_FALSE(again->probe.contact);
  EXPECT_NEAR(m.actual()[kZ], stopped, 1e-3);

  m.Push(ProbeSeg(4, 100, true));  // G23 up: contact is lost where the tip leaves the face, z = 50
  m.RunUntilIdle(120);
  ev = m.TakeEvents();
  const Event* brk = Find(ev, EventKind::kCompleted, 4);
  ASSERT_NE(brk, nullptr);
  EXPECT_TRUE(brk->probe.contact);
  EXPECT_FALSE(brk->probe.already);
  EXPECT_NEAR(brk->probe.position[kZ], 50.0, 1e-4);

  m.Push(ProbeSeg(5, 100, true));  // G23 while clear: already
  m.RunUntilIdle(120);
  ev = m.TakeEvents();
  ASSERT_NE(Find(ev, EventKind::kCompleted, 5), nullptr);
  EXPECT_TRUE(Find(ev, EventKind::kCompleted, 5)->probe.already);
}

TEST(Probe, DrivingTheStylusPastItsOvertravelIsAlarm602) {
  MachineConfig cfg = DefaultMachineConfig("hmc");
  cfg.probe_overtravel = 0.01;  // far less than the stopping distance at 600 mm/min
  Machine m(cfg, ClockKind::kVirtual);
  m.SetPartModel(1, partmodel::LoadPartModel(kBlock));
  m.SetPallets(1, 0);
  m.Push(Rapid(1, 100, 100, 100));
  m.Push(ProbeSeg(2, 0, false));
  m.RunUntilIdle(120);
  auto ev = m.TakeEvents();
  bool alarm = false;
  for (const Event& e : ev)
    alarm = alarm || (e.kind == EventKind::kAlarm && e.alarm.code == AlarmCode::kProbeOvertravel);
  EXPECT_TRUE(alarm);
  EXPECT_EQ(m.alarm().code, AlarmCode::kProbeOvertravel);
  // With the default 5 mm the same move ends normally (see the test above).
}

}  // namespace
}  // namespace cell::servo
