// The part model: distances to each feature, make (G22) and break (G23) trips with the ball radius, a part
// turned by a rotary table, and file errors. Every expected value is worked out in the comment beside it.
#include "cell/partmodel/part_model.h"

#include <gtest/gtest.h>

#include <string>

#include "cell/error/error.h"

namespace cell::partmodel {
namespace {

// The shared test part: common/partmodel/testdata/block.toml.
const std::string kBlock = std::string(CELL_SOURCE_DIR) + "/common/partmodel/testdata/block.toml";

Pose P(double x, double y, double z, double b = 0) {
  return {x, y, z, 0, b, 0};
}

TEST(PartModel, DistanceToEachFeature) {
  PartModel m = LoadPartModel(kBlock);
  EXPECT_NEAR(m.Distance(Eigen::Vector3d(0, 0, 60)), 10, 1e-12);     // 10 above the face
  EXPECT_NEAR(m.Distance(Eigen::Vector3d(200, 200, 40)), 20, 1e-9);  // bore axis: 20 to the wall
  EXPECT_LT(m.Distance(Eigen::Vector3d(0, 0, 40)), 0);               // inside the block
  EXPECT_NEAR(m.Distance(Eigen::Vector3d(300, 300, 80)), 10, 1e-9);  // 10 above the boss (top at 70)
  EXPECT_NEAR(m.Distance(Eigen::Vector3d(400, 100, 90)), 20, 1e-9);  // 30 from the centre, radius 10
}

TEST(PartModel, BoxesAreStepsAndTurnedBoxesAngledFaces) {
  PartModel m = ParsePartModel(R"(
[[box]]
min = [0, 0, 0]
max = [100, 50, 20]
)",
                               "step.toml");
  EXPECT_NEAR(m.Distance(Eigen::Vector3d(50, 25, 30)), 10, 1e-12);                 // above the top face
  EXPECT_NEAR(m.Distance(Eigen::Vector3d(110, 25, 10)), 10, 1e-12);                // beside the end face
  EXPECT_NEAR(m.Distance(Eigen::Vector3d(110, 60, 10)), std::sqrt(200.0), 1e-12);  // off the edge
  EXPECT_NEAR(m.Distance(Eigen::Vector3d(50, 25, 15)), -5, 1e-12);                 // 5 under the top

  // A 100 x 100 x 20 block turned 30 degrees about Y: its top face's normal is (sin 30, 0, cos 30), so a
  // point 40 above the centre is 40 cos 30 - 10 = 24.6410 from it.
  PartModel tilted = ParsePartModel(R"(
[[box]]
min = [-50, -50, -10]
max = [50, 50, 10]
rotate = [0, 30, 0]
)",
                                    "tilted.toml");
  EXPECT_NEAR(tilted.Distance(Eigen::Vector3d(0, 0, 40)), 24.641016, 1e-6);
}

TEST(PartModel, MakeTripsWhereTheBallTouches) {
  PartModel m = LoadPartModel(kBlock);
  // Down onto the face z = 50 from 100 to 0 with a 3 mm ball: the centre stops at 53, t = 47/100.
  Trip t = m.Probe(true, P(100, 100, 100), P(100, 100, 0), 3.0);
  ASSERT_EQ(t.kind, Trip::kEvent);
  EXPECT_NEAR(t.t, 0.47, 1e-9);
  // Across the bore from its axis toward +X: the wall is at 220, the centre stops at 217 (t = 17/40).
  t = m.Probe(true, P(200, 200, 40), P(240, 200, 40), 3.0);
  ASSERT_EQ(t.kind, Trip::kEvent);
  EXPECT_NEAR(t.t, 17.0 / 40.0, 1e-9);
  // Nothing in the way: no event.
  EXPECT_EQ(m.Probe(true, P(100, 400, 100), P(100, 400, 60), 3.0).kind, Trip::kNone);
  // Already touching at the start (the centre 1 mm into the contact band).
  EXPECT_EQ(m.Probe(true, P(100, 100, 52), P(100, 100, 0), 3.0).kind, Trip::kAlready);
}

