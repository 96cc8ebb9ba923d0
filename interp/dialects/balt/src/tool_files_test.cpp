// The MP3 files as text: FI1COR (ln 8305-8331), GE1TOL (ln 8450-8475), FILEOR.
#include "tool_files.h"

#include <gtest/gtest.h>

namespace cell::interp::balt {
namespace {

// ln 8305-8316: the tape image, one record per line, the first after '%'.
TEST(ToolFiles, OffsetsTapeImage) {
  auto t = ParseOffsets("% 1 Z.0K.0\n  2 Z200.0K25.0\n%\n", {}, true);
  ASSERT_EQ(t.entries().size(), 2u);
  EXPECT_EQ(t.entries()[1].tool, "2");
  EXPECT_DOUBLE_EQ(t.entries()[1].length, 200);
  EXPECT_DOUBLE_EQ(t.entries()[1].diameter, 25);
  EXPECT_EQ(t.entries()[1].length_axis, 'Z');
}

// ln 8239-8284: the keyboard echo form, a length on X, the alternative unit, c/m wear values.
TEST(ToolFiles, OffsetsOtherForms) {
  auto t = ParseOffsets("[TOOL COMP] 1, Z-2.15,K20\n3 X50 K10\n-4 Z1 K.5\n5 Z.0K.0c.0m.0c.0m.0\n", {}, true);
  ASSERT_EQ(t.entries().size(), 4u);
  EXPECT_DOUBLE_EQ(t.Find("1")->length, -2.15);
  EXPECT_EQ(t.Find("3")->length_axis, 'X');
  EXPECT_DOUBLE_EQ(t.Find("4")->length, 25.4);
  EXPECT_DOUBLE_EQ(t.Find("4")->diameter, 12.7);
}

TEST(ToolFiles, OffsetsNeedLengthAndK) {
  try {
    (void)ParseOffsets("1 Z5\n", {}, true);
    FAIL();
  } catch (const FileError& e) {
    EXPECT_EQ(e.code, 71);
    EXPECT_EQ(e.line, 1);
  }
  EXPECT_THROW((void)ParseOffsets("G1 X10\n", {}, true), FileError);
}

// ln 8475: VTU,2,T12,[TOOL COMP]12,t60,t2,t60,B
TEST(ToolFiles, ToolLife) {
  auto f = ParseToolLife("VTU,2,T12,[TOOL COMP]12,t60,t2,t60,B\nVTU,12,T12,[TOOL COMP] 12,t60,t2,t60,B\n");
  ASSERT_EQ(f.tools.size(), 2u);
  EXPECT_EQ(f.tools[2].alt_tool, 12);
  EXPECT_EQ(f.tools[2].alt_offset, 12);
  EXPECT_EQ(f.tools[2].status, 'B');
  auto again = ParseToolLife(f.Format());
  EXPECT_EQ(again.tools[12].left_min, 60);
  EXPECT_THROW((void)ParseToolLife("VTU,2,T12\n"), FileError);
}

TEST(ToolFiles, Origins) {
  auto o = ParseOrigins("%\n0 X0 Y0 Z0\n1 X100 Y50\n-2 X1\n%\n", true);
  ASSERT_EQ(o.size(), 3u);
  EXPECT_DOUBLE_EQ(o[1].v[kY], 50);
  EXPECT_DOUBLE_EQ(o[2].v[kX], 25.4);
  EXPECT_EQ(o[1].axes, (1u << kX) | (1u << kY));
  auto back = ParseOrigins(FormatOrigins(o), true);
  EXPECT_DOUBLE_EQ(back[2].v[kX], 25.4);
  EXPECT_THROW((void)ParseOrigins("1 X1 Y1 Z1 A1\n", true), FileError);
}

}  // namespace
// FI1RAN (ln 8541-8548): the manual's records; a special tool on exactly 3 consecutive pockets; FILMS4 71
// for a record that is not 4 digits, a tool in two places, a special tool on 2 or 4 pockets.
TEST(ToolFiles, RandomToolFile) {
  RandomToolFile f =
      ParseRandomTools("0001-----\n0002-----\n9003-----\n9003-----\n9003-----\n0000\n0004-----\n");
  EXPECT_EQ(f.pocket, (std::map<int, int>{{1, 1}, {2, 2}, {3, 3}, {4, 7}}));
  EXPECT_TRUE(f.special.at(3));
  EXPECT_FALSE(f.special.at(4));
  auto code_line = [](const std::string& text) {
    try {
      ParseRandomTools(text);
    } catch (const FileError& e) {
      return std::make_pair(e.code, e.line);
    }
    return std::make_pair(0, 0);
  };
  EXPECT_EQ(code_line("0001\n12\n"), std::make_pair(71, 2));
  EXPECT_EQ(code_line("0001\n00012\n"), std::make_pair(71, 2));
  EXPECT_EQ(code_line("0001\n0002\n0001\n"), std::make_pair(71, 3));
  EXPECT_EQ(code_line("9003\n9003\n0001\n"), std::make_pair(71, 1));
  EXPECT_EQ(code_line("9003\n9003\n9003\n9003\n"), std::make_pair(71, 4));
  EXPECT_EQ(code_line("9003\n9003\n"), std::make_pair(71, 1));
}

}  // namespace cell::interp::balt
