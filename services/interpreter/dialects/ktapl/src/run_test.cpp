// Library-level tests of the run API and the metadata helper.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include "cell/error/error.h"
#include "cell/interp/interp.h"
#include "cell/interp/ktapl.h"

namespace cell::interp {
namespace {

std::vector<std::string> RunAll(const std::string& text, Diagnostic* diag = nullptr) {
  RunOptions o;
  o.program_name = "T";
  o.program_text = text;
  auto run = StartRun(o);
  std::vector<std::string> out;
  for (;;) {
    Step s = run->Next();
    if (s.kind == Step::kCanon) {
      out.push_back(ToJsonLine(s.canon));
      continue;
    }
    if (s.kind == Step::kError && diag) *diag = s.diag;
    if (s.kind == Step::kError && !diag) ADD_FAILURE() << s.diag.Format();
    return out;
  }
}

TEST(Run, FirstOpIsUnitsAndMotionCarriesUsedAxes) {
  auto out = RunAll("%\n(NAM,TEST)\nN10 G71 G0 X10. F0\nN20 Y5. Z2.\nM30\n");
  ASSERT_EQ(out.size(), 4u);
  EXPECT_EQ(out[0], R"({"op":"units","line":3,"length":"mm","x_mode":"radius"})");
  EXPECT_EQ(out[1], R"({"op":"rapid","line":3,"x":10.0000})");
  EXPECT_EQ(out[2], R"({"op":"rapid","line":4,"x":10.0000,"y":5.0000,"z":2.0000})");
  EXPECT_EQ(out[3], R"({"op":"end","line":5,"m":30,"shuttle":true})");
}

// Parsed blocks of subroutine bodies and GTO loops are cached by (text, offset) in a fixed table; more
// distinct repeated blocks than the table has slots must still each run their own words, and a cached
// expression word must see the current parameter values.
TEST(Run, RepeatedBlocksRunTheirOwnWordsThroughTheParseCache) {
  std::string text = "%\nG71 G90 G0 X0 Y0 F0\n";
  const int kSubs = 20, kBlocks = 20;  // 400 distinct repeated blocks
  for (int k = 1; k <= kSubs; ++k) {
    text += "(DFS,S" + std::to_string(k) + ")\n";
    for (int b = 0; b < kBlocks; ++b) text += "G01 G91 F100. X," + std::to_string(k) + ".*L1\n";
    text += "(END)\n";
  }
  text += "(PAR,L101=1.)\n(LBL,1)\n";
  for (int k = 1; k <= kSubs; ++k) text += "(CLS,S" + std::to_string(k) + ",1,L1=L101)\n";
  text += "(PAR,L101=L101+1.)\n(IFT,L101<3.5,(GTO,1))\nM30\n";
  auto out = RunAll(text);
  // Passes with L1 = 1, 2, 3: every block of S<k> moves X by k*L1 mm. (units, the moves, end: the G0 to
  // where the slides already are moves nothing and emits nothing.)
  ASSERT_EQ(out.size(), 1u + 3u * kSubs * kBlocks + 1u);
  double x = 0;
  for (int pass = 1; pass <= 3; ++pass) {
    for (int k = 1; k <= kSubs; ++k) {
      for (int b = 0; b < kBlocks; ++b) {
        x += k * pass;
        size_t i = 1 + ((pass - 1) * kSubs + (k - 1)) * kBlocks + b;
        ASSERT_NE(out[i].find(fmt::format("\"x\":{:.4f},", x)), std::string::npos) << i << " " << out[i];
      }
    }
  }
}

TEST(Run, UnknownAndUnimplementedDialects) {
  RunOptions o;
  o.dialect = "okuma";
  try {
    StartRun(o);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kUnimplemented);
  }
  o.dialect = "fanuc";
  try {
    StartRun(o);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kInvalidArgument);
  }
}

TEST(Run, ErrorStopsTheRunAndKeepsEarlierOutput) {
  Diagnostic d;
  auto out = RunAll("G71G0X1.F0\nG04 X1. F2.\n", &d);
  EXPECT_EQ(out.size(), 2u);
  EXPECT_EQ(d.line, 2);
  EXPECT_EQ(d.text, "NO AXIS WORDS ALLOWED IN A G04 BLOCK");
  EXPECT_EQ(d.Format().rfind("T:2:", 0), 0u);
}

TEST(Run, LibrarySubroutineReportsTheCallingLine) {
  RunOptions o;
  o.program_name = "T";
  o.program_text = "G71G0F0\n(CLS,SUB1,2)\nM30\n";
  o.library = [](const std::string& name) -> std::optional<std::string> {
    if (name == "SUB1") return std::string("(DFS,SUB1,SAVE)\nG91X1.\n(END)\n");
    return std::nullopt;
  };
  auto run = StartRun(o);
  std::vector<Canon> moves;
  for (;;) {
    Step s = run->Next();
    if (s.kind != Step::kCanon) break;
    if (s.canon.op == Op::kRapid) moves.push_back(s.canon);
  }
  ASSERT_EQ(moves.size(), 2u);
  EXPECT_EQ(moves[0].line, 2);
  EXPECT_DOUBLE_EQ(moves[1].pos[kX], 2.0);
}

