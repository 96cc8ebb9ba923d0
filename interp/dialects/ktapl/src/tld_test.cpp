// The one TLD parser (manual ln 3975-4097), through the dialect's tool-table form (cellctl tools load,
// cell-interp --tools) and through a program's (TLD,...).
#include <gtest/gtest.h>

#include "cell/error/error.h"
#include "cell/interp/ktapl.h"
#include "tld.h"

namespace cell::interp {
namespace {

tooltable::ToolTable Load(std::string_view text, const tooltable::ToolTable& base = {}) {
  return KtaplDialect().ParseToolTable(text, "tools.tld", base);
}

std::string ErrorOf(std::string_view text) {
  try {
    Load(text);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// ln 4063: N12 (TLD,S12T33412CP.02D-.25L345H5.9)
TEST(Tld, PrimaryDataSetFromManual) {
  auto t = Load("G71\nN12 (TLD,S12T33412CP.02D-.25L345H5.9)\n");
  ASSERT_EQ(t.entries().size(), 1u);
  const tooltable::ToolEntry& e = t.entries()[0];
  EXPECT_EQ(e.tool, "33412");
  EXPECT_EQ(e.socket, 12);
  EXPECT_TRUE(e.check);
  EXPECT_FALSE(e.manual);
  EXPECT_DOUBLE_EQ(e.length, 0.02);
  EXPECT_DOUBLE_EQ(e.diameter, -0.25);             // compensations are signed (E45)
  EXPECT_DOUBLE_EQ(e.life_left_min, 3 * 60 + 45);  // L345 read as hhmm right-aligned (catalogue 13.3 #23)
  EXPECT_DOUBLE_EQ(e.max_hp, 5.9);
}

// ln 4052: "L2241 = 22 Hours and 41 Minutes".
TEST(Tld, LifeIsHoursAndMinutes) {
  EXPECT_DOUBLE_EQ(Load("(TLD,T5L2241)").entries()[0].life_left_min, 22 * 60 + 41);
  EXPECT_NE(ErrorOf("(TLD,T5L2260)").find("MINUTES"), std::string::npos);
  EXPECT_NE(ErrorOf("(TLD,T5L9960)").find("tools.tld:1:"), std::string::npos);
}

// ln 4069 suffix set 5, ln 4097 the process compensation for pallet 12 (inch: G70 is the default of the
// example's program).
TEST(Tld, SuffixAndProcessCompensation) {
  auto t = Load(
      "G70\n(TLD,S12T33412CP.02D-.25L345H5.9)\nN13(TLD,S12T33412.5CP.02D-.25L345H5.9)\n"
      "N14(TLD,T33412.5W12P.0003D-.0004)\n");
  ASSERT_EQ(t.entries().size(), 2u);
  EXPECT_EQ(t.entries()[1].tool, "33412.5");
  EXPECT_NEAR(t.entries()[0].length, 0.02 * 25.4, 1e-9);
  ASSERT_EQ(t.process_comps().size(), 1u);
  EXPECT_EQ(t.process_comps()[0].tool, "33412.5");
  EXPECT_EQ(t.process_comps()[0].pallet, 12);
  EXPECT_NEAR(t.process_comps()[0].length, 0.0003 * 25.4, 1e-12);
  EXPECT_NEAR(t.process_comps()[0].diameter, -0.0004 * 25.4, 1e-12);
  EXPECT_NE(ErrorOf("(TLD,T33412.8)").find("suffix"), std::string::npos);  // suffix 1-7 only
  // ln 4073: the data set first.
  EXPECT_NE(ErrorOf("(TLD,T99W12P.0003)").find("PRIMARY OR SUFFIX"), std::string::npos);
  // ln 4085-4089: only T, W, P and D; +-9.999 mm.
  EXPECT_NE(ErrorOf("(TLD,T1)\n(TLD,T1W3S4P.1)").find("ONLY T, W, P AND D"), std::string::npos);
  EXPECT_NE(ErrorOf("G71\n(TLD,T1)\n(TLD,T1W3P10.)").find("OUTSIDE"), std::string::npos);
  // W 1-255, or 1-127 on coded pallets (ln 4081-4083).
  EXPECT_NE(ErrorOf("(TLD,T1)\n(TLD,T1W256P.1)").find("OUTSIDE 1-255"), std::string::npos);
}

TEST(Tld, FormsFlagsUnitsAndImpliedDecimals) {
  auto t = Load(
      "%\n(NAM,TOOLS)\n(TLD,S1T1001P100.D10.)\n(tld,s2t0042BE)\nN1G70\nN2%TLD,S4T7P1.D-.5%\n"
      "N3G71\nN4(TLD,S5T8P1.)\nN5(TLD,S6T9P1500D-250)\n");
  ASSERT_EQ(t.entries().size(), 5u);
  EXPECT_DOUBLE_EQ(t.Find("1001")->length, 100.0);
  EXPECT_TRUE(t.Find("42")->broken);
  EXPECT_TRUE(t.Find("42")->worn);
  EXPECT_DOUBLE_EQ(t.Find("7")->length, 25.4);
  EXPECT_DOUBLE_EQ(t.Find("7")->diameter, -12.7);
  EXPECT_DOUBLE_EQ(t.Find("8")->length, 1.0);
  // Without a point a P or D has an axis word's implied decimals (G71: three).
  EXPECT_DOUBLE_EQ(t.Find("9")->length, 1.5);
  EXPECT_DOUBLE_EQ(t.Find("9")->diameter, -0.25);
}

TEST(Tld, LoadReplacesWholeDataSetsOnTopOfTheTable) {
  tooltable::ToolTable base({tooltable::ToolEntry{.tool = "1", .socket = 1, .length = 50, .worn = true},
                             tooltable::ToolEntry{.tool = "2", .socket = 2, .length = 70}});
  auto t = Load("G71\n(TLD,S1T1P60.)\n", base);
  EXPECT_DOUBLE_EQ(t.Find("1")->length, 60);
  EXPECT_FALSE(t.Find("1")->worn);
  EXPECT_DOUBLE_EQ(t.Find("2")->length, 70);
  // All or nothing: a bad statement leaves the table as it was.
  EXPECT_THROW(Load("(TLD,S1T1P61.)\n(TLD,T3W1P.1)\n", base), Error);
}

TEST(Tld, ErrorsCarryFileLineAndColumn) {
  EXPECT_EQ(ErrorOf("\n(TLD,S1T1X5)"), "tools.tld:2:10: error: Input Source Error (TLD letter X)");
  EXPECT_EQ(ErrorOf("(TLD,S1P1.)"), "tools.tld:1:6: error: TLD NEEDS A T TOOL NUMBER");
  EXPECT_EQ(ErrorOf("(TLD,S1T12345678)"),
            "tools.tld:1:9: error: bad tool number '12345678' (1-7 digits expected)");
  EXPECT_EQ(ErrorOf("(TLD,T1T2)"), "tools.tld:1:8: error: TLD LETTER T GIVEN TWICE");
  EXPECT_EQ(ErrorOf("(TLD,T1P)"), "tools.tld:1:9: error: TLD P NEEDS A NUMBER");
  EXPECT_NE(ErrorOf("(TLD,T1").find("tools.tld:1:1:"), std::string::npos);
  EXPECT_EQ(ErrorOf("(TLD,S1MT1)").substr(0, 14), "tools.tld:1:8:");
  EXPECT_NE(ErrorOf("(TLD,T1P1000.)").find("OUTSIDE"), std::string::npos);  // +-999.999 mm
  EXPECT_NE(ErrorOf("(TLD,T1H100)").find("0-99.9"), std::string::npos);
  EXPECT_NE(ErrorOf("(TLD,TL5)").find("ONLY ALLOWED IN A PROGRAM"), std::string::npos);
}

// Issue 13 item 4: the manual's ranges, reported at the letter that breaks them, and the same limits for a
// data set from a station file (ktapl::CheckToolEntry, millimetres). Sign alone is no error (ln 4039, 4045:
// "Plus (+) is assumed unless a minus (-) is entered"; ln 4063: D-.25).
TEST(Tld, RangesOfTheManualInOnePlace) {
  // ln 4043, 4049: +-.001 to +-999.999 mm (G71), +-.0001 to +-39.37 in (G70); both signs, both ends.
  auto t = Load("G71\n(TLD,S1T1P-999.999D999.999)\nG70\n(TLD,S2T2P39.37D-39.37)\n");
  EXPECT_DOUBLE_EQ(t.Find("1")->length, -999.999);
  EXPECT_DOUBLE_EQ(t.Find("2")->diameter, -39.37 * 25.4);
  EXPECT_EQ(ErrorOf("G71\n(TLD,S1T1P.1D-1000.)"),
            "tools.tld:2:13: error: TLD D VALUE -1000 OUTSIDE +-999.999 (manual ln 4041-4049)");
  EXPECT_EQ(ErrorOf("G70\n(TLD,S1T1P39.371)"),
            "tools.tld:2:10: error: TLD P VALUE 39.371 OUTSIDE +-39.37 (manual ln 4041-4049)");
  // ln 4091: process compensations +-9.999 mm / +-.3937 in.
  EXPECT_EQ(ErrorOf("G71\n(TLD,T1)\n(TLD,T1W3P-9.999D10.)"),
            "tools.tld:3:17: error: TLD D VALUE 10 OUTSIDE +-9.999 (manual ln 4091)");
  EXPECT_EQ(Load("G70\n(TLD,T1)\n(TLD,T1W3P-.3937D.3937)").process_comps().size(), 1u);
  // S 1-999, L up to 9959 (ln 4051), H up to 99.9 (ln 4059).
  EXPECT_EQ(ErrorOf("(TLD,S1000T1)"), "tools.tld:1:7: error: TLD S VALUE 1000 OUTSIDE 1-999");
  EXPECT_EQ(ErrorOf("(TLD,S0T1)"), "tools.tld:1:7: error: TLD S VALUE 0 OUTSIDE 1-999");
  EXPECT_DOUBLE_EQ(Load("(TLD,S999T1L9959H99.9)").entries()[0].life_left_min, 99 * 60 + 59);
  EXPECT_EQ(ErrorOf("(TLD,T1L10000)"), "tools.tld:1:9: error: TLD L VALUE 10000 OUTSIDE 0-9959");
  EXPECT_EQ(ErrorOf("(TLD,T1H99.91)"), "tools.tld:1:8: error: TLD H HORSEPOWER OUTSIDE 0-99.9");

  // A data set from elsewhere (a station file), in mm: the same limits.
  using tooltable::ToolEntry;
  EXPECT_EQ(ktapl::CheckToolEntry(ToolEntry{.tool = "33412",
                                            .socket = 12,
                                            .length = 0.02,
                                            .diameter = -0.25,
                                            .life_left_min = 225,
                                            .max_hp = 5.9}),
            "");
  EXPECT_EQ(ktapl::CheckToolEntry(ToolEntry{
                .tool = "1", .socket = 1, .length = -999.999, .diameter = 999.999, .life_left_min = 5999}),
            "");
  EXPECT_EQ(ktapl::CheckToolEntry(ToolEntry{.tool = "1", .socket = 1, .length = 1000}),
            "TLD P VALUE 1000 MM OUTSIDE +-999.999 MM (manual ln 4041-4049)");
  EXPECT_EQ(ktapl::CheckToolEntry(ToolEntry{.tool = "1", .socket = 1, .diameter = -1000.5}),
            "TLD D VALUE -1000.5 MM OUTSIDE +-999.999 MM (manual ln 4041-4049)");
  EXPECT_EQ(ktapl::CheckToolEntry(ToolEntry{.tool = "1", .socket = 1000}), "TLD S VALUE 1000 OUTSIDE 1-999");
  EXPECT_EQ(ktapl::CheckToolEntry(ToolEntry{.tool = "1", .socket = 1, .life_left_min = 6000}),
            "TLD L TOOL LIFE 6000 MIN OUTSIDE 0-5999 MIN (L9959: 99 HOURS 59 MINUTES, manual ln 4051)");
  EXPECT_EQ(ktapl::CheckToolEntry(ToolEntry{.tool = "1", .socket = 1, .max_hp = 100}),
            "TLD H HORSEPOWER OUTSIDE 0-99.9");
  EXPECT_EQ(ktapl::CheckToolEntry(ToolEntry{.tool = "1", .socket = 4, .manual = true}),
            "TLD MANUAL TOOL (M) CANNOT HAVE A SOCKET (S)");
  EXPECT_NE(ktapl::CheckToolEntry(ToolEntry{.tool = "1", .socket = 1, .x_offset = 2}).find("lathe offsets"),
            std::string::npos);
  EXPECT_NE(ktapl::CheckToolEntry(ToolEntry{.tool = "33412.8", .socket = 1}), "");
  // Through the dialect interface (what the station config calls).
  EXPECT_EQ(KtaplDialect().CheckToolEntry(ToolEntry{.tool = "1", .socket = 1, .length = 1000}),
            ktapl::CheckToolEntry(ToolEntry{.tool = "1", .socket = 1, .length = 1000}));
}

TEST(Tld, TextWithoutTldIsAnError) {
  EXPECT_NE(ErrorOf("").find("no TLD statement found"), std::string::npos);
  EXPECT_NE(ErrorOf("%\nG0X1.\nM30\n").find("no TLD statement found"), std::string::npos);
}

// ch. 8 "TLD - Tool Table Load Substitution": T, P and D may be parameters inside a program.
TEST(Tld, ParameterSubstitution) {
  ktapl::TldContext ctx;
  ctx.param = [](int n, int) { return n == 111 ? 1.7 : (n == 99 ? 2.5 : -0.5); };
  ktapl::TldStatement st = ktapl::ParseTld("TL111PL99D-L10", ctx);
  ASSERT_TRUE(st.entry);
  EXPECT_EQ(st.entry->tool, "1.7");
  EXPECT_DOUBLE_EQ(st.entry->length, 2.5);
  EXPECT_DOUBLE_EQ(st.entry->diameter, 0.5);
}

}  // namespace
}  // namespace cell::interp