TEST(PartModel, BreakTripsWhereTheBallLeaves) {
  PartModel m = LoadPartModel(kBlock);
  // From 1 mm past contact (centre at 52) up to 100: contact is lost at 53, t = 1/48.
  Trip t = m.Probe(false, P(100, 100, 52), P(100, 100, 100), 3.0);
  ASSERT_EQ(t.kind, Trip::kEvent);
  EXPECT_NEAR(t.t, 1.0 / 48.0, 1e-9);
  // Not touching at the start: already broken.
  EXPECT_EQ(m.Probe(false, P(100, 100, 60), P(100, 100, 100), 3.0).kind, Trip::kAlready);
  // Moving along the face while touching: the contact is never lost.
  EXPECT_EQ(m.Probe(false, P(0, 0, 52), P(50, 0, 52), 3.0).kind, Trip::kNone);
  // An empty model is never touched: a break is already there.
  EXPECT_EQ(PartModel().Probe(false, P(0, 0, 0), P(1, 0, 0), 3.0).kind, Trip::kAlready);
}

TEST(PartModel, TheRotaryTableTurnsThePart) {
  // Material beyond x = 10 on a B table turning about the Y axis through the origin. The probe stays at
  // (0, 0, 100); turning the table by +b (clockwise from above) brings the model point under the probe to
  // (100 sin b, 0, 100 cos b). With a 3 mm ball it touches when 100 sin b = 7: b = asin(0.07) = 4.013987.
  PartModel m = ParsePartModel(R"(
[rotary]
b_center = [0, 0, 0]
[[box]]
min = [10, -50, -200]
max = [200, 50, 200]
)",
                               "table.toml");
  Trip t = m.Probe(true, P(0, 0, 100, 0), P(0, 0, 100, 10), 3.0);
  ASSERT_EQ(t.kind, Trip::kEvent);
  EXPECT_NEAR(t.t * 10, 4.013987, 1e-5);
  // Turning the other way takes the face away: no contact.
  EXPECT_EQ(m.Probe(true, P(0, 0, 100, 0), P(0, 0, 100, -10), 3.0).kind, Trip::kNone);
}

TEST(PartModel, FileErrorsNameTheKey) {
  try {
    ParsePartModel("[[bore]]\ntop = [0,0,0]\naxis = [0,0,1]\ndepth = 5\n", "p.toml");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("p.toml: bore[0].diameter: missing"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ParsePartModel("[[cone]]\n", "p.toml"), Error);
  EXPECT_THROW(ParsePartModel("[[sphere]]\ncenter = [0,0]\ndiameter = 3\n", "p.toml"), Error);
  try {
    ParsePartModel("[[box]]\nmin = [0,0,0]\nmax = [1,1,1]\nrotation = [0,0,1]\n", "p.toml");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("p.toml: box[0].rotation: unknown key; allowed min, max, rotate"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(ParsePartModel("[[box]]\nmin = [0,0,0]\nmax = [1,0,1]\n", "p.toml"), Error);
  EXPECT_THROW(ParsePartModel("[rotary]\nd_center = [0,0,0]\n", "p.toml"), Error);
  EXPECT_THROW(LoadPartModel("/nonexistent/part.toml"), Error);
}

// The first --probe-model format (lines of boxes) is still read, as point contact: a point moving +X from 0
// stops on the box's face at X 10 when probed with no ball.
TEST(PartModel, LineFormatIsPointContact) {
  PartModel m = ParsePartModel("# a wall\nbox 10 -50 -50 20 50 50  # x from 10\n\n", "old.probe");
  EXPECT_TRUE(m.point_contact());
  Trip t = m.Probe(true, P(0, 0, 0, 0), P(20, 0, 0, 0), 0.0);
  ASSERT_EQ(t.kind, Trip::kEvent);
  EXPECT_NEAR(t.t * 20, 10.0, 1e-6);
  EXPECT_FALSE(ParsePartModel("[[box]]\nmin = [0,0,0]\nmax = [1,1,1]\n", "p.toml").point_contact());
  try {
    ParsePartModel("box 1 2 3\n", "old.probe");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("old.probe:1: expected 'box XMIN YMIN ZMIN XMAX YMAX ZMAX'"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(ParsePartModel("box 0 0 0 1 1 1\nsphere 1 2 3 4\n", "old.probe"), Error);
}

}  // namespace
}  // namespace cell::partmodel
