// Okuma runs through the dialect: order of actions, variables in and out, diagnostics.
#include <gtest/gtest.h>

#include "cell/interp/okuma.h"

namespace cell::interp {
namespace {

std::vector<std::string> RunLines(const std::string& text, std::map<std::string, double> vars = {},
                                  Run** keep = nullptr, std::string* diag = nullptr) {
  RunOptions o;
  o.program_name = "T.MIN";
  o.program_text = text;
  o.variables = std::move(vars);
  static std::unique_ptr<Run> run;
  run = OkumaDialect().StartRun(o);
  std::vector<std::string> out;
  for (;;) {
    Step s = run->Next();
    if (s.kind == Step::kCanon) {
      out.push_back(ToJsonLine(s.canon));
      continue;
    }
    if (s.kind == Step::kError && diag) *diag = s.diag.Format();
    if (s.kind == Step::kError && !diag) ADD_FAILURE() << s.diag.Format();
    break;
  }
  if (keep) *keep = run.get();
  return out;
}

TEST(OkumaRun, UnitsFirstDiameterModeAndAMove) {
  auto out = RunLines("O100\nN1 G00 X100 Z50\nN2 G01 X80 F0.2\nN3 M02\n");
  ASSERT_GE(out.size(), 4u);
  EXPECT_EQ(out[0], R"({"op":"units","line":2,"length":"mm","x_mode":"diameter"})");
}

TEST(OkumaRun, CommonVariablesComeInAndGoOut) {
  cell::interp::Run* run = nullptr;
  RunLines("N1 V1=V1+1 V5=10\nM02\n", {{"V1", 19}}, &run);
  auto v = run->Variables();
  EXPECT_EQ(v["V1"], 20);
  EXPECT_EQ(v["V5"], 10);
}

TEST(OkumaRun, UserAlarmStopsTheRunWithTheManualsNumber) {
  std::string diag;
  RunLines("N101 VUACM[1]='PART'\nN102 VUACM[5]='=GEAR'\nN103 VDOUT[992]=1000\nM02\n", {}, nullptr, &diag);
  EXPECT_EQ(diag, "T.MIN:3:6: error: [2288] Alarm B User reserve code 1000 PART=GEAR");
}

}  // namespace
}  // namespace cell::interp
