#include "cell/scheduler/program_source.h"

#include <gtest/gtest.h>

#include "cell/error/error.h"

namespace cell::scheduler {
namespace {

// The heading itself is read by the dialect (KT-APL: heading_test); these are the scheduler's rules on top
// of it.
std::string ErrorOf(std::string_view text) {
  try {
    ReadProgramMeta(text, "ktapl", "P1");
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kInvalidArgument);
    return e.what();
  }
  return "";
}

TEST(ProgramMeta, ToolsNormalisedAndDeduplicated) {
  auto m = ReadProgramMeta("%\n(NAM,GEAR HOUSING)\n(UTL,T12,0034,T7654321,12)\n(UTL,0)\n(UCY,600)\nN10G71\n",
                           "ktapl", "GH");
  EXPECT_EQ(m.dialect, "ktapl");
  EXPECT_EQ(m.name, "GH");
  EXPECT_EQ(m.tools, (std::vector<std::string>{"12", "34", "7654321", "0"}));
  ASSERT_TRUE(m.ucy_s);
  EXPECT_EQ(*m.ucy_s, 600);
  EXPECT_FALSE(ReadProgramMeta("%\n(UTL,1)\nN10G0X1.\n", "ktapl", "X").ucy_s);
  // Another dialect's heading has no UTL or UCY: no tools, no backlog; an unknown dialect is an error.
  auto ok = ReadProgramMeta("O1000\nG00 X10\nM02\n", "okuma", "LATHE.MIN");
  EXPECT_EQ(ok.dialect, "okuma");
  EXPECT_TRUE(ok.tools.empty());
  EXPECT_FALSE(ok.ucy_s);
  EXPECT_THROW(ReadProgramMeta("(UCY,5)", "", "NODIALECT"), Error);
}

TEST(ProgramMeta, MalformedUtlOrUcyIsAnErrorWithNameLineAndColumn) {
  EXPECT_EQ(ErrorOf("%\n(UTL,T12345678)"),
            "P1:2:6: error: UTL entry 'T12345678' is not a tool number (up to 7 digits, optionally prefixed "
            "with T)");
  EXPECT_EQ(ErrorOf("(UTL,1,,2)"),
            "P1:1:8: error: UTL entry '' is not a tool number (up to 7 digits, optionally prefixed with T)");
  EXPECT_EQ(ErrorOf("(UTL,)"), "P1:1:6: error: (UTL,...) lists no tools");
  EXPECT_EQ(ErrorOf("(UCY,1.5)"), "P1:1:6: error: UCY value '1.5' is not whole seconds (UCY,nnnnnnn)");
  EXPECT_EQ(ErrorOf("(UCY,12345678)"),
            "P1:1:6: error: UCY value '12345678' is not a cycle time in seconds (up to 7 digits)");
  EXPECT_EQ(ErrorOf("(UCY,1)\n(UCY,2)"), "P1:2:1: error: second (UCY,...) ignored (first on line 1)");
  EXPECT_EQ(ErrorOf("(UTL,1"), "P1:1:1: error: (UTL,...) without closing ')'");
  EXPECT_EQ(ErrorOf("(UCY)"), "P1:1:5: error: expected ',' after UCY");
  // Heading order and NAM are not the scheduler's business.
  EXPECT_EQ(ErrorOf("N1 G0 X0\n(UCY,5)\n(UTL,1)\n(NAM,)\n(NAM,A)"), "");
}

TEST(ProgramSources, MemoryAndText) {
  MemoryProgramSource mem;
  mem.Put("A", "(UCY,10)", "ktapl");
  EXPECT_EQ(mem.Lookup("A")->ucy_s.value_or(0), 10);
  EXPECT_FALSE(mem.Lookup("B"));
  TextProgramSource text([](std::string_view n) -> std::optional<StoredProgram> {
    if (n == "Q") return StoredProgram{"(UTL,9)(UCY,3)", "ktapl", ""};
    if (n == "BAD") return StoredProgram{"(UCY,x)", "ktapl", ""};
    if (n == "PLATE") return StoredProgram{"[[plane]]\n", "", "part_model"};
    return std::nullopt;
  });
  // A part model: no heading is read (it has no dialect), no tools, no cycle time.
  EXPECT_TRUE(text.Lookup("PLATE")->part_model);
  EXPECT_TRUE(text.Lookup("PLATE")->tools.empty());
  EXPECT_FALSE(text.Lookup("PLATE")->ucy_s);
  EXPECT_FALSE(text.Lookup("Q")->part_model);
  EXPECT_EQ(text.Lookup("Q")->tools, std::vector<std::string>{"9"});
  EXPECT_EQ(text.Lookup("Q")->ucy_s.value_or(0), 3);
  EXPECT_FALSE(text.Lookup("R"));
  EXPECT_THROW(text.Lookup("BAD"), Error);
}

}  // namespace
}  // namespace cell::scheduler
