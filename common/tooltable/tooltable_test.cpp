#include "cell/tooltable/tooltable.h"

#include <gtest/gtest.h>

#include "cell/error/error.h"

namespace cell::tooltable {
namespace {

std::string ErrorOf(std::string_view text) {
  try {
    ParseTld(text, "tools.tld");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// Manual example, seed line 4063: N12 (TLD,S12T33412CP.02D-.25L345H5.9)
TEST(TldParse, PrimaryDataSetFromManual) {
  auto sts = ParseTld("N12 (TLD,S12T33412CP.02D-.25L345H5.9)\n");
  ASSERT_EQ(sts.size(), 1u);
  ASSERT_TRUE(sts[0].entry);
  const ToolEntry& e = *sts[0].entry;
  EXPECT_EQ(e.tool, "33412");
  EXPECT_EQ(e.socket, 12);
  EXPECT_TRUE(e.check);
  EXPECT_FALSE(e.manual);
  EXPECT_DOUBLE_EQ(e.length, 0.02);
  EXPECT_DOUBLE_EQ(e.diameter, -0.25);
  EXPECT_EQ(e.life_left_min, 3 * 60 + 45);  // L345 read as hhmm right-aligned (catalogue 13.3 #23)
  EXPECT_DOUBLE_EQ(e.max_hp, 5.9);
  EXPECT_EQ(sts[0].line, 1);
  EXPECT_EQ(sts[0].column, 5);
}

// Seed line 4052: "L2241 = 22 Hours and 41 Minutes".
TEST(TldParse, LifeIsHoursAndMinutes) {
  auto sts = ParseTld("(TLD,T5L2241)");
  EXPECT_EQ(sts.at(0).entry->life_left_min, 22 * 60 + 41);
  EXPECT_NE(ErrorOf("(TLD,T5L2260)").find("minutes"), std::string::npos);
  EXPECT_NE(ErrorOf("(TLD,T5L9960)").find("tools.tld:1:"), std::string::npos);
}

// Seed line 4069: suffix data set 5 of the same tool.
TEST(TldParse, SuffixToolNumberKeepsDecimal) {
  auto sts = ParseTld("N13(TLD,S12T33412.5CP.02D-.25L345H5.9)");
  EXPECT_EQ(sts.at(0).entry->tool, "33412.5");
  EXPECT_NE(ErrorOf("(TLD,T33412.8)").find("suffix"), std::string::npos);  // suffix 1-7 only
}

// Seed line 4097: process compensation for pallet 12.
TEST(TldParse, ProcessCompensation) {
  auto sts = ParseTld("N14(TLD,T33412.5W12P.0003D-.0004)");
  ASSERT_TRUE(sts.at(0).process);
  EXPECT_FALSE(sts[0].entry);
  EXPECT_EQ(sts[0].process->tool, "33412.5");
  EXPECT_EQ(sts[0].process->pallet, 12);
  EXPECT_DOUBLE_EQ(sts[0].process->length, 0.0003);
  EXPECT_DOUBLE_EQ(sts[0].process->diameter, -0.0004);
  // Only T, W, P and D are allowed in a process compensation (seed lines 4085-4088).
  EXPECT_NE(ErrorOf("(TLD,S3T1W12P.1)").find("only T, W, P and D"), std::string::npos);
  // Process values are limited to +-9.999 mm (seed line 4089).
  EXPECT_NE(ErrorOf("(TLD,T1W12P10.)").find("outside"), std::string::npos);
  // Coded pallets stop at 127.
  ParseOptions coded;
  coded.max_pallet = 127;
  EXPECT_THROW(ParseTld("(TLD,T1W128P.1)", "x", coded), Error);
  EXPECT_NO_THROW(ParseTld("(TLD,T1W128P.1)"));
}

TEST(TldParse, BriefFormAndFlags) {
  auto sts = ParseTld("%\n(NAM,TOOLS)\n(TLD,S1T1001P100.D10.)\n(tld,s2t0042BE)\n");
  ASSERT_EQ(sts.size(), 2u);
  EXPECT_EQ(sts[0].line, 3);
  EXPECT_EQ(sts[0].entry->tool, "1001");
  EXPECT_DOUBLE_EQ(sts[0].entry->length, 100.0);
  EXPECT_DOUBLE_EQ(sts[0].entry->diameter, 10.0);
  EXPECT_EQ(sts[1].entry->tool, "42");
  EXPECT_TRUE(sts[1].entry->broken);
  EXPECT_TRUE(sts[1].entry->worn);
}

TEST(TldParse, EiaFormAndInchUnits) {
  auto sts = ParseTld("N1G70\nN2%TLD,S4T7P1.D-.5%\nN3G71\nN4(TLD,S5T8P1.)\n");
  ASSERT_EQ(sts.size(), 2u);
  EXPECT_DOUBLE_EQ(sts[0].entry->length, 25.4);
  EXPECT_DOUBLE_EQ(sts[0].entry->diameter, -12.7);
  EXPECT_DOUBLE_EQ(sts[1].entry->length, 1.0);
}

TEST(TldParse, ErrorsCarryLineAndColumn) {
  EXPECT_EQ(ErrorOf("\n(TLD,S1T1X5)"), "tools.tld:2:10: error: unknown TLD letter 'X'");
  EXPECT_EQ(ErrorOf("(TLD,S1P1.)"), "tools.tld:1:6: error: TLD without a T tool number");
  EXPECT_EQ(ErrorOf("(TLD,S1T12345678)"),
            "tools.tld:1:9: error: bad tool number '12345678' (1-7 digits expected)");
  EXPECT_EQ(ErrorOf("(TLD,T1T2)"), "tools.tld:1:8: error: TLD letter T given twice");
  EXPECT_EQ(ErrorOf("(TLD,T1"), "tools.tld:1:1: error: TLD statement without closing ')'");
  EXPECT_EQ(ErrorOf("(TLD,T1P)"), "tools.tld:1:9: error: TLD P needs a number");
  EXPECT_EQ(ErrorOf("(TLD,S1MT1)").substr(0, 14), "tools.tld:1:8:");
  EXPECT_NE(ErrorOf("(TLD,T1P1000.)").find("outside"), std::string::npos);  // +-999.999 mm
  EXPECT_NE(ErrorOf("(TLD,T1H100)").find("0-99.9"), std::string::npos);
}

TEST(ToolNumber, Normalize) {
  EXPECT_EQ(NormalizeToolNumber("T0012"), "12");
  EXPECT_EQ(NormalizeToolNumber("1234567"), "1234567");
  EXPECT_EQ(NormalizeToolNumber("33412.5"), "33412.5");
  EXPECT_EQ(NormalizeToolNumber("t7.0"), "7");
  EXPECT_THROW(NormalizeToolNumber("12345678"), Error);
  EXPECT_THROW(NormalizeToolNumber("T"), Error);
  EXPECT_THROW(NormalizeToolNumber("12A"), Error);
  EXPECT_EQ(BaseTool("33412.5"), "33412");
}

TEST(ToolTableMerge, AddsAndReplacesByToolNumber) {
  ToolTable t({ToolEntry{.tool = "1", .socket = 1, .length = 50}});
  t.Merge(ParseTld("(TLD,S1T1P60.)\n(TLD,S2T2P70.)"));
  ASSERT_EQ(t.entries().size(), 2u);
  EXPECT_DOUBLE_EQ(t.Find("1")->length, 60);
  EXPECT_EQ(t.Find("2")->socket, 2);
  EXPECT_TRUE(t.Holds("2"));
  EXPECT_FALSE(t.Holds("3"));
}

TEST(ToolTableMerge, SuffixSetHoldsBaseToolButBrokenDoesNot) {
  ToolTable t;
  t.Merge(ParseTld("(TLD,S1T33412.5)\n(TLD,S2T9B)"));
  EXPECT_TRUE(t.Holds("33412"));
  EXPECT_TRUE(t.Holds("33412.5"));
  EXPECT_FALSE(t.Holds("33412.4"));
  EXPECT_FALSE(t.Holds("9"));  // broken
}

TEST(ToolTableMerge, ProcessCompNeedsDataSetFirst) {
  ToolTable t;
  EXPECT_THROW(t.Merge(ParseTld("(TLD,T5W3P.1)")), Error);
  EXPECT_TRUE(t.entries().empty());
  t.Merge(ParseTld("(TLD,S1T5)\n(TLD,T5W3P.1)\n(TLD,T5W3P.2)"));
  ASSERT_EQ(t.process_comps().size(), 1u);
  EXPECT_DOUBLE_EQ(t.process_comps()[0].length, 0.2);
}

}  // namespace
}  // namespace cell::tooltable