TEST(ToolTable, TldExamples) {
  // Manual ln 4063-4097: primary, suffix 5, and the process compensation for pallet 12.
  auto t = ParseKtaplToolTable(
      "G70\n(TLD,S12T33412CP.02D-.25L345H5.9)\n(TLD,S12T33412.5CP.02D-.25L345H5.9)\n"
      "(TLD,T33412.5W12P.0003D-.0004)\n");
  ASSERT_EQ(t.size(), 3u);
  EXPECT_EQ(t[2].tool, "33412.5");
  EXPECT_EQ(t[2].pallet, 12);
  EXPECT_NEAR(t[2].length, 0.0003 * 25.4, 1e-9);
  EXPECT_EQ(t[0].tool, "33412");
  EXPECT_EQ(t[0].socket, 12);
  EXPECT_TRUE(t[0].check);
  EXPECT_NEAR(t[0].length, 0.02 * 25.4, 1e-9);
  EXPECT_NEAR(t[0].diameter, -0.25 * 25.4, 1e-9);
  EXPECT_EQ(t[0].life_min, 3 * 60 + 45);
  EXPECT_DOUBLE_EQ(t[0].max_hp, 5.9);
  EXPECT_THROW(ParseKtaplToolTable("(TLD,T99W12P.0003)\n"), Error);
}

}  // namespace
}  // namespace cell::interp

namespace cell::interp {
namespace {

class FakeEnv : public Environment {
 public:
  int probes = 0;
  std::string waited;
  ProbeResult Probe(bool contact, const std::array<double, kAxisCount>& from,
                    const std::array<double, kAxisCount>& to) override {
    ++probes;
    ProbeResult r;
    r.event = contact;
    r.at = from;
    r.at[kX] = (from[kX] + to[kX]) / 2;  // contact half way
    return r;
  }
  void WaitInputs(const std::string& spec) override { waited = spec; }
  std::optional<double> SystemParameter(int n) override {
    if (n == 3500) return 42.0;
    return std::nullopt;
  }
};

TEST(Service, EnvironmentAnswersQueueBusters) {
  FakeEnv env;
  RunOptions o;
  o.program_name = "S";
  o.program_text =
      "G71 G0 X0 F0\nG22 X10. F100.\n(PAR,L1000=L3042+L3500)\n(WAI,I04D,1=1, I03D,3=0)\nXL1000\nM30\n";
  o.env = &env;
  auto run = StartRun(o);
  std::vector<Canon> ops;
  for (Step s = run->Next(); s.kind == Step::kCanon; s = run->Next()) ops.push_back(s.canon);
  EXPECT_EQ(env.probes, 1);
  EXPECT_EQ(env.waited, "I04D,1=1,I03D,3=0");
  auto mp = run->MachineParameters();
  ASSERT_TRUE(mp.count(1000));
  EXPECT_DOUBLE_EQ(mp[1000], 5.0 + 42.0);  // contact at X5 (mm, G71) + L3500 from the environment
  EXPECT_DOUBLE_EQ(mp[1021], 8.0);         // event happened
  bool moved = false;
  for (const auto& c : ops) moved |= c.op == Op::kLinear && c.pos[kX] == 47.0;  // F100 is modal after G22
  EXPECT_TRUE(moved);
}

TEST(Service, SaveCallbackGetsTheDefinitionText) {
  RunOptions o;
  o.program_name = "S";
  o.program_text = "(DFS,DRILL25,SAVE)\nG91X1.F0\n(END)\n(DFC,G881)\nZ1.\n(END)\n";
  std::map<std::string, std::string> saved;
  o.save = [&](const std::string& name, const std::string& text) { saved[name] = text; };
  auto run = StartRun(o);
  while (run->Next().kind == Step::kCanon) {
  }
  ASSERT_EQ(saved.size(), 1u);  // G881 has no SAVE
  EXPECT_EQ(saved["DRILL25"], "G91X1.F0\n(END)\n");
}

TEST(Service, ParamsSetUnitsPalletAndParameters) {
  RunOptions o;
  o.program_name = "S";
  o.program_text = "G0 F0 XL1000 YL3020\n";
  o.params = {{"UNITS", "mm"}, {"PALLET", "38"}, {"L1000", "12.5"}};
  auto run = StartRun(o);
  Step u = run->Next();
  ASSERT_EQ(u.kind, Step::kCanon);
  EXPECT_TRUE(u.canon.metric);
  Step m = run->Next();
  ASSERT_EQ(m.kind, Step::kCanon);
  EXPECT_DOUBLE_EQ(m.canon.pos[kX], 12.5);
  EXPECT_DOUBLE_EQ(m.canon.pos[kY], 38.0);
  EXPECT_EQ(run->Next().kind, Step::kEnd);
  EXPECT_EQ(run->Next().kind, Step::kEnd);  // stays at the end
}

}  // namespace
}  // namespace cell::interp
