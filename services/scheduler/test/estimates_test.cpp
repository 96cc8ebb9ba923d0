// Predicted and learned cycle times in the scheduler (docs/scheduler.md "Estimates"): the backlog of a
// program without UCY is its estimate on the winning station, a stated UCY wins, each visit teaches the
// estimate by LearnEstimate's bounded rule, and predictions are kept with the program's revision. The
// scheduler only asks for predictions: these tests answer them when they choose (the service's
// PredictionQueue does it on its worker, prediction_queue_test.cpp).
#include "cell/scheduler/estimates.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <utility>

#include "cell/scheduler/json.h"
#include "cell/scheduler/scheduler.h"
#include "fake_cell.h"

namespace cell::scheduler {
namespace {

using testing::FakeCell;
using testing::TempDir;

class FakePredictor : public Predictor {
 public:
  Predicted Predict(std::string_view program, std::string_view station, std::chrono::milliseconds,
                    std::stop_token) override {
    ++calls;
    if (transient) return {std::nullopt, "the program store did not answer", true};
    auto it = seconds.find({std::string(program), std::string(station)});
    if (it == seconds.end()) return {std::nullopt, "waits for inputs"};
    return {it->second, ""};
  }
  std::string Basis(std::string_view) override { return basis; }
  std::map<std::pair<std::string, std::string>, double> seconds;
  std::string basis = "b1";
  bool transient = false;
  int calls = 0;
};

// The scheduler's asks, kept until the test answers them.
struct Asks {
  std::vector<PredictionRequest> requests;
  void Attach(FakeCell& c, Predictor& p) {
    c.sched->SetPredictor(&p, [this](const PredictionRequest& r) { requests.push_back(r); });
  }
  // Answers each distinct request asked so far with `p`; returns how many there were.
  std::size_t Answer(FakeCell& c, FakePredictor& p) {
    std::vector<PredictionRequest> asked = std::exchange(requests, {});
    std::sort(asked.begin(), asked.end());
    asked.erase(std::unique(asked.begin(), asked.end()), asked.end());
    for (const auto& r : asked)
      c.Take(c.sched->PredictionAnswered(r, p.Predict(r.program, r.station, std::chrono::seconds(10), {})));
    return asked.size();
  }
};

const char* kEmco = "%\nN0010 G00 X50. Z10.\nN0020 M30\n";

void Emco(FakeCell& c, const std::string& id) {
  c.Take(c.sched->StationOnline(id, "emco"));
  c.Take(c.sched->StationTools(id, testing::Tools({})));
}

TEST(LearnEstimate, MeanOfTheFirstRunsThenAMovingAverageWithinBounds) {
  EXPECT_DOUBLE_EQ(LearnEstimate(100, 100, 120, 0), 120);                       // weight 1: the first run
  EXPECT_DOUBLE_EQ(LearnEstimate(120, 100, 110, 1), 115);                       // 1/2: the mean of two
  EXPECT_DOUBLE_EQ(LearnEstimate(115, 100, 1000, 2), 115 + (200 - 115) / 3.0);  // 1000 counts as 2 x 100
  EXPECT_DOUBLE_EQ(LearnEstimate(100, 100, 10, 2), 100 + (50 - 100) / 3.0);     // 10 counts as 0.5 x 100
  EXPECT_DOUBLE_EQ(LearnEstimate(100, 100, 150, 9), 110);                       // 1/10 < 0.2: weight 0.2
}

// A program without UCY (an EMCO program has none) adds its prediction on the station that wins.
TEST(Estimates, ProgramWithoutUcyAddsItsEstimateOnTheWinner) {
  FakeCell c;
  FakePredictor p;
  p.seconds[{"TURN", "EM01"}] = 95.4;
  p.seconds[{"TURN", "EM02"}] = 80.0;
  Asks asks;
  asks.Attach(c, p);
  c.programs.Put("TURN", kEmco, "emco");
  Emco(c, "EM01");
  Emco(c, "EM02");
  c.Route("R", {"EM01,EM02:TURN"});
  EXPECT_EQ(asks.Answer(c, p), 2u);  // asked when the route was defined, on both of its stations
  const std::int64_t j1 = c.Operate("R", 1);
  EXPECT_EQ(c.StationOf(j1), "EM01");  // both at 0 s: listed first
  EXPECT_EQ(c.Backlog("EM01"), 95);    // 95.4 s rounded
  const std::int64_t j2 = c.Operate("R", 2);
  EXPECT_EQ(c.StationOf(j2), "EM02");
  EXPECT_EQ(c.Backlog("EM02"), 80);
  EXPECT_DOUBLE_EQ(c.sched->Job(j1)->predicted_s.value(), 95.4);
  EXPECT_EQ(ToJson(*c.sched->Job(j2), true)["predicted_s"], 80.0);
  c.Complete(c.InHand("EM01").dispatch_id, 100.0);
  EXPECT_EQ(c.Backlog("EM01"), 0);
}

// UCY is the program's own statement (seed 4136): it stays the backlog; the prediction is shown beside it.
TEST(Estimates, StatedUcyWins) {
  FakeCell c;
  FakePredictor p;
  p.seconds[{"P1", "KT01"}] = 100.0;
  Asks asks;
  asks.Attach(c, p);
  c.Program("P1", {}, 300);
  c.Online("KT01");
  c.Route("R", {"KT01:P1"});
  asks.Answer(c, p);
  const std::int64_t j = c.Operate("R", 1);
  EXPECT_EQ(c.Backlog("KT01"), 300);
  EXPECT_DOUBLE_EQ(c.sched->Job(j)->predicted_s.value(), 100.0);
}

TEST(Estimates, EachVisitTeachesTheEstimate) {
  FakeCell c;
  FakePredictor p;
  p.seconds[{"TURN", "EM01"}] = 100.0;
  Asks asks;
  asks.Attach(c, p);
  c.programs.Put("TURN", kEmco, "emco");
  Emco(c, "EM01");
  c.Route("R", {"EM01:TURN"});
  asks.Answer(c, p);
  const double actual[] = {120, 110, 1000};
  for (int i = 0; i < 3; ++i) {
    c.Operate("R", i + 1);
    c.Complete(c.InHand("EM01").dispatch_id, actual[i]);
  }
  ProgramEstimates e = c.sched->Estimates("TURN");
  ASSERT_EQ(e.stations.size(), 1u);
  EXPECT_DOUBLE_EQ(e.stations[0].predicted_s.value(), 100.0);
  EXPECT_EQ(e.stations[0].runs, 3);
  EXPECT_NEAR(e.stations[0].estimate_s.value(), 115 + 85 / 3.0, 1e-9);
  c.Operate("R", 9);
  EXPECT_EQ(c.Backlog("EM01"), 143);  // the learned 143.3 s, not the predicted 100 s
}

TEST(Estimates, KeptWithTheRevisionAcrossARestart) {
  TempDir dir;
  FakeCell c(dir.db());
  FakePredictor p;
  p.seconds[{"TURN", "EM01"}] = 42.0;
  Asks asks;
  asks.Attach(c, p);
  c.programs.Put("TURN", kEmco, "emco");
  Emco(c, "EM01");
  Emco(c, "EM02");
  ProgramEstimates e = c.sched->Estimates("TURN");
  ASSERT_EQ(e.stations.size(), 2u);
  EXPECT_FALSE(e.stations[0].predicted_s);  // asked for, not made by the call
  EXPECT_EQ(e.stations[0].why, "not predicted yet: asked for");
  EXPECT_EQ(p.calls, 0);
  EXPECT_EQ(asks.Answer(c, p), 2u);
  e = c.sched->Estimates("TURN");
  EXPECT_EQ(e.stations[0].predicted_s, 42.0);
  EXPECT_FALSE(e.stations[1].predicted_s);
  EXPECT_EQ(e.stations[1].why, "waits for inputs");  // a definite answer without a number: kept
  EXPECT_EQ(p.calls, 2);
  c.sched->Estimates("TURN");
  EXPECT_EQ(asks.Answer(c, p), 0u);  // kept
  c.Restart();
  asks.Attach(c, p);
  EXPECT_EQ(c.sched->Estimates("TURN").stations[0].estimate_s, 42.0);
  EXPECT_EQ(asks.Answer(c, p), 0u);  // kept in the database
  c.programs.Put("TURN", std::string(kEmco) + "\n", "emco");
  c.sched->Estimates("TURN");
  EXPECT_EQ(asks.Answer(c, p), 2u);  // a new revision is predicted again
  p.basis = "b2";
  c.sched->Estimates("TURN");
  EXPECT_EQ(asks.Answer(c, p), 2u);  // and so is a changed station model
  EXPECT_EQ(p.calls, 6);
}

// A transient failure (the program store did not answer, the time limit passed) is not kept: the pair is
// asked for again at its next need, and the allocation meanwhile counts what it would without a predictor.
TEST(Estimates, TransientFailureIsNotKept) {
  FakeCell c;
  FakePredictor p;
  p.seconds[{"TURN", "EM01"}] = 60.0;
  p.transient = true;
  Asks asks;
  asks.Attach(c, p);
  c.programs.Put("TURN", kEmco, "emco");
  Emco(c, "EM01");
  c.Route("R", {"EM01:TURN"});
  EXPECT_EQ(asks.Answer(c, p), 1u);
  ASSERT_FALSE(c.notes.empty());
  EXPECT_NE(c.notes.back().find("not made (the program store did not answer)"), std::string::npos)
      << c.notes.back();
  EXPECT_EQ(c.sched->Estimates("TURN").stations[0].why, "not predicted yet: asked for");
  const std::int64_t j1 = c.Operate("R", 1);
  EXPECT_EQ(c.Backlog("EM01"), 0);
  EXPECT_FALSE(c.sched->Job(j1)->predicted_s);
  p.transient = false;
  EXPECT_EQ(asks.Answer(c, p), 1u);  // asked again (program show and the allocation: one request)
  c.Operate("R", 2);
  EXPECT_EQ(c.Backlog("EM01"), 60);
}

// Until the answer comes, an allocation counts UCY or nothing, as before predictions; the next one uses it.
TEST(Estimates, AllocationDoesNotWaitForThePrediction) {
  FakeCell c;
  FakePredictor p;
  p.seconds[{"TURN", "EM01"}] = 50.0;
  Asks asks;
  asks.Attach(c, p);
  c.programs.Put("TURN", kEmco, "emco");
  Emco(c, "EM01");
  c.Route("R", {"EM01:TURN"});
  const std::int64_t j1 = c.Operate("R", 1);
  EXPECT_EQ(c.StationOf(j1), "EM01");
  EXPECT_EQ(c.Backlog("EM01"), 0);
  EXPECT_FALSE(c.sched->Job(j1)->predicted_s);
  EXPECT_EQ(p.calls, 0);
  asks.Answer(c, p);
  const std::int64_t j2 = c.Operate("R", 2);
  EXPECT_EQ(c.Backlog("EM01"), 50);
  EXPECT_DOUBLE_EQ(c.sched->Job(j2)->predicted_s.value(), 50.0);
}

// Without a predictor the backlog is UCY alone, as before.
TEST(Estimates, NoPredictorNoEstimate) {
  FakeCell c;
  c.programs.Put("TURN", kEmco, "emco");
  Emco(c, "EM01");
  c.Route("R", {"EM01:TURN"});
  const std::int64_t j = c.Operate("R", 1);
  EXPECT_EQ(c.Backlog("EM01"), 0);
  EXPECT_FALSE(c.sched->Job(j)->predicted_s);
  EXPECT_EQ(c.sched->Estimates("TURN").stations[0].why, "no predictor");
}

// The plan runs the allocation rule forward on the estimates: three pallets through a two-operation route
// (op 1 on EM01 or EM02, op 2 on EM01 only), every visit 100 s.
TEST(Plan, TheRuleRunForwardOnTheEstimates) {
  FakeCell c;
  FakePredictor p;
  p.seconds[{"TURN", "EM01"}] = 100.0;
  p.seconds[{"TURN", "EM02"}] = 100.0;
  Asks asks;
  asks.Attach(c, p);
  c.programs.Put("TURN", kEmco, "emco");
  Emco(c, "EM01");
  Emco(c, "EM02");
  c.Route("R", {"EM01,EM02:TURN", "EM01:TURN"});
  c.Route("W", {"EM03:TURN"});
  asks.Answer(c, p);
  const std::int64_t j1 = c.Operate("R", 1), j2 = c.Operate("R", 2), j3 = c.Operate("R", 3);
  const std::int64_t w = c.Operate("W", 4);
  const std::vector<PlanRow> plan = c.sched->Plan();
  const std::int64_t t0 = c.now_ms;
  struct Want {
    std::int64_t job;
    int op;
    std::string station;
    std::int64_t start_s, end_s;
  };
  // EM01 holds pallet 1 and then 3 (ties at 0 s and 100 s go to EM01, listed first), EM02 pallet 2; the
  // second operations queue on EM01 as their pallets become ready: 1 at 100 s, 2 at 100 s, 3 at 200 s.
  const std::vector<Want> want = {{j1, 0, "EM01", 0, 100},   {j1, 1, "EM01", 200, 300},
                                  {j2, 0, "EM02", 0, 100},   {j2, 1, "EM01", 300, 400},
                                  {j3, 0, "EM01", 100, 200}, {j3, 1, "EM01", 400, 500}};
  ASSERT_EQ(plan.size(), want.size() + 1);
  for (std::size_t i = 0; i < want.size(); ++i) {
    EXPECT_EQ(plan[i].job, want[i].job) << i;
    EXPECT_EQ(plan[i].op, want[i].op) << i;
    EXPECT_EQ(plan[i].station, want[i].station) << i;
    EXPECT_EQ(plan[i].start_ms, t0 + want[i].start_s * 1000) << i;
    EXPECT_EQ(plan[i].end_ms, t0 + want[i].end_s * 1000) << i;
  }
  EXPECT_EQ(plan.back().job, w);
  EXPECT_FALSE(plan.back().start_ms);
  EXPECT_NE(plan.back().waiting_for.find("EM03"), std::string::npos) << plan.back().waiting_for;
  const nlohmann::json j = ToJson(plan);
  EXPECT_EQ(j[0]["op"], 1);
  EXPECT_TRUE(j[0]["waiting_for"].is_null());
  EXPECT_TRUE(j.back()["start"].is_null());
}

}  // namespace
}  // namespace cell::scheduler
