// Okuma tool data in its own form (the manual's VTOFX/VTOFZ/VNSRX/VNSRZ variables).
#include "tool_data.h"

#include <gtest/gtest.h>

#include "cell/error/error.h"

namespace cell::interp::okuma {
namespace {

TEST(OkumaToolData, ParsesAssignmentsIntoEntriesByNumber) {
  auto t = ParseToolDataText(
      "%\n(OK01 TOOLS)\nVTOFX[1]=0.5 VTOFZ[1]=-0.25 VNSRX[1]=0.8 VNSRZ[1]=0.8 VNSRP[1]=3\n"
      "VTOFZ[5]=2.634\nVNSRZ[4]=0.8\n",
      "t.tools", {});
  ASSERT_NE(t.Find("1"), nullptr);
  EXPECT_DOUBLE_EQ(t.Find("1")->x_offset, 0.5);
  EXPECT_DOUBLE_EQ(t.Find("1")->z_offset, -0.25);
  EXPECT_DOUBLE_EQ(t.Find("1")->nose_radius, 0.8);
  EXPECT_EQ(t.Find("1")->tip, 3);
  EXPECT_EQ(t.Find("1")->socket, 1);
  EXPECT_DOUBLE_EQ(t.Find("5")->z_offset, 2.634);   // ln 7731
  EXPECT_DOUBLE_EQ(t.Find("4")->nose_radius, 0.8);  // ln 7743
  auto again = ParseToolDataText(ToolDataText(t), "round", {});
  EXPECT_EQ(again, t);
}

TEST(OkumaToolData, RejectsAnythingElseWithALocation) {
  try {
    ParseToolDataText("VTOFX[1]=1\nG00 X10\n", "bad.tools", {});
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("bad.tools:2:1: error:", 0), 0u) << e.what();
  }
  EXPECT_THROW(ParseToolDataText("(nothing)\n", "empty", {}), Error);
  EXPECT_THROW(ParseToolDataText("VTOFX[97]=1\n", "range", {}), Error);
  EXPECT_THROW(ParseToolDataText("VNSRP[1]=12\n", "tip", {}), Error);
}

}  // namespace
}  // namespace cell::interp::okuma
