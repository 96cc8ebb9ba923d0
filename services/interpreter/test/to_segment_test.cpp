// Canonical commands to the servo's segments (ToSegment): the lathe ops reach the servo's lathe kind.
#include <gtest/gtest.h>

#include <optional>

#include "cell/station/to_segment.h"

namespace cell::station {
namespace {

using interp::Canon;

TEST(ToSegment, ThreadCarriesLeadLeadChangeAndStartAngle) {
  Canon c;
  c.line = 7;
  interp::ThreadOp& t = c.Set<interp::ThreadOp>();
  t.to.pos[interp::kX] = 38.2;  // a diameter, as every lathe X
  t.to.pos[interp::kZ] = -30;
  t.to.used = (1u << interp::kX) | (1u << interp::kZ);
  t.lead = 1.5;
  t.lead_change = 0.05;
  t.start_angle = 180;
  auto s = ToSegment(c);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->kind(), cell::SEGMENT_THREAD);
  EXPECT_EQ(s->line(), 7);
  EXPECT_DOUBLE_EQ(s->target()[0], 38.2);
  EXPECT_DOUBLE_EQ(s->target()[2], -30);
  EXPECT_EQ(s->axis_mask(), 0b101);
  EXPECT_DOUBLE_EQ(s->thread_lead(), 1.5);
  EXPECT_DOUBLE_EQ(s->thread_lead_change(), 0.05);
  EXPECT_DOUBLE_EQ(s->thread_start_angle(), 180);
  EXPECT_FALSE(s->exact_stop());
  t.exact_stop = true;  // Okuma G65: the thread ends in position even when a thread follows
  EXPECT_TRUE(ToSegment(c)->exact_stop());
}

// A live tool's op is a spindle segment of the live tool, never of the work spindle (Okuma M13 SB=400,
// manual ln 1868-1871); the work spindle joined as C no longer turns as a spindle.
TEST(ToSegment, LiveToolSpindleIsTheLiveToolsSegment) {
  Canon c;
  interp::SpindleOp& sp = c.Set<interp::SpindleOp>();
  sp.spindle = interp::SpindleId::kLiveTool;
  sp.dir = interp::SpindleDir::kCw;
  sp.rpm = 400;
  ASSERT_TRUE(ToSegment(c));
  EXPECT_EQ(ToSegment(c)->kind(), cell::SEGMENT_SPINDLE);
  EXPECT_TRUE(ToSegment(c)->live_tool());
  EXPECT_EQ(ToSegment(c)->spindle_mode(), 1);
  EXPECT_DOUBLE_EQ(ToSegment(c)->spindle_rpm(), 400);
  sp.spindle = interp::SpindleId::kMain;
  sp.dir = interp::SpindleDir::kAxis;  // joined as C: the servo's C-axis joint (docs/axis-servo.md)
  ASSERT_TRUE(ToSegment(c));
  EXPECT_FALSE(ToSegment(c)->live_tool());
  EXPECT_EQ(ToSegment(c)->spindle_mode(), 4);
}

TEST(ToSegment, SpindleCarriesConstantSurfaceSpeedAndTheLimit) {
  Canon c;
  interp::SpindleOp& sp = c.Set<interp::SpindleOp>();
  sp.dir = interp::SpindleDir::kCw;
  sp.rpm = 800;
  sp.css = 150;
  sp.max_rpm = 2500;
  auto s = ToSegment(c);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->kind(), cell::SEGMENT_SPINDLE);
  EXPECT_EQ(s->spindle_mode(), 1);
  EXPECT_DOUBLE_EQ(s->spindle_rpm(), 800);
  EXPECT_DOUBLE_EQ(s->css_surface_speed(), 150);
  EXPECT_DOUBLE_EQ(s->spindle_max_rpm(), 2500);
}

TEST(ToSegment, PerRevolutionFeedAndArcPlanes) {
  Canon c;
  interp::ArcOp& a = c.Set<interp::ArcOp>();
  a.plane = {interp::kZ, interp::kX};
  a.feed = {0.2, interp::FeedMode::kPerRev, false};
  a.angle = 90;
  auto s = ToSegment(c);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->plane_first(), interp::kZ);
  EXPECT_EQ(s->plane_second(), interp::kX);
  EXPECT_EQ(s->feed_mode(), 1);
  EXPECT_DOUBLE_EQ(s->feed(), 0.2);
  EXPECT_EQ(s->turns(), 0);
  // Every pair keeps its order and its sense: Balt-System (DPI,X,Z) G2 is not G18 G2 (DESIGN section 4).
  a.plane = {interp::kX, interp::kZ};
  a.cw = true;
  s = ToSegment(c);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->plane_first(), interp::kX);
  EXPECT_EQ(s->plane_second(), interp::kZ);
  EXPECT_FALSE(s->ccw());
  a.plane = {interp::kY, interp::kX};
  a.cw = false;
  s = ToSegment(c);
  ASSERT_TRUE(s);
  EXPECT_EQ(s->plane_first(), interp::kY);
  EXPECT_EQ(s->plane_second(), interp::kX);
  EXPECT_TRUE(s->ccw());
  // Messages, tool selection and file ops are the CNC's own: no segment.
  Canon m;
  m.Set<interp::MessageOp>().text = "x";
  EXPECT_FALSE(ToSegment(m));
}

// Okuma's C after M110 (docs/canonical-commands.md: `c` normalised with `c_travel`): M15 C270 then M15 C0
// turns +90 (E-52, manual ln 4786-4799), so the servo, whose C does not wrap, is sent 360, not 0; a later
// move that gives no turn stays where the last one ended; a -10 turn from there is 350.
TEST(RotaryUnwrap, CFollowsTheTurnsNotTheNormalisedPosition) {
  RotaryUnwrap unwrap;
  auto move = [&](double c, std::optional<double> travel, double x = 60) {
    Canon op;
    interp::RapidOp& r = op.Set<interp::RapidOp>();
    r.to.pos[interp::kX] = x;
    r.to.pos[interp::kC] = c;
    r.to.used = (1u << interp::kX) | (1u << interp::kC);
    if (travel) {
      r.to.travel[interp::kC] = *travel;
      r.to.travel_mask = 1u << interp::kC;
    }
    auto seg = ToSegment(op);
    unwrap.Apply(op, *seg);
    return seg->target()[interp::kC];
  };
  EXPECT_DOUBLE_EQ(move(0, std::nullopt), 0);
  EXPECT_DOUBLE_EQ(move(270, 270.0), 270);
  EXPECT_DOUBLE_EQ(move(0, 90.0), 360);
  EXPECT_DOUBLE_EQ(move(0, std::nullopt, 120), 360);  // X alone: C stays
  EXPECT_DOUBLE_EQ(move(350, -10.0), 350);
  EXPECT_DOUBLE_EQ(move(10, 20.0), 370);
  // A dialect that gives no turn is sent as it is.
  RotaryUnwrap plain;
  Canon op;
  interp::LinearOp& l = op.Set<interp::LinearOp>();
  l.to.pos[interp::kC] = 400;
  l.to.used = 1u << interp::kC;
  auto seg = ToSegment(op);
  plain.Apply(op, *seg);
  EXPECT_DOUBLE_EQ(seg->target()[interp::kC], 400);
}

}  // namespace
}  // namespace cell::station
