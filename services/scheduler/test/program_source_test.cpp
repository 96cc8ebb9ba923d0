#include "cell/scheduler/program_source.h"

#include <gtest/gtest.h>

#include "cell/error/error.h"

namespace cell::scheduler {
namespace {

std::string ErrorOf(std::string_view text) {
  try {
    ExtractKtaplMeta(text, "P1");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// KT-APL FMS heading (seed lines 4146-4150): %, (NAM) optional, (UTL) optional, (UCY) required.
TEST(KtaplMeta, ReadsFmsHeading) {
  auto m = ExtractKtaplMeta("%\n(NAM,GEAR HOUSING)\n(UTL,T12,0034,T7654321,12)\n(UCY,600)\nN10G71\n", "GH");
  EXPECT_EQ(m.name, "GH");
  EXPECT_EQ(m.tools, (std::vector<std::string>{"12", "34", "7654321"}));
  ASSERT_TRUE(m.ucy_s);
  EXPECT_EQ(*m.ucy_s, 600);
}

TEST(KtaplMeta, EiaFormsCaseAndSeveralUtl) {
  auto m = ExtractKtaplMeta("%\n%utl,1,2%\n(UTL, T3 )\n%UCY,45%\n", "X");
  EXPECT_EQ(m.tools, (std::vector<std::string>{"1", "2", "3"}));
  EXPECT_EQ(m.ucy_s.value_or(-1), 45);
}

TEST(KtaplMeta, UcyAbsentAndCommentsIgnored) {
  auto m = ExtractKtaplMeta("%\n! (UCY,5) is only a comment\nN10G0X1.\n", "X");
  EXPECT_FALSE(m.ucy_s);
  EXPECT_TRUE(m.tools.empty());
}

TEST(KtaplMeta, ErrorsNameLineAndColumn) {
  EXPECT_EQ(ErrorOf("%\n(UTL,T12345678)"),
            "P1:2:6: error: UTL tool number must be up to 7 digits, optionally prefixed with T: 'T12345678'");
  EXPECT_EQ(ErrorOf("(UTL,1,,2)"),
            "P1:1:8: error: UTL tool number must be up to 7 digits, optionally prefixed with T: ''");
  EXPECT_EQ(ErrorOf("(UCY,1.5)"), "P1:1:6: error: UCY needs whole seconds of up to 7 digits (UCY,nnnnnnn)");
  EXPECT_EQ(ErrorOf("(UCY,12345678)"),
            "P1:1:6: error: UCY needs whole seconds of up to 7 digits (UCY,nnnnnnn)");
  EXPECT_EQ(ErrorOf("(UCY,1)\n(UCY,2)"), "P1:2:1: error: second UCY statement");
  EXPECT_EQ(ErrorOf("(UCY,1,2)"), "P1:1:8: error: UCY takes one value: (UCY,seconds)");
  EXPECT_EQ(ErrorOf("(UTL,1"), "P1:1:1: error: UTL statement without closing ')'");
}

TEST(ProgramSources, MemoryAndText) {
  MemoryProgramSource mem;
  mem.Put("A", "(UCY,10)");
  EXPECT_EQ(mem.Lookup("A")->ucy_s.value_or(0), 10);
  EXPECT_FALSE(mem.Lookup("B"));
  TextProgramSource text([](std::string_view n) -> std::optional<std::string> {
    if (n == "Q") return std::string("(UTL,9)(UCY,3)");
    return std::nullopt;
  });
  EXPECT_EQ(text.Lookup("Q")->tools, std::vector<std::string>{"9"});
  EXPECT_FALSE(text.Lookup("R"));
}

}  // namespace
}  // namespace cell::scheduler
