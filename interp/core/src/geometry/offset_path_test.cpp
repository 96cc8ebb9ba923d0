// Offset-path geometry (cutter and tool-nose radius compensation); cases from the KT-APL manual's figures.
#include "cell/interp/geometry/offset_path.h"

#include <gtest/gtest.h>

#include <cmath>

namespace cell::interp::geom {
namespace {

constexpr double kEps = 1e-9;
constexpr int kX = 0, kY = 1;

Path Line(Vec2 a, Vec2 b) {
  Path p;
  p.start = a;
  p.end = b;
  return p;
}

Path ArcPath(Vec2 a, Vec2 b, Vec2 c, bool cw, double sweep) {
  Path p;
  p.arc = true;
  p.start = a;
  p.end = b;
  p.center = c;
  p.cw = cw;
  p.sweep = sweep;
  return p;
}

void ExpectNear(Vec2 got, Vec2 want, double eps = 1e-6) {
  EXPECT_NEAR(got.x, want.x, eps);
  EXPECT_NEAR(got.y, want.y, eps);
}

// Fig 2.4/2.5: G41 puts the cutter left of the path looking along the cut, G42 right.
TEST(OffsetPath, LineOffsetsLeftAndRight) {
  Path p = Line({0, 0}, {10, 0});
  ExpectNear(OffsetStart(p, 5, kLeft), {0, 5});
  ExpectNear(OffsetEnd(p, 5, kLeft), {10, 5});
  ExpectNear(OffsetStart(p, 5, kRight), {0, -5});
  EXPECT_NEAR(Extent(p), 10, kEps);
  EXPECT_NEAR(RemainingLength(p, 5, kLeft, 2, 3), 5, kEps);
}

// A ccw arc has its centre on the left: G41 is inside (radius r - R), G42 outside (r + R).
TEST(OffsetPath, ArcOffsetsInsideAndOutside) {
  Path p = ArcPath({10, 0}, {0, 10}, {0, 0}, false, 90);
  ExpectNear(StartTangent(p), {0, 1});
  ExpectNear(EndTangent(p), {-1, 0});
  EXPECT_TRUE(InsideArc(p, kLeft));
  EXPECT_FALSE(InsideArc(p, kRight));
  EXPECT_NEAR(OffsetRadiusAtStart(p, 4, kLeft), 6, kEps);
  EXPECT_NEAR(OffsetRadiusAtEnd(p, 4, kRight), 14, kEps);
  ExpectNear(OffsetStart(p, 4, kLeft), {6, 0});
  ExpectNear(OffsetEnd(p, 4, kRight), {0, 14});
  // 90 degrees of the radius-6 offset arc: 6 * pi / 2.
  EXPECT_NEAR(RemainingLength(p, 4, kLeft, 0, 0), 3 * M_PI, 1e-9);
  // A cw arc has its centre on the right.
  Path q = ArcPath({0, 10}, {10, 0}, {0, 0}, true, 90);
  EXPECT_TRUE(InsideArc(q, kRight));
  ExpectNear(OffsetStart(q, 4, kRight), {0, 6});
}

TEST(OffsetPath, Intersections) {
  Vec2 out[2];
  ASSERT_EQ(IntersectLineLine({0, 5}, {1, 0}, {5, 0}, {0, 1}, out), 1);
  ExpectNear(out[0], {5, 5});
  EXPECT_EQ(IntersectLineLine({0, 5}, {1, 0}, {0, 0}, {-1, 0}, out), 0);  // parallel
  // y = -5 against the circle of radius 15 about (10, 0): (x - 10)^2 = 200.
  ASSERT_EQ(IntersectLineCircle({0, -5}, {1, 0}, {10, 0}, 15, out), 2);
  ExpectNear(out[0], {10 - std::sqrt(200.0), -5});
  ExpectNear(out[1], {10 + std::sqrt(200.0), -5});
  EXPECT_EQ(IntersectLineCircle({0, 20}, {1, 0}, {10, 0}, 15, out), 0);
  // Circles of radius 5 about (0,0) and (8,0): x = 4, y = +-3.
  ASSERT_EQ(IntersectCircleCircle({0, 0}, 5, {8, 0}, 5, out), 2);
  ExpectNear(out[0], {4, 3});
  ExpectNear(out[1], {4, -3});
  EXPECT_EQ(IntersectCircleCircle({0, 0}, 5, {20, 0}, 5, out), 0);
  EXPECT_EQ(IntersectCircleCircle({0, 0}, 5, {0, 0}, 5, out), 0);
}

// Fig 6.20: a turn toward the compensation (G41, left turn) ends both offset lines at their intersection.
TEST(OffsetPath, TurnTowardTheCompensationIntersects) {
  Corner k = ComputeCorner(Line({0, 0}, {10, 0}), Line({10, 0}, {10, 10}), 5, kLeft, false);
  EXPECT_EQ(k.kind, Corner::kToward);
  EXPECT_TRUE(k.intersects);
  EXPECT_FALSE(k.fill_in);
  ExpectNear(k.a_end, {5, 5});  // y = 5 meets x = 10 - 5
  ExpectNear(k.b_start, {5, 5});
  EXPECT_NEAR(k.a_trim, 5, 1e-9);
  EXPECT_NEAR(k.b_trim, 5, 1e-9);
}

// Fig 6.23: a turn away (G42, left turn) gets a fill-in arc of the comp radius about the programmed corner.
TEST(OffsetPath, TurnAwayGetsAFillInArc) {
  Corner k = ComputeCorner(Line({0, 0}, {10, 0}), Line({10, 0}, {10, 10}), 5, kRight, false);
  EXPECT_EQ(k.kind, Corner::kAway);
  ASSERT_TRUE(k.fill_in);
  ExpectNear(k.a_end, {10, -5});
  ExpectNear(k.b_start, {15, 0});
  EXPECT_FALSE(k.fill_cw);  // G42: the cutter goes round the corner counter-clockwise
  EXPECT_NEAR(k.fill_sweep, 90, 1e-9);
  // G41 with a right turn: clockwise.
  Corner c = ComputeCorner(Line({0, 0}, {10, 0}), Line({10, 0}, {10, -10}), 5, kLeft, false);
  ASSERT_TRUE(c.fill_in);
  EXPECT_TRUE(c.fill_cw);
  ExpectNear(c.a_end, {10, 5});
  ExpectNear(c.b_start, {15, 0});
  EXPECT_NEAR(c.fill_sweep, 90, 1e-9);
}

// G46 (ln 1658-1676): no fill-in block; the offset lines are extended to their intersection.
TEST(OffsetPath, BypassExtendsTheOffsetPaths) {
  Corner k = ComputeCorner(Line({0, 0}, {10, 0}), Line({10, 0}, {10, 10}), 5, kRight, true);
  EXPECT_EQ(k.kind, Corner::kAway);
  EXPECT_FALSE(k.fill_in);
  ExpectNear(k.a_end, {15, -5});
  EXPECT_NEAR(k.a_trim, -5, 1e-9);
  EXPECT_NEAR(k.b_trim, -5, 1e-9);
  // A reversal has no intersection ahead: a fill-in half circle even under G46.
  Corner r = ComputeCorner(Line({0, 0}, {10, 0}), Line({10, 0}, {0, 0}), 5, kLeft, true);
  ASSERT_TRUE(r.fill_in);
  EXPECT_TRUE(r.fill_cw);
  EXPECT_NEAR(r.fill_sweep, 180, 1e-9);
  ExpectNear(r.b_start, {10, -5});
}

TEST(OffsetPath, TangentPathsAndZeroRadiusNeedNoCorner) {
  // Line into a ccw arc that continues its direction (centre (10, 10), radius 10).
  Path a = Line({0, 0}, {10, 0});
  Path b = ArcPath({10, 0}, {20, 10}, {10, 10}, false, 90);
  Corner k = ComputeCorner(a, b, 5, kLeft, false);
  EXPECT_EQ(k.kind, Corner::kNone);
  ExpectNear(k.a_end, {10, 5});
  Corner z = ComputeCorner(Line({0, 0}, {10, 0}), Line({10, 0}, {10, 10}), 0, kLeft, false);
  EXPECT_EQ(z.kind, Corner::kNone);
  ExpectNear(z.a_end, {10, 0});
}

// Line (+X) into a ccw arc about (10, 0) starting at (0, 0) (tangent -Y: a right turn), G42 toward:
// the offset line y = -5 meets the offset circle of radius 10 + 5 at x = 10 - sqrt(200).
TEST(OffsetPath, LineIntoArcTowardTheCompensation) {
  Path a = Line({-10, 0}, {0, 0});
  Path b = ArcPath({0, 0}, {20, 0}, {10, 0}, false, 180);
  Corner k = ComputeCorner(a, b, 5, kRight, false);
  ASSERT_EQ(k.kind, Corner::kToward);
  ExpectNear(k.a_end, {10 - std::sqrt(200.0), -5});
  EXPECT_NEAR(k.a_trim, std::sqrt(200.0) - 10, 1e-9);
  // b starts at 180 degrees on its offset circle; the intersection is at atan2(-5, -sqrt(200)).
  double at = std::atan2(-5, -std::sqrt(200.0)) * 180 / M_PI + 360;  // 199.47
  EXPECT_NEAR(k.b_trim, at - 180, 1e-9);
}

// Fig 6.26: a short path between two turns toward the compensation would run backwards.
TEST(OffsetPath, ShortPathBetweenTwoTurnsTowardRunsBackwards) {
  Path a = Line({0, 0}, {20, 0});
  Path b = Line({20, 0}, {20, 4});  // 4 long
  Path c = Line({20, 4}, {0, 4});
  Corner k1 = ComputeCorner(a, b, 5, kLeft, false);
  Corner k2 = ComputeCorner(b, c, 5, kLeft, false);
  EXPECT_NEAR(RemainingLength(b, 5, kLeft, k1.b_trim, k2.a_trim), 4 - 5 - 5, 1e-9);
}

}  // namespace
}  // namespace cell::interp::geom
