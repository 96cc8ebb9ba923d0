// The EMCO tool data file (X/Z/R/L per correction).
#include "tool_table.h"

#include <gtest/gtest.h>

#include "cell/error/error.h"

namespace cell::interp::emco {
namespace {

TEST(ToolData, CorrectionsWithTurretPositionsAndUnits) {
  tooltable::ToolTable t = ParseToolData(
      "% tool data\n(EDIT TOOL DATA)\nT0303 X-12.500 Z-30.250 R0.400 L3\n07 X0 Z-41500 R.8 L2\n", "t.tools",
      {});
  ASSERT_EQ(t.entries().size(), 2u);
  const tooltable::ToolEntry* a = t.Find("3");
  ASSERT_NE(a, nullptr);
  EXPECT_EQ(a->socket, 3);
  EXPECT_DOUBLE_EQ(a->x_offset, -25.0);  // X is a radius; the model keeps the diameter
  EXPECT_DOUBLE_EQ(a->z_offset, -30.25);
  EXPECT_DOUBLE_EQ(a->nose_radius, 0.4);
  EXPECT_EQ(a->tip, 3);
  const tooltable::ToolEntry* b = t.Find("7");
  ASSERT_NE(b, nullptr);
  EXPECT_EQ(b->socket, 0);
  EXPECT_DOUBLE_EQ(b->z_offset, -41.5);  // no decimal point: um, as on tape
  EXPECT_DOUBLE_EQ(b->nose_radius, 0.8);
  EXPECT_EQ(b->tip, 2);
}

TEST(ToolData, LoadChangesOnlyWhatItNamesAndRoundTrips) {
  tooltable::ToolEntry kept;
  kept.tool = "5";
  kept.socket = 5;
  kept.life_left_min = 30;
  tooltable::ToolTable base({kept});
  tooltable::ToolTable t = ParseToolData("05 Z-10. R0.2 L3\n", "t", base);
  const tooltable::ToolEntry* e = t.Find("5");
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->socket, 5);
  EXPECT_DOUBLE_EQ(e->life_left_min, 30);
  EXPECT_DOUBLE_EQ(e->z_offset, -10);
  std::string text = FormatToolData(t);
  EXPECT_EQ(text, "T0505 X0.000 Z-10.000 R0.200 L3\n");
  EXPECT_EQ(ParseToolData(text, "again", {}).entries()[0].z_offset, -10);
}

TEST(ToolData, ErrorsNameTheLineAndColumn) {
  auto err = [](const std::string& text) {
    try {
      ParseToolData(text, "bad.tools", {});
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(err("01 X1. Q2\n"), "bad.tools:1:8: error: unexpected 'Q' (tool data are X, Z, R and L)");
  EXPECT_EQ(err("\n100 X1.\n"), "bad.tools:2:1: error: [690] INVALID INDEX ENTERED (correction 100: 01-99)");
  EXPECT_EQ(err("T0001 X1.\n"),
            "bad.tools:1:1: error: [430] INVALID T-WORD (T0001: a correction needs its tool number)");
  EXPECT_EQ(err("01 L12\n"), "bad.tools:1:4: error: L is the tip position code 0-9");
  EXPECT_EQ(err("01 R-1.\n"), "bad.tools:1:4: error: R (nose radius) may not be negative");
  EXPECT_EQ(err("(nothing)\n"),
            "bad.tools: no tool data found (an EMCO tool table is lines of <correction> X.. Z.. R.. L..)");
}

}  // namespace
}  // namespace cell::interp::emco
