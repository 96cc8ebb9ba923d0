// Dispatch rules of DESIGN §5 on a scripted fake cell. Manual references are to the KT-APL seed
// (/work/shared/seeds/kearney-trecker-kt-apl.txt): UCY at lines 4126-4154, UTL at 4286-4312, pallet maps at
// 838-854.
#include "cell/scheduler/scheduler.h"

#include <gtest/gtest.h>

#include <functional>

#include "cell/error/error.h"
#include "cell/scheduler/json.h"
#include "fake_cell.h"

namespace cell::scheduler {
namespace {

using testing::FakeCell;

Errc CodeOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.code();
  }
  ADD_FAILURE() << "no error";
  return Errc::kInternal;
}

// "When a Define Route command is executed, the Host computer will in succession open each named part program
// (USING) ... and extract the tool numbers listed in the UTL Statement" (seed line 4292).
TEST(DefineRoute, ExtractsUtlAndUcyPerOperation) {
  FakeCell c;
  c.Program("P1", {"T12", "7"}, 300);
  c.Program("P2", {"12", "99"}, 200);
  c.Program("P3", {}, 50);
  RouteView r = c.Route("R", {"KT01,KT02:P1,P2", "KT03:P3"});
  ASSERT_EQ(r.ops.size(), 2u);
  EXPECT_EQ(r.ops[0].stations, (std::vector<std::string>{"KT01", "KT02"}));
  EXPECT_EQ(r.ops[0].tools, (std::vector<std::string>{"12", "7", "99"}));
  EXPECT_EQ(r.ops[0].ucy_s, (std::vector<std::int64_t>{300, 200}));
  EXPECT_TRUE(r.ops[1].tools.empty());
  EXPECT_TRUE(r.valid);
  EXPECT_EQ(c.sched->Route("R")->ops[1].programs, std::vector<std::string>{"P3"});
}

