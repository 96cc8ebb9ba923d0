// Predicted cycle times through the real processes (issue 40): a mixed cell (KT01, KT-APL; EM01, EMCO) with
// the program store, the scheduler and each station's interpreter and axis servo on the virtual clock.
// `program show --json` gives the scheduler's prediction per station (a number on the station of the
// program's dialect, null and the reason on the other), `job show` the prediction its allocation used beside
// the cycle_s the station measured, and after the run the estimate has learned from it.
#include <chrono>
#include <cmath>
#include <ctime>
#include <fstream>
#include <functional>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <httplib.h>
#include <nlohmann/json.hpp>

#include "cell/testing/cell_fixture.h"
#include "emco_thread_program.h"

using namespace cell::testing;
using nlohmann::json;

namespace {

class PredictCell : public CellFixture {
 protected:
  PredictCell() : CellFixture("cell-predict-") {}
  void SetUp() override { Up("KT01,EM01"); }

  // The dashboard's /api/plan once `ready` holds of it (it asks the scheduler every 3 s and after job
  // events), or null after 30 s.
  json GanttWhen(const std::function<bool(const json&)>& ready) {
    std::string url = ReadFile(cell_.data_dir() + "/dashboard.url");
    url = url.substr(0, url.find('\n'));
    httplib::Client web("127.0.0.1", std::stoi(url.substr(url.rfind(':') + 1)));
    for (auto until = std::chrono::steady_clock::now() + std::chrono::seconds(30);
         std::chrono::steady_clock::now() < until;
         std::this_thread::sleep_for(std::chrono::milliseconds(200))) {
      auto r = web.Get("/api/plan");
      if (!r || r->status != 200) continue;
      json g = json::parse(r->body, nullptr, false);
      if (g.is_object() && ready(g)) return g;
    }
    return json();
  }
  static json Pallet(const json& rows, int pallet) {
    for (const json& r : rows)
      if (r["pallet"] == pallet) return r;
    return json();
  }
  // Seconds since the epoch of an ISO-8601 UTC time in whole seconds ("2026-11-30T12:00:00Z").
  static double Secs(const json& iso) {
    std::tm tm{};
    const std::string text = iso.is_string() ? iso.get<std::string>() : "";
    if (!strptime(text.c_str(), "%Y-%m-%dT%H:%M:%SZ", &tm)) return -1;
    return static_cast<double>(timegm(&tm));
  }

  void RunCorpus(const std::string& dialect, const std::string& station, int pallet,
                 const std::vector<std::string>& cases);

