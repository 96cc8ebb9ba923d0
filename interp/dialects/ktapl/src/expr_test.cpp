// Appendix A function values and the 8-significant-digit display format (manual ln 11169-11369).
#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <string>
#include <string_view>

#include "cell/interp/ktapl.h"
#include "expr.h"

namespace cell::interp::ktapl {
namespace {

class Ctx : public ExprContext {
 public:
  std::map<int, double> p;
  double Param(int n) override {
    auto it = p.find(n);
    if (it == p.end()) throw ExprError{"Error L number NOT in table", 0};
    return it->second;
  }
  bool ParamDefined(int n) override { return p.count(n) > 0; }
  double Letter(char c) override { return c == 'X' ? 2.5 : 0; }
  bool ActiveCode(char gm, int code) override {
    return gm == 'G' && (code == 70 || code == 90 || code == 94);
  }
};

std::string Show(const char* expr) {
  Ctx c;
  return FormatKtNumber(EvalValue(expr, c));
}

TEST(AppendixA, FunctionExamplesPrintAsInTheManual) {
  EXPECT_EQ(Show("SQ(10.)"), "100.00000");  // ln 11218
  EXPECT_EQ(Show("SQ(100.)"), "10000.000");
  EXPECT_EQ(Show("SQRT(25.)"), "5.0000000");
  EXPECT_EQ(Show("SQRT(2500.)"), "50.000000");
  EXPECT_EQ(Show("ABS(-10.)"), "10.000000");
  EXPECT_EQ(Show("ASN(1.)"), "90.000000");
  EXPECT_EQ(Show("ASN(-1.)"), "-90.000000");
  EXPECT_EQ(Show("ACS(1.)"), "0.0");
  EXPECT_EQ(Show("ACS(-1.)"), "180.00000");
  EXPECT_EQ(Show("INT(23.01)"), "23.000000");
  EXPECT_EQ(Show("INT(.25)"), "0.0");
  EXPECT_EQ(Show("INT(-9999.9999)"), "-9999.0000");
  EXPECT_EQ(Show("FRA(1.25)"), ".25000000");
  EXPECT_EQ(Show("FRA(-9999.9999)"), "-.99990000");
  EXPECT_EQ(Show("LOG(45.6845)"), "1.6597688");
  EXPECT_EQ(Show("LOG(9090.5432)"), "3.9585898");
  EXPECT_EQ(Show("LOG(.0001)"), "-4.0000000");
  EXPECT_EQ(Show("ALOG(1.25)"), "17.782794");
  EXPECT_EQ(Show("ALOG(-.5)"), ".31622776");
  EXPECT_EQ(Show("ALOG(-2.5)"), ".00316227");
  EXPECT_EQ(Show("LN(23.01)"), "3.1359289");
  EXPECT_EQ(Show("LN(1.25)"), ".22314355");
  EXPECT_EQ(Show("LN(.0001)"), "-9.2103403");
  EXPECT_EQ(Show("EXP(3.89)"), "48.910886");
  EXPECT_EQ(Show("EXP(-9.)"), ".00012340");
  EXPECT_EQ(Show("EXP(6.5)"), "665.14163");
}

TEST(AppendixA, RoundingIdioms) {
  Ctx c;
  c.p[1] = 1.2345;  // ln 11173-11207
  EXPECT_DOUBLE_EQ(EvalValue("INT(L1)", c), 1.0);
  EXPECT_NEAR(EvalValue("INT(L1*10.)/10.", c), 1.2, 1e-12);
  EXPECT_NEAR(EvalValue("INT(L1*100.)/100.", c), 1.23, 1e-12);
  EXPECT_NEAR(EvalValue("INT(L1*1000.)/1000.", c), 1.234, 1e-12);
  EXPECT_NEAR(EvalValue("INT(L1*1000.+.5)/1000.", c), 1.235, 1e-12);
  c.p[1] = 1.5;
  EXPECT_DOUBLE_EQ(EvalValue("INT(L1+.5)", c), 2.0);
  c.p[1] = 1.4999;
  EXPECT_DOUBLE_EQ(EvalValue("INT(L1+.5)", c), 1.0);
}

TEST(AppendixA, DomainErrorsUseTheManualTexts) {
  Ctx c;
  try {
    EvalValue("SQRT(-1.)", c);
    FAIL();
  } catch (const ExprError& e) {
    EXPECT_EQ(e.text, "Error: negative square root attempted");
  }
  try {
    EvalValue("ASN(1.5)", c);
    FAIL();
  } catch (const ExprError& e) {
    EXPECT_EQ(e.text, "ASN argument error: ASN(n) -1.0000 <= n <= 1.0000");
  }
  EXPECT_THROW(EvalValue("TAN(90.)", c), ExprError);
  EXPECT_THROW(EvalValue("1./0", c), ExprError);
  try {
    EvalValue("((((((((( 1. )))))))))", c);
    FAIL();
  } catch (const ExprError& e) {
    EXPECT_EQ(e.text, "Error - exceeds 8 open parentheses");
  }
  EXPECT_NO_THROW(EvalValue("(((((((( 1. ))))))))", c));
}

TEST(Expressions, PrecedenceAndSin) {
  Ctx c;
  EXPECT_DOUBLE_EQ(EvalValue("6+2*5", c), 16.0);            // ln 8587
  EXPECT_NEAR(EvalValue("10.*SIN(45.)", c), 7.0711, 1e-4);  // ln 8643
  EXPECT_DOUBLE_EQ(EvalValue("X + .1", c), 2.6);
}

// EvalValue takes the common forms (operands joined by + - * / with no * or / after a + or -) without the
// descent; whatever it answers must be the descent's own value to the bit, or the descent's own error.
std::string Outcome(std::string_view expr, Ctx& c, bool descent_only) {
  char buf[64];
  try {
    double v;
    if (descent_only) {
      ExprParser p(expr, c);
      v = p.Value();
      if (!p.AtEnd()) return "SYNTAX ERROR IN EXPRESSION @" + std::to_string(p.pos());
    } else {
      v = EvalValue(expr, c);
    }
    std::snprintf(buf, sizeof buf, "%a", v);
    return buf;
  } catch (const ExprError& e) {
    return e.text + " @" + std::to_string(e.offset);
  }
}

TEST(Expressions, FastPathGivesTheDescentsValueOrError) {
  Ctx c;
  c.p = {{0, 0.0}, {1, 1.5}, {2, -2.25}, {3, 0.1}, {5, 2.0}, {101, 0.003}, {102, 999999998.0}};
  for (const char* e :
       {"-L5",      "L101+.001", "L101*2.+1.", "2.",        "3",           ".5",          "L1-L2-L3",
        "L1/L2*L3", "L1*L2+L3",  "L1+L2*L3",   "L1-L2/L3",  " L1 + 2 ",    "\tL1\t*\t3.", "-0",
        "+L1",      "2*-L1",     "L1/-L3",     "l101+.001", "L1/0",        "L1/L0",       "L99+1",
        "L3070",    "L3070*2",   "L102+10.",   "L102*L102", "1000000000.", "999999999.",  "X+1",
        "x*2",      "SQRT(4.)",  "LN(2.)",     "L(1)+1",    "--L1",        "L1 2",        "",
        " ",        "L",         ".",          "1..2",      "XY",          "L4000",       "L1+",
        "*L1",      "L1+(2)",    "L 1+1",      "0.1+0.2",   "1./3.*3.",    "L3/L3/L3",    "7-L1-L2*2"}) {
    EXPECT_EQ(Outcome(e, c, false), Outcome(e, c, true)) << e;
  }
}

TEST(Conditions, ManualForms) {
  Ctx c;
  c.p[100] = 10;
  c.p[200] = 5;
  c.p[5] = 1;
  EXPECT_TRUE(EvalCondition("G70ANDG94ANDG90", c));  // ln 9131
  EXPECT_FALSE(EvalCondition("G71", c));
  EXPECT_TRUE(EvalCondition("(L100 = 10.)AND(L200 = 5.)", c));  // ln 9307
  EXPECT_TRUE(EvalCondition("NOTDEF(L6)", c));
  EXPECT_FALSE(EvalCondition("NOTDEF(L5)ANDNOTDEF(L6)", c));  // ln 9336-9342
  EXPECT_TRUE(EvalCondition("NOTDEF(L5)ORNOTDEF(L6)", c));
  EXPECT_TRUE(EvalCondition("NOT(DEF(L806))", c));
  EXPECT_TRUE(EvalCondition("L100 < > 1.", c));
  EXPECT_TRUE(EvalCondition("L100 > = 10.", c));
  EXPECT_TRUE(EvalCondition("L200 =< 5.", c));
  EXPECT_FALSE(EvalCondition("L200 < 5.", c));
}

TEST(NumberFormat, ChapterSevenExamples) {
  EXPECT_EQ(FormatKtNumber(9.8), "9.8000000");       // ln 3460
  EXPECT_EQ(FormatKtNumber(123.4567), "123.45670");  // ln 8168
  EXPECT_EQ(FormatKtNumber(-45.67), "-45.670000");
  EXPECT_EQ(FormatKtNumber(1987), "1987.0000");
  EXPECT_EQ(FormatKtNumber(123.456), "123.45600");
  EXPECT_EQ(FormatKtNumber(0), "0.0");
  EXPECT_EQ(FormatKtNumber(0.0333), ".03330000");
  EXPECT_EQ(FormatKtNumber(1234567), "1234567.0");
}

}  // namespace
}  // namespace cell::interp::ktapl