// UCY is "REQUIRED" in the KT/FMS heading (seed lines 4146-4150); a missing program is not found.
TEST(DefineRoute, MissingProgramOrUcyIsAClearError) {
  FakeCell c;
  c.Program("NOUCY", {"1"}, -1);
  EXPECT_EQ(CodeOf([&] { c.Route("R", {"KT01:GHOST"}); }), Errc::kNotFound);
  EXPECT_EQ(CodeOf([&] { c.Route("R", {"KT01:NOUCY"}); }), Errc::kFailedPrecondition);
  try {
    c.Route("R", {"KT01:NOUCY"});
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("program 'NOUCY' has no (UCY,seconds)"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("route R op 1"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(c.sched->Route("R"));
  EXPECT_TRUE(c.sched->Stations().empty());  // a refused route registers no station
  c.Program("OK", {}, 5);
  EXPECT_EQ(CodeOf([&] { c.Route("R", {"KT01,KT01:OK"}); }), Errc::kInvalidArgument);
}

// UCY belongs to KT-APL: a program of another dialect (an EMCO lathe program has no heading statements) is
// a route operation without a cycle time, adding nothing to the station's backlog.
TEST(DefineRoute, OtherDialectsNeedNoUcy) {
  FakeCell c;
  c.programs.Put("THREAD", "%\nN0010 G00 X50. Z10.\nN0020 M30\n", "emco");
  RouteView r = c.Route("R", {"EM01:THREAD"});
  ASSERT_EQ(r.ops.size(), 1u);
  EXPECT_TRUE(r.valid);
  EXPECT_EQ(r.ops[0].ucy_s, (std::vector<std::int64_t>{0}));
}

// "If two or more stations are eligible ... the station with the shortest backlog is allocated" (seed
// 4132-4134) and "the UCY is extracted from each part program to be executed, summed and added to the
// backlog" (4130).
TEST(Operate, ShortestBacklogWinsAndUcySumJoinsIt) {
  FakeCell c;
  c.Program("LONG", {}, 500);
  c.Program("A", {}, 100);
  c.Program("B", {}, 40);
  c.Online("KT01");
  c.Online("KT02");
  c.Route("PRELOAD", {"KT01:LONG"});
  c.Route("R", {"KT01,KT02:A,B"});
  c.Operate("PRELOAD", 1);
  EXPECT_EQ(c.Backlog("KT01"), 500);
  const auto job = c.Operate("R", 2);
  EXPECT_EQ(c.StationOf(job), "KT02");
  EXPECT_EQ(c.State(job), JobState::kDispatched);
  EXPECT_EQ(c.Backlog("KT02"), 140);
  ASSERT_EQ(c.received["KT02"].size(), 1u);
  EXPECT_EQ(c.received["KT02"][0].programs, (std::vector<std::string>{"A", "B"}));
  EXPECT_EQ(c.received["KT02"][0].pallet, 2);
  // Each program's UCY leaves the backlog when that program completes.
  const auto id = c.received["KT02"][0].dispatch_id;
  c.Take(c.sched->RunStarted(id));
  EXPECT_EQ(c.State(job), JobState::kRunning);
  c.Take(c.sched->ProgramFinished(id, 0));
  EXPECT_EQ(c.Backlog("KT02"), 40);
  c.Take(c.sched->ProgramFinished(id, 0));  // a repeated report changes nothing
  EXPECT_EQ(c.Backlog("KT02"), 40);
  c.Take(c.sched->RunFinished(id, 123.5));
  EXPECT_EQ(c.Backlog("KT02"), 0);
  auto v = c.sched->Job(job).value();
  EXPECT_EQ(v.state, JobState::kCompleted);
  EXPECT_EQ(v.cycle_s.value_or(0), 123.5);
  EXPECT_NE(v.started_ms, 0);
  EXPECT_NE(v.finished_ms, 0);
}

TEST(Operate, TiesGoToTheStationListedFirst) {
  FakeCell c;
  c.Program("A", {}, 100);
  c.Online("KT01");
  c.Online("KT02");
  c.Route("R12", {"KT01,KT02:A"});
  c.Route("R21", {"KT02,KT01:A"});
  const auto j1 = c.Operate("R21", 1);
  EXPECT_EQ(c.StationOf(j1), "KT02");  // 0 s each: KT02 is listed first
  const auto j2 = c.Operate("R12", 2);
  EXPECT_EQ(c.StationOf(j2), "KT01");  // KT01 has 0 s, KT02 100 s
  const auto j3 = c.Operate("R12", 3);
  EXPECT_EQ(c.StationOf(j3), "KT01");  // 100 s each: KT01 is listed first
  auto d = c.sched->Job(j3)->decisions.back();
  EXPECT_EQ(d.winner, "KT01");
  EXPECT_NE(d.why.find("tie at backlog 100 s"), std::string::npos) << d.why;
  ASSERT_EQ(d.considered.size(), 2u);
  EXPECT_EQ(d.considered[1].station, "KT02");
  EXPECT_EQ(d.considered[1].backlog_s, 100);
}

// "All tools which are listed in the UTL statement must be at the named machine in order for the machine to
// be allocated" (seed lines 4294-4296).
TEST(Operate, MissingToolsMakeThePalletWaitUntilAToolLoadReleasesIt) {
  FakeCell c;
  c.Program("A", {"1001", "T2002"}, 60);
  c.Online("KT01", {"1001"});
  c.Online("KT02", {"2002", "5"});
  c.Route("R", {"KT01,KT02:A"});
  const auto job = c.Operate("R", 7);
  EXPECT_EQ(c.State(job), JobState::kWaiting);
  EXPECT_EQ(c.Reason(job), "no eligible station: KT01 missing tools 2002; KT02 missing tools 1001");
  EXPECT_TRUE(c.all.empty());
  // Host tool data: a data set loaded into KT02's table and republished.
  auto table = c.sched->StationToolTable("KT02").value();
  table.Upsert(tooltable::ToolEntry{.tool = "1001", .socket = 9, .length = 120, .diameter = 12});
  c.Take(c.sched->StationTools("KT02", table));
  EXPECT_EQ(c.State(job), JobState::kDispatched);
  EXPECT_EQ(c.StationOf(job), "KT02");
  EXPECT_EQ(c.Reason(job), "");
  auto v = c.sched->Job(job).value();
  ASSERT_EQ(v.decisions.size(), 2u);
  EXPECT_EQ(v.decisions[0].winner, "");
  EXPECT_EQ(v.decisions[0].considered[0].missing_tools, std::vector<std::string>{"2002"});
  EXPECT_EQ(v.decisions[1].trigger, "tool table of KT02 changed");
  EXPECT_EQ(v.decisions[1].winner, "KT02");
}

TEST(Operate, QueuedPalletsLeaveAStationThatLosesATool) {
  FakeCell c;
  c.Program("A", {"7"}, 100);
  c.Online("KT01", {"7"});
  c.Online("KT02");
  c.Route("R", {"KT01,KT02:A"});
  const auto j1 = c.Operate("R", 1);
  const auto j2 = c.Operate("R", 2);
  EXPECT_EQ(c.StationOf(j2), "KT01");  // queued behind pallet 1
  EXPECT_EQ(c.Backlog("KT01"), 200);
  c.Take(c.sched->StationTools("KT01", testing::Tools({"8"})));
  EXPECT_EQ(c.State(j1), JobState::kDispatched);  // already handed out: the station deals with it
  EXPECT_EQ(c.State(j2), JobState::kWaiting);
  EXPECT_EQ(c.Reason(j2), "no eligible station: KT01 missing tools 7; KT02 missing tools 7");
  EXPECT_EQ(c.Backlog("KT01"), 100);
  EXPECT_EQ(c.sched->Job(j2)->decisions.back().trigger, "re-queued: tool table of KT01 changed");
  c.Take(c.sched->StationTools("KT02", testing::Tools({"7"})));
  EXPECT_EQ(c.StationOf(j2), "KT02");
}

TEST(Operate, BrokenToolDoesNotCount) {
  FakeCell c;
  c.Program("A", {"9"}, 60);
  c.Online("KT01");
  tooltable::ToolTable t({tooltable::ToolEntry{.tool = "9", .socket = 1, .broken = true}});
  c.Take(c.sched->StationTools("KT01", t));
  c.Route("R", {"KT01:A"});
  const auto job = c.Operate("R", 1);
  EXPECT_EQ(c.Reason(job), "no eligible station: KT01 missing tools 9");
}

// Issue 15: a station holds tool N when some entry of N is neither worn nor broken. A worn primary with a
// usable alternate still holds it; once the alternate wears out too, the pallet goes to the other station.
TEST(Operate, WornToolsCountOnlyThroughAUsableAlternate) {
  FakeCell c;
  c.Program("A", {"9"}, 60);
  c.Online("KT01");
  c.Online("KT02");
  tooltable::ToolTable kt01({tooltable::ToolEntry{.tool = "9", .socket = 1, .worn = true},
                             tooltable::ToolEntry{.tool = "9", .socket = 2, .life_left_min = 5}});
  c.Take(c.sched->StationTools("KT01", kt01));
  c.Take(c.sched->StationTools("KT02", testing::Tools({"9"})));
  c.Route("R", {"KT01,KT02:A"});
  const auto j1 = c.Operate("R", 1);
  EXPECT_EQ(c.StationOf(j1), "KT01");             // the tie goes to the station listed first
  c.Complete(c.received["KT01"][0].dispatch_id);  // both backlogs are 0 again
  tooltable::ToolTable worn({tooltable::ToolEntry{.tool = "9", .socket = 1, .worn = true},
                             tooltable::ToolEntry{.tool = "9", .socket = 2, .worn = true}});
  c.Take(c.sched->StationTools("KT01", worn));
  c.Take(c.sched->StationTools("KT02", testing::Tools({"9"})));
  const auto j2 = c.Operate("R", 2);
  EXPECT_EQ(c.StationOf(j2), "KT02");
  const auto job = c.sched->Job(j2);
  ASSERT_TRUE(job && !job->decisions.empty());
  const auto& d = job->decisions.back();
  ASSERT_FALSE(d.considered.empty());
  EXPECT_FALSE(d.considered[0].eligible);
}

TEST(Operate, OfflineStationsAreNamedAndOnlineReleases) {
  FakeCell c;
  c.Program("A", {}, 60);
  c.sched->ConfigureStation("KT01", "ktapl");
  c.Route("R", {"KT01,KT02:A"});
  const auto job = c.Operate("R", 3);
  EXPECT_EQ(c.Reason(job), "no eligible station: KT01 offline; KT02 offline");
  c.Online("KT02");
  EXPECT_EQ(c.StationOf(job), "KT02");
  EXPECT_EQ(c.received["KT02"].size(), 1u);
}

// "A station accepts several pallets and runs them in order": one in hand, the rest queued behind it.
TEST(Operate, AStationRunsItsPalletsInOrder) {
  FakeCell c;
  c.Program("A", {}, 10);
  c.Online("KT01");
  c.Route("R", {"KT01:A"});
  const auto j1 = c.Operate("R", 1);
  const auto j2 = c.Operate("R", 2);
  const auto j3 = c.Operate("R", 3);
  EXPECT_EQ(c.Backlog("KT01"), 30);
  ASSERT_EQ(c.received["KT01"].size(), 1u);
  EXPECT_EQ(c.received["KT01"][0].pallet, 1);
  EXPECT_EQ(c.sched->Station("KT01")->queue.size(), 3u);
  c.Complete(c.received["KT01"][0].dispatch_id);
  ASSERT_EQ(c.received["KT01"].size(), 2u);
  EXPECT_EQ(c.received["KT01"][1].pallet, 2);
  c.Complete(c.received["KT01"][1].dispatch_id);
  c.Complete(c.received["KT01"][2].dispatch_id);
  EXPECT_EQ(c.received["KT01"][2].pallet, 3);
  for (auto j : {j1, j2, j3}) EXPECT_EQ(c.State(j), JobState::kCompleted);
  EXPECT_EQ(c.Backlog("KT01"), 0);
}

TEST(Operate, MultiOperationRouteMovesThePalletOn) {
  FakeCell c;
  c.Program("ROUGH", {"1"}, 100);
  c.Program("FINISH", {"2"}, 50);
  c.Online("KT01", {"1"});
  c.Online("KT02", {"1"});
  c.Route("R", {"KT01:ROUGH", "KT02:FINISH"});
  const auto job = c.Operate("R", 5);
  c.Complete(c.InHand("KT01").dispatch_id, 90);
  // The second operation needs tool 2, which KT02 lacks: the pallet waits there.
  EXPECT_EQ(c.State(job), JobState::kWaiting);
  EXPECT_EQ(c.Reason(job), "no eligible station: KT02 missing tools 2");
  EXPECT_EQ(c.sched->Job(job)->op_index, 1);
  c.Take(c.sched->StationTools("KT02", testing::Tools({"1", "2"})));
  const auto d = c.InHand("KT02");
  EXPECT_EQ(d.op_index, 1);
  EXPECT_EQ(d.programs, std::vector<std::string>{"FINISH"});
  EXPECT_EQ(c.Backlog("KT02"), 50);
  c.Complete(d.dispatch_id, 40);
  auto v = c.sched->Job(job).value();
  EXPECT_EQ(v.state, JobState::kCompleted);
  EXPECT_EQ(v.cycle_s.value_or(0), 130);
  EXPECT_EQ(v.station, "KT02");
}

TEST(Operate, StationRunReportsApplyOnceAndInOrder) {
  FakeCell c;
  c.Program("A", {}, 100);
  c.Program("B", {}, 40);
  c.Online("KT01");
  c.Route("R", {"KT01:A,B"});
  const auto j = c.Operate("R", 1);
  const auto id = c.InHand("KT01").dispatch_id;
  c.Take(c.sched->ReportRun({id, RunStatus::kRunning, 1, std::nullopt, ""}));
  EXPECT_EQ(c.State(j), JobState::kRunning);
  EXPECT_EQ(c.Backlog("KT01"), 40);
  c.Take(c.sched->ReportRun({id, RunStatus::kRunning, 0, std::nullopt, ""}));  // older sample: no change
  EXPECT_EQ(c.Backlog("KT01"), 40);
  c.Take(c.sched->ReportRun({id, RunStatus::kCompleted, 2, 77.0, ""}));
  EXPECT_EQ(c.State(j), JobState::kCompleted);
  EXPECT_EQ(c.sched->Job(j)->cycle_s.value_or(0), 77.0);
  EXPECT_EQ(c.Backlog("KT01"), 0);
  const auto notes = c.notes.size();
  c.Take(c.sched->ReportRun({id, RunStatus::kCompleted, 2, 77.0, ""}));  // re-delivered: ignored
  EXPECT_EQ(c.sched->Job(j)->cycle_s.value_or(0), 77.0);
  EXPECT_GT(c.notes.size(), notes);
  const auto j2 = c.Operate("R", 2);
  c.Take(
      c.sched->ReportRun({c.InHand("KT01").dispatch_id, RunStatus::kFailed, 0, std::nullopt, "M99 alarm"}));
  EXPECT_EQ(c.State(j2), JobState::kFailed);
  EXPECT_EQ(c.Reason(j2), "station KT01: M99 alarm");
}

// Health policy (docs/scheduler.md §5): pallets allocated to a station that vanishes and not yet handed out
// are re-queued; the pallet it holds waits for the station's own report, which alone knows whether it ran.
TEST(Health, VanishedStationRequeuesQueuedAndItsWordSettlesTheOneItHolds) {
  FakeCell c;
  c.Program("A", {}, 100);
  c.Online("KT01");
  c.Online("KT02");
  c.Route("ONLY1", {"KT01:A"});
  c.Route("BOTH", {"KT01,KT02:A"});
  const auto running = c.Operate("ONLY1", 1);
  const auto queued = c.Operate("ONLY1", 2);
  const auto held = c.InHand("KT01").dispatch_id;
  c.Take(c.sched->RunStarted(held));
  const auto b1 = c.Operate("BOTH", 3);  // KT02 (0 s)
  const auto b2 = c.Operate("BOTH", 4);  // KT02 (100 s) vs KT01 (200 s)
  const auto b3 = c.Operate("BOTH", 5);  // KT02 (200 s) vs KT01 (200 s): tie, KT01 listed first
  EXPECT_EQ(c.StationOf(b3), "KT01");
  EXPECT_EQ(c.Backlog("KT01"), 300);
  c.Take(c.sched->StationOffline("KT01"));
  EXPECT_EQ(c.State(running), JobState::kRunning);
  EXPECT_EQ(c.Reason(running),
            "station KT01 went offline holding pallet 1: waiting for its report on dispatch " +
                std::to_string(held) + " (job cancel releases it)");
  EXPECT_TRUE(c.sched->DispatchLive(held));
  EXPECT_TRUE(c.cancels.empty());  // a station that only lost contact goes on with its run
  EXPECT_EQ(c.State(queued), JobState::kWaiting);
  EXPECT_EQ(c.Reason(queued), "no eligible station: KT01 offline");
  EXPECT_EQ(c.StationOf(b3), "KT02");  // re-queued onto the other listed station
  EXPECT_EQ(c.Backlog("KT01"), 100);   // the pallet it holds
  EXPECT_EQ(c.Backlog("KT02"), 300);
  EXPECT_EQ(c.sched->Job(b3)->decisions.back().trigger, "re-queued: station KT01 went offline");
  // KT01 comes back: it is asked again about the dispatch it held (same id), and its report settles it: the
  // restarted station lost the run.
  const auto before = c.received["KT01"].size();
  c.Online("KT01");
  ASSERT_EQ(c.received["KT01"].size(), before + 1);
  EXPECT_EQ(c.received["KT01"].back().dispatch_id, held);
  EXPECT_TRUE(c.received["KT01"].back().resent);
  c.Take(c.sched->ReportRun({held, RunStatus::kFailed, 0, std::nullopt, "station restarted during the run"}));
  EXPECT_EQ(c.State(running), JobState::kFailed);
  EXPECT_EQ(
      c.Reason(running),
      "station KT01 went offline while running pallet 1 (program 1 of 1): station restarted during the run; "
      "the pallet needs an operator");
  // The waiting pallet goes to it.
  EXPECT_EQ(c.State(queued), JobState::kDispatched);
  EXPECT_EQ(c.InHand("KT01").pallet, 2);
  (void)b1;
  (void)b2;
}

// A station that finished its pallet and died before anyone heard it says so when it is back: the job
// completes, once (before, the pallet was failed at once and the late report ignored: chaos test, stop 54).
TEST(Health, APalletFinishedWhileItsStationWasAwayCompletes) {
  FakeCell c;
  c.Program("A", {}, 100);
  c.Program("B", {}, 50);
  c.Online("KT01");
  c.Online("KT02");
  c.Route("R", {"KT01:A", "KT02:B"});
  const auto j = c.Operate("R", 1);
  const auto first = c.InHand("KT01").dispatch_id;
  c.Take(c.sched->RunStarted(first));
  c.Take(c.sched->StationOffline("KT01"));
  c.Online("KT01");
  c.Take(c.sched->ReportRun({first, RunStatus::kCompleted, 1, 90.0, ""}));
  EXPECT_EQ(c.State(j), JobState::kDispatched);  // on to its second operation
  EXPECT_EQ(c.Reason(j), "");
  EXPECT_EQ(c.InHand("KT02").pallet, 1);
  c.Complete(c.InHand("KT02").dispatch_id, 40.0);
  EXPECT_EQ(c.State(j), JobState::kCompleted);
  EXPECT_EQ(c.sched->Job(j)->cycle_s.value_or(0), 130.0);
}

// A station back online while in fault (a restarted process seen twice for a moment: DUPLICATE) is not
// asked about the pallet it holds until the fault clears; then it is, and its word settles the pallet (a
// pallet once stayed RUNNING for good, "waiting for its report": issue 43's week).
TEST(Health, AStationBackInFaultIsAskedWhenTheFaultClears) {
  FakeCell c;
  c.Program("A", {}, 100);
  c.Online("KT01");
  c.Route("R", {"KT01:A"});
  const auto j = c.Operate("R", 1);
  const auto held = c.InHand("KT01").dispatch_id;
  c.Take(c.sched->RunStarted(held));
  c.Take(c.sched->StationOffline("KT01"));
  c.Take(c.sched->StationCondition("KT01", true, "DUPLICATE", "cell-interpreter/KT01 runs in 2 processes"));
  const auto before = c.received["KT01"].size();
  c.Online("KT01");
  EXPECT_EQ(c.received["KT01"].size(), before);  // in fault: not asked yet
  c.Take(c.sched->StationCondition("KT01", false));
  ASSERT_EQ(c.received["KT01"].size(), before + 1);
  EXPECT_EQ(c.received["KT01"].back().dispatch_id, held);
  EXPECT_TRUE(c.received["KT01"].back().resent);
  c.Take(c.sched->ReportRun({held, RunStatus::kCompleted, 1, 90.0, ""}));
  EXPECT_EQ(c.State(j), JobState::kCompleted);
  EXPECT_EQ(c.Reason(j), "");
}

// A run's end is an event; one lost (its station replaced its participant as it ended) would leave the pallet
// RUNNING for good. A dispatch nothing was heard of for the quiet time is asked about again, and the
// station's answer (the run as recorded) settles it. Not while it is being delivered, nor on a station away
// or in fault.
TEST(Health, ADispatchSilentForLongIsAskedAgain) {
  using std::chrono::seconds;
  FakeCell c;
  c.Program("A", {}, 100);
  c.Online("KT01");
  c.Online("KT02");
  c.Route("R1", {"KT01:A"});
  c.Route("R2", {"KT02:A"});
  const auto j = c.Operate("R1", 1);
  const auto k = c.Operate("R2", 2);
  const auto held = c.InHand("KT01").dispatch_id;
  const auto other = c.InHand("KT02").dispatch_id;
  c.now_ms += 60'000;
  const auto before = c.all.size();
  c.Take(c.sched->AskSilent(seconds(30)));
  EXPECT_EQ(c.all.size(), before);  // sent, not answered yet: the sender's to deliver
  c.Take(c.sched->DispatchAcknowledged(held));
  c.Take(c.sched->RunStarted(other));
  c.Take(c.sched->StationCondition("KT02", true, "1234", "SPINDLE OVERLOAD"));
  c.now_ms += 29'000;
  c.Take(c.sched->AskSilent(seconds(30)));
  EXPECT_EQ(c.all.size(), before);  // heard of 29 s ago
  c.now_ms += 1'000;
  c.Take(c.sched->AskSilent(seconds(30)));
  ASSERT_EQ(c.all.size(), before + 1);  // KT01's; KT02 is in fault
  EXPECT_EQ(c.all.back().dispatch_id, held);
  EXPECT_TRUE(c.all.back().resent);
  c.Take(c.sched->AskSilent(seconds(30)));
  EXPECT_EQ(c.all.size(), before + 1);  // asked: quiet again for 30 s
  c.Take(c.sched->ReportRun({held, RunStatus::kCompleted, 1, 80.0, ""}));
  EXPECT_EQ(c.State(j), JobState::kCompleted);
  EXPECT_EQ(c.State(k), JobState::kRunning);
}

// A handed-out pallet whose station vanished stays with it: the station may hold it in its queue. If the
// station only stalled, its report clears the interruption; if it says it never started it, the pallet is
// free again (a new dispatch id).
TEST(Health, AHandedOutPalletWaitsForItsStationsWord) {
  FakeCell c;
  c.Program("A", {}, 100);
  c.Online("KT01");
  c.Online("KT02");
  c.Route("BOTH", {"KT01,KT02:A"});
  const auto j1 = c.Operate("BOTH", 1);  // KT01
  const auto j2 = c.Operate("BOTH", 2);  // KT02
  const auto d1 = c.InHand("KT01").dispatch_id;
  const auto d2 = c.InHand("KT02").dispatch_id;
  c.Take(c.sched->DispatchAcknowledged(d1));
  c.Take(c.sched->StationOffline("KT01"));
  c.Take(c.sched->StationOffline("KT02"));
  EXPECT_EQ(c.State(j1), JobState::kDispatched);
  EXPECT_EQ(c.StationOf(j1), "KT01");
  c.Online("KT01");
  c.Take(c.sched->ReportRun({d1, RunStatus::kRunning, 0, std::nullopt, ""}));
  EXPECT_EQ(c.State(j1), JobState::kRunning);
  EXPECT_EQ(c.Reason(j1), "");
  // KT02 comes back without it (never received, cancelled before it started): the pallet goes elsewhere.
  c.Online("KT02");
  RunReport never{d2, RunStatus::kFailed, 0, std::nullopt,
                  "cancelled by the scheduler before the station received it"};
  never.started = false;
  c.Take(c.sched->ReportRun(never));
  EXPECT_FALSE(c.sched->DispatchLive(d2));
  EXPECT_EQ(c.State(j2), JobState::kDispatched);
  EXPECT_NE(c.InHand(c.StationOf(j2)).dispatch_id, d2);
  EXPECT_EQ(c.sched->Job(j2)->decisions.back().trigger,
            "re-queued: station KT02 went offline before starting it");
}

TEST(Health, FaultInterruptsAndClearingReleases) {
  FakeCell c;
  c.Program("A", {}, 100);
  c.Online("KT01");
  c.Route("R", {"KT01:A"});
  const auto j = c.Operate("R", 1);
  EXPECT_EQ(c.received["KT01"].size(), 1u);  // handed out, not started
  const auto first = c.received["KT01"][0].dispatch_id;
  c.Take(c.sched->StationCondition("KT01", true, "1234", "SPINDLE OVERLOAD"));
  // The station is told to drop the dispatch it holds; it stays the station's until it says it did.
  ASSERT_EQ(c.cancels.size(), 1u);
  EXPECT_EQ(c.cancels[0].dispatch_id, first);
  EXPECT_EQ(c.State(j), JobState::kDispatched);
  RunReport dropped{first, RunStatus::kFailed, 0, std::nullopt, "cancelled by the scheduler"};
  dropped.started = false;
  c.Take(c.sched->ReportRun(dropped));
  EXPECT_EQ(c.State(j), JobState::kWaiting);
  EXPECT_FALSE(c.sched->DispatchLive(first));
  EXPECT_EQ(c.Reason(j), "no eligible station: KT01 in fault (alarm 1234)");
  EXPECT_EQ(c.Backlog("KT01"), 0);
  c.Take(c.sched->StationCondition("KT01", false));
  EXPECT_EQ(c.State(j), JobState::kDispatched);
  ASSERT_EQ(c.received["KT01"].size(), 2u);
  EXPECT_NE(c.received["KT01"][1].dispatch_id, first);
  // A fault under a running pallet: the station aborts it on the cancel and says so; the pallet needs an
  // operator.
  const auto second = c.received["KT01"][1].dispatch_id;
  c.Take(c.sched->RunStarted(second));
  c.Take(c.sched->StationCondition("KT01", true, "1234", "SPINDLE OVERLOAD"));
  EXPECT_EQ(c.State(j), JobState::kRunning);
  c.Take(c.sched->ReportRun({second, RunStatus::kFailed, 0, std::nullopt, "cancelled by the scheduler"}));
  EXPECT_EQ(c.State(j), JobState::kFailed);
  EXPECT_EQ(
      c.Reason(j),
      "station KT01 raised fault 1234 while running pallet 1 (program 1 of 1): cancelled by the scheduler; "
      "the pallet needs an operator");
}

TEST(Jobs, CancelReleasesBacklogAndTellsTheStation) {
  FakeCell c;
  c.Program("A", {}, 100);
  c.Online("KT01");
  c.Route("R", {"KT01:A"});
  const auto j1 = c.Operate("R", 1);
  const auto j2 = c.Operate("R", 2);
  c.Take(c.sched->Cancel("cancel-2", j2));
  EXPECT_EQ(c.State(j2), JobState::kCancelled);
  EXPECT_TRUE(c.cancels.empty());  // it was only queued
  EXPECT_EQ(c.Backlog("KT01"), 100);
  c.Take(c.sched->Cancel("cancel-1", j1, "wrong fixture"));
  EXPECT_EQ(c.Reason(j1), "wrong fixture");
  ASSERT_EQ(c.cancels.size(), 1u);
  EXPECT_EQ(c.cancels[0].dispatch_id, c.received["KT01"][0].dispatch_id);
  EXPECT_EQ(c.Backlog("KT01"), 0);
  c.Take(c.sched->Cancel("cancel-1", j1));  // same key: nothing new
  EXPECT_EQ(CodeOf([&] { c.sched->Cancel("cancel-1b", j1); }), Errc::kFailedPrecondition);
  EXPECT_EQ(CodeOf([&] { c.sched->Cancel("cancel-x", 999); }), Errc::kNotFound);
  // The pallet is free again.
  EXPECT_NO_THROW(c.Operate("R", 1));
}

TEST(Jobs, IdempotencyKeysAndPalletRules) {
  FakeCell c;
  c.Program("A", {}, 100);
  c.Online("KT01");
  c.Route("R", {"KT01:A"});
  const auto j = c.Operate("R", 1, "k1");
  JobResult again = c.sched->Operate("k1", "R", 1);
  EXPECT_TRUE(again.replayed);
  EXPECT_EQ(again.job_id, j);
  EXPECT_TRUE(again.effects.dispatches.empty());
  EXPECT_EQ(c.sched->Jobs().size(), 1u);
  EXPECT_EQ(CodeOf([&] { c.Operate("R", 1); }), Errc::kFailedPrecondition);  // pallet busy
  EXPECT_EQ(CodeOf([&] { c.Operate("R", 0); }), Errc::kInvalidArgument);
  EXPECT_EQ(CodeOf([&] { c.Operate("R", 256); }), Errc::kInvalidArgument);
  EXPECT_EQ(CodeOf([&] { c.Operate("NOPE", 2); }), Errc::kNotFound);
  EXPECT_NO_THROW(c.Operate("R", 255));
  FakeCell coded;  // a coded-pallet module: 1-127 (seed lines 852, 4081-4083)
  coded.sched->ConfigureStation("KT01", "ktapl", true);
  coded.Program("A", {}, 1);
  coded.Route("R", {"KT01:A"});
  EXPECT_EQ(CodeOf([&] { coded.Operate("R", 128); }), Errc::kInvalidArgument);
  EXPECT_NO_THROW(coded.Operate("R", 127));
}

// A coded-pallet FMS module (station file `coded_pallets = true`, KT04) holds pallets 1-127 only: "Machines
// which have coded pallets (FMS, ...) are limited to pallet numbers in a range from 1 to 127" (KT-APL seed
// lines 4081-4083). Pallet 200 is never allocated to it; an operation that lists only such modules refuses
// it.
TEST(Jobs, ACodedPalletModuleNeverGetsPallets128To255) {
  FakeCell c;
  c.sched->ConfigureStation("KT04", "ktapl", true);
  c.Program("A", {}, 100);
  c.Online("KT01");
  c.Online("KT04");
  c.Route("ONLY4", {"KT04:A"});
  c.Route("BOTH", {"KT04,KT01:A"});
  // KT04 is listed first with the same backlog (0 s): without the rule it would win pallet 200.
  const auto j = c.Operate("BOTH", 200);
  EXPECT_EQ(c.StationOf(j), "KT01");
  ASSERT_EQ(c.sched->Job(j)->decisions.back().considered.size(), 1u);
  // The plan projects a later operation by the same rule: KT04 is free and listed first, but not for 203.
  c.Route("TWO", {"KT01:A", "KT04,KT01:A"});
  c.Operate("TWO", 203);
  const auto plan = c.sched->Plan();
  ASSERT_EQ(plan.size(), 3u);
  EXPECT_EQ(plan[2].pallet, 203);
  EXPECT_EQ(plan[2].op, 1);
  EXPECT_EQ(plan[2].station, "KT01");
  std::string why;
  try {
    c.Operate("ONLY4", 201);
  } catch (const Error& e) {
    why = e.what();
  }
  EXPECT_NE(why.find("pallet 201 cannot go to KT04 (operation 1 of route 'ONLY4')"), std::string::npos)
      << why;
  EXPECT_EQ(c.sched->Jobs().size(), 2u);  // nothing recorded
  c.sched->SetPalletMap("m", 202, {"A"});
  EXPECT_EQ(CodeOf([&] { c.sched->RunPallet("run202", 202, "KT04"); }), Errc::kInvalidArgument);
  // Pallets 1-127 go to KT04 as to any station (listed first, 0 s each).
  EXPECT_EQ(c.StationOf(c.Operate("BOTH", 127)), "KT04");
}

// Issue 13: a key binds the whole command. The same command under a used key is a replay (the first outcome,
// nothing new); a different one is refused with kFailedPrecondition naming both, and never runs.
TEST(Jobs, AnIdempotencyKeyBindsTheWholeCommand) {
  FakeCell c;
  c.Program("A", {}, 100);
  c.Program("B", {}, 50);
  c.Online("KT01");
  c.Route("PUMP", {"KT01:A"});
  c.Route("VALVE", {"KT01:B"});
  const auto j = c.Operate("PUMP", 250, "s7:route-operate");
  EXPECT_EQ(c.sched->Operate("s7:route-operate", "PUMP", 250).job_id, j);
  auto refused = [&](const std::function<void()>& f) {
    try {
      f();
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), Errc::kFailedPrecondition) << e.what();
      return std::string(e.what());
    }
    ADD_FAILURE() << "a different command under a used key was not refused";
    return std::string();
  };
  std::string why = refused([&] { c.sched->Operate("s7:route-operate", "VALVE", 251); });
  EXPECT_NE(why.find("'s7:route-operate' was already used for another command"), std::string::npos) << why;
  EXPECT_NE(why.find("PUMP"), std::string::npos) << why;
  EXPECT_NE(why.find("VALVE"), std::string::npos) << why;
  refused([&] { c.sched->Operate("s7:route-operate", "PUMP", 251); });
  EXPECT_EQ(c.sched->Jobs().size(), 1u);  // pallet 251 was never operated
  EXPECT_FALSE(c.sched->Job(j + 1));

  RouteSpec spec{"R2", {ParseOpSpec("KT01:A")}};
  c.sched->DefineRoute("d", spec);
  EXPECT_NO_THROW(c.sched->DefineRoute("d", spec));
  refused([&] { c.sched->DefineRoute("d", RouteSpec{"R2", {ParseOpSpec("KT01:B")}}); });
  refused([&] { c.sched->DefineRoute("d", RouteSpec{"R3", {ParseOpSpec("KT01:A")}}); });
  EXPECT_EQ(c.sched->Route("R2")->ops[0].programs, std::vector<std::string>{"A"});
  EXPECT_FALSE(c.sched->Route("R3"));

  c.sched->SetPalletMap("m", 3, {"A", "B"});
  refused([&] { c.sched->SetPalletMap("m", 3, {"B", "A"}); });
  EXPECT_EQ(*c.sched->PalletMap(3), (std::vector<std::string>{"A", "B"}));
  const auto j2 = c.sched->RunPallet("p", 3, "KT01").job_id;
  EXPECT_EQ(c.sched->RunPallet("p", 3, "KT01").job_id, j2);
  refused([&] { c.sched->RunPallet("p", 4, "KT01"); });

  const auto j3 = c.Operate("VALVE", 9);
  c.sched->Cancel("c", j3);
  EXPECT_NO_THROW(c.sched->Cancel("c", j3));
  refused([&] { c.sched->Cancel("c", j); });
  EXPECT_EQ(c.State(j), JobState::kDispatched);
}

// "A Pallet Map consists of from 1 to 75 standard part programs" (seed line 842).
TEST(PalletMaps, OneToSeventyFivePrograms) {
  FakeCell c;
  std::vector<std::string> progs;
  for (int i = 0; i < 76; ++i) c.Program("P" + std::to_string(i), {}, 10);
  for (int i = 0; i < 75; ++i) progs.push_back("P" + std::to_string(i));
  c.sched->SetPalletMap("m1", 12, progs);
  EXPECT_EQ(c.sched->PalletMap(12)->size(), 75u);
  progs.push_back("P75");
  EXPECT_EQ(CodeOf([&] { c.sched->SetPalletMap("m2", 12, progs); }), Errc::kInvalidArgument);
  EXPECT_EQ(CodeOf([&] { c.sched->SetPalletMap("m3", 12, {}); }), Errc::kInvalidArgument);
  EXPECT_EQ(CodeOf([&] { c.sched->SetPalletMap("m4", 256, {"A"}); }), Errc::kInvalidArgument);
  EXPECT_EQ(c.sched->PalletMap(12)->size(), 75u);
  EXPECT_FALSE(c.sched->PalletMap(13));
}

// Issue 39 item 5: `pallet set 6 NOPROG` was accepted and refused only at `pallet run`. A map is refused
// when the store does not hold one of its programs, and nothing is mapped.
TEST(PalletMaps, AProgramTheStoreDoesNotHoldIsRefusedAtSet) {
  FakeCell c;
  c.Program("A", {}, 10);
  try {
    c.sched->SetPalletMap("m", 6, {"A", "NOPROG"});
    ADD_FAILURE() << "a map naming a missing program was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kNotFound);
    EXPECT_EQ(std::string(e.what()), "pallet 6: program 'NOPROG' not found");
  }
  EXPECT_FALSE(c.sched->PalletMap(6));
  c.sched->SetPalletMap("m2", 6, {"A"});
  EXPECT_EQ(c.sched->PalletMap(6)->size(), 1u);
}

TEST(PalletMaps, RunPalletOnAStation) {
  FakeCell c;
  c.Program("A", {"5"}, 30);
  c.programs.Put("NOFMS", "%\nN10M30\n", "ktapl");  // a non-FMS program: no UCY, 0 s of backlog
  c.Online("KT01", {"5"});
  c.sched->SetPalletMap("m", 9, {"A", "NOFMS"});
  JobResult r = c.sched->RunPallet("run9", 9, "KT01");
  c.Take(r.effects);
  EXPECT_EQ(c.State(r.job_id), JobState::kDispatched);
  EXPECT_EQ(c.InHand("KT01").programs, (std::vector<std::string>{"A", "NOFMS"}));
  EXPECT_EQ(c.Backlog("KT01"), 30);
  EXPECT_EQ(c.sched->Job(r.job_id)->kind, "pallet");
  EXPECT_EQ(CodeOf([&] { c.sched->RunPallet("x", 10, "KT01"); }), Errc::kNotFound);
  EXPECT_EQ(CodeOf([&] { c.sched->RunPallet("y", 9, "KT09"); }), Errc::kNotFound);
}

// Balt-System keeps programs in the control's memories (issue 35 item 4): a map may name "BS01/MP2:P9" (P9 in
// BS01's memory MP2, run by BS01 only) or a plain name a station holds in its own namespace (MP1) when HOST
// does not hold it; the station reads it from there (docs/scheduler.md, "Program names").
TEST(PalletMaps, ProgramsInAStationsMemory) {
  FakeCell c;
  const char* balt = "%:P9\nN1 G0 X10 Y10\nM30\n";
  c.programs.Put("BS01/MP2:P9", balt, "balt");
  c.programs.Put("BS01:PROG1", balt, "balt");
  c.Take(c.sched->StationOnline("BS01", "balt"));
  c.Take(c.sched->StationOnline("BS02", "balt"));
  c.sched->SetPalletMap("m", 4, {"BS01/MP2:P9", "PROG1"});
  JobResult r = c.sched->RunPallet("run4", 4, "BS01");
  c.Take(r.effects);
  EXPECT_EQ(c.State(r.job_id), JobState::kDispatched);
  EXPECT_EQ(c.InHand("BS01").programs, (std::vector<std::string>{"BS01/MP2:P9", "PROG1"}));
  // Another station reads neither BS01's memory nor BS01's namespace.
  c.sched->SetPalletMap("m5", 5, {"BS01/MP2:P9"});
  try {
    c.sched->RunPallet("run5", 5, "BS02");
    ADD_FAILURE() << "BS02 was sent a program in BS01's memory";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kFailedPrecondition);
    EXPECT_EQ(std::string(e.what()),
              "pallet 5: program 'BS01/MP2:P9' is in BS01's memory: only BS01 runs it, not BS02");
  }
  c.sched->SetPalletMap("m6", 6, {"PROG1"});
  EXPECT_EQ(CodeOf([&] { c.sched->RunPallet("run6", 6, "BS02"); }), Errc::kNotFound);
  EXPECT_EQ(CodeOf([&] { c.sched->SetPalletMap("m7", 7, {"BS01/MP3:P9"}); }), Errc::kNotFound);
  EXPECT_EQ(CodeOf([&] { c.sched->SetPalletMap("m8", 8, {"BS01/MP9:P9"}); }), Errc::kInvalidArgument);
  // A route names them the same way, quoted for the ':' (route.h).
  RouteView route = c.Route("R", {"BS01:\"BS01/MP2:P9\",PROG1"});
  EXPECT_TRUE(route.valid);
  EXPECT_EQ(CodeOf([&] { c.Route("R2", {"BS01,BS02:\"BS01/MP2:P9\""}); }), Errc::kFailedPrecondition);
}