  // `program show --json` until the scheduler's answer for `station` has come (a number, or the reason there
  // is none): it predicts on a worker of its own, after the first show asked (docs/scheduler.md §14). The
  // last shown at the deadline otherwise. Also prints how long the prediction took to appear.
  json WaitPredicted(const std::string& name, const std::string& station) {
    const auto t0 = std::chrono::steady_clock::now();
    json shown;
    for (;;) {
      shown = CtlJson({"program", "show", name, "--json"});
      const json& why = shown["predicted_why"][station];
      if (shown["predicted_s"][station].is_number() ||
          (why.is_string() && why.get<std::string>().rfind("not predicted yet", 0) != 0))
        break;
      if (std::chrono::steady_clock::now() - t0 > std::chrono::seconds(60)) return shown;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    std::cout << name << " on " << station << ": the prediction appeared after "
              << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() << " s\n";
    return shown;
  }
};

TEST_F(PredictCell, ProgramShowPredictsJobShowComparesAndTheEstimateLearns) {
  const std::string path = cell_.data_dir() + "/THREAD.emco";
  std::ofstream(path) << kEmcoThreadE59;
  auto put = Ctl({"program", "put", path, "--name", "THREAD", "--dialect", "emco"});
  ASSERT_EQ(put.code, 0) << put.out << put.err;

  json shown = WaitPredicted("THREAD", "EM01");
  ASSERT_TRUE(shown["predicted_s"].is_object()) << shown.dump();
  ASSERT_TRUE(shown["predicted_s"]["EM01"].is_number()) << shown.dump();
  const double predicted = shown["predicted_s"]["EM01"].get<double>();
  EXPECT_GT(predicted, 20.12) << shown.dump();
  EXPECT_LT(predicted, 21.36) << shown.dump();
  EXPECT_TRUE(shown["predicted_why"]["EM01"].is_null()) << shown.dump();
  shown = WaitPredicted("THREAD", "KT01");  // asked with EM01's, answered after it
  EXPECT_TRUE(shown["predicted_s"]["KT01"].is_null()) << shown.dump();
  EXPECT_NE(shown["predicted_why"]["KT01"].get<std::string>().find("KT01 runs ktapl"), std::string::npos)
      << shown.dump();
  EXPECT_EQ(shown["estimate_s"]["EM01"], predicted) << shown.dump();
  EXPECT_EQ(shown["estimate_runs"]["EM01"], 0) << shown.dump();

  ASSERT_EQ(Ctl({"route", "define", "EMR", "--op", "EM01:THREAD"}).code, 0);
  auto op = Ctl({"route", "operate", "EMR", "--pallet", "7"});
  ASSERT_EQ(op.code, 0) << op.err;
  const std::string job = op.out.substr(0, op.out.find('\n'));
  // The allocation added the estimate to EM01's backlog (an EMCO program has no UCY).
  auto wait = Ctl({"job", "wait", job, "--timeout", "60"});
  ASSERT_EQ(wait.code, 0) << wait.out << wait.err;
  json j = CtlJson({"job", "show", job, "--json"});
  ASSERT_TRUE(j["cycle_s"].is_number()) << j.dump();
  ASSERT_TRUE(j["predicted_s"].is_number()) << j.dump();
  EXPECT_DOUBLE_EQ(j["predicted_s"].get<double>(), predicted);
  const double actual = j["cycle_s"].get<double>();
  // The same servo model on the same virtual clock: within 1 % (issue 40's target).
  EXPECT_NEAR(predicted, actual, 0.01 * actual) << j.dump();
  std::cout << "THREAD on EM01: predicted " << predicted << " s, actual " << actual << " s\n";

  json after = CtlJson({"program", "show", "THREAD", "--json"});
  EXPECT_EQ(after["estimate_runs"]["EM01"], 1) << after.dump();
  EXPECT_NEAR(after["estimate_s"]["EM01"].get<double>(), actual, 1e-6) << after.dump();  // the first run
  EXPECT_EQ(after["predicted_s"]["EM01"], predicted) << after.dump();
}

// KT-APL corpus programs (those station_corpus_test runs on KT01), each as a pallet run one after another:
// the prediction its allocation used against the machine seconds KT01 measured (the figures are printed).
// A prediction is for the run from the state a pallet arrives in (docs/predict.md, judgement call 4), and
// the servo starts every run from there whatever the run before left (Machine::ToArrival): each agrees
// within 1 % (issue 40's target), not only the first (before that: 0.95-1.04 for the later ones, their first
// approach move and tool change from where the last run left the axes and the magazine).
// Also p2_6_01_g98_at_centre: its FWR between two moves waits for the inspection writer, wall time in which
// the servo let the axes settle on (0.22 machine seconds, 0.84 against the prediction) until it stood still
// while every segment sent had completed (Receiver::AwaitingProducer).
TEST_F(PredictCell, CorpusProgramsOnKt01) {
  RunCorpus("ktapl", "KT01", 10,
            {"p2_5_25_arc_cw_absolute", "p2_5_27_full_circle", "p2_5_32_helix", "p2_5_33_r_arc",
             "p2_5_34_r_sign", "p1_e23_cls_run_count", "p1_e10_g82", "p2_6_01_g98_at_centre"});
}

// Two EMCO threads one after another (G33, manual ln 2302-2355): each waits for the spindle's index mark, and
// the second run's spindle starts from the index mark as the first's did (the pallet's arrival orients it,
// Machine::ToArrival); before, it started wherever the first run had stopped it (0.989).
TEST_F(PredictCell, ThreadsOneAfterAnotherOnEm01) {
  RunCorpus("emco", "EM01", 30, {"e41_g33_abs", "e41_g33_inc", "e41_g33_abs"});
}

// Each corpus program of `dialect` as a pallet run on `station`, one after another from pallet `pallet`: the
// prediction its allocation used against the machine seconds the station measured (printed), within 1 %.
void PredictCell::RunCorpus(const std::string& dialect, const std::string& station, int pallet,
                            const std::vector<std::string>& cases) {
  for (const auto& c : cases) {
    const std::string name = "C" + std::to_string(pallet);
    auto put = Ctl({"program", "put", SourceDir() + "/tests/conformance/" + dialect + "/" + c + "." + dialect,
                    "--name", name, "--dialect", dialect});
    ASSERT_EQ(put.code, 0) << c << ": " << put.out << put.err;
    // The allocation uses a prediction only once it is there: wait for it, as an operator would look.
    const json shown = WaitPredicted(name, station);
    ASSERT_TRUE(shown["predicted_s"][station].is_number()) << c << ": " << shown.dump();
    ASSERT_EQ(Ctl({"pallet", "set", std::to_string(pallet), name}).code, 0);
    auto run = Ctl({"pallet", "run", std::to_string(pallet), "--station", station});
    ASSERT_EQ(run.code, 0) << run.err;
    const std::string job = run.out.substr(0, run.out.find('\n'));
    auto wait = Ctl({"job", "wait", job, "--timeout", "60"});
    ASSERT_EQ(wait.code, 0) << c << ": " << wait.out << wait.err;
    json j = CtlJson({"job", "show", job, "--json"});
    ASSERT_TRUE(j["predicted_s"].is_number()) << c << ": " << j.dump();
    const double predicted = j["predicted_s"].get<double>(), actual = j["cycle_s"].get<double>();
    std::cout << c << " on " << station << ": predicted " << predicted << " s, actual " << actual
              << " s, ratio " << predicted / actual << "\n";
    EXPECT_NEAR(predicted, actual, 0.01 * actual) << c;
    ++pallet;
  }
}

// `cellctl plan`: a pallet whose only station is down waits, with the reason, and no times; the dashboard's
// Gantt chart shows the same plan.
TEST_F(PredictCell, PlanShowsAWaitingPalletAndTheDashboardDrawsIt) {
  const std::string path = cell_.data_dir() + "/P1.ktapl";
  std::ofstream(path) << "%\n(NAM,P1)\n(UCY,120)\nG71 G90\nG0 X100. Y100. Z100. F0\nM30\n";
  ASSERT_EQ(Ctl({"program", "put", path, "--name", "P1", "--dialect", "ktapl"}).code, 0);
  ASSERT_EQ(Ctl({"route", "define", "W", "--op", "KT02:P1"}).code, 0);
  auto op = Ctl({"route", "operate", "W", "--pallet", "3"});
  ASSERT_EQ(op.code, 0) << op.err;
  json plan = CtlJson({"plan", "--json"});
  ASSERT_TRUE(plan.is_array()) << plan.dump();
  ASSERT_EQ(plan.size(), 1u) << plan.dump();
  EXPECT_EQ(plan[0]["pallet"], 3);
  EXPECT_EQ(plan[0]["route"], "W");
  EXPECT_EQ(plan[0]["op"], 1);
  EXPECT_TRUE(plan[0]["start"].is_null()) << plan.dump();
  EXPECT_TRUE(plan[0]["end"].is_null()) << plan.dump();
  EXPECT_NE(plan[0]["waiting_for"].get<std::string>().find("KT02"), std::string::npos) << plan.dump();

  // The dashboard's Gantt chart (issue 40 item 4): KT01 stops its first pallet at an M00, so the second is
  // queued behind it; /api/plan lists both on KT01 with their times as `cellctl plan --json` does, the
  // waiting pallet with its reason, and what ran so far.
  const std::string stop = cell_.data_dir() + "/S1.ktapl";
  std::ofstream(stop) << "%\n(NAM,S1)\n(UCY,300)\nG71 G90\nG0 X100. Y100. Z100. F0\nM00\nM30\n";
  ASSERT_EQ(Ctl({"program", "put", stop, "--name", "S1", "--dialect", "ktapl"}).code, 0);
  ASSERT_EQ(Ctl({"route", "define", "G", "--op", "KT01:S1"}).code, 0);
  ASSERT_EQ(Ctl({"route", "operate", "G", "--pallet", "4"}).code, 0);
  ASSERT_EQ(Ctl({"route", "operate", "G", "--pallet", "5"}).code, 0);
  const json gantt = GanttWhen([](const json& g) {
    for (const json& r : g["planned"])
      if (r["pallet"] == 5) return true;
    return false;
  });
  plan = CtlJson({"plan", "--json"});
  std::cout << "cellctl plan: " << plan.dump() << "\n/api/plan: " << gantt.dump() << "\n";
  ASSERT_TRUE(gantt.is_object()) << "no /api/plan with pallet 5";
  EXPECT_TRUE(gantt["error"].is_null()) << gantt.dump();
  for (int pallet : {4, 5}) {
    const json want = Pallet(plan, pallet), got = Pallet(gantt["planned"], pallet);
    ASSERT_TRUE(want.is_object() && got.is_object()) << pallet << plan.dump() << gantt.dump();
    EXPECT_EQ(got["station"], "KT01");
    EXPECT_EQ(got["job"], want["job"]);
    EXPECT_EQ(got["op"], want["op"]);
    EXPECT_EQ(got["station"], want["station"]);
    // The dashboard's plan is at most a few seconds older than cellctl's: the same visits, as long.
    EXPECT_NEAR(Secs(got["start"]), Secs(want["start"]), 10) << pallet;
    EXPECT_NEAR(Secs(got["end"]), Secs(want["end"]), 10) << pallet;
    EXPECT_NEAR(Secs(got["end"]) - Secs(got["start"]), Secs(want["end"]) - Secs(want["start"]), 2) << pallet;
  }
  // Pallet 5 follows pallet 4 on KT01, its 300 s of UCY after it; pallet 3 waits with its reason.
  EXPECT_EQ(Pallet(gantt["planned"], 5)["start"], Pallet(gantt["planned"], 4)["end"]);
  EXPECT_NEAR(Secs(Pallet(gantt["planned"], 5)["end"]) - Secs(Pallet(gantt["planned"], 5)["start"]), 300, 1);
  ASSERT_TRUE(Pallet(gantt["waiting"], 3).is_object()) << gantt.dump();
  EXPECT_NE(Pallet(gantt["waiting"], 3)["waiting_for"].get<std::string>().find("KT02"), std::string::npos);
  EXPECT_EQ(gantt["next"]["KT01"]["pallet"], 5) << gantt.dump();
  const json ran = GanttWhen([](const json& g) { return !g["ran"].empty(); });
  ASSERT_TRUE(ran.is_object()) << "the dashboard saw nothing run";
  EXPECT_EQ(ran["ran"][0]["station"], "KT01");
  EXPECT_EQ(ran["ran"][0]["pallet"], 4);
  EXPECT_TRUE(ran["ran"][0]["end"].is_null()) << "pallet 4 is stopped at its M00, not ended";
}

}  // namespace
