// The parts comparer (issue 33 item 3): what FinishedContour keeps and joins, and what CompareContours
// reports.
#include <gtest/gtest.h>

#include "cell/oracle/oracle.h"

namespace cell::oracle {
namespace {

Move Line(int line, Vec3 end) {
  Move m;
  m.kind = MoveKind::kLine;
  m.line = line;
  m.end = end;
  return m;
}

Move Arc(int line, Vec3 end, Vec3 center, bool cw) {
  Move m = Line(line, end);
  m.kind = MoveKind::kArc;
  m.center = center;
  m.cw = cw;
  m.plane = 18;  // a lathe's ZX: x and z in plane
  return m;
}

Move Rapid(int line, Vec3 end) {
  Move m = Line(line, end);
  m.kind = MoveKind::kRapid;
  return m;
}

PartProgram Lines(int first, int last) {
  PartProgram p;
  p.finish.push_back({first, last});
  return p;
}

TEST(Parts, CollinearLinesAndASplitArcAreOneElementEach) {
  std::vector<Move> moves{Rapid(1, {10, 0, 2}), Line(2, {10, 0, 0}), Line(3, {10, 0, -5}),
                          Arc(4, {12, 0, -7}, {12, 0, -5}, true), Arc(5, {14, 0, -5}, {12, 0, -5}, true)};
  Contour c = FinishedContour(moves, Lines(2, 5), 1e-4);
  ASSERT_EQ(c.elements.size(), 2u);
  EXPECT_EQ(c.starts[0], (Vec3{10, 0, 2}));  // where the rapid left the tool
  EXPECT_EQ(c.elements[0].end, (Vec3{10, 0, -5}));
  EXPECT_EQ(c.elements[1].end, (Vec3{14, 0, -5}));
}

TEST(Parts, AReversedLineIsNotJoined) {  // a tap's feed in and out
  std::vector<Move> moves{Rapid(1, {0, 0, 5}), Line(2, {0, 0, -12}), Line(2, {0, 0, 5})};
  EXPECT_EQ(FinishedContour(moves, Lines(2, 2), 1e-4).elements.size(), 2u);
}

TEST(Parts, CornerArcsBecomeThePointWhereTheLinesMeet) {
  // Down -Z to (10, -4), round the corner (10, -5) on an arc of radius 1 about (11, -4), on along +X: the two
  // lines meet at the corner.
  std::vector<Move> moves{Rapid(1, {10, 0, 0}), Line(2, {10, 0, -4}), Arc(2, {11, 0, -5}, {11, 0, -4}, false),
                          Line(3, {20, 0, -5})};
  PartProgram p = Lines(2, 3);
  p.corner_arcs = 1;
  Contour c = FinishedContour(moves, p, 1e-4);
  ASSERT_EQ(c.elements.size(), 2u);
  EXPECT_NEAR(c.elements[0].end[0], 10, 1e-9);
  EXPECT_NEAR(c.elements[0].end[2], -5, 1e-9);
  EXPECT_EQ(c.starts[1], c.elements[0].end);
}

TEST(Parts, ThePassLastKeepsOnlyTheRunSinceTheProgramWentBack) {
  std::vector<Move> moves{Line(5, {1, 0, 0}), Line(6, {1, 1, 0}), Rapid(9, {0, 0, 0}), Line(5, {2, 0, 0}),
                          Line(6, {2, 2, 0})};
  PartProgram p = Lines(5, 6);
  EXPECT_EQ(FinishedContour(moves, p, 1e-4).elements.size(), 4u);
  p.last_pass = true;
  Contour c = FinishedContour(moves, p, 1e-4);
  ASSERT_EQ(c.elements.size(), 2u);
  EXPECT_EQ(c.elements[1].end, (Vec3{2, 2, 0}));
}

TEST(Parts, BottomsAreThePlungesThatEndDeepest) {
  std::vector<Move> moves{Rapid(7, {20, 0, -24}), Line(7, {18, 0, -24}),  Rapid(7, {18.5, 0, -24}),
                          Line(7, {16, 0, -24}),  Rapid(7, {20, 0, -26}), Line(7, {16, 0, -26})};
  PartProgram p = Lines(99, 99);
  p.bottoms.push_back({7, 7});
  Contour c = FinishedContour(moves, p, 1e-4);
  ASSERT_EQ(c.elements.size(), 2u);
  EXPECT_EQ(c.elements[0].kind, MoveKind::kSet);
  EXPECT_EQ(c.elements[1].end, (Vec3{16, 0, -26}));
}

TEST(Parts, TheFirstDifferenceIsReportedByElementAndField) {
  std::vector<Move> a{Rapid(1, {10, 0, 0}), Line(2, {10, 0, -4}), Arc(3, {12, 0, -6}, {12, 0, -4}, true)};
  std::vector<Move> b = a;
  Contour ca = FinishedContour(a, Lines(2, 3), 1e-4);
  EXPECT_FALSE(CompareContours(ca, FinishedContour(b, Lines(2, 3), 1e-4), 1e-3));
  b[2].cw = false;
  auto d = CompareContours(ca, FinishedContour(b, Lines(2, 3), 1e-4), 1e-3);
  ASSERT_TRUE(d);
  EXPECT_EQ(d->index, 2u);
  EXPECT_EQ(d->field, "direction");
  b = a;
  b[0].end[2] = 0.002;  // the contour starts elsewhere
  d = CompareContours(ca, FinishedContour(b, Lines(2, 3), 1e-4), 1e-3);
  ASSERT_TRUE(d);
  EXPECT_EQ(d->field, "start z");
  b = a;
  b.pop_back();
  d = CompareContours(ca, FinishedContour(b, Lines(2, 3), 1e-4), 1e-3);
  ASSERT_TRUE(d);
  EXPECT_EQ(d->field, "element count");
}

}  // namespace
}  // namespace cell::oracle