// A pallet map may name the pallet's part model (type part_model in the store): it goes to the station
// with the programs (the station hands it to its servo), adds no tools and no backlog; one per map, and not
// alone (docs/scheduler.md, "Part models").
TEST(PalletMaps, APartModelRidesAlongWithThePrograms) {
  FakeCell c;
  c.Program("A", {"5"}, 30);
  c.Program("B", {"5"}, 20);
  c.programs.Put("PLATE9", "[[plane]]\npoint = [0, 0, 50]\nnormal = [0, 0, 1]\n", "", "part_model");
  c.programs.Put("PLATE10", "[[plane]]\npoint = [0, 0, 40]\nnormal = [0, 0, 1]\n", "", "part_model");
  c.Online("KT01", {"5"});
  c.sched->SetPalletMap("m", 9, {"PLATE9", "A", "B"});
  JobResult r = c.sched->RunPallet("run9", 9, "KT01");
  c.Take(r.effects);
  EXPECT_EQ(c.State(r.job_id), JobState::kDispatched);
  EXPECT_EQ(c.InHand("KT01").programs, (std::vector<std::string>{"PLATE9", "A", "B"}));
  EXPECT_EQ(c.Backlog("KT01"), 50);
  c.sched->SetPalletMap("m2", 10, {"PLATE9", "PLATE10", "A"});
  try {
    c.sched->RunPallet("run10", 10, "KT01");
    ADD_FAILURE() << "two part models accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kInvalidArgument);
    EXPECT_EQ(std::string(e.what()), "pallet 10: names 2 part models (PLATE9, PLATE10); a pallet holds one");
  }
  c.sched->SetPalletMap("m3", 11, {"PLATE9"});
  EXPECT_EQ(CodeOf([&] { c.sched->RunPallet("run11", 11, "KT01"); }), Errc::kInvalidArgument);
}

