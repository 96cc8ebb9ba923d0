// The one reader of the KT-APL heading (NAM, UTL, UCY) that the interpreter, the program store and the
// scheduler share; their own tests cover only what each does with the result.
#include "cell/interp/ktapl.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "cell/interp/ktapl_statements.h"

namespace cell::interp {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::IsEmpty;
using Kind = HeadingNotice::Kind;

// Every warning as "line N: text", one a line.
std::string Joined(const Heading& md) {
  std::string s;
  for (const auto& w : md.notices) s += w.Format() + "\n";
  return s;
}

// The kValue warnings as "MNE LINE:COL: text" (what the scheduler turns into errors).
std::vector<std::string> ValueProblems(const Heading& md) {
  std::vector<std::string> out;
  for (const auto& w : md.notices) {
    if (w.kind == Kind::kValue)
      out.push_back(w.key + " " + std::to_string(w.line) + ":" + std::to_string(w.column) + ": " + w.text);
  }
  return out;
}

// KT-APL FMS heading (seed lines 4146-4150): %, (NAM) optional, (UTL) optional, (UCY) required.
TEST(KtaplMeta, FmsHeading) {
  Heading md = ReadKtaplHeading(
      "%\n(NAM, GEAR HOUSING)\n(UTL,12,T3,4567)\n(UCY,840)\nN10 G0 G90 XL1500 Y10. S400 F0 M3\n"
      "N20 (PAR, L25 = 123.456) ! set a parameter\nN30 M30\n",
      {.part_program = true});
  ASSERT_TRUE(md.name);
  EXPECT_EQ(*md.name, "GEAR HOUSING");
  EXPECT_THAT(md.tools, ElementsAre("12", "3", "4567"));
  ASSERT_TRUE(md.cycle_s);
  EXPECT_DOUBLE_EQ(*md.cycle_s, 840);
  EXPECT_THAT(md.notices, IsEmpty()) << Joined(md);

  // Tool numbers as written (T dropped, zeros kept), duplicates kept; CR LF line ends.
  md = ReadKtaplHeading("%\r\n(NAM,GH)\r\n(UTL,T12,0034,T7654321,12,t0033412)\r\n(UCY,600)\r\nN10G71\r\n");
  EXPECT_THAT(md.tools, ElementsAre("12", "0034", "7654321", "12", "0033412"));
  EXPECT_DOUBLE_EQ(md.cycle_s.value_or(0), 600);
  EXPECT_THAT(md.notices, IsEmpty()) << Joined(md);
}

TEST(KtaplMeta, EiaFormsCaseAndSeveralUtl) {
  Heading md = ReadKtaplHeading("%\n%UTL,1,2%\n%UCY,30.5%\nN1 G0 X1 F0\nN2 M30\n");
  EXPECT_FALSE(md.name);
  EXPECT_THAT(md.tools, ElementsAre("1", "2"));
  EXPECT_DOUBLE_EQ(md.cycle_s.value_or(0), 30.5);  // decimals unless whole_seconds
  EXPECT_THAT(md.notices, IsEmpty()) << Joined(md);

  // Several UTL blocks add up; consecutive ones are one tool list.
  md = ReadKtaplHeading("%\n%utl,1,2%\n(UTL, T3 )\n( ucy ,45)\n");
  EXPECT_THAT(md.tools, ElementsAre("1", "2", "3"));
  EXPECT_DOUBLE_EQ(md.cycle_s.value_or(-1), 45);
  EXPECT_THAT(md.notices, IsEmpty()) << Joined(md);
}

TEST(KtaplMeta, CommentsQuotesAndSeveralStatementsPerBlock) {
  Heading md = ReadKtaplHeading(
      "%\n! (UCY,5) is only a comment\nN10G0X1. ! (UTL,7)\n"
      "N20 (MSG,\"(UTL,8)\")\nN30 M30\n");
  EXPECT_FALSE(md.cycle_s);
  EXPECT_THAT(md.tools, IsEmpty());
  EXPECT_THAT(md.notices, IsEmpty()) << Joined(md);

  md = ReadKtaplHeading("%\n(UTL,9)(UCY,3)\n");
  EXPECT_THAT(md.tools, ElementsAre("9"));
  EXPECT_DOUBLE_EQ(md.cycle_s.value_or(0), 3);
  EXPECT_THAT(md.notices, IsEmpty()) << Joined(md);
}

TEST(KtaplMeta, PlacementProblemsAreOrderWarningsAndTheValuesAreRead) {
  // UCY before UTL, both after a numbered block.
  Heading md = ReadKtaplHeading("%\n(NAM,PUMP341)\nN10 G0 X0 F0\n(UCY,100)\n(UTL,5)\nN20 M30\n");
  EXPECT_EQ(md.name.value_or(""), "PUMP341");
  EXPECT_THAT(md.tools, ElementsAre("5"));
  EXPECT_DOUBLE_EQ(md.cycle_s.value_or(0), 100);
  EXPECT_EQ(Joined(md),
            "line 4: (UCY,...) must come in the heading, after %, (NAM,...) and (UTL,...)\n"
            "line 5: (UTL,...) must come right after % or (NAM,...) (FMS heading: %, NAM, UTL, UCY)\n");
  for (const auto& w : md.notices) EXPECT_EQ(w.kind, Kind::kOrder) << w.Format();
  EXPECT_EQ(md.notices[0].key, "UCY");
  EXPECT_EQ(md.notices[0].column, 1);

  // UCY not directly after UTL.
  md = ReadKtaplHeading("%\n(NAM,A)\n(UTL,5)\nN1 G0 X0 F0\n(UCY,100)\nN2 M30\n");
  EXPECT_EQ(Joined(md), "line 5: (UCY,...) must come directly after (UTL,...) (line 3)\n");

  // No % first; NAM after a numbered block and with an N number (also behind a block delete).
  md = ReadKtaplHeading("N5 G0 X0 F0\nN6 (NAM,LATE)\n(UTL,1)\n(UCY,2)\nN7 M30\n");
  EXPECT_EQ(md.name.value_or(""), "LATE");
  EXPECT_EQ(Joined(md),
            "line 2: (NAM,...) carries no sequence number\n"
            "line 2: (NAM,...) must come before the first numbered block\n"
            "the FMS heading must start with a % line (rewind stop) before NAM, UTL and UCY\n");
  EXPECT_EQ(md.notices.back().line, 0);
  EXPECT_THAT(Joined(ReadKtaplHeading("%\n/ N6 (NAM,X)\n")), HasSubstr("carries no sequence number"));

  // A program without UTL or UCY needs no %; a blank or comment line does not break the heading.
  EXPECT_THAT(ReadKtaplHeading("(NAM,PLAIN)\nN10 G0 X1. F0\nN20 M30\n").notices, IsEmpty());
  EXPECT_THAT(ReadKtaplHeading("\n%\n\n! heading\n(NAM,A)\n\n(UTL,1)\n! cycle\n(UCY,2)\n").notices,
              IsEmpty());
}

TEST(KtaplMeta, UtlWithoutUcyOnlyForPartPrograms) {
  const char* text = "%\n(UTL,1)\nN1 M30\n";
  EXPECT_THAT(ReadKtaplHeading(text).notices, IsEmpty());
  Heading md = ReadKtaplHeading(text, {.part_program = true});
  EXPECT_EQ(Joined(md),
            "line 2: (UTL,...) without (UCY,...): KT/FMS part programs need a cycle time right after the "
            "tool list\n");
  EXPECT_EQ(md.notices[0].kind, Kind::kOrder);
}

TEST(KtaplMeta, MalformedEntriesAndValuesAreLeftOut) {
  Heading md = ReadKtaplHeading("%\n(UTL,12,X7,12345678,T0033412)\n(UCY,ten)\nN1 M30\n");
  EXPECT_THAT(md.tools, ElementsAre("12", "0033412"));
  EXPECT_FALSE(md.cycle_s);
  EXPECT_THAT(
      ValueProblems(md),
      ElementsAre("UTL 2:9: UTL entry 'X7' is not a tool number (up to 7 digits, optionally prefixed with T)",
                  "UTL 2:12: UTL entry '12345678' is not a tool number (up to 7 digits, optionally prefixed "
                  "with T)",
                  "UCY 3:6: UCY value 'ten' is not a cycle time in seconds (up to 7 digits)"));

  md = ReadKtaplHeading("%\n(UCY,10)\n(UTL,12345678)\n");
  EXPECT_THAT(md.tools, IsEmpty());
  EXPECT_THAT(
      ValueProblems(md),
      ElementsAre("UTL 3:6: UTL entry '12345678' is not a tool number (up to 7 digits, optionally prefixed "
                  "with T)",
                  "UTL 3:6: (UTL,...) lists no tools"));
  EXPECT_THAT(Joined(md), HasSubstr("line 3: (UTL,...) must come right after % or (NAM,...)"));

  // Columns are those of the entry or value as written.
  EXPECT_THAT(ValueProblems(ReadKtaplHeading("%\n(UTL,T12345678)")),
              ElementsAre(HasSubstr("UTL 2:6: UTL entry 'T12345678'"), "UTL 2:6: (UTL,...) lists no tools"));
  EXPECT_THAT(ValueProblems(ReadKtaplHeading("(UTL,1,,2)")), ElementsAre(HasSubstr("UTL 1:8: UTL entry ''")));
  EXPECT_THAT(ValueProblems(ReadKtaplHeading("(UTL,)")), ElementsAre("UTL 1:6: (UTL,...) lists no tools"));
  EXPECT_THAT(ValueProblems(ReadKtaplHeading("(UCY,12345678)")),
              ElementsAre("UCY 1:6: UCY value '12345678' is not a cycle time in seconds (up to 7 digits)"));
  EXPECT_THAT(ValueProblems(ReadKtaplHeading("(UCY, 1,2)")),
              ElementsAre("UCY 1:7: UCY value '1,2' is not a cycle time in seconds (up to 7 digits)"));
}

TEST(KtaplMeta, SecondNamAndUcyAreIgnored) {
  Heading md = ReadKtaplHeading("%\n(NAM,A)\n(NAM,B)\n(UCY,1)\n(UCY,2)\n");
  EXPECT_EQ(md.name.value_or(""), "A");
  EXPECT_DOUBLE_EQ(md.cycle_s.value_or(0), 1);
  EXPECT_THAT(ValueProblems(md), ElementsAre("NAM 3:1: second (NAM,...) ignored (first on line 2)",
                                             "UCY 5:1: second (UCY,...) ignored (first on line 4)"));
}

TEST(KtaplMeta, BrokenStatements) {
  EXPECT_THAT(ValueProblems(ReadKtaplHeading("(UTL,1")),
              ElementsAre("UTL 1:1: (UTL,...) without closing ')'"));
  EXPECT_THAT(ValueProblems(ReadKtaplHeading("N1 (MSG,A)%UCY,5")),
              ElementsAre("UCY 1:11: (UCY,...) without closing '%'"));
  EXPECT_THAT(ValueProblems(ReadKtaplHeading("(UTL)\n(UCY 5)\n(UTLX,1)")),
              ElementsAre("UTL 1:5: expected ',' after UTL", "UCY 2:6: expected ',' after UCY",
                          "UTL 3:5: expected ',' after UTL"));
  // Nothing is read from them.
  Heading md = ReadKtaplHeading("%\n(UTL 5)\n(UCY,3\n");
  EXPECT_THAT(md.tools, IsEmpty());
  EXPECT_FALSE(md.cycle_s);
}

TEST(KtaplMeta, NameRules) {
  EXPECT_FALSE(ReadKtaplHeading("%\n(NAM, )\n").name);
  EXPECT_THAT(ValueProblems(ReadKtaplHeading("%\n(NAM, )\n")),
              ElementsAre("NAM 2:7: (NAM,...) has an empty name"));
  Heading md = ReadKtaplHeading("%\n(NAM," + std::string(33, 'A') + ")\n(NAM,X)\n");
  EXPECT_EQ(md.name.value_or(""), std::string(33, 'A'));  // kept whole; the store's name rules decide
  EXPECT_THAT(Joined(md),
              HasSubstr("line 2: NAM name '" + std::string(33, 'A') + "' is longer than 32 characters"));
  EXPECT_THAT(Joined(ReadKtaplHeading("%\n(NAM,PUMP-341)\n")),
              HasSubstr("NAM name 'PUMP-341' should have only letters, digits and spaces"));
}

TEST(KtaplMeta, WholeSecondsOption) {
  Heading md = ReadKtaplHeading("%\n(UCY,1.5)\n", {.whole_seconds = true});
  EXPECT_FALSE(md.cycle_s);
  EXPECT_THAT(ValueProblems(md), ElementsAre("UCY 2:6: UCY value '1.5' is not whole seconds (UCY,nnnnnnn)"));
  EXPECT_DOUBLE_EQ(ReadKtaplHeading("%\n(UCY,1.5)\n").cycle_s.value_or(0), 1.5);
  EXPECT_DOUBLE_EQ(ReadKtaplHeading("%\n(UCY,1234567)\n", {.whole_seconds = true}).cycle_s.value_or(0),
                   1234567);
}

TEST(KtaplStatements, FindStatementsReportsWhereAnUnclosedStatementStarts) {
  std::string error;
  size_t at = 0;
  auto sts = ktapl::FindStatements("N1 (MSG,\"a)\")(PAR,L1=(2)) ( utl", &error, &at);
  ASSERT_EQ(sts.size(), 2u);
  EXPECT_EQ(sts[0].mnemonic, "MSG");
  EXPECT_EQ(sts[1].body, "L1=(2)");
  EXPECT_EQ(error, "MISSING CONTROL-IN CHARACTER");
  EXPECT_EQ(at, 26u);
}

}  // namespace
}  // namespace cell::interp
