// The contour on hand-made paths: corners, corner words, start and exit moves, with the values worked out
// in the comments.
#include "contour.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace cell::interp::balt {
namespace {

using geom::Path;
using geom::Vec2;

Canon Line(double x, double y, int line) {
  Canon c;
  c.line = line;
  LinearOp& l = c.Set<LinearOp>();
  l.to.pos[kX] = x;
  l.to.pos[kY] = y;
  l.to.used = 3;
  l.feed.rate = 100;
  return c;
}

Path Seg(Vec2 a, Vec2 b) {
  Path p;
  p.start = a;
  p.end = b;
  return p;
}

struct Fixture {
  Contour k;
  std::vector<Canon> out;
  void Drain() {
    for (auto& c : k.TakeChecked()) out.push_back(std::move(c));
  }
  void Move(Vec2 a, Vec2 b, int line, bool hold = false) {
    Path p = Seg(a, b);
    k.Take(Line(b.x, b.y, line), &p, hold);
    Drain();
  }
  Vec2 At(std::size_t i) const { return {out[i].target()->pos[kX], out[i].target()->pos[kY]}; }
};

// ISO radius corner (ln 3172-3185): (0,0) -> (100,0) -> (100,100) with r5 between: the line ends at
// (95,0), a 90 degree CCW arc about (95,5) to (100,5), then the second line.
TEST(Contour, RadiusCornerWordWithoutCompensation) {
  Fixture f;
  f.k.Sync({});
  f.Move({0, 0}, {100, 0}, 1, true);
  f.k.Corner('r', 5, 2);
  f.Move({100, 0}, {100, 100}, 3);
  f.k.Release();
  f.Drain();
  ASSERT_EQ(f.out.size(), 3u);
  EXPECT_NEAR(f.At(0).x, 95, 1e-9);
  const ArcOp& a = f.out[1].As<ArcOp>();
  EXPECT_EQ(f.out[1].line, 2);
  EXPECT_FALSE(a.cw);
  EXPECT_NEAR(a.center[0], 95, 1e-9);
  EXPECT_NEAR(a.center[1], 5, 1e-9);
  EXPECT_NEAR(a.angle, 90, 1e-9);
  EXPECT_NEAR(f.At(2).y, 100, 1e-9);
}

// Bevel b5 (ln 3190-3200) between (50,0)->(150,50) and (150,50)->(100,50): 5 back along the first from the
// corner, 5 along the second.
TEST(Contour, Bevel) {
  Fixture f;
  f.k.Sync({});
  f.Move({0, 0}, {50, 0}, 1);
  f.Move({50, 0}, {150, 50}, 2, true);
  f.k.Corner('b', 5, 3);
  f.Move({150, 50}, {100, 50}, 4);
  f.k.Release();
  f.Drain();
  ASSERT_EQ(f.out.size(), 4u);
  double len = std::hypot(100.0, 50.0);
  EXPECT_NEAR(f.At(1).x, 150 - 5 * 100 / len, 1e-9);
  EXPECT_NEAR(f.At(1).y, 50 - 5 * 50 / len, 1e-9);
  EXPECT_NEAR(f.At(2).x, 145, 1e-9);
  EXPECT_NEAR(f.At(2).y, 50, 1e-9);
}

// G41 radius 5 round a square corner, (0,0) start: start move to (10,5) at 90 degrees to the first line
// (10,0)->(50,0) (left of +X is +Y), the inside corner with (50,0)->(50,40) at (45,5), the G40 exit move
// from the second line's offset end (45,40) to the programmed (50,60).
TEST(Contour, StartCornerAndExit) {
  Fixture f;
  f.k.Sync({});
  f.k.Start(geom::kLeft, 5, 41);
  f.Move({0, 0}, {10, 0}, 1);
  f.Move({10, 0}, {50, 0}, 2);
  f.Move({50, 0}, {50, 40}, 3);
  f.k.Stop();
  f.Move({50, 40}, {50, 60}, 4);
  f.Drain();
  ASSERT_EQ(f.out.size(), 4u);
  EXPECT_NEAR(f.At(0).x, 10, 1e-9);
  EXPECT_NEAR(f.At(0).y, 5, 1e-9);
  EXPECT_NEAR(f.At(1).x, 45, 1e-9);
  EXPECT_NEAR(f.At(1).y, 5, 1e-9);
  EXPECT_NEAR(f.At(2).x, 45, 1e-9);
  EXPECT_NEAR(f.At(2).y, 40, 1e-9);
  EXPECT_NEAR(f.At(3).x, 50, 1e-9);
  EXPECT_NEAR(f.At(3).y, 60, 1e-9);
  EXPECT_FALSE(f.k.engaged());
}

// An outside corner meets at the intersection of the offset lines; r0 rolls round it instead (ln 3186).
TEST(Contour, OutsideCornerIntersectionOrRoll) {
  for (bool roll : {false, true}) {
    Fixture f;
    f.k.Sync({});
    f.k.Start(geom::kRight, 5, 42);
    f.Move({0, 0}, {10, 0}, 1);
    f.Move({10, 0}, {50, 0}, 2);
    if (roll) f.k.Corner('r', 0, 3);
    f.Move({50, 0}, {50, 40}, 4);
    f.k.Release();
    f.Drain();
    if (!roll) {
      ASSERT_EQ(f.out.size(), 3u);
      EXPECT_NEAR(f.At(1).x, 55, 1e-9);  // right of +X is -Y, right of +Y is +X: (55,-5)
      EXPECT_NEAR(f.At(1).y, -5, 1e-9);
    } else {
      ASSERT_EQ(f.out.size(), 4u);
      EXPECT_NEAR(f.At(1).x, 50, 1e-9);  // (50,-5), a 90 degree arc about (50,0) to (55,0)
      EXPECT_NEAR(f.At(1).y, -5, 1e-9);
      EXPECT_NEAR(f.out[2].As<ArcOp>().angle, 90, 1e-9);
      EXPECT_NEAR(f.At(2).x, 55, 1e-9);
      EXPECT_NEAR(f.At(2).y, 0, 1e-9);
    }
  }
}

TEST(Contour, InsideArcSmallerThanTheCutterIsAnError) {
  Fixture f;
  f.k.Sync({});
  f.k.Start(geom::kLeft, 5, 41);
  f.Move({0, 0}, {10, 0}, 1);
  Path arc;
  arc.arc = true;
  arc.start = {10, 0};
  arc.end = {10, 6};
  arc.center = {10, 3};
  arc.cw = false;  // CCW with the cutter on the left: inside, radius 3 < 5
  arc.sweep = 180;
  Canon c = Line(10, 6, 2);
  EXPECT_THROW(f.k.Take(std::move(c), &arc, false), ContourError);
}

// An element long enough for either corner's trim but not for both (ln 3080-3216, FILMS4 77): found when the
// element after it arrives. With the cutter (radius 5) on the left of A (10,0)->(50,0), B (50,0)->(50,8) and
// C (50,8)->(30,8), A would end at the corner (45,5), 3 mm from C: 2 mm inside the contour. It is not handed
// out; the start move to (10,5), far from C, is.
TEST(Contour, AnElementTooShortForBothCornersLeavesTheCornerBeforeItUnwritten) {
  Fixture f;
  f.k.Sync({});
  f.k.Start(geom::kLeft, 5, 41);
  f.Move({0, 0}, {10, 0}, 1);   // start move
  f.Move({10, 0}, {50, 0}, 2);  // A
  f.Move({50, 0}, {50, 8}, 3);  // B: 8 mm, trimmed by 5 at each end
  Path c = Seg({50, 8}, {30, 8});
  EXPECT_THROW(f.k.Take(Line(30, 8, 4), &c, false), ContourError);
  f.Drain();
  for (std::size_t i = 0; i < f.out.size(); ++i) {
    const Vec2 p = f.At(i);
    const double dx = std::max({30 - p.x, 0.0, p.x - 50});
    EXPECT_GE(std::hypot(dx, 8 - p.y), 5 - 2e-3)
        << "move " << i << " ends inside the contour at " << p.x << "," << p.y;
  }
  ASSERT_EQ(f.out.size(), 1u);  // the start move only: A's end at the corner waits for B, which fails
  EXPECT_NEAR(f.At(0).x, 10, 1e-9);
  EXPECT_NEAR(f.At(0).y, 5, 1e-9);
}

// G41 with radius 5 on: the start move to the offset start (4,-6.928) of a CCW arc of radius 13 about the
// origin from 300 to 360 degrees, (6.5,-11.258) -> (13,0), taken (its corner waits for the next move).
void StartAndArc(Fixture& f) {
  f.k.Sync({});
  f.k.Start(geom::kLeft, 5, 41);
  const Vec2 s{6.5, -13 * std::sqrt(3.0) / 2};
  f.Move({6.5, -30}, s, 1);
  Path arc;
  arc.arc = true;
  arc.start = s;
  arc.end = {13, 0};
  arc.center = {0, 0};
  arc.sweep = 60;
  Canon c;
  c.line = 2;
  ArcOp& a = c.Set<ArcOp>();
  a.to.pos[kX] = 13;
  a.to.used = 3;
  a.feed.rate = 100;
  a.angle = 60;
  a.plane = {kX, kY};
  f.k.Take(std::move(c), &arc, false);
  f.Drain();
}

// An outside corner where an arc meets (balt.md judgement call 50, ln 3082): G41 radius 5, a CCW arc about
// (0,0) of radius 13 from -60 to 0 degrees (the cutter inside it: offset radius 8), then the line
// (13,0)->(40,0), a right turn of 90 degrees, away from the cutter. The offset elements meet on the
// arc's offset circle 38.7 degrees past its end, at (6.245,5); the tangents' offsets (x = 8, y = 5) meet
// at (8,5): the arc ends at its offset end (8,0), the tool goes straight to (8,5) and along the line's
// offset to (40,5).
TEST(Contour, OutsideCornerAfterAnArcMeetsOnTheTangent) {
  Fixture f;
  StartAndArc(f);
  f.Move({13, 0}, {40, 0}, 3);
  f.k.Release();
  f.Drain();
  ASSERT_EQ(f.out.size(), 4u);
  EXPECT_NEAR(f.At(0).x, 4, 1e-9);
  EXPECT_NEAR(f.At(0).y, -4 * std::sqrt(3.0), 1e-9);
  EXPECT_NEAR(f.out[1].As<ArcOp>().angle, 60, 1e-9);  // not extended along its circle
  EXPECT_NEAR(f.At(1).x, 8, 1e-9);
  EXPECT_NEAR(f.At(1).y, 0, 1e-9);
  EXPECT_EQ(f.out[2].line, 2);
  EXPECT_NEAR(f.At(2).x, 8, 1e-9);  // straight along the arc's tangent offset
  EXPECT_NEAR(f.At(2).y, 5, 1e-9);
  EXPECT_NEAR(f.At(3).x, 40, 1e-9);
  EXPECT_NEAR(f.At(3).y, 5, 1e-9);
}

// The same arc, then a line turning 150 degrees right, (13,0)->(13,0)+20(0.5,-0.866): its offset (through
// (17.330,2.5)) misses the arc's offset circle of radius 8, and the tangents' offsets would meet far out
// at (8,18.660); the fill-in arc about the corner stays (judgement call 50), CW 150 degrees from (8,0).
TEST(Contour, OutsideCornerAfterAnArcKeepsTheFillInWhereTheOffsetsDoNotMeet) {
  Fixture f;
  StartAndArc(f);
  const Vec2 d{0.5, -std::sqrt(3.0) / 2};
  f.Move({13, 0}, {13 + 20 * d.x, 20 * d.y}, 3);
  f.k.Release();
  f.Drain();
  ASSERT_EQ(f.out.size(), 4u);
  EXPECT_NEAR(f.At(1).x, 8, 1e-9);
  EXPECT_NEAR(f.At(1).y, 0, 1e-9);
  const ArcOp& fill = f.out[2].As<ArcOp>();
  EXPECT_TRUE(fill.cw);
  EXPECT_NEAR(fill.angle, 150, 1e-9);
  EXPECT_NEAR(f.At(2).x, 13 - 5 * d.y, 1e-9);
  EXPECT_NEAR(f.At(2).y, 5 * d.x, 1e-9);
}

}  // namespace
}  // namespace cell::interp::balt