// Issue 13 item 5: a program runs only on a station of its own controller. `route define` and `pallet run`
// refuse a program whose dialect (the program store's record) differs from a listed station's (its station
// file, ConfigureStation), with one line naming both, and record nothing; a program re-put in another dialect
// makes the routes that use it invalid.
TEST(Dialects, ProgramsRunOnlyOnStationsOfTheirDialect) {
  FakeCell c;
  c.Program("PUMP", {}, 100);  // a KT-APL program (FakeCell::Program stores "ktapl")
  c.programs.Put("SHAFT.MIN", "O100\nG00 X10. Z5.\nM02\n", "okuma");
  c.Online("KT01");
  c.sched->ConfigureStation("OK01", "okuma");
  const std::string why =
      "program 'PUMP' is ktapl (Kearney & Trecker KT-APL) but station OK01 runs okuma (Okuma OSP-E100L); a "
      "station runs programs of its own dialect only";
  for (const char* op : {"OK01:PUMP", "KT01,OK01:PUMP"}) {
    try {
      c.Route("R", {op});
      ADD_FAILURE() << op << ": accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.code(), Errc::kFailedPrecondition);
      EXPECT_EQ(std::string(e.what()), "route R op 1: " + why);
    }
  }
  EXPECT_FALSE(c.sched->Route("R"));
  EXPECT_TRUE(c.Route("R", {"KT01:PUMP"}).valid);

  c.sched->SetPalletMap("m", 7, {"PUMP"});
  try {
    c.sched->RunPallet("run-ok", 7, "OK01");
    ADD_FAILURE() << "pallet run accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kFailedPrecondition);
    EXPECT_EQ(std::string(e.what()), "pallet 7: " + why);
  }
  EXPECT_TRUE(c.sched->Jobs().empty());  // no job, the pallet is free
  JobResult kt = c.sched->RunPallet("run-kt", 7, "KT01");
  c.Take(kt.effects);
  EXPECT_EQ(c.State(kt.job_id), JobState::kDispatched);
  c.sched->SetPalletMap("m8", 8, {"SHAFT.MIN"});
  EXPECT_EQ(CodeOf([&] { c.sched->RunPallet("run-kt8", 8, "KT01"); }), Errc::kFailedPrecondition);
  c.Take(c.sched->StationOnline("OK01", "okuma"));
  JobResult ok = c.sched->RunPallet("run-ok8", 8, "OK01");
  c.Take(ok.effects);
  EXPECT_EQ(c.State(ok.job_id), JobState::kDispatched);

  // PUMP is put again as an Okuma program: route R no longer qualifies.
  c.programs.Put("PUMP", "O1\nM02\n", "okuma");
  c.Take(c.sched->ProgramChanged("PUMP"));
  auto r = c.sched->Route("R").value();
  EXPECT_FALSE(r.valid);
  EXPECT_NE(r.invalid_reason.find("program 'PUMP' is okuma (Okuma OSP-E100L) but station KT01 runs ktapl"),
            std::string::npos)
      << r.invalid_reason;
}

