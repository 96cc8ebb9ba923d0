// The interpreter service runs the same programs on a station (issue 4): a handful of positive KT-APL
// conformance programs with motion go through the program store, a pallet map and the station KT01
// (interpreter + axis servo on the virtual clock) to a COMPLETED job with machine time; a negative-corpus
// program fails the job with the interpreter's compiler-style diagnostic as its reason.
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cell/testing/cell_fixture.h"

using namespace cell::testing;
using nlohmann::json;

namespace {

const std::string kCorpus = "/tests/conformance/ktapl/";

class StationCorpus : public CellFixture {
 protected:
  StationCorpus() : CellFixture("cell-station-corpus-") {}
  void SetUp() override { Up("KT01"); }
  void Put(const std::string& corpus_case, const std::string& name) {
    auto r = Ctl({"program", "put", SourceDir() + kCorpus + corpus_case + ".ktapl", "--name", name,
                  "--dialect", "ktapl"});
    ASSERT_EQ(r.code, 0) << corpus_case << ": " << r.out << r.err;
  }
  // A program that is not a corpus file (it needs the station's own tools).
  void PutText(const std::string& text, const std::string& name) {
    std::string path = cell_.data_dir() + "/" + name + ".ktapl";
    std::ofstream(path) << text;
    auto r = Ctl({"program", "put", path, "--name", name, "--dialect", "ktapl"});
    ASSERT_EQ(r.code, 0) << name << ": " << r.out << r.err;
  }
  // Maps the programs to pallet P, runs it on KT01 and waits for the end; returns the job id.
  std::string RunPallet(const std::string& pallet, const std::vector<std::string>& names,
                        int expect_wait_code) {
    std::vector<std::string> set = {"pallet", "set", pallet};
    set.insert(set.end(), names.begin(), names.end());
    auto s = Ctl(set);
    EXPECT_EQ(s.code, 0) << s.err;
    auto run = Ctl({"pallet", "run", pallet, "--station", "KT01"});
    EXPECT_EQ(run.code, 0) << run.err;
    std::string job = run.out.substr(0, run.out.find('\n'));
    auto wait = Ctl({"job", "wait", job, "--timeout", "40"});
    EXPECT_EQ(wait.code, expect_wait_code) << wait.out << wait.err;
    return job;
  }
};

TEST_F(StationCorpus, PositiveProgramsWithMotionComplete) {
  // Arcs (absolute, full circle, helix, R with both signs), DFS/CLS with a run count and the App. D G82
  // cycle from the shipped library; all inside KT01's travel (X -5..800, Y -5..700, Z -5..750 mm) and
  // without tools the station does not have (the corpus's 8-9 and 9-4 programs leave that envelope).
  const std::vector<std::pair<std::string, std::string>> cases = {{"p2_5_25_arc_cw_absolute", "ARC25"},
                                                                  {"p2_5_27_full_circle", "CIRC27"},
                                                                  {"p2_5_32_helix", "HELIX32"},
                                                                  {"p2_5_33_r_arc", "RARC33"},
                                                                  {"p2_5_34_r_sign", "RSIGN34"},
                                                                  {"p1_e23_cls_run_count", "CLSE23"},
                                                                  {"p1_e10_g82", "G82E10"}};
  std::vector<std::string> names;
  for (auto& [c, n] : cases) {
    Put(c, n);
    names.push_back(n);
  }
  // Cutter compensation on the station (the corpus's cc_* cases use a T1 that KT01 does not have): KT01's
  // T1002 (D 12.7 mm) round an outside square with G41, fill-in arcs at the corners, G40 ramp-off.
  PutText(
      "%\n(NAM,CCSQ)\nG71 T1002\nM06\nG90 G0 X100. Y100. Z100. F0\nG1 Z50. F500.\nG41 X120. Y100.\n"
      "Y200.\nX220.\nY100.\nX120.\nG40 X100.\nG0 Z100. F0\nM30\n",
      "CCSQ");
  names.push_back("CCSQ");
  std::string job = RunPallet("5", names, 0);
  auto shown = CtlJson({"job", "show", job, "--json"});
  ASSERT_TRUE(shown.is_object());
  EXPECT_EQ(shown["state"], "COMPLETED") << shown.dump();
  EXPECT_EQ(shown["station"], "KT01");
  EXPECT_TRUE(shown["reason"].is_null()) << shown.dump();
  ASSERT_TRUE(shown["cycle_s"].is_number()) << shown.dump();
  EXPECT_GT(shown["cycle_s"].get<double>(), 0.0);

  // The durable run record: every program ran, with positive machine time from the servo's clock.
  auto list = CtlJson({"inspect", "ls", "run-KT01-*", "--json"});
  ASSERT_TRUE(list.is_array());
  ASSERT_EQ(list.size(), 1u) << list.dump();
  auto rec = Ctl({"inspect", "cat", list[0]["name"].get<std::string>()});
  ASSERT_EQ(rec.code, 0) << rec.err;
  auto r = json::parse(rec.out, nullptr, false);
  ASSERT_TRUE(r.is_object()) << rec.out;
  EXPECT_EQ(r["station"], "KT01");
  EXPECT_EQ(r["pallet"], 5);
  EXPECT_EQ(r["programs"], json(names));
  EXPECT_EQ(r["completed"], true);
  ASSERT_TRUE(r["machine_s"].is_number()) << rec.out;
  EXPECT_GT(r["machine_s"].get<double>(), 0.0);
  EXPECT_NEAR(r["machine_s"].get<double>(), shown["cycle_s"].get<double>(), 1e-6);
}

TEST_F(StationCorpus, ProgramErrorFailsTheJobWithTheDiagnostic) {
  // App. D: every fixed cycle starts (IFT,G91,M99M0G80); the corpus expects the M99 alarm at 3:1.
  Put("neg_g91_fixed_cycle", "BADCYC");
  std::string diag = ReadFile(SourceDir() + kCorpus + "neg_g91_fixed_cycle.diag");
  diag = diag.substr(0, diag.find('\n'));
  const std::string prefix = "neg_g91_fixed_cycle.ktapl";
  ASSERT_EQ(diag.rfind(prefix, 0), 0u) << diag;
  diag = "BADCYC" + diag.substr(prefix.size());  // PROGRAM is the stored name on a station
  ASSERT_NE(diag.find(":3:1: error: [M99] "), std::string::npos) << diag;

  std::string job = RunPallet("6", {"BADCYC"}, 1);
  auto shown = CtlJson({"job", "show", job, "--json"});
  ASSERT_TRUE(shown.is_object());
  EXPECT_EQ(shown["state"], "FAILED") << shown.dump();
  ASSERT_TRUE(shown["reason"].is_string()) << shown.dump();
  EXPECT_NE(shown["reason"].get<std::string>().find(diag), std::string::npos)
      << "reason: " << shown["reason"] << "\nwanted: " << diag;
}

}  // namespace
