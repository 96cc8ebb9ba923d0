// Probe simulation: contact geometry against planes, bores, bosses and spheres; no contact at the end of
// travel; part-model file errors.
#include <gtest/gtest.h>

#include "cell/error/error.h"
#include "cell/servo/machine.h"
#include "test_util.h"

namespace cell::servo {
namespace {

using testing::Find;
using testing::Rapid;

const char* kPart = R"(
# block top face at z = 50 with a bore, a boss and a sphere on it
[[plane]]
point = [0, 0, 50]
normal = [0, 0, 1]
[[bore]]
top = [200, 200, 50]
axis = [0, 0, 1]
diameter = 40
depth = 30
[[boss]]
base = [300, 300, 50]
axis = [0, 0, 1]
diameter = 30
height = 20
[[sphere]]
center = [400, 100, 60]
diameter = 20
)";

struct Hit {
  bool contact;
  AxisVector pos;
  AxisVector final_pos;
};

Hit Probe(const AxisVector& from, const AxisVector& to, double feed = 600) {
  Machine m(DefaultMachineConfig("hmc"), ClockKind::kVirtual);
  m.SetPartModel(1, ParsePartModel(kPart, "part.toml"));
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

TEST(Probe, PlaneTripAtBallRadiusAboveFace) {
  Hit h = Probe(P(100, 100, 100), P(100, 100, 0));
  ASSERT_TRUE(h.contact);
  EXPECT_NEAR(h.pos[kZ], 53.0, 1e-4);  // 6 mm ball: centre 3 mm above the face
  EXPECT_NEAR(h.pos[kX], 100.0, 1e-4);
  // Stops shortly after the trip, far from the programmed end.
  EXPECT_LT(h.final_pos[kZ], 53.0);
  EXPECT_GT(h.final_pos[kZ], 52.0);
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
  EXPECT_NEAR(sphere.pos[kZ], 73.0, 1e-4);
  // Diagonal approach to the sphere: contact where |centre - c| = 13.
  Hit diag = Probe(P(430, 100, 90), P(400, 100, 60));
  ASSERT_TRUE(diag.contact);
  EXPECT_NEAR((diag.pos.head<3>() - Eigen::Vector3d(400, 100, 60)).norm(), 13.0, 1e-4);
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

TEST(PartModel, DistanceAndErrors) {
  PartModel m = ParsePartModel(kPart, "part.toml");
  EXPECT_NEAR(m.Distance({0, 0, 60}), 10, 1e-12);
  EXPECT_NEAR(m.Distance({200, 200, 40}), 20, 1e-9);  // centre of the bore: 20 to the wall
  EXPECT_LT(m.Distance({0, 0, 40}), 0);
  try {
    ParsePartModel("[[bore]]\ntop = [0,0,0]\naxis = [0,0,1]\ndepth = 5\n", "p.toml");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("p.toml: bore[0].diameter: missing"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ParsePartModel("[[cone]]\n", "p.toml"), Error);
  EXPECT_THROW(ParsePartModel("[[sphere]]\ncenter = [0,0]\ndiameter = 3\n", "p.toml"), Error);
}

}  // namespace
}  // namespace cell::servo
