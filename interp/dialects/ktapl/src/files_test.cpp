// Files a KT-APL program writes (manual ch. 7 ln 7886-8395): the inspection header and records byte for byte
// against the manual's examples 7-11 to 7-17, and the completion flags set only when the environment (the
// station: the inspection writer) says the operation is durable.
#include <gtest/gtest.h>

#include "cell/interp/ktapl.h"

namespace cell::interp {
namespace {

// A control with serial number 345879 on pallet 3452 on 13 December 1989 at 12:24 (ln 7898-7906).
class FileEnv : public Environment {
 public:
  std::vector<Canon> asked;
  bool durable = true;
  std::string error;
  std::optional<double> SystemVariable(const std::string& name) override {
    if (name == "L3060") return 345879.0;
    if (name == "L3020") return 3452.0;
    return std::nullopt;
  }
  std::array<int, 6> Now() override { return {1989, 12, 13, 12, 24, 5}; }
  FileResult FileOperation(const Canon& op) override {
    asked.push_back(op);
    FileResult r;
    r.done = durable;
    r.error = error;
    return r;
  }
};

struct Ran {
  std::string file;  // the lines written, each ending in a newline
  std::vector<Op> ops;
  std::map<std::string, double> vars;
  std::string error;
};

Ran RunWith(FileEnv& env, const std::string& text) {
  RunOptions o;
  o.program_name = "F";
  o.program_text = text;
  o.env = &env;
  auto run = KtaplDialect().StartRun(o);
  Ran r;
  for (;;) {
    Step s = run->Next();
    if (s.kind != Step::kCanon) {
      if (s.kind == Step::kError) r.error = s.diag.Format();
      break;
    }
    r.ops.push_back(s.canon.op());
    if (auto* w = std::get_if<FileWriteOp>(&s.canon.p)) r.file += w->text + "\n";
  }
  r.vars = run->Variables();
  return r;
}

TEST(Files, OifWritesTheControlsHeaderThenTheDelimiter) {
  // Example 7-11 (ln 7894-7908): N120G36 N130(OIF,PUMP341).
  FileEnv env;
  Ran r = RunWith(env, "N120G36\nN130(OIF,PUMP341)\nN140G37\n");
  EXPECT_EQ(r.error, "");
  EXPECT_EQ(r.file,
            "CONTROL SERIAL NUMBER = 345879\n"
            "PALLET CODE/PART NUMBER = 3452\n"
            "89:12:13 12:24\n"
            "------------------------------\n");
  ASSERT_GE(env.asked.size(), 2u);
  EXPECT_EQ(env.asked.front().op(), Op::kFileOpen);
  EXPECT_EQ(env.asked.back().op(), Op::kFileClose);  // G37 closes (ln 7910)
}

TEST(Files, BlanksAroundANameSubstitutionAreNotPartOfTheName) {
  // E39 (ln 3818-3830): TEST<L25>, TEST<L25I> and TEST < L25I > < L27I > name TEST123.45600, TEST123 and
  // TEST1231; a blank away from a substitution stays (names like CYL BORES1, ln 8767).
  FileEnv env;
  Ran r =
      RunWith(env,
              "N200 (PAR, L25 = 123.456)\nN300(OPF,TEST<L25>)\nN400 (CLF)\nN500(OPF,TEST<L25I>)\nN600 (CLF)\n"
              "N700 (PAR, L27 = 1.567)\nN800 (OPF, TEST < L25I > < L27I >)\nN900 (CLF)\n"
              "N910 (OPF,CYL BORES<L27I>)\n");
  EXPECT_EQ(r.error, "");
  std::vector<std::string> names;
  for (const Canon& c : env.asked) {
    if (auto* o = std::get_if<FileOpenOp>(&c.p)) names.push_back(o->name);
  }
  EXPECT_EQ(names, (std::vector<std::string>{"TEST123.45600", "TEST123", "TEST1231", "CYL BORES1"}));
}

TEST(Files, MsgLinesAreFollowedByAnEmptyLineWhileTheFileIsOpen) {
  // Example 7-16 (ln 8049-8071).
  FileEnv env;
  Ran r = RunWith(env,
                  "N90 G36\nN100 (OIF, TESTFILE)\nN580 (MSG,THIS WRITTEN WITH \"MSG\".)\nN590 (MSG,THIS IS A "
                  "TEST.)\nN950 G37\n(MSG,NOT WRITTEN)\n");
  EXPECT_EQ(r.error, "");
  EXPECT_EQ(r.file,
            "CONTROL SERIAL NUMBER = 345879\nPALLET CODE/PART NUMBER = 3452\n89:12:13 "
            "12:24\n------------------------------\n"
            "THIS WRITTEN WITH \"MSG\".\n\nTHIS IS A TEST.\n\n");
}

TEST(Files, OpfHasNoHeader) {
  // Example 7-17 (ln 8079-8097): the same with OPF/CLF and no G36: the two text lines only.
  FileEnv env;
  Ran r = RunWith(env,
                  "N100 (OPF, TESTFILE)\nN580 (MSG,THIS WRITTEN WITH \"MSG\".)\nN590 (MSG,THIS IS A TEST.)\n"
                  "N950 (CLF)\n");
  EXPECT_EQ(r.error, "");
  EXPECT_EQ(r.file, "THIS WRITTEN WITH \"MSG\".\n\nTHIS IS A TEST.\n\n");
}

TEST(Files, L1050IsSetOnlyWhenTheCloseIsDurable) {
  // Example 7-14 (ln 7997-8004): L1050 = 0, OPF ... CLF, then the program waits for L1050.
  FileEnv env;
  Ran done = RunWith(env, "N20(PAR,L1050=0)\nN100(OPF,PUMP123)\n(FWR,\"A\")\nN200(CLF)\n");
  EXPECT_EQ(done.error, "");
  EXPECT_DOUBLE_EQ(done.vars["L1050"], 1.0);

  FileEnv slow;
  slow.durable = false;  // the writer has not acknowledged: the flag stays clear
  Ran pending = RunWith(slow, "N20(PAR,L1050=0)\nN100(OPF,PUMP123)\n(FWR,\"A\")\nN200(CLF)\n");
  EXPECT_EQ(pending.error, "");
  EXPECT_DOUBLE_EQ(pending.vars["L1050"], 0.0);
}

TEST(Files, ADeviceErrorStopsTheRunUnlessCerCoversTheDisk) {
  FileEnv env;
  env.error = "FILE ALREADY EXISTS";
  Ran r = RunWith(env, "(OPF,PUMP123)\n");
  EXPECT_NE(r.error.find("FILE ALREADY EXISTS"), std::string::npos) << r.error;

  // (CER,MAS): the warning is a message and the program goes on (ln 8364-8370).
  FileEnv cer;
  cer.error = "FILE ALREADY EXISTS";
  Ran on = RunWith(cer, "(CER,MAS)\n(OPF,PUMP123)\nG71 G0 X1. F0\n");
  EXPECT_EQ(on.error, "");
  EXPECT_NE(std::find(on.ops.begin(), on.ops.end(), Op::kMessage), on.ops.end());
  EXPECT_NE(std::find(on.ops.begin(), on.ops.end(), Op::kRapid), on.ops.end());
}

}  // namespace
}  // namespace cell::interp
