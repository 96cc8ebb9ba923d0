// Tip position codes of lathe tools (ISO/DIN layout, X up, Z to the right).
#include "cell/interp/geometry/tool_nose.h"

#include <gtest/gtest.h>

namespace cell::interp::geom {
namespace {

TEST(ToolNose, CodesWalkRoundTheNoseCounterClockwise) {
  // 3 8 4 5 1 6 2 7 is the order the EMCO manual's table of tool shapes lists them (ln 2544-2551): starting
  // at the bottom left and going round counter-clockwise.
  const int order[8] = {3, 8, 4, 5, 1, 6, 2, 7};
  const Vec2 want[8] = {{-1, -1}, {0, -1}, {1, -1}, {1, 0}, {1, 1}, {0, 1}, {-1, 1}, {-1, 0}};
  for (int i = 0; i < 8; ++i) {
    Vec2 v = NoseTipOffset(order[i], 0.4);
    EXPECT_DOUBLE_EQ(v.x, want[i].x * 0.4) << order[i];
    EXPECT_DOUBLE_EQ(v.y, want[i].y * 0.4) << order[i];
  }
}

TEST(ToolNose, CentreCodesAndOutOfRangeHaveNoOffset) {
  for (int tip : {0, 9, -1, 10}) {
    Vec2 v = NoseTipOffset(tip, 0.8);
    EXPECT_EQ(v.x, 0) << tip;
    EXPECT_EQ(v.y, 0) << tip;
  }
}

}  // namespace
}  // namespace cell::interp::geom