TEST(Routes, RevalidatedWhenAProgramChanges) {
  FakeCell c;
  c.Program("A", {"1"}, 100);
  c.Online("KT01", {"1", "2"});
  c.Online("KT02", {"1"});
  c.Route("R", {"KT02,KT01:A"});
  // A new revision needs tool 2 and takes longer.
  c.Program("A", {"1", "2"}, 150);
  c.Take(c.sched->ProgramChanged("A"));
  auto r = c.sched->Route("R").value();
  EXPECT_TRUE(r.valid);
  EXPECT_EQ(r.ops[0].tools, (std::vector<std::string>{"1", "2"}));
  const auto j = c.Operate("R", 1);
  EXPECT_EQ(c.StationOf(j), "KT01");
  EXPECT_EQ(c.Backlog("KT01"), 150);
  // The program loses its UCY: the route is invalid and OPERATE refuses it; a waiting pallet waits for it.
  c.Program("A", {"1"}, -1);
  c.Take(c.sched->ProgramChanged("A"));
  r = c.sched->Route("R").value();
  EXPECT_FALSE(r.valid);
  EXPECT_NE(r.invalid_reason.find("no (UCY,seconds)"), std::string::npos);
  EXPECT_EQ(CodeOf([&] { c.Operate("R", 2); }), Errc::kFailedPrecondition);
  // Fixed again: valid.
  c.Program("A", {"1"}, 80);
  c.Take(c.sched->ProgramChanged("A"));
  EXPECT_TRUE(c.sched->Route("R")->valid);
  EXPECT_EQ(c.StationOf(c.Operate("R", 2)), "KT02");
}

