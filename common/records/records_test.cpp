#include <gtest/gtest.h>

#include "cell/error/error.h"
#include "cell/records/entries.h"
#include "cell/records/job.h"
#include "cell/records/names.h"
#include "cell/records/page.h"
#include "cell/records/station.h"
#include "cell/records/time.h"

namespace cell::records {
namespace {

TEST(Names, EveryWireValueHasItsWord) {
  EXPECT_EQ(ExecutionName(cell::EXECUTION_FEED_HOLD), "FEED_HOLD");
  EXPECT_EQ(ExecutionName(cell::EXECUTION_UNAVAILABLE), "UNAVAILABLE");
  EXPECT_EQ(ConditionName(cell::CONDITION_WARNING), "WARNING");
  for (auto s : {cell::JOB_QUEUED, cell::JOB_WAITING, cell::JOB_DISPATCHED, cell::JOB_RUNNING,
                 cell::JOB_COMPLETED, cell::JOB_FAILED, cell::JOB_CANCELLED})
    EXPECT_EQ(JobStateFromName(JobStateName(s)), s);
  EXPECT_FALSE(JobStateFromName("DONE"));
  EXPECT_TRUE(IsTerminalJobState("CANCELLED"));
  EXPECT_FALSE(IsTerminalJobState("RUNNING"));
  EXPECT_EQ(RunStateName(cell::RUN_ACTIVE), "ACTIVE");
}

TEST(Time, WholeSecondsForRecordsMicrosecondsForMtconnect) {
  const std::int64_t ns = 1795833600123456789;  // 2026-11-28T02:40:00.123456789Z
  EXPECT_EQ(IsoTime(ns), "2026-11-28T02:40:00Z");
  EXPECT_EQ(IsoTimeMicros(ns), "2026-11-28T02:40:00.123456Z");
  EXPECT_EQ(IsoTime(0), "");
  EXPECT_TRUE(TimeOrNull(0).is_null());
  EXPECT_EQ(TimeOrNull(ns), "2026-11-28T02:40:00Z");
}

TEST(Station, NotAnnouncedReadsUnavailableWhateverItLastSaid) {
  StationStatus s;
  s.execution = "ACTIVE";
  s.program = "P1";
  s.line = 30;
  StationAlarm dup{true, "DUPLICATE", "two servos", 1};
  StationFacts f{"KT01", "ktapl", false, &s, &dup, 12};
  auto row = StationRow(f);
  EXPECT_EQ(row["execution"], "UNAVAILABLE");
  EXPECT_EQ(row["condition"], "UNAVAILABLE");
  EXPECT_TRUE(row["program"].is_null());
  EXPECT_TRUE(row["line"].is_null());
  EXPECT_TRUE(row["alarm_code"].is_null());
  EXPECT_EQ(row["backlog_s"], 12);
  // Announced but silent so far: still no state to report.
  f.online = true;
  f.status = nullptr;
  EXPECT_EQ(StationRow(f)["condition"], "UNAVAILABLE");
}

TEST(Station, LiveRowCarriesTheStatusAndARaisedAlarm) {
  StationStatus s;
  s.execution = "FEED_HOLD";
  s.program = "P1";
  s.line = 30;
  s.pallet = 4;
  StationFacts f{"KT01", "ktapl", true, &s, nullptr, 0};
  auto row = StationRow(f);
  EXPECT_EQ(row["execution"], "FEED_HOLD");
  EXPECT_EQ(row["condition"], "NORMAL");
  EXPECT_EQ(row["pallet"], 4);
  EXPECT_EQ(row["line"], 30);
  EXPECT_TRUE(row["tool"].is_null());
  StationAlarm dup{true, "DUPLICATE", "two servos", 1};
  f.alarm = &dup;
  row = StationRow(f);
  EXPECT_EQ(row["condition"], "FAULT");
  EXPECT_EQ(row["alarm_code"], "DUPLICATE");
  dup.active = false;
  EXPECT_EQ(StationRow(f)["condition"], "NORMAL");
}

TEST(Job, UnsetFieldsAreNullAndDecisionsListTheirMissingTools) {
  Job j;
  j.id = 7;
  j.state = "WAITING";
  j.kind = "route";
  j.route = "R1";
  j.pallet = 3;
  Decision d;
  d.considered.push_back({"KT01", true, false, false, 0, {"1001", "1002"}});
  j.decisions.push_back(d);
  auto out = JobJson(j, true);
  EXPECT_TRUE(out["station"].is_null());
  EXPECT_TRUE(out["started"].is_null());
  EXPECT_TRUE(out["cycle_s"].is_null());
  EXPECT_EQ(out["decisions"][0]["considered"][0]["missing_tools"], nlohmann::json::array({"1001", "1002"}));
  EXPECT_FALSE(JobJson(j, false).contains("decisions"));

  cell::JobInfo w;
  w.job_id(7);
  w.state(cell::JOB_WAITING);
  w.cycle_s(-1);
  cell::JobDecision wd;
  cell::DecisionStation ws;
  ws.missing_tools("1001,1002");
  wd.considered().push_back(ws);
  w.decisions().push_back(wd);
  Job back = FromWire(w);
  // The round trip the page sees: what the scheduler publishes reads back as the same record.
  j.decision_count = 1;
  j.decisions[0].considered[0].missing_tools.assign(100, "1234567");
  const Job trip = FromWire(ToWire(j));
  EXPECT_EQ(JobJson(trip, false), JobJson(j, false));
  const auto& tools = trip.decisions[0].considered[0].missing_tools;
  ASSERT_FALSE(tools.empty());
  EXPECT_LT(tools.size(), 100u);
  EXPECT_EQ(tools.back(), "+" + std::to_string(100 - (tools.size() - 1)) + " more");
  EXPECT_EQ(back.state, "WAITING");
  EXPECT_FALSE(back.cycle_s);
  EXPECT_EQ(back.decisions[0].considered[0].missing_tools, (std::vector<std::string>{"1001", "1002"}));
}

TEST(Entries, InspectionNamesTellStationAndKind) {
  auto run = InspectionEntryOf("run-KT01-12.json");
  EXPECT_EQ(run.station, "KT01");
  EXPECT_EQ(run.kind, "run");
  EXPECT_EQ(InspectionEntryOf("run-CELL-A-7.json").station, "CELL-A");  // a station id may hold '-'
  auto file = InspectionEntryOf("KT02/PROBE1");
  EXPECT_EQ(file.station, "KT02");
  EXPECT_EQ(file.kind, "inspection");
  EXPECT_TRUE(InspectionRow(file)["size"].is_null());
  file.size = 10;
  EXPECT_EQ(InspectionRow(file)["size"], 10);
  ProgramEntry p{"PUMP341", "HOST", "part", "ktapl", 2, 120, true, false, false};
  auto row = ProgramRow(p);
  EXPECT_EQ(row["protected"], true);
  EXPECT_EQ(row["revision"], 2);
}

// A page holds `limit` rows or what fits in the bound, whichever is less; the refused row starts the next.
TEST(Page, ShrinksToFitItsBoundAndStopsAtItsLimit) {
  PageBuilder by_limit(2);
  EXPECT_TRUE(by_limit.Add({{"id", 1}}));
  EXPECT_TRUE(by_limit.Add({{"id", 2}}));
  EXPECT_FALSE(by_limit.Add({{"id", 3}}));
  EXPECT_TRUE(by_limit.more());
  EXPECT_EQ(by_limit.Text(), R"([{"id":1},{"id":2}])");
  // {"id":1} is 8 bytes: "[" + 8 + "," + 8 + "]" = 19 fits 19, a third row would need 28.
  PageBuilder by_bytes(0, 19);
  EXPECT_TRUE(by_bytes.Add({{"id", 1}}));
  EXPECT_TRUE(by_bytes.Add({{"id", 2}}));
  EXPECT_FALSE(by_bytes.Add({{"id", 3}}));
  EXPECT_EQ(by_bytes.Text().size(), 19u);
  PageBuilder empty(5);
  EXPECT_EQ(empty.Text(), "[]");
  EXPECT_FALSE(empty.more());
  PageBuilder tiny(0, 4);
  EXPECT_THROW(tiny.Add({{"id", 1}}), Error);
}

// The client follows the cursor of each page's last row until it has `limit` rows or the service is done.
TEST(Page, CollectFollowsTheCursorToTheLimitOrTheEnd) {
  std::vector<std::string> asked;
  auto service = [&](const std::string& after, std::uint32_t want) {  // ids 1..10, 3 per page at most
    asked.push_back(after + "/" + std::to_string(want));
    Page p;
    int id = after.empty() ? 1 : std::stoi(after) + 1;
    for (; id <= 10 && p.rows.size() < 3 && (want == 0 || p.rows.size() < want); ++id)
      p.rows.push_back({{"id", id}});
    p.more = id <= 10;
    return p;
  };
  nlohmann::json all = CollectPages(0, "", "id", service);
  ASSERT_EQ(all.size(), 10u);
  EXPECT_EQ(all.back()["id"], 10);
  EXPECT_EQ(asked, (std::vector<std::string>{"/0", "3/0", "6/0", "9/0"}));
  asked.clear();
  all = CollectPages(5, "2", "id", service);
  ASSERT_EQ(all.size(), 5u);
  EXPECT_EQ(all.front()["id"], 3);
  EXPECT_EQ(all.back()["id"], 7);
  EXPECT_EQ(asked, (std::vector<std::string>{"2/5", "5/2"}));
  EXPECT_TRUE(CollectPages(0, "10", "id", service).empty());  // after the last
  auto liar = [](const std::string&, std::uint32_t) { return Page{nlohmann::json::array(), true}; };
  EXPECT_THROW(CollectPages(0, "", "name", liar), Error);
}

}  // namespace
}  // namespace cell::records
