// Runs through the library: what the CLI corpus cannot see (variables in and out, files saved for the
// station, library look-ups, the environment's probe answers).
#include <gtest/gtest.h>

#include <map>

#include "cell/error/error.h"
#include "cell/interp/balt.h"

namespace cell::interp {
namespace {

std::vector<Canon> RunAll(RunOptions opt, std::unique_ptr<cell::interp::Run>* keep = nullptr,
                          std::string* error = nullptr) {
  opt.program_name = "test";
  auto run = BaltDialect().StartRun(opt);
  std::vector<Canon> out;
  for (;;) {
    Step s = run->Next();
    if (s.kind == Step::kCanon) {
      out.push_back(s.canon);
      continue;
    }
    if (s.kind == Step::kError && error) *error = s.diag.Format();
    break;
  }
  if (keep) *keep = std::move(run);
  return out;
}

// E parameters come in by their names and go out changed (DESIGN §6 station vars).
TEST(BaltRun, VariablesInAndOut) {
  RunOptions opt;
  opt.variables = {{"E30", 2.5}, {"E1", 7}, {"L5", 1}};
  opt.program_text = "E31=E30*2\nE2=E1+0.6\nE25=0.1\n";
  std::unique_ptr<cell::interp::Run> run;
  RunAll(opt, &run);
  auto v = run->Variables();
  EXPECT_DOUBLE_EQ(v["E30"], 2.5);
  EXPECT_DOUBLE_EQ(v["E31"], 5);
  EXPECT_DOUBLE_EQ(v["E2"], 8);                           // a byte: 7.6 rounds to 8
  EXPECT_DOUBLE_EQ(v["E25"], static_cast<double>(0.1f));  // RE keeps 7 digits
  EXPECT_EQ(v.count("L5"), 0u);
}

// A station keeps every E parameter within its format (ln 5497, Table 5.8); what a run reports is kept.
TEST(BaltRun, KeptVariables) {
  const Dialect& b = BaltDialect();
  EXPECT_EQ(b.CheckVariable("E0", 255), "");
  EXPECT_EQ(b.CheckVariable("E19", -32768), "");
  EXPECT_EQ(b.CheckVariable("E999", 1.5e12), "");
  for (const char* bad : {"E", "E01", "e3", "L1500", "E12345", "E3X", ""})
    EXPECT_NE(b.CheckVariable(bad, 1).find("E0..E9999"), std::string::npos) << bad;
  EXPECT_NE(b.CheckVariable("E3", 256).find("byte"), std::string::npos);
  EXPECT_NE(b.CheckVariable("E12", 1.5).find("integer"), std::string::npos);
  EXPECT_NE(b.CheckVariable("E40", 1e14).find("long real"), std::string::npos);
  RunOptions opt;
  opt.variables = {{"E30", 2.5}};
  opt.program_text = "E31=E30*2\nE2=E1+0.6\nE25=0.1\nE12=-7\n";
  std::unique_ptr<cell::interp::Run> run;
  RunAll(opt, &run);
  for (const auto& [name, value] : run->Variables()) EXPECT_EQ(b.CheckVariable(name, value), "") << name;
}

// RQO changes the origin file, TOF the tool life file: both are handed to `save` for the station's memory.
TEST(BaltRun, SavesTheFilesItChanges) {
  std::map<std::string, std::string> lib = {
      {"FILEOR", "0 X0 Y0 Z0\n3 X10\n"},
      {"GE1TOL", "VTU,13,T14,[TOOL COMP]14,t60,t2,t60,B\nVTU,14,T14,[TOOL COMP]14,t60,t2,t60,B\n"}};
  std::map<std::string, std::string> saved;
  RunOptions opt;
  opt.library = [&](const std::string& n) -> std::optional<std::string> {
    auto it = lib.find(n);
    return it == lib.end() ? std::nullopt : std::optional<std::string>(it->second);
  };
  opt.save = [&](const std::string& n, const std::string& text) { saved[n] = text; };
  opt.program_text = "E31=0.25\n(RQO,3,XE31)\nT13.13 M6\n(TOF,13)\nM30\n";
  std::string err;
  RunAll(opt, nullptr, &err);
  EXPECT_EQ(err, "");
  EXPECT_NE(saved["FILEOR/MP3"].find("3 X+10.250"), std::string::npos) << saved["FILEOR/MP3"];
  EXPECT_NE(saved["GE1TOL/MP3"].find("VTU,13,T14,[TOOL COMP]14,t60,t2,t60,A"), std::string::npos)
      << saved["GE1TOL/MP3"];
}

// A memory that cannot take the changed file (the store's FILMS3 15 NO FREE SECTORS, ln 223, 9758-9759)
// stops the run at the block that changed it, with the store's message: the change is not kept silently.
TEST(BaltRun, AFullMemoryStopsTheRunThatSavesIntoIt) {
  std::map<std::string, std::string> lib = {{"FILEOR", "0 X0 Y0 Z0\n3 X10\n"}};
  RunOptions opt;
  opt.library = [&](const std::string& n) -> std::optional<std::string> {
    auto it = lib.find(n);
    return it == lib.end() ? std::nullopt : std::optional<std::string>(it->second);
  };
  opt.save = [](const std::string&, const std::string&) {
    throw cell::Error(cell::Errc::kFailedPrecondition, "[FILMS3 15] NO FREE SECTORS: BS01/MP3 is full");
  };
  opt.program_text = "G0 X1\n(RQO,3,X0.25)\nG0 X2\n";
  std::string err;
  auto out = RunAll(opt, nullptr, &err);
  EXPECT_NE(err.find(":2:1: error: [FILMS3 15] NO FREE SECTORS: BS01/MP3 is full"), std::string::npos) << err;
  ASSERT_FALSE(out.empty());
  EXPECT_EQ(out.back().line, 1);  // nothing after the refused block
}

// RQU changes the tool table the run hands back (Run::Tools) and says so in a tool_data op.
TEST(BaltRun, RequalificationChangesTheToolTable) {
  RunOptions opt;
  opt.tools = BaltDialect().ParseToolTable("10 Z100 K20\n", "t", {});
  opt.program_text = "(RQU,10,10,Z0.2,K-0.1)\n";
  std::unique_ptr<cell::interp::Run> run;
  auto out = RunAll(opt, &run);
  ASSERT_FALSE(out.empty());
  EXPECT_EQ(out.back().op(), Op::kToolData);
  auto t = run->Tools();
  EXPECT_NEAR(t.Find("10")->length, 100.2, 1e-9);
  EXPECT_NEAR(t.Find("10")->diameter, 19.9, 1e-9);
}

// A probe contact from the environment: G72 stores the touching point, probe-radius compensated.
class Wall : public Environment {
 public:
  ProbeResult Probe(const ProbeMove& m) override {
    const AxisArray& from = m.from;
    const AxisArray& to = m.to;
    ProbeResult r;
    if ((from[kX] - 50) * (to[kX] - 50) <= 0) {
      r.event = true;
      r.at = from;
      r.at[kX] = 50;
    }
    return r;
  }
};

TEST(BaltRun, ProbeThroughTheEnvironment) {
  Wall wall;
  RunOptions opt;
  opt.env = &wall;
  opt.tools = BaltDialect().ParseToolTable("30 Z0 K6\n", "t", {});
  opt.program_text = "T30.30 M6\n(DPT,10,5,500)\nG72 X50 Y0 E40\n";
  std::unique_ptr<cell::interp::Run> run;
  std::string err;
  RunAll(opt, &run, &err);
  EXPECT_EQ(err, "");
  EXPECT_NEAR(run->Variables()["E40"], 50, 1e-9);
  EXPECT_NEAR(run->Variables()["E41"], 0, 1e-9);
}

// '#' (ln 7536-7586): the block waits for the machine to finish what came before it. The environment is asked
// once, after the moves before the block have been handed out, and not for blocks without '#'.
class SyncLog : public Environment {
 public:
  explicit SyncLog(const std::vector<Canon>& out) : out_(out) {}
  void Synchronize() override { seen.push_back(out_.size()); }
  std::vector<std::size_t> seen;