TEST(Routes, WaitingPalletFollowsProgramChanges) {
  FakeCell c;
  c.Program("A", {"1"}, 100);
  c.Online("KT01");
  c.Route("R", {"KT01:A"});
  const auto j = c.Operate("R", 1);
  EXPECT_EQ(c.Reason(j), "no eligible station: KT01 missing tools 1");
  c.programs.Remove("A");
  c.Take(c.sched->ProgramChanged("A"));
  EXPECT_EQ(c.Reason(j), "route R op 1: program 'A' not found");
  c.Program("A", {}, 100);  // the new revision needs no tool
  c.Take(c.sched->ProgramChanged("A"));
  EXPECT_EQ(c.State(j), JobState::kDispatched);
}

// DESIGN §5: "a PSELECT with Q=n dispatches n runs of the main program to the station, one after another; IF
// and VSET read and write the station's common variables V1-V200". Okuma seed lines 8791-8924.
TEST(Schedules, PselectRunsOneAfterAnotherWithStationVariables) {
  FakeCell c;
  c.Take(c.sched->StationOnline("OK01", "okuma"));
  c.Take(c.sched->StationVariables("OK01", {{1, 7}}));
  const char* text =
      "N001 VSET V2=0\n"
      "N010 IF [V1 LT 7] N900\n"
      "N020 PSELECT A.MIN,O100,,Q=2\n"
      "N030 VSET V2=V2+1\n"
      "N040 IF [V2 LT 2] N020\n"
      "N050 PSELECT MD1:B.MIN,O200\n"
      "END\n"
      "N900 PSELECT C.MIN\n";
  JobResult r = c.sched->RunSchedule("sched-1", "SHAFT-1.SDF", text, "OK01");
  c.Take(r.effects);
  ASSERT_EQ(r.effects.variables.size(), 1u);  // VSET V2=0 goes to the station
  EXPECT_EQ(r.effects.variables[0].station, "OK01");
  EXPECT_EQ(r.effects.variables[0].number, 2);
  EXPECT_EQ(r.effects.variables[0].value, 0);
  std::vector<std::string> order;
  for (int guard = 0; guard < 10 && c.State(r.job_id) != JobState::kCompleted; ++guard) {
    const DispatchAction d = c.InHand("OK01");
    ASSERT_TRUE(d.schedule_run);
    EXPECT_EQ(d.pallet, 0);
    order.push_back(d.programs.at(0) + "/" + d.schedule_run->program + "#" +
                    std::to_string(d.schedule_run->index));
    c.Complete(d.dispatch_id);
  }
  EXPECT_EQ(order, (std::vector<std::string>{"A.MIN/O100#1", "A.MIN/O100#2", "A.MIN/O100#1", "A.MIN/O100#2",
                                             "B.MIN/O200#1"}));
  EXPECT_EQ(c.State(r.job_id), JobState::kCompleted);
  EXPECT_EQ(c.sched->StationCommonVariables("OK01").at(2), 2);
  auto v = c.sched->Job(r.job_id).value();
  EXPECT_EQ(v.kind, "schedule");
  EXPECT_EQ(v.schedule, "SHAFT-1.SDF");
}

