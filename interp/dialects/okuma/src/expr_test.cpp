// Okuma User Task expressions: the manual's own sample values (seed ln 582-617, 8297-8314).
#include "expr.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

namespace cell::interp::okuma {
namespace {

class Vars : public VarReader {
 public:
  std::map<int, double> common;
  std::map<std::string, double> locals;
  double Common(int n, int) override { return common[n]; }
  double Local(uint64_t name, int col) override {
    auto it = locals.find(UnpackName(name));
    if (it == locals.end()) Fail(col, "local variable " + UnpackName(name) + " is not defined");
    return it->second;
  }
  Value System(uint64_t name, const Value*, int col) override {
    if (UnpackName(name) == "VPAI") return {3.14159265358979323846, false};
    Fail(col, "no system variables here");
  }
};

double Eval(const std::string& text, Vars& v) {
  std::vector<Node> pool;
  ExprParser p(text, 0, pool);
  int32_t root = p.Parse();
  EXPECT_EQ(p.pos(), text.size()) << text;
  return Evaluate(pool, root, v).v;
}

TEST(OkumaExpr, ManualSampleValues) {
  Vars v;
  // ln 582-617: the table of operations and functions.
  EXPECT_EQ(Eval("$A EOR $C", v), 6);                       // 1010 EOR 1100 = 0110
  EXPECT_EQ(Eval("$A OR $C", v), 14);                       // 1110
  EXPECT_EQ(Eval("$A AND $C", v), 8);                       // 1000
  EXPECT_EQ(static_cast<int>(Eval("NOT 5", v)) & 0xf, 10);  // NOT 0101 = 1010 (low 4 bits)
  EXPECT_EQ(Eval("5+3", v), 8);
  EXPECT_EQ(Eval("5-3", v), 2);
  EXPECT_EQ(Eval("5*3", v), 15);
  EXPECT_EQ(Eval("15/5", v), 3);
  EXPECT_NEAR(Eval("SIN[30]", v), 0.5, 1e-12);
  EXPECT_NEAR(Eval("COS[60]", v), 0.5, 1e-12);
  EXPECT_NEAR(Eval("TAN[45]", v), 1, 1e-12);
  EXPECT_NEAR(Eval("ATAN[1]", v), 45, 1e-12);
  EXPECT_NEAR(Eval("ATAN2[1,SQRT[3]]", v), 30, 1e-9);
  EXPECT_EQ(Eval("SQRT[16]", v), 4);
  EXPECT_EQ(Eval("ABS[-3]", v), 3);
  EXPECT_EQ(Eval("BIN[$25]", v), 25);
  EXPECT_EQ(Eval("BCD[25]", v), 0x25);
  EXPECT_EQ(Eval("ROUND[127.63]", v), 128);
  EXPECT_EQ(Eval("FIX[127.63]", v), 127);
  EXPECT_EQ(Eval("FUP[127.63]", v), 128);
  EXPECT_NEAR(Eval("DROUND[13.26462]", v), 13.265, 1e-12);
  EXPECT_NEAR(Eval("DFIX[13.26462]", v), 13.264, 1e-12);
  EXPECT_NEAR(Eval("DFUP[13.26462]", v), 13.265, 1e-12);
  EXPECT_EQ(Eval("MOD[17,5]", v), 2);
}

TEST(OkumaExpr, PrecedenceBracketsAndVariables) {
  Vars v;
  v.common = {{2, 1}, {3, 2}, {4, 3}, {5, 10}, {6, 4}, {7, 2}, {8, 1}};
  // ln 8322-8333: V1 = [V2+V3]*V4+[V5-V6]/V7+V8 = 3*3 + 6/2 + 1 = 13
  EXPECT_EQ(Eval("[V2+V3]*V4+[V5-V6]/V7+V8", v), 13);
  v.locals["XP2"] = 35;
  EXPECT_EQ(Eval("100+XP2", v), 135);  // ln 7440
  EXPECT_EQ(Eval("[V5 EQ 10]", v), 1);
  EXPECT_EQ(Eval("[V5 LT 5]", v), 0);
  EXPECT_NEAR(Eval("VPAI", v), 3.14159265, 1e-8);
}

TEST(OkumaExpr, ExpressionEndsAtABlankUnlessAnOperatorFollows) {
  std::vector<Node> pool;
  std::string s = "XD1 Z=5";
  ExprParser p(s, 0, pool);
  p.Parse();
  EXPECT_EQ(p.pos(), 3u);
  std::string t = "- [XH1*2] -0.2 F0.05";
  pool.clear();
  ExprParser q(t, 0, pool);
  q.Parse();
  EXPECT_EQ(t.substr(q.pos()), " F0.05");
}

TEST(OkumaExpr, Errors) {
  Vars v;
  EXPECT_THROW(Eval("ABC+1", v), RunError);  // undefined local
  EXPECT_THROW(Eval("1/0", v), RunError);
  std::vector<Node> pool;
  std::string bad = "COS(V10)";
  EXPECT_THROW(ExprParser(bad, 0, pool).Parse(), RunError);
  std::string v0 = "V201";
  EXPECT_THROW(ExprParser(v0, 0, pool).Parse(), RunError);
  std::string sys = "VFOO";
  EXPECT_THROW(ExprParser(sys, 0, pool).Parse(), RunError);
}

// The names a local variable may not take (ln 7593-7603), tested as packed integers: every one of them, and
// names that only share letters with one.
TEST(OkumaExpr, ReservedNames) {
  for (const char* r :
       {"AA",  "ZB",  "BC",  "LT",  "GE",   "OR",   "AND",  "EOR",  "NOT", "QA",    "PZ",     "PW", "IF",
        "END", "RTS", "GET", "PUT", "CALL", "GOTO", "READ", "VSET", "SIN", "ATAN2", "DROUND", "MOD"}) {
    EXPECT_TRUE(IsReservedName(r)) << r;
  }
  for (const char* ok : {"DP", "AC", "ORR", "AN", "CAL", "CALLS", "ATAN3", "DROUNDX", "GOTOA", "SI"}) {
    EXPECT_FALSE(IsReservedName(ok)) << ok;
  }
  EXPECT_TRUE(IsLocalName("DP"));
  EXPECT_FALSE(IsLocalName("LT"));
  EXPECT_FALSE(IsLocalName("END"));
}

// An expression ends at a blank unless an operator follows; a word operator counts only as a whole word.
TEST(OkumaExpr, WordOperatorAfterBlank) {
  Vars v;
  v.common[1] = 1;
  EXPECT_EQ(Eval("V1 LT 2", v), 1);
  EXPECT_EQ(Eval("V1+1 EQ 2 AND 1", v), 1);
  EXPECT_EQ(Eval("0 OR V1", v), 1);
  for (std::string t : {"V1+2 LTX=1", "V1+2 LT2", "V1+2 ORX=1", "V1+2 DP=3"}) {
    std::vector<Node> pool;
    ExprParser p(t, 0, pool);
    Evaluate(pool, p.Parse(), v);
    EXPECT_EQ(p.pos(), 4u) << t;
  }
}

// The fast path for operands joined by + - * / (ExprParser::Simple) builds the nodes the full descent builds:
// inside [ ] only the descent runs (col0 0 keeps the columns those of the unbracketed text).
TEST(OkumaExpr, SimplePathBuildsTheDescentsNodes) {
  for (std::string e : {"V1+0.001", "V2+100", "V1*2+1", "V1-2-3", "V1/2*3", "V1+2*3", "1.5", "V200",
                        ".5*V3-7", "12345678", "v12+3", "V1+2.", "V1*V2/V3+V4-5"}) {
    std::vector<Node> fast, full;
    ExprParser pf(e, 0, fast);
    const int32_t rf = pf.Parse();
    const std::string bracketed = "[" + e + "]";
    ExprParser pd(bracketed, 0, full, 0);
    const int32_t rd = pd.Parse();
    EXPECT_EQ(pf.pos(), e.size()) << e;
    EXPECT_EQ(rf, rd) << e;
    ASSERT_EQ(fast.size(), full.size()) << e;
    for (size_t i = 0; i < fast.size(); ++i) {
      EXPECT_EQ(fast[i].op, full[i].op) << e << " node " << i;
      EXPECT_EQ(fast[i].a, full[i].a) << e << " node " << i;
      EXPECT_EQ(fast[i].b, full[i].b) << e << " node " << i;
      EXPECT_EQ(fast[i].num, full[i].num) << e << " node " << i;
      EXPECT_EQ(fast[i].integer, full[i].integer) << e << " node " << i;
      EXPECT_EQ(fast[i].col, full[i].col) << e << " node " << i;
    }
  }
}

}  // namespace
}  // namespace cell::interp::okuma
