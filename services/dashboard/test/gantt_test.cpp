// The Gantt chart's data (gantt.h): a fake plan as the scheduler answers SCHED_PLAN beside the visits the
// view kept from run events, through GanttJson and through /api/plan.
#include <gtest/gtest.h>
#include <httplib.h>

#include "cell/dashboard/gantt.h"
#include "cell/dashboard/server.h"
#include "cell/records/time.h"
#include "test_stations.h"

namespace cell::dashboard {
namespace {

using nlohmann::json;

constexpr std::int64_t kSecond = 1000000000;
// 2026-11-30T12:00:00Z
constexpr std::int64_t kNoon = 1796040000 * kSecond;

std::string At(std::int64_t s) {
  return records::IsoTime(kNoon + s * kSecond);
}

json Row(int job, int pallet, int op, const std::string& station, std::int64_t start, std::int64_t end) {
  return {{"job", job},         {"pallet", pallet},   {"route", "R1"},  {"op", op},
          {"station", station}, {"start", At(start)}, {"end", At(end)}, {"waiting_for", nullptr}};
}

// What `cellctl plan --json` prints for a cell: KT01 runs job 1 now and job 2 next, OK01 has job 1's second
// operation after it; job 3 waits for a tool.
PlanFetch FakePlan() {
  PlanFetch p;
  p.rows = json::array({Row(1, 11, 1, "KT01", -30, 60),
                        Row(1, 11, 2, "OK01", 60, 150),
                        Row(2, 12, 1, "KT01", 60, 100),
                        {{"job", 3},
                         {"pallet", 13},
                         {"route", "R1"},
                         {"op", 1},
                         {"station", nullptr},
                         {"start", nullptr},
                         {"end", nullptr},
                         {"waiting_for", "no eligible station: KT01 lacks tool 7777"}}});
  p.fetched_ns = kNoon - kSecond;
  return p;
}

TEST(Gantt, PlannedByStationWaitingWithTheirReasonAndWhatEachStationDoesNow) {
  const json g = GanttJson({"KT01", "OK01"}, FakePlan(), json::array(), kNoon);
  EXPECT_EQ(g["now"], At(0));
  EXPECT_EQ(g["fetched"], At(-1));
  EXPECT_TRUE(g["error"].is_null());
  EXPECT_EQ(g["stations"], json::array({"KT01", "OK01"}));
  ASSERT_EQ(g["planned"].size(), 3u);
  // By station, then start: KT01's two visits, then OK01's.
  EXPECT_EQ(g["planned"][0]["job"], 1);
  EXPECT_EQ(g["planned"][1]["job"], 2);
  EXPECT_EQ(g["planned"][2]["station"], "OK01");
  ASSERT_EQ(g["waiting"].size(), 1u);
  EXPECT_EQ(g["waiting"][0]["pallet"], 13);
  EXPECT_EQ(g["waiting"][0]["waiting_for"], "no eligible station: KT01 lacks tool 7777");
  // KT01 holds job 1 (started 30 s ago, ends in 60 s) and runs job 2 next; OK01 is idle until job 1 comes.
  EXPECT_EQ(g["current"]["KT01"]["job"], 1);
  EXPECT_EQ(g["next"]["KT01"]["job"], 2);
  EXPECT_TRUE(g["current"]["OK01"].is_null());
  EXPECT_EQ(g["next"]["OK01"]["op"], 2);
}

TEST(Gantt, AFailedAskKeepsTheLastPlanAndSaysWhy) {
  PlanFetch p = FakePlan();
  p.error = "the scheduler's plan: no reply in 5 s";
  const json g = GanttJson({"KT01", "OK01"}, p, json::array(), kNoon);
  EXPECT_EQ(g["error"], "the scheduler's plan: no reply in 5 s");
  EXPECT_EQ(g["planned"].size(), 3u);
  const json never = GanttJson({"KT01"}, PlanFetch{}, json(), kNoon);
  EXPECT_TRUE(never["fetched"].is_null());
  EXPECT_EQ(never["ran"], json::array());
  EXPECT_TRUE(never["next"]["KT01"].is_null());
}

// The view keeps each dispatch as it ran: from its start to its end, its job's operation, and a run first
// seen at its end (the dashboard started later) from its machine seconds before it.
TEST(Gantt, TheViewKeepsWhatRanFromRunEvents) {
  CellView view(testing::TwoStations());
  JobIn j;
  j.id = 1;
  j.state = "RUNNING";
  j.pallet = 11;
  j.op_index = 1;
  view.Job(j);
  RunIn r;
  r.dispatch_id = 7;
  r.station = "KT01";
  r.job_id = 1;
  r.pallet = 11;
  r.state = "QUEUED";
  view.Run(r);
  EXPECT_EQ(view.Ran(), json::array());  // not on the machine yet
  r.state = "ACTIVE";
  r.started_ns = kNoon - 90 * kSecond;
  view.Run(r);
  json ran = view.Ran();
  ASSERT_EQ(ran.size(), 1u);
  EXPECT_EQ(ran[0]["start"], At(-90));
  EXPECT_TRUE(ran[0]["end"].is_null());
  r.state = "COMPLETED";
  r.programs_done = 1;
  r.machine_s = 60;
  r.time_ns = kNoon - 30 * kSecond;
  view.Run(r);
  RunIn late{8, "OK01", "LATHE1", "COMPLETED", 2, 12, 1, 40, kNoon, 0};
  view.Run(late);
  ran = view.Ran();
  ASSERT_EQ(ran.size(), 2u);
  EXPECT_EQ(ran[0], json({{"job", 1},
                          {"pallet", 11},
                          {"op", 1},
                          {"station", "KT01"},
                          {"start", At(-90)},
                          {"end", At(-30)},
                          {"state", "COMPLETED"}}));
  EXPECT_EQ(ran[1]["start"], At(-40));
  EXPECT_EQ(ran[1]["end"], At(0));
}

TEST(Gantt, ApiPlanServesTheKeptPlanBesideWhatRan) {
  CellView view(testing::TwoStations());
  ServerOptions o;
  o.listen = {"127.0.0.1", 0};
  HttpServer srv(view, o);
  int asked = 0;
  srv.SetPlanSource([&asked] {
    ++asked;
    return FakePlan();
  });
  srv.Start();
  RunIn r{7, "KT01", "PUMP341", "ACTIVE", 1, 11, 0, 0, 0, records::NowNs()};
  view.Run(r);
  httplib::Client c("127.0.0.1", srv.port());
  auto res = c.Get("/api/plan");
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 200);
  EXPECT_EQ(res->get_header_value("Content-Type"), "application/json");
  const json g = json::parse(res->body);
  EXPECT_EQ(g["planned"].size(), 3u);
  EXPECT_EQ(g["waiting"][0]["job"], 3);
  ASSERT_EQ(g["ran"].size(), 1u);
  EXPECT_EQ(g["ran"][0]["station"], "KT01");
  EXPECT_EQ(asked, 1);
  srv.Stop();

  HttpServer bare(view, o);  // no scheduler to ask: an empty plan that says so
  bare.Start();
  httplib::Client c2("127.0.0.1", bare.port());
  auto none = c2.Get("/api/plan");
  ASSERT_TRUE(none);
  EXPECT_EQ(json::parse(none->body)["planned"], json::array());
  EXPECT_FALSE(json::parse(none->body)["error"].is_null());
}

}  // namespace
}  // namespace cell::dashboard