// A schedule program runs on the control from its first block to END with nothing between its PSELECTs, and
// its loops count in the station's common variables (Okuma seed lines 8767-8790, 8866-8924): a second
// schedule on the station waits unstepped (its VSET V1=100 would break the first's loop) and a pallet waits,
// until the running schedule ends; then the second schedule starts, and after it the pallet. The simulated
// week (chaos_test Chaos.Week) found two schedules on one station taking turns: four runs for one, two for
// the other.
TEST(Schedules, OneScheduleAtATimeHasItsStationToItself) {
  FakeCell c;
  c.Take(c.sched->StationOnline("OK01", "okuma"));
  c.programs.Put("P.MIN", "O1\nG00 X10\nM02\n", "okuma");
  c.Route("R", {"OK01:P.MIN"});
  JobResult first = c.sched->RunSchedule(
      "a", "S1.SDF", "N1 VSET V1=0\nN2 PSELECT A.MIN,O1\nVSET V1=V1+1\nIF [V1 LT 2] N2\nEND", "OK01");
  c.Take(first.effects);
  JobResult second = c.sched->RunSchedule("b", "S2.SDF", "VSET V1=100\nPSELECT B.MIN,O2\nEND", "OK01");
  c.Take(second.effects);
  EXPECT_TRUE(second.effects.variables.empty());
  EXPECT_EQ(c.State(second.job_id), JobState::kWaiting);
  EXPECT_EQ(c.Reason(second.job_id), "OK01 runs schedule job " + std::to_string(first.job_id) +
                                         ": this schedule starts when that one ends");
  const auto pallet = c.Operate("R", 1);
  EXPECT_EQ(c.Reason(pallet), "no eligible station: OK01 runs schedule job " + std::to_string(first.job_id));
  for (int run = 1; run <= 2; ++run) {
    const DispatchAction d = c.InHand("OK01");
    EXPECT_EQ(d.job_id, first.job_id) << "run " << run;
    c.Complete(d.dispatch_id);
  }
  EXPECT_EQ(c.State(first.job_id), JobState::kCompleted);
  EXPECT_EQ(c.sched->StationCommonVariables("OK01").at(1), 100);  // the second's VSET, sent as it started
  const DispatchAction b = c.InHand("OK01");
  EXPECT_EQ(b.job_id, second.job_id);
  EXPECT_EQ(b.programs, std::vector<std::string>{"B.MIN"});
  EXPECT_EQ(c.Reason(pallet), "no eligible station: OK01 runs schedule job " + std::to_string(second.job_id));
  c.Complete(b.dispatch_id);
  EXPECT_EQ(c.State(second.job_id), JobState::kCompleted);
  EXPECT_EQ(c.InHand("OK01").job_id, pallet);
}

