// GTL definitions against values derived by hand from the manual's figures (§5.15).
#include "gtl.h"

#include <gtest/gtest.h>

#include <cmath>

namespace cell::interp::balt::gtl {
namespace {

Operand Pt(double x, double y, bool literal = true) {
  Operand o;
  o.kind = Operand::kPoint;
  o.e.kind = Element::kPoint;
  o.e.p = {x, y};
  o.literal = literal;
  return o;
}
Operand Circle(double x, double y, double r) {
  Operand o;
  o.kind = Operand::kCircle;
  o.e.kind = Element::kCircle;
  o.e.p = {x, y};
  o.e.r = r;
  o.literal = true;
  return o;
}
Operand Num(Operand::Kind k, double v) {
  Operand o;
  o.kind = k;
  o.v = v;
  return o;
}
Operand Ref(const Element& e) {
  Operand o;
  o.kind = e.kind == Element::kLine ? Operand::kLine
                                    : (e.kind == Element::kCircle ? Operand::kCircle : Operand::kPoint);
  o.e = e;
  return o;
}

constexpr double kEps = 1e-6;

// Fig 5.47: l1 = X40 Y20, X60 Y70 runs from the first point to the second.
TEST(Gtl, LineThroughTwoPoints) {
  Element l = Define('l', {Pt(40, 20), Pt(60, 70)});
  EXPECT_NEAR(l.AngleDeg(), std::atan2(50, 20) * 180 / M_PI, kEps);
  EXPECT_NEAR(l.p.x, 40, kEps);
}

// Fig 5.51: l1 = I60 J80 r40, a45: a CCW circle is touched on its right-hand side going at 45 degrees,
// at centre + r (sin a, -cos a) = (88.284, 51.716).
TEST(Gtl, LineTangentAtAngle) {
  Element l = Define('l', {Circle(60, 80, 40), Num(Operand::kAngle, 45)});
  EXPECT_NEAR(l.p.x, 60 + 40 * std::sin(M_PI / 4), kEps);
  EXPECT_NEAR(l.p.y, 80 - 40 * std::cos(M_PI / 4), kEps);
  // The same with a CW circle touches the other side.
  Element m = Define('l', {Circle(60, 80, -40), Num(Operand::kAngle, 45)});
  EXPECT_NEAR(m.p.x, 60 - 40 * std::sin(M_PI / 4), kEps);
}

// Line-circle intersections are numbered along the line (Fig 5.43): reversing the line with s2 gives the
// first point of the original.
TEST(Gtl, LineCircleIntersectionOrder) {
  Element l4 = Define('l', {Pt(0, 0), Num(Operand::kAngle, 0)});
  Operand c3 = Circle(10, 0, 5);
  Element p1 = Define('p', {Ref(l4), c3});
  Element p2 = Define('p', {Ref(l4), c3, Num(Operand::kS2, 0)});
  Element p3 = Define('p', {Ref(l4.Reversed()), c3, Num(Operand::kS2, 0)});
  EXPECT_NEAR(p1.p.x, 5, kEps);
  EXPECT_NEAR(p2.p.x, 15, kEps);
  EXPECT_NEAR(p3.p.x, 5, kEps);
}

// Circle-circle: the first point is left of the line from the first centre to the second (Fig 5.44).
TEST(Gtl, CircleCircleIntersectionOrder) {
  Operand c1 = Circle(0, 0, 5), c2 = Circle(6, 0, 5);
  Element p1 = Define('p', {c1, c2});
  Element p2 = Define('p', {c1, c2, Num(Operand::kS2, 0)});
  Element p3 = Define('p', {c2, c1, Num(Operand::kS2, 0)});
  EXPECT_NEAR(p1.p.x, 3, kEps);
  EXPECT_NEAR(p1.p.y, 4, kEps);
  EXPECT_NEAR(p2.p.y, -4, kEps);
  EXPECT_NEAR(p3.p.y, 4, kEps);
}

// Fig 5.69: c2 = m70 a30 r15 has its centre at (70 cos 30, 70 sin 30) = (60.622, 35); polar points are
// read by the executor, a circle literal is stored as it is.
TEST(Gtl, CircleLiteral) {
  Element c = Define('c', {Circle(60.6217782649107, 35, 15)});
  EXPECT_NEAR(c.r, 15, kEps);
}

// A circle of radius r tangent to two lines (Fig 5.70): its centre is r to the left of both (r signed).
TEST(Gtl, CircleTangentToTwoLines) {
  Element l1 = Define('l', {Pt(0, 0), Num(Operand::kAngle, 0)});
  Element l2 = Define('l', {Pt(10, 0), Num(Operand::kAngle, 90)});
  Element c = Define('c', {Ref(l1), Ref(l2), Num(Operand::kRadius, 3)});
  EXPECT_NEAR(c.p.x, 7, kEps);
  EXPECT_NEAR(c.p.y, 3, kEps);
}

// Tangent to two circles with a given radius: the shorter arc from the first to the second (Fig 5.75).
// c1 (0,0) r10 and c2 (20,0) r10 (CCW), radius -5 (CW): centres 15 from both, (10, +-11.180); from c1's
// contact to c2's the CW arc is 83.6 degrees about (10, -11.180) and 276.4 about (10, 11.180).
TEST(Gtl, CircleTangentToTwoCirclesMinorArc) {
  Operand c1 = Circle(0, 0, 10), c2 = Circle(20, 0, 10);
  Element a = Define('c', {c1, c2, Num(Operand::kRadius, -5)});
  Element b = Define('c', {c2, c1, Num(Operand::kRadius, -5)});
  EXPECT_NEAR(a.p.x, 10, kEps);
  EXPECT_NEAR(a.p.y, -std::sqrt(125.0), kEps);
  EXPECT_NEAR(b.p.y, std::sqrt(125.0), kEps);  // the operand order selects the other one
  EXPECT_NEAR(a.r, -5, kEps);
}

// Three points give the circle through them, directed p1 -> p2 -> p3 (Fig 5.81).
TEST(Gtl, CircleThroughThreePoints) {
  Element c = Define('c', {Pt(10, 0), Pt(0, 10), Pt(-10, 0)});
  EXPECT_NEAR(c.p.x, 0, kEps);
  EXPECT_NEAR(c.p.y, 0, kEps);
  EXPECT_NEAR(c.r, 10, kEps);  // counter-clockwise
  Element d = Define('c', {Pt(-10, 0), Pt(0, 10), Pt(10, 0)});
  EXPECT_NEAR(d.r, -10, kEps);
}

// Centre at a point, tangent to a circle: the smaller radius, s2 the larger (Fig 5.80).
TEST(Gtl, CircleCentredTangentToCircle) {
  Operand c1 = Circle(0, 0, 50);
  Element a = Define('c', {Pt(10, 0), c1});
  Element b = Define('c', {Pt(10, 0), c1, Num(Operand::kS2, 0)});
  EXPECT_NEAR(a.r, 40, kEps);
  EXPECT_NEAR(b.r, 60, kEps);
}

// Parallel line and concentric circle at a distance: positive on the left (Fig 5.61, 5.83).
TEST(Gtl, OffsetsToTheLeft) {
  Element l1 = Define('l', {Pt(0, 0), Num(Operand::kAngle, 0)});
  Element l2 = Define('l', {Ref(l1), Num(Operand::kDistance, 20)});
  EXPECT_NEAR(l2.p.y, 20, kEps);
  Element c = Define('c', {Circle(0, 0, 50), Num(Operand::kDistance, -10)});
  EXPECT_NEAR(c.r, 60, kEps);
}

TEST(Gtl, NoFormIsASyntaxError) {
  try {
    (void)Define('l', {Num(Operand::kRadius, 3)});
    FAIL();
  } catch (const GeomError& e) {
    EXPECT_EQ(e.code, 11);
  }
}

TEST(Gtl, ParallelLinesDoNotIntersect) {
  Element l1 = Define('l', {Pt(0, 0), Num(Operand::kAngle, 0)});
  Element l2 = Define('l', {Pt(0, 5), Num(Operand::kAngle, 0)});
  try {
    (void)Define('p', {Ref(l1), Ref(l2)});
    FAIL();
  } catch (const GeomError& e) {
    EXPECT_EQ(e.code, 77);
  }
}

}  // namespace
}  // namespace cell::interp::balt::gtl
