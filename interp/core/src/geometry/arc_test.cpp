// Arc geometry shared by the dialects: radius and centre forms, full circles, the control's checks.
#include "cell/interp/geometry/arc.h"

#include <gtest/gtest.h>

namespace cell::interp::geom {
namespace {

TEST(Arc, PlanesAsRs274DefinesThem) {
  EXPECT_EQ(AxesOf(Plane::kXY).normal, kZ);
  EXPECT_EQ(AxesOf(Plane::kZX).first, kZ);  // G18: Z then X, cw seen from +Y
  EXPECT_EQ(AxesOf(Plane::kZX).second, kX);
  EXPECT_EQ(AxesOf(Plane::kYZ).normal, kX);
}

TEST(Arc, RadiusFormMinorAndMajor) {
  // A quarter circle of radius 10 from (10,0) to (0,10), counter-clockwise: centre (0,0), 90 degrees; the
  // major arc the same way round has its centre at (10,10) and sweeps 270.
  ArcSolution minor = ArcFromRadius({10, 0}, {0, 10}, 10, false, false, 0.001);
  ASSERT_EQ(minor.error, ArcError::kNone);
  EXPECT_NEAR(minor.center.x, 0, 1e-9);
  EXPECT_NEAR(minor.center.y, 0, 1e-9);
  EXPECT_NEAR(minor.sweep, 90, 1e-9);
  ArcSolution major = ArcFromRadius({10, 0}, {0, 10}, 10, false, true, 0.001);
  EXPECT_NEAR(major.center.x, 10, 1e-9);
  EXPECT_NEAR(major.center.y, 10, 1e-9);
  EXPECT_NEAR(major.sweep, 270, 1e-9);
  // Clockwise the minor arc's centre is the other one.
  ArcSolution cw = ArcFromRadius({10, 0}, {0, 10}, 10, true, false, 0.001);
  EXPECT_NEAR(cw.center.x, 10, 1e-9);
  EXPECT_NEAR(cw.sweep, 90, 1e-9);
}

TEST(Arc, RadiusFormErrors) {
  EXPECT_EQ(ArcFromRadius({1, 1}, {1, 1}, 5, true, false, 0.001).error, ArcError::kFullCircleWithRadius);
  EXPECT_EQ(ArcFromRadius({0, 0}, {10, 0}, 4, true, false, 0.001).error, ArcError::kRadiusTooSmall);
  EXPECT_EQ(ArcFromRadius({0, 0}, {0.0001, 0}, 0.0005, true, false, 0.001).error, ArcError::kBelowMinimum);
  // A radius of exactly half the chord is a semicircle.
  ArcSolution half = ArcFromRadius({0, 0}, {10, 0}, 5, true, false, 0.001);
  EXPECT_EQ(half.error, ArcError::kNone);
  EXPECT_NEAR(half.sweep, 180, 1e-6);
}

TEST(Arc, CentreFormFullCirclesAndTolerance) {
  ArcSolution full = ArcFromCenter({10, 0}, {10, 0}, {0, 0}, true, 0.001, 0.013);
  EXPECT_EQ(full.error, ArcError::kNone);
  EXPECT_EQ(full.sweep, 360);
  EXPECT_NEAR(ArcFromCenter({10, 0}, {0, -10}, {0, 0}, true, 0.001, 0.013).sweep, 90, 1e-9);
  EXPECT_NEAR(ArcFromCenter({10, 0}, {0, -10}, {0, 0}, false, 0.001, 0.013).sweep, 270, 1e-9);
  ArcSolution off = ArcFromCenter({10, 0}, {0, 10.02}, {0, 0}, false, 0.001, 0.013);
  EXPECT_EQ(off.error, ArcError::kRadiiDiffer);
  EXPECT_NEAR(off.radius_end, 10.02, 1e-9);
  EXPECT_EQ(ArcFromCenter({0, 0}, {0, 0}, {0, 0.0001}, false, 0.001, 0.013).error, ArcError::kBelowMinimum);
}

}  // namespace
}  // namespace cell::interp::geom