TEST(Schedules, AlarmsFailTheJobAndBadProgramsAreRefused) {
  FakeCell c;
  c.Take(c.sched->StationOnline("OK01", "okuma"));
  EXPECT_EQ(CodeOf([&] { c.sched->RunSchedule("k0", "BAD.SDF", "G00 X1\nEND", "OK01"); }),
            Errc::kInvalidArgument);
  EXPECT_EQ(CodeOf([&] { c.sched->RunSchedule("k1", "S.SDF", "END", "OK09"); }), Errc::kNotFound);
  JobResult r = c.sched->RunSchedule("k2", "S.SDF", "PSELECT A.MIN,O1\nPSELECT A.MIN,O2,,Q=V9\nEND", "OK01");
  c.Take(r.effects);
  c.Complete(c.InHand("OK01").dispatch_id);
  EXPECT_EQ(c.State(r.job_id), JobState::kFailed);
  EXPECT_EQ(c.Reason(r.job_id), "S.SDF:2:21: error: repeat count Q=0 outside 1-9999");
  JobResult e = c.sched->RunSchedule("k3", "E.SDF", "END", "OK01");
  EXPECT_EQ(c.State(e.job_id), JobState::kCompleted);
}

// Issue 39: `job show` of a job that waited through many changes failed "reply too large". The first
// decision and the newest that fit are kept, with a count of those left out between them.
TEST(Views, AJobShowKeepsTheFirstAndNewestDecisionsWithinTheBound) {
  nlohmann::json job = {{"id", 7}, {"state", "WAITING"}, {"decisions", nlohmann::json::array()}};
  for (int i = 1; i <= 100; ++i) job["decisions"].push_back({{"seq", i}, {"why", std::string(90, 'w')}});
  EXPECT_EQ(FitJobShow(job, 1u << 20), job);  // fits: unchanged, no count
  const nlohmann::json fit = FitJobShow(job, 2000);
  EXPECT_LE(fit.dump().size(), 2000u);
  const auto& kept = fit["decisions"];
  ASSERT_GE(kept.size(), 3u);
  EXPECT_EQ(kept.front()["seq"], 1);
  EXPECT_EQ(kept.back()["seq"], 100);
  for (std::size_t i = 2; i < kept.size(); ++i) EXPECT_EQ(kept[i]["seq"], kept[i - 1]["seq"].get<int>() + 1);
  EXPECT_EQ(fit["decisions_omitted"], 100 - static_cast<int>(kept.size()));
  EXPECT_EQ(fit["state"], "WAITING");
}

TEST(Views, JsonShapesOfDesignSection6) {
  FakeCell c;
  c.Program("A", {"3"}, 100);
  c.Online("KT01", {"3"});
  c.Route("R", {"KT01:A"});
  const auto j = c.Operate("R", 4);
  auto job = nlohmann::json(ToJson(c.sched->Job(j).value(), true));
  for (const char* k : {"id", "state", "route", "pallet", "station", "reason", "started", "finished",
                        "cycle_s", "decisions"}) {
    EXPECT_TRUE(job.contains(k)) << k;
  }
  EXPECT_EQ(job["state"], "DISPATCHED");
  EXPECT_TRUE(job["reason"].is_null());
  EXPECT_TRUE(job["started"].is_null());
  EXPECT_EQ(job["decisions"][0]["winner"], "KT01");
  EXPECT_EQ(job["decisions"][0]["considered"][0]["backlog_s"], 0);
  c.Complete(c.InHand("KT01").dispatch_id, 95.5);
  job = ToJson(c.sched->Job(j).value(), false);
  EXPECT_EQ(job["started"], "2026-11-18T11:06:40Z");
  EXPECT_EQ(job["cycle_s"], 95.5);
  EXPECT_FALSE(job.contains("decisions"));
  // job ls asks for no decisions (Jobs(false)); each row still counts them.
  EXPECT_EQ(ToJson(c.sched->Jobs(false).at(0), false)["decision_count"], 1);
  // The station row is the records module's (station ls and the dashboard print it); the scheduler's view
  // gives it the backlog and the online state it keeps.
  auto st = c.sched->Station("KT01").value();
  EXPECT_EQ(st.backlog_s, 0);
  EXPECT_TRUE(st.online);
  auto tools = ToolsJson(c.sched->StationToolTable("KT01").value());
  EXPECT_EQ(tools[0]["tool"], "3");
  EXPECT_EQ(tools[0]["socket"], 1);
  EXPECT_EQ(tools[0]["length"], 100.0);
}

}  // namespace
}  // namespace cell::scheduler
