// Cutter diameter compensation geometry and look-ahead (dialects/ktapl/src/cutter_comp.h). The expected
// numbers are worked by hand in the comments; the manual lines are of seeds/kearney-trecker-kt-apl.txt.
#include "cutter_comp.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "cell/interp/interp.h"
#include "cell/interp/ktapl.h"

namespace cell::interp::ktapl::cc {
namespace {

constexpr double kEps = 1e-9;

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
TEST(CutterCompGeometry, LineOffsetsLeftAndRight) {
  Path p = Line({0, 0}, {10, 0});
  ExpectNear(OffsetStart(p, 5, kLeft), {0, 5});
  ExpectNear(OffsetEnd(p, 5, kLeft), {10, 5});
  ExpectNear(OffsetStart(p, 5, kRight), {0, -5});
  EXPECT_NEAR(Extent(p), 10, kEps);
  EXPECT_NEAR(RemainingLength(p, 5, kLeft, 2, 3), 5, kEps);
}

// A ccw arc has its centre on the left: G41 is inside (radius r - R), G42 outside (r + R).
TEST(CutterCompGeometry, ArcOffsetsInsideAndOutside) {
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

TEST(CutterCompGeometry, Intersections) {
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
TEST(CutterCompGeometry, TurnTowardTheCompensationIntersects) {
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
TEST(CutterCompGeometry, TurnAwayGetsAFillInArc) {
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
TEST(CutterCompGeometry, BypassExtendsTheOffsetPaths) {
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

TEST(CutterCompGeometry, TangentPathsAndZeroRadiusNeedNoCorner) {
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
TEST(CutterCompGeometry, LineIntoArcTowardTheCompensation) {
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
TEST(CutterCompGeometry, ShortPathBetweenTwoTurnsTowardRunsBackwards) {
  Path a = Line({0, 0}, {20, 0});
  Path b = Line({20, 0}, {20, 4});  // 4 long
  Path c = Line({20, 4}, {0, 4});
  Corner k1 = ComputeCorner(a, b, 5, kLeft, false);
  Corner k2 = ComputeCorner(b, c, 5, kLeft, false);
  EXPECT_NEAR(RemainingLength(b, 5, kLeft, k1.b_trim, k2.a_trim), 4 - 5 - 5, 1e-9);
}

// ---------------------------------------------------------------------------------------------------------
// Look-ahead

struct Feed {
  Compensator comp;
  std::vector<Canon> out;
  void Drain() {
    for (auto& c : comp.Ready()) out.push_back(c);
    comp.Ready().clear();
  }
  void Move(double x, double y, int line, Op op = Op::kLinear) {
    Canon c;
    c.op = op;
    c.line = line;
    c.pos[kX] = x;
    c.pos[kY] = y;
    c.used = 3;
    c.feed = op == Op::kRapid ? 0 : 100;
    comp.Take(std::move(c));
    Drain();
  }
  void Other(Op op, int line) {
    Canon c;
    c.op = op;
    c.line = line;
    comp.Take(std::move(c));
    Drain();
  }
  void End() {
    comp.EndBlock(true);
    Drain();
  }
};

Compensator::Setup Setup41(double x, double y) {
  Compensator::Setup s;
  s.radius = 5;
  s.side = kLeft;
  s.pos[kX] = x;
  s.pos[kY] = y;
  return s;
}

// Ramp-on (ln 6453, 6466, Fig 6.12) to 90 degrees of the next path, an intersection corner, a fill-in corner,
// the ops of a block in between placed after the corner, and the end of the program.
// Runs `step` and expects a compensation error with `alarm` ("" for the rules without a number).
template <class Step>
void ExpectCompError(Step step, const char* alarm) {
  try {
    step();
    ADD_FAILURE() << "no compensation error";
  } catch (const CompError& e) {
    EXPECT_EQ(e.alarm, alarm);
  }
}

TEST(CutterCompLookAhead, RampCornersAndHeldOps) {
  Feed f;
  f.comp.RampOn(Setup41(0, -20));
  EXPECT_TRUE(f.comp.engaged());
  f.Move(0, 0, 1);  // ramp-on, +Y
  f.End();
  EXPECT_TRUE(f.comp.on());
  EXPECT_TRUE(f.out.empty());  // held until the next path is known
  f.Move(20, 0, 2);            // +X: next path; left normal (0, 1) -> ramp ends at (0, 5)
  f.End();
  ASSERT_EQ(f.out.size(), 1u);
  EXPECT_EQ(f.out[0].line, 1);
  EXPECT_NEAR(f.out[0].pos[kX], 0, 1e-9);
  EXPECT_NEAR(f.out[0].pos[kY], 5, 1e-9);
  f.Other(Op::kCoolant, 3);  // a block without motion: held behind block 2
  f.End();
  EXPECT_EQ(f.out.size(), 1u);
  f.Move(20, 20, 4);  // +Y: a left turn, toward G41 -> block 2 ends at (15, 5)
  f.End();
  ASSERT_EQ(f.out.size(), 3u);
  EXPECT_EQ(f.out[1].line, 2);
  EXPECT_NEAR(f.out[1].pos[kX], 15, 1e-9);
  EXPECT_NEAR(f.out[1].pos[kY], 5, 1e-9);
  EXPECT_EQ(f.out[2].op, Op::kCoolant);
  f.Move(40, 20, 5);  // +X: a right turn, away -> block 4 ends at (15, 20), fill-in cw to (20, 25)
  f.End();
  ASSERT_EQ(f.out.size(), 5u);
  EXPECT_NEAR(f.out[3].pos[kX], 15, 1e-9);
  EXPECT_NEAR(f.out[3].pos[kY], 20, 1e-9);
  EXPECT_EQ(f.out[4].op, Op::kArc);
  EXPECT_EQ(f.out[4].line, 4);
  EXPECT_TRUE(f.out[4].cw);
  EXPECT_NEAR(f.out[4].pos[kX], 20, 1e-9);
  EXPECT_NEAR(f.out[4].pos[kY], 25, 1e-9);
  EXPECT_NEAR(f.out[4].center[0], 20, 1e-9);
  EXPECT_NEAR(f.out[4].center[1], 20, 1e-9);
  EXPECT_NEAR(f.out[4].turns, 90, 1e-9);
  EXPECT_EQ(f.out[4].plane, "xy");
  f.comp.Finish();
  f.Drain();
  ASSERT_EQ(f.out.size(), 6u);
  EXPECT_NEAR(f.out[5].pos[kX], 40, 1e-9);  // its own offset end
  EXPECT_NEAR(f.out[5].pos[kY], 25, 1e-9);
  EXPECT_FALSE(f.comp.engaged());
}

// G40 without motion (ln 6532): the cutter stays offset; a Z move stays there, the next move in the
// plane goes from there to its programmed point.
TEST(CutterCompLookAhead, CancelWithoutMotionLeavesTheOffset) {
  Feed f;
  f.comp.RampOn(Setup41(0, -20));
  f.Move(0, 0, 1);
  f.End();
  f.Move(20, 0, 2);
  f.End();
  f.comp.Cancel();
  f.End();
  ASSERT_EQ(f.out.size(), 2u);
  EXPECT_NEAR(f.out[1].pos[kY], 5, 1e-9);
  EXPECT_TRUE(f.comp.engaged());
  EXPECT_FALSE(f.comp.on());
  Canon z;
  z.op = Op::kRapid;
  z.line = 4;
  z.pos = {20, 0, 50};
  f.comp.Take(std::move(z));
  f.Drain();
  f.End();
  ASSERT_EQ(f.out.size(), 3u);
  EXPECT_NEAR(f.out[2].pos[kY], 5, 1e-9);
  EXPECT_NEAR(f.out[2].pos[kZ], 50, 1e-9);
  f.Move(30, 0, 5);
  f.End();
  ASSERT_EQ(f.out.size(), 4u);
  EXPECT_NEAR(f.out[3].pos[kY], 0, 1e-9);
  EXPECT_FALSE(f.comp.engaged());
}

TEST(CutterCompLookAhead, Errors) {
  {  // ramp-on without motion in the plane (ln 1617, 6466)
    Feed f;
    f.comp.RampOn(Setup41(0, 0));
    try {
      f.End();
      FAIL();
    } catch (const CompError& e) {
      EXPECT_EQ(e.at, CompError::kAtCode);
      EXPECT_EQ(e.alarm, "");
    }
  }
  {  // more than four blocks without motion in the plane (ln 6670-6688)
    Feed f;
    f.comp.RampOn(Setup41(0, -20));
    f.Move(0, 0, 1);
    f.End();
    for (int i = 0; i < 4; ++i) f.End();
    ExpectCompError([&] { f.End(); }, "0003");
  }
  {  // inside arc smaller than the comp (ln 6658-6668)
    Feed f;
    f.comp.RampOn(Setup41(0, 0));
    f.Move(4, 0, 1);
    f.End();
    Canon c;
    c.op = Op::kArc;
    c.pos[kX] = 4;
    c.center = {0, 0, 0};
    c.cw = false;
    c.turns = 360;
    ExpectCompError([&] { f.comp.Take(std::move(c)); }, "0004");
  }
  {  // Fig 6.26, ln 6621-6640: an 8 mm path between two turns toward a 5 mm comp: each corner alone fits
     // (8 - 5 >= 0), both together cut it back by 10 -> error in the previous block at the second corner
    Feed f;
    f.comp.RampOn(Setup41(0, -20));
    f.Move(0, 0, 1);
    f.End();
    f.Move(20, 0, 2);
    f.End();
    f.Move(20, 8, 3);
    f.End();
    ExpectCompError([&] { f.Move(0, 8, 4); }, "0001");
  }
  {  // a 4 mm path cut back by 5 at its start: error in the current block
    Feed f;
    f.comp.RampOn(Setup41(0, -20));
    f.Move(0, 0, 1);
    f.End();
    f.Move(20, 0, 2);
    f.End();
    ExpectCompError([&] { f.Move(20, 4, 3); }, "0002");
  }
}

// ---------------------------------------------------------------------------------------------------------
// Through the run

// The manual's U-head program (ln 7172-7231, Fig 7.4): diameter comp in the G18 G21 (Z, U) plane, the
// ramp-on on a Z move, arcs, G42 at F0 to retract, G40 with M25. The insert tip D.031 in (R .0155 in) is
// primary compensation; suffix 7 holds the same diameter for the TIP-OFFSET subroutine, which sets a G98
// offset of -.031 on U (programmed U = machine U + .031).
TEST(CutterCompRun, ManualUHeadExample) {
  RunOptions o;
  o.program_name = "UHEAD";
  o.tools = ParseKtaplToolTable("G70\n(TLD,T1P2.D.031)\n(TLD,T1.7P3.D.031)\n");
  o.program_text =
      "(DFS,TIP-OFFSET)\n(UAT,7)\n(PAR,L1=L3018)\n(UAT,0)\nM25U0\nG98UL1\n(END)\n"
      "G70G90G94T1\nG48H1\nM6\n(CLS,TIP-OFFSET)\nZ20.M25S500M3M8\nX0Y0F0\nU2.\nG18G21\n"
      "G41Z.1\nZ-.05F5.\nU1.75\nU1.5Z-.3I1.75K-.3G02\nU1.25Z-.55R.25G03\nU.75\nU.5Z-.8\n"
      "Z,-(1. + .1)\nU.4G42F0\nZ.1\nZ20.M25G40\nM30\n";
  auto run = StartRun(o);
  std::vector<Canon> moves;
  for (;;) {
    Step s = run->Next();
    if (s.kind == Step::kError) FAIL() << s.diag.Format();
    if (s.kind == Step::kEnd) break;
    if (s.canon.op == Op::kRapid || s.canon.op == Op::kLinear || s.canon.op == Op::kArc)
      moves.push_back(s.canon);
  }
  auto find = [&](int line) -> const Canon* {
    for (const auto& m : moves) {
      if (m.line == line) return &m;
    }
    return nullptr;
  };
  // Line 16, G41Z.1 (travel -Z, left = -U): U 2. - .031 - .0155 = 1.9535 in; Z .1 + length comp 2. in.
  const Canon* ramp = find(16);
  ASSERT_NE(ramp, nullptr);
  EXPECT_NEAR(ramp->pos[kU], 1.9535 * 25.4, 1e-6);
  EXPECT_NEAR(ramp->pos[kZ], 2.1 * 25.4, 1e-6);
  // Line 17, Z-.05 turns left (toward G41) into the -U face: it ends on the face's offset z = -.05 + .0155.
  const Canon* bore = find(17);
  ASSERT_NE(bore, nullptr);
  EXPECT_NEAR(bore->pos[kZ], (2. - .05 + .0155) * 25.4, 1e-6);
  // Line 26, Z20.M25G40 ramps off to the programmed U .4 (machine .369).
  ASSERT_FALSE(moves.empty());
  EXPECT_EQ(moves.back().line, 26);
  EXPECT_NEAR(moves.back().pos[kU], .369 * 25.4, 1e-6);
  EXPECT_NEAR(moves.back().pos[kZ], 20. * 25.4, 1e-6);
}

}  // namespace
}  // namespace cell::interp::ktapl::cc
