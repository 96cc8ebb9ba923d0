// Okuma OSP schedule programs: seed /work/shared/seeds/okuma-osp-e100l.txt SECTION 14, lines 8767-8962.
#include "cell/scheduler/schedule_program.h"

#include <gtest/gtest.h>

#include <map>

#include "cell/error/error.h"

namespace cell::scheduler::schedule {
namespace {

struct Vars : Variables {
  double Get(int n) override { return v[n]; }
  void Set(int n, double value) override { v[n] = value; }
  std::map<int, double> v;
};

std::vector<Run> RunAll(const std::string& text, Vars& vars, std::string* alarm = nullptr) {
  Runner r(std::make_shared<Program>(Parse(text, "S.SDF")));
  std::vector<Run> runs;
  for (int i = 0; i < 10000; ++i) {
    Step s = r.Next(vars);
    if (s.kind == Step::Kind::kRun) {
      runs.push_back(s.run);
      continue;
    }
    if (s.kind == Step::Kind::kAlarm && alarm) *alarm = s.alarm;
    break;
  }
  return runs;
}

std::string ParseError(const std::string& text) {
  try {
    Parse(text, "S.SDF");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// E-SCH-1 (seed 8926-8962): O100 x20, O200 x15, O300 x25 with V1/V2/V3 as counters; the catalogue's
// reconstruction with IF loops.
TEST(Schedule, WorkedExampleWithCounters) {
  Vars vars;
  vars.v[1] = 99;  // common variables persist on the station: VSET resets them
  const auto runs = RunAll(
      "N001 VSET V1=0 V2=0 V3=0\n"
      "N010 PSELECT A.MIN,O100\n"
      "N011 VSET V1=V1+1\n"
      "N012 IF [V1 LT 20] N010\n"
      "N020 PSELECT B.MIN,O200\n"
      "N021 VSET V2=V2+1\n"
      "N022 IF [V2 LT 15] N020\n"
      "N030 PSELECT C.MIN,O300 (part C)\n"
      "N031 VSET V3=V3+1\n"
      "N032 IF [V3 LT 25] N030\n"
      "END\n",
      vars);
  ASSERT_EQ(runs.size(), 60u);
  EXPECT_EQ(runs[0].main_file, "MD1:A.MIN");
  EXPECT_EQ(runs[0].program, "O100");
  EXPECT_EQ(runs[19].program, "O100");
  EXPECT_EQ(runs[20].program, "O200");
  EXPECT_EQ(runs[35].program, "O300");
  EXPECT_EQ(runs[59].main_file, "MD1:C.MIN");
  EXPECT_EQ(vars.v[1], 20);
  EXPECT_EQ(vars.v[2], 15);
  EXPECT_EQ(vars.v[3], 25);
}

// The same schedule with repeat counts: "PSELECT ... Q" runs the main program n times (seed 8853-8864).
TEST(Schedule, RepeatCountsRunOneAfterAnother) {
  Vars vars;
  const auto runs = RunAll(
      "PSELECT MD1:A.MIN,O100,,Q=20\n"
      "PSELECT MD1:B.MIN,O200,,Q15\n"
      "PSELECT MD1:C.MIN,O300,,Q 25\n"
      "END\n",
      vars);
  ASSERT_EQ(runs.size(), 60u);
  EXPECT_EQ(runs[0].index, 1);
  EXPECT_EQ(runs[0].count, 20);
  EXPECT_EQ(runs[19].index, 20);
  EXPECT_EQ(runs[20].program, "O200");
  EXPECT_EQ(runs[20].count, 15);
  EXPECT_EQ(runs[59].program, "O300");
  EXPECT_EQ(runs[59].index, 25);
}

// Defaults MD1, A, MIN; subprogram file defaults MD1 and SUB (seed 8808-8851).
TEST(Schedule, PselectDefaults) {
  Program p = Parse("PSELECT\nPSELECT ,O7,LIB\nPSELECT X:PART,,MD2:S.SSB,Q=V5*2\nEND", "S.SDF");
  ASSERT_EQ(p.blocks.size(), 4u);
  EXPECT_EQ(p.blocks[0].main_file.Full(), "MD1:A.MIN");
  EXPECT_EQ(p.blocks[0].program, "");
  EXPECT_FALSE(p.blocks[0].sub_file);
  EXPECT_EQ(p.blocks[1].sub_file->Full(), "MD1:LIB.SUB");
  EXPECT_EQ(p.blocks[2].main_file.Full(), "X:PART.MIN");
  EXPECT_EQ(p.blocks[2].sub_file->Full(), "MD2:S.SSB");
  Vars vars;
  vars.v[5] = 2;
  EXPECT_EQ(RunAll("PSELECT X:PART,,,Q=V5*2\nEND", vars).size(), 4u);
}

TEST(Schedule, StationEntryCarriesPselectsOperandsWithoutTheDevice) {
  Vars vars;
  auto runs =
      RunAll("PSELECT\nPSELECT B.MIN,O200\nPSELECT C,,MD1:S.SSB\nPSELECT MD2:D.MIN,O4,LIB\nEND", vars);
  ASSERT_EQ(runs.size(), 4u);
  EXPECT_EQ(StationEntry(runs[0]), "A.MIN");
  EXPECT_EQ(StationEntry(runs[1]), "B.MIN,O200");
  EXPECT_EQ(StationEntry(runs[2]), "C.MIN,,S.SSB");
  EXPECT_EQ(StationEntry(runs[3]), "D.MIN,O4,LIB.SUB");
}

TEST(Schedule, ContinuationCommentsAndBlocksAfterEnd) {
  Vars vars;
  const auto runs = RunAll(
      "%\n"
      "(a comment line)\n"
      "N1 VSET V1=1\n"
      "$ V2=2\n"
      "PSELECT A.MIN,O1,,Q=[V1+V2]\n"
      "END\n"
      "THIS IS IGNORED\n",
      vars);
  EXPECT_EQ(runs.size(), 3u);
  EXPECT_EQ(vars.v[2], 2);
}

// "If other blocks are specified, an alarm will occur" (seed 8774); block delete is invalid (8785).
TEST(Schedule, ParseAlarms) {
  EXPECT_EQ(
      ParseError("G00 X10\nEND"),
      "S.SDF:1:1: error: illegal block G in a schedule program (PSELECT, GOTO, IF, VSET or END expected)");
  EXPECT_EQ(ParseError("/PSELECT A.MIN\nEND"),
            "S.SDF:1:1: error: block delete is not allowed in a schedule program");
  EXPECT_EQ(ParseError("PSELECT A*.MIN\nEND"), "S.SDF:1:9: error: '*' or '?' in a file name");
  EXPECT_EQ(ParseError("PSELECT A.MIN,100\nEND"),
            "S.SDF:1:15: error: program name O + up to 4 characters expected");
  EXPECT_EQ(ParseError("PSELECT A.MIN\n"), "S.SDF:2:1: error: a schedule program must end with END");
  EXPECT_EQ(ParseError("VSET ABC=1\nEND"),
            "S.SDF:1:6: error: VSET needs a common, system or output variable on the left, not 'ABC'");
  EXPECT_EQ(ParseError("VSET V1=VDOUT[5]\nEND"),
            "S.SDF:1:9: error: output variable VDOUT[5] on the right side");
  EXPECT_EQ(ParseError("VSET V201=1\nEND"), "S.SDF:1:6: error: V201 is not a common variable (V1-V200)");
  EXPECT_EQ(ParseError("IF [V1 XX 2] N1\nEND"),
            "S.SDF:1:8: error: comparison operator LT, LE, EQ, NE, GE or GT expected");
  EXPECT_EQ(ParseError("GOTO 10\nEND"), "S.SDF:1:6: error: sequence name (Nxxxx) expected");
  EXPECT_EQ(ParseError("N10PSELECT\nEND"), "S.SDF:1:1: error: bad sequence name N10PSELECT");
}

TEST(Schedule, RunAlarms) {
  Vars vars;
  std::string alarm;
  EXPECT_TRUE(RunAll("PSELECT A.MIN,O1,,Q=0\nEND", vars, &alarm).empty());
  EXPECT_EQ(alarm, "S.SDF:1:21: error: repeat count Q=0 outside 1-9999");
  EXPECT_TRUE(RunAll("PSELECT A.MIN,O1,,Q=10000\nEND", vars, &alarm).empty());
  EXPECT_EQ(alarm, "S.SDF:1:21: error: repeat count Q=10000 outside 1-9999");
  EXPECT_EQ(RunAll("PSELECT A.MIN,O1,,Q=9999\nEND", vars).size(), 9999u);
  RunAll("GOTO N99\nEND", vars, &alarm);
  EXPECT_EQ(alarm, "S.SDF:1:1: error: sequence name N99 not found");
  RunAll("VSET V1=LOCL+1\nEND", vars, &alarm);
  EXPECT_EQ(alarm,
            "S.SDF:1:9: error: variable LOCL is not available to a schedule run by the cell (only V1-V200)");
  RunAll("VSET V1=1/[V2-V2]\nEND", vars, &alarm);
  EXPECT_EQ(alarm, "S.SDF:1:10: error: division by zero");
  RunAll("N1 GOTO N1\nEND", vars, &alarm);
  EXPECT_EQ(alarm, "S.SDF:1:1: error: the schedule loops without selecting a program");
}

TEST(Schedule, AllComparisonsAndResumeFromPosition) {
  Vars vars;
  vars.v[1] = 3;
  const char* text =
      "IF [V1 LT 3] N9\nIF [V1 GT 3] N9\nIF [V1 NE 3] N9\nIF [V1 EQ 3] N2\nN9 GOTO N99\n"
      "N2 IF [V1 LE 2] N9\nIF [-V1 GE -2] N9\nPSELECT A.MIN,O5,,Q=2\nEND";
  auto prog = std::make_shared<Program>(Parse(text, "S.SDF"));
  Runner r(prog);
  Step s = r.Next(vars);
  ASSERT_EQ(s.kind, Step::Kind::kRun);
  EXPECT_EQ(s.run.program, "O5");
  EXPECT_EQ(s.run.index, 1);
  // A restarted scheduler resumes from the saved position.
  Runner resumed(prog, r.position());
  s = resumed.Next(vars);
  ASSERT_EQ(s.kind, Step::Kind::kRun);
  EXPECT_EQ(s.run.index, 2);
  EXPECT_EQ(resumed.Next(vars).kind, Step::Kind::kEnd);
  EXPECT_EQ(resumed.Next(vars).kind, Step::Kind::kEnd);
}

}  // namespace
}  // namespace cell::scheduler::schedule