 private:
  const std::vector<Canon>& out_;
};

TEST(BaltRun, SynchronisedBlockWaitsForTheMachine) {
  std::vector<Canon> out;
  SyncLog log(out);
  RunOptions opt;
  opt.env = &log;
  opt.program_name = "test";
  opt.program_text = "G1 X10 F100\nN20 #(DLY,1)\nG1 X20\n&SK5=1\n";
  auto run = BaltDialect().StartRun(opt);
  for (Step st = run->Next(); st.kind == Step::kCanon; st = run->Next()) out.push_back(st.canon);
  ASSERT_EQ(log.seen.size(), 1u);
  EXPECT_EQ(log.seen[0], 2u);  // units and the X10 move were out before the '#' block ran
  EXPECT_EQ(out.size(), 5u);   // then its dwell, the X20 move, the SK5 output
}

TEST(BaltRun, ReportsTheFirstErrorWithItsAlarm) {
  RunOptions opt;
  opt.program_text = "G1 X10 F100\n(BNC,NOWHR)\n";
  std::string err;
  auto out = RunAll(opt, nullptr, &err);
  EXPECT_EQ(err, "test:2:6: error: [FILMS4 34] UNDEFINED LABEL: \"NOWHR\"");
  EXPECT_EQ(out.size(), 2u);  // units and the move before the error
}

// CLS finds a %:NAME program of the main file wherever it is: the search goes a MiB at a time (a mapped file
// gives the searched pages back), so headers across, at and past window boundaries must all be found, and a
// name that only starts like the header ("%:SUBAX") or is not at a line start is not it.
TEST(BaltRun, ClsFindsProgramsOfTheMainFileFarAway) {
  for (std::size_t filler : {std::size_t{0}, (std::size_t{1} << 20) - 40, (std::size_t{1} << 20) + 3,
                             (std::size_t{3} << 20) + 17}) {
    RunOptions opt;
    std::string text = "%:MAIN\n(CLS,SUBA)\nM30\n%\n%:SUBAX\nG X99\n%\n; %:SUBA\n";
    while (text.size() < filler) text += "; filler filler filler filler filler\n";
    text += "%:SUBA\nG X7\n%\n";
    opt.program_text = text;
    std::string error;
    auto out = RunAll(opt, nullptr, &error);
    ASSERT_EQ(error, "") << filler;
    ASSERT_FALSE(out.empty()) << filler;
    bool moved = false;
    for (const Canon& c : out) {
      if (const auto* r = c.If<RapidOp>()) moved = moved || r->to.pos[0] == 7;
    }
    EXPECT_TRUE(moved) << filler;
  }
}

}  // namespace
}  // namespace cell::interp
