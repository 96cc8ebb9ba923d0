// The station core without DDS: queue order, execution, cancel, the panel, and what programs leave in the
// CNC's memory (KT-APL machine parameters and TLD, manual ln 8513-8525 and 3975-4097), at each step.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "cell/store/sqlite.h"
#include "harness.h"

namespace cell::station::testing {
namespace {

double Target(const cell::MotionSegment& s, int axis) {
  return s.target()[static_cast<size_t>(axis)];
}

using StationCore = StationHarness;

TEST_F(StationCore, RunsDispatchesInArrivalOrderOnceEach) {
  Put("P", Moves(2));
  EXPECT_EQ(Dispatch(30, {"P"}).state(), cell::RUN_QUEUED);
  clock_.Advance(std::chrono::seconds(1));
  EXPECT_EQ(Dispatch(10, {"P"}).state(), cell::RUN_QUEUED);
  clock_.Advance(std::chrono::seconds(1));
  EXPECT_EQ(Dispatch(20, {"P"}).state(), cell::RUN_QUEUED);
  // A re-sent request (a restarted scheduler) gets the state the station has; nothing is queued twice.
  EXPECT_EQ(Dispatch(10, {"P"}).state(), cell::RUN_QUEUED);
  EXPECT_EQ(station_->Status().queued(), 3);

  std::vector<std::int32_t> order;
  while (station_->RunNext()) order.push_back(io_.runs.back().dispatch_id());
  EXPECT_EQ(order, (std::vector<std::int32_t>{30, 10, 20}));
  for (std::int32_t id : {30, 10, 20}) {
    EXPECT_EQ(io_.LastRun(id)->state(), cell::RUN_COMPLETED) << id;
    EXPECT_EQ(servo_.Ran(id, cell::SEGMENT_END).size(), 1u) << id;
  }
  EXPECT_EQ(Dispatch(10, {"P"}).state(), cell::RUN_COMPLETED);
  EXPECT_FALSE(station_->RunNext());
  EXPECT_EQ(station_->Status().queued(), 0);
  EXPECT_EQ(station_->Status().part_count(), 3u);
  EXPECT_EQ(station_->Status().execution(), cell::EXECUTION_PROGRAM_COMPLETED);
}

TEST_F(StationCore, RefusesMalformedRequests) {
  auto wrong = Request(1, {"P"});
  wrong.station("KT02");
  EXPECT_THROW(station_->OnRun(wrong), Error);
  EXPECT_THROW(station_->OnRun(Request(0, {"P"})), Error);
  EXPECT_THROW(station_->OnRun(Request(1, {})), Error);
  EXPECT_THROW(station_->OnRun(Request(1, {"P"}, 1, 10000)), Error);
  EXPECT_FALSE(station_->RunNext());
}

TEST_F(StationCore, RunsEveryProgramOfTheMapRepeatAndReportsProgress) {
  Put("A", Moves(1));
  Put("B", Moves(2), "HOST");  // not in KT01's namespace: HOST is next
  ASSERT_EQ(station_->OnRun(Request(5, {"A", "B"}, 7, 2)).state(), cell::RUN_QUEUED);
  auto end = RunOne(5);
  EXPECT_EQ(end.state(), cell::RUN_COMPLETED) << end.reason();
  EXPECT_EQ(end.programs_done(), 4);
  EXPECT_EQ(end.pallet(), 7);
  EXPECT_EQ(io_.fetched, (std::vector<std::string>{"A", "B", "A", "B"}));
  // A status per program start and end (the scheduler takes UCY off the backlog at each end).
  std::vector<int> done;
  for (const auto& r : io_.runs)
    if (r.state() == cell::RUN_ACTIVE) done.push_back(r.programs_done());
  EXPECT_EQ(done, (std::vector<int>{0, 1, 1, 2, 2, 3, 3, 4}));
  ASSERT_EQ(io_.records.size(), 1u);  // the run record went to the inspection writer
  EXPECT_TRUE(io_.records[0].run().completed());
  EXPECT_EQ(io_.records[0].run().dispatch_id(), 5);
}

// While a run goes on the status is sampled every status period, but published only when it changed: a
// block of two commands (here the move and its M08) or a long move is one sample, not one per period.
TEST_F(StationCore, TheRunsPeriodicStatusIsPublishedOnlyWhenItChanged) {
  options_.status_period = Clock::Duration(-1);  // a sample at every command
  Make();
  Put("A", "G71 G90\nG01 X0 Y0 Z100. F0\nS1000 M03\nX1. F1000. M08\nX2.\nM30\n");
  ASSERT_EQ(station_->OnRun(Request(5, {"A"})).state(), cell::RUN_QUEUED);
  const std::size_t before = io_.status.size();
  EXPECT_EQ(RunOne(5).state(), cell::RUN_COMPLETED);
  std::set<int> lines;
  for (std::size_t i = before; i < io_.status.size(); ++i) {
    lines.insert(io_.status[i].line());
    if (i == before) continue;
    cell::StationStatus a = io_.status[i - 1], b = io_.status[i];
    a.updated_ns(0);
    b.updated_ns(0);
    EXPECT_NE(a, b) << "sample " << i << " repeats the one before it (line " << b.line() << ")";
  }
  for (int line : {2, 3, 4, 5}) EXPECT_TRUE(lines.count(line)) << "line " << line << " never shown";
}

// The text of each program a run starts goes out for the toolpath view (topics::kStationProgram), whole up to
// the sample's 65,536 characters; a longer one goes with its size and no text, so that no page draws a cut
// program as if it were whole.
TEST_F(StationCore, EachProgramARunStartsIsPublishedWithItsText) {
  Put("A", Moves(1));
  std::string big = Moves(1);
  big.insert(big.find('\n') + 1, std::string(70000, '\n'));  // empty blocks
  Put("BIG", big);
  ASSERT_EQ(station_->OnRun(Request(6, {"A", "BIG"})).state(), cell::RUN_QUEUED);
  EXPECT_EQ(RunOne(6).state(), cell::RUN_COMPLETED);
  ASSERT_EQ(io_.programs_run.size(), 2u);
  const cell::StationProgram& a = io_.programs_run[0];
  EXPECT_EQ(a.station().to_string(), "KT01");
  EXPECT_EQ(a.dispatch_id(), 6);
  EXPECT_EQ(a.program().to_string(), "A");
  EXPECT_EQ(a.text().to_string(), Moves(1));
  EXPECT_EQ(a.size(), Moves(1).size());
  const cell::StationProgram& b = io_.programs_run[1];
  EXPECT_EQ(b.program().to_string(), "BIG");
  EXPECT_EQ(b.size(), big.size());
  EXPECT_TRUE(b.text().to_string().empty());
}

TEST_F(StationCore, MissingProgramAndProgramErrorFailTheRun) {
  ASSERT_EQ(Dispatch(1, {"NOPE"}).state(), cell::RUN_QUEUED);
  auto miss = RunOne(1);
  EXPECT_EQ(miss.state(), cell::RUN_FAILED);
  EXPECT_EQ(miss.reason(), "program 'NOPE' is not in KT01 or HOST");

  Put("BAD", "G71\nG01 X10. F1000.\nG31\nM30\n");
  ASSERT_EQ(Dispatch(2, {"BAD"}).state(), cell::RUN_QUEUED);
  auto bad = RunOne(2);
  EXPECT_EQ(bad.state(), cell::RUN_FAILED);
  EXPECT_NE(bad.reason().to_string().find("BAD:3:"), std::string::npos) << bad.reason();
  EXPECT_EQ(station_->Status().condition(), cell::CONDITION_WARNING);
  EXPECT_EQ(station_->Status().execution(), cell::EXECUTION_STOPPED);
  Command(cell::STATION_RESET);
  EXPECT_EQ(station_->Status().condition(), cell::CONDITION_NORMAL);
}

TEST_F(StationCore, CancelOfAQueuedDispatchNeverRunsIt) {
  Put("P", Moves(1));
  Dispatch(1, {"P"});
  Dispatch(2, {"P"});
  EXPECT_EQ(Cancel(1).state(), cell::RUN_QUEUED);  // the state it had
  EXPECT_EQ(Cancel(1).state(), cell::RUN_CANCELLED);
  EXPECT_EQ(Cancel(99).state(), cell::RUN_CANCELLED);  // unknown: nothing to do
  EXPECT_TRUE(station_->RunNext());
  EXPECT_FALSE(station_->RunNext());
  EXPECT_TRUE(servo_.Ran(1, cell::SEGMENT_END).empty());
  EXPECT_EQ(io_.LastRun(2)->state(), cell::RUN_COMPLETED);
}

// A run does not start while the program store is away (restarting): it waits for it, 30 s, and only then
// fails the run with a reason that says so, before any motion.
TEST_F(StationCore, ARunWaitsForTheProgramStoreBeforeItStarts) {
  Put("P", Moves(1));
  io_.store_absent = true;
  Dispatch(1, {"P"});
  const auto failed = RunOne(1);
  EXPECT_EQ(failed.state(), cell::RUN_FAILED);
  EXPECT_EQ(failed.reason(), "no program store on the bus for station KT01 (waited 30 s)");
  EXPECT_TRUE(io_.fetched.empty());
  EXPECT_TRUE(servo_.Ran(1, cell::SEGMENT_END).empty());
  io_.store_absent = false;
  Dispatch(2, {"P"});
  EXPECT_EQ(RunOne(2).state(), cell::RUN_COMPLETED);
  EXPECT_EQ(io_.store_waited,
            (std::vector<Clock::Duration>{std::chrono::seconds(30), std::chrono::seconds(30)}));
}

// The work thread takes a queued dispatch while a cancel for it is on its way: one of the two has it, whole.
// A cancel that comes second finds the run active and stops it as a running one (Station::OnRun); a run start
// that comes second finds nothing to take. Both are single statements under the database's lock, so the
// cancel cannot be overwritten by the start nor the start by the cancel (docs/station.md "Run queue").
TEST_F(StationCore, ACancelAndTheRunStartNeverBothHaveAQueuedDispatch) {
  Put("P", Moves(1));
  Dispatch(1, {"P"});
  Dispatch(2, {"P"});
  StationDb raw(db());
  const auto taken = raw.TakeNext(5);  // the work thread had dispatch 1 first
  ASSERT_TRUE(taken);
  EXPECT_EQ(taken->dispatch_id, 1);
  EXPECT_FALSE(raw.CancelQueued(1, "cancelled by the scheduler", 6));
  EXPECT_EQ(raw.FindRun(1), RunState::kActive);
  EXPECT_EQ(raw.Progress(1).first, 5);
  EXPECT_TRUE(raw.CancelQueued(2, "cancelled by the scheduler", 7));  // the cancel had dispatch 2 first
  EXPECT_FALSE(raw.TakeNext(8));
  EXPECT_EQ(raw.FindRun(2), RunState::kCancelled);
  EXPECT_EQ(raw.Progress(2).first, 0);  // never started
}

// A scheduler that lost sight of the station asks again about the dispatch it held (the same request, or a
// cancel after a fault): the station answers from its database, on the run topic too, since the end may have
// been published by a process that died before anyone read it (docs/scheduler.md §5).
TEST_F(StationCore, AskedAgainTheStationSaysWhatBecameOfADispatch) {
  Put("P", Moves(1));
  Dispatch(1, {"P"});
  ASSERT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  io_.runs.clear();
  const auto again = Dispatch(1, {"P"});
  EXPECT_EQ(again.state(), cell::RUN_COMPLETED);
  // The reply carries the run as recorded too: the scheduler settles the dispatch from it even when the
  // event is lost (issue 43).
  EXPECT_EQ(again.run().dispatch_id(), 1);
  EXPECT_EQ(again.run().state(), cell::RUN_COMPLETED);
  EXPECT_EQ(again.run().programs_done(), 1);
  EXPECT_GT(again.run().machine_s(), 0.0);
  ASSERT_EQ(io_.runs.size(), 1u);
  EXPECT_EQ(io_.runs[0].state(), cell::RUN_COMPLETED);
  EXPECT_EQ(io_.runs[0].programs_done(), 1);
  EXPECT_EQ(io_.runs[0].job_id(), 101);
  EXPECT_GT(io_.runs[0].started_ns(), 0);
  EXPECT_GT(io_.runs[0].machine_s(), 0.0);
  io_.runs.clear();
  EXPECT_EQ(Cancel(1).state(), cell::RUN_COMPLETED);  // too late to cancel: said again as it ended
  ASSERT_EQ(io_.runs.size(), 1u);
  EXPECT_EQ(io_.runs[0].state(), cell::RUN_COMPLETED);

  // Cancelled from the queue: said as a run that never started.
  Dispatch(2, {"P"});
  io_.runs.clear();
  const auto dropped = Cancel(2);
  EXPECT_EQ(dropped.state(), cell::RUN_QUEUED);
  EXPECT_EQ(dropped.run().state(), cell::RUN_CANCELLED);  // as it is now
  EXPECT_EQ(dropped.run().started_ns(), 0);
  ASSERT_EQ(io_.runs.size(), 1u);
  EXPECT_EQ(io_.runs[0].state(), cell::RUN_CANCELLED);
  EXPECT_EQ(io_.runs[0].started_ns(), 0);

  // Cancelled before it arrived: kept as cancelled and said as never started; the request arriving late
  // cannot start it (the scheduler has given the pallet to another dispatch).
  io_.runs.clear();
  EXPECT_EQ(Cancel(3).state(), cell::RUN_CANCELLED);
  ASSERT_EQ(io_.runs.size(), 1u);
  EXPECT_EQ(io_.runs[0].state(), cell::RUN_CANCELLED);
  EXPECT_EQ(io_.runs[0].job_id(), 103);
  EXPECT_EQ(io_.runs[0].started_ns(), 0);
  EXPECT_EQ(Dispatch(3, {"P"}).state(), cell::RUN_CANCELLED);
  EXPECT_FALSE(station_->RunNext());
  EXPECT_TRUE(servo_.Ran(3, cell::SEGMENT_END).empty());
  Make();  // and so it stays across a restart
  EXPECT_EQ(Dispatch(3, {"P"}).state(), cell::RUN_CANCELLED);
  EXPECT_FALSE(station_->RunNext());
}

TEST_F(StationCore, CancelOfTheRunningDispatchStopsSendingAndAbortsTheMachine) {
  Put("LONG", Moves(40));
  Dispatch(3, {"LONG"});
  bool cancelled = false;
  script_ = [&] {
    if (!cancelled && servo_.ran.size() >= 6) {
      cancelled = true;
      EXPECT_EQ(Cancel(3).state(), cell::RUN_ACTIVE);
    }
  };
  auto end = RunOne(3);
  EXPECT_EQ(end.state(), cell::RUN_CANCELLED);
  EXPECT_EQ(end.reason(), "cancelled");
  EXPECT_LT(servo_.written.size(), 20u);  // it stopped sending
  ASSERT_FALSE(io_.control.empty());
  EXPECT_EQ(io_.control.back().abort_run(), 3);  // the servo stops the run too
  ASSERT_EQ(io_.records.size(), 1u);
  EXPECT_FALSE(io_.records[0].run().completed());
}

TEST_F(StationCore, PanelHoldIsPersistedAndTheServosReportShowsFeedHold) {
  EXPECT_FALSE(station_->Control().feed_hold());
  auto rev = Command(cell::STATION_FEED_HOLD).revision();
  EXPECT_TRUE(io_.control.back().feed_hold());
  EXPECT_EQ(io_.control.back().revision(), rev);
  cell::StationRequest o;
  o.op(cell::STATION_OVERRIDE);
  o.feed_override(0.5);
  o.rapid_override(-1);  // unchanged
  station_->OnCommand(o);
  EXPECT_DOUBLE_EQ(io_.control.back().feed_override(), 0.5);
  EXPECT_DOUBLE_EQ(io_.control.back().rapid_override(), 1.0);
  o.feed_override(2.5);
  EXPECT_THROW(station_->OnCommand(o), Error);

  // A restarted interpreter keeps the machine held (the panel is persisted).
  Make();
  EXPECT_TRUE(station_->Control().feed_hold());
  EXPECT_DOUBLE_EQ(station_->Control().feed_override(), 0.5);
  EXPECT_TRUE(io_.control.back().feed_hold());

  // The display follows the servo's report, not the button: FEED_HOLD while held mid-run, ACTIVE after.
  Put("P", Moves(6));
  Dispatch(1, {"P"});
  std::vector<cell::Execution> shown;
  servo_.hold = true;
  script_ = [&] {
    shown.push_back(station_->Status().execution());
    if (clock_.waits() == 10) {
      EXPECT_EQ(station_->Status().execution(), cell::EXECUTION_FEED_HOLD);
      Command(cell::STATION_CYCLE_START);
      servo_.hold = false;
    }
  };
  EXPECT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  EXPECT_NE(std::find(shown.begin(), shown.end(), cell::EXECUTION_FEED_HOLD), shown.end());
  EXPECT_NE(std::find(shown.begin(), shown.end(), cell::EXECUTION_ACTIVE), shown.end());
  EXPECT_FALSE(station_->Control().feed_hold());
}

// ---- what programs change, kept ----

// Manual ln 8513-8525 (machine parameters survive the program), 3975-4097 (TLD): a program sets L1500 and
// loads tool 4001 with a 50 mm length; the next program reads L1500 as its X and uses 4001, whose length
// offsets Z (programmed Z100. -> 150 mm).
const char* kSetter = "G71\n(PAR,L1500=7.)\n(TLD,S6T4001P50.D10.L130)\nG90 G01 X0 Y0 Z100. F0\nM30\n";
const char* kReader = "G71\nT4001 M06\nG90 G01 XL1500 Y0 Z100. F0\nM30\n";

TEST_F(StationCore, MachineParametersAndToolDataSurviveTheProgramAndTheProcess) {
  Put("SET", kSetter);
  Put("USE", kReader);
  Dispatch(1, {"SET"});
  ASSERT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  EXPECT_EQ(Variables().at("L1500"), 7.0);
  ASSERT_NE(Tool("4001"), nullptr);
  EXPECT_DOUBLE_EQ(Tool("4001")->length, 50.0);
  EXPECT_EQ(Tool("4001")->socket, 6);
  EXPECT_EQ(Tool("4001")->life_left_min, 90);
  // Published: the variables by the dialect's own name, the tool table with the new tool.
  EXPECT_EQ(io_.LastVariables().at("L1500"), 7.0);
  ASSERT_FALSE(io_.tools.empty());
  EXPECT_EQ(io_.tools.back().tools().back().tool(), "4001");

  Make();  // a restarted process starts from what was committed
  EXPECT_EQ(Variables().at("L1500"), 7.0);
  ASSERT_NE(Tool("4001"), nullptr);
  EXPECT_EQ(io_.LastVariables().at("L1500"), 7.0);  // announced again at start

  Dispatch(2, {"USE"});
  ASSERT_EQ(RunOne(2).state(), cell::RUN_COMPLETED);
  auto moves = servo_.Ran(2, cell::SEGMENT_RAPID);
  ASSERT_FALSE(moves.empty());
  EXPECT_NEAR(Target(moves.back(), 0), 7.0, 1e-9);
  EXPECT_NEAR(Target(moves.back(), 2), 150.0, 1e-9);
  ASSERT_EQ(servo_.Ran(2, cell::SEGMENT_TOOL_CHANGE).size(), 1u);
  EXPECT_EQ(servo_.Ran(2, cell::SEGMENT_TOOL_CHANGE)[0].tool(), "4001");
}

TEST_F(StationCore, TheNextProgramOfTheSameDispatchStartsFromWhatTheFirstCommitted) {
  Put("SET", kSetter);
  Put("USE", kReader);
  // Just before USE is fetched, the first program's changes are on disk: a second connection sees them.
  std::optional<MemoryImage> on_disk;
  io_.on_fetch = [&](const std::string& name) {
    if (name == "USE") on_disk = StationDb(db()).LoadMemory();
  };
  Dispatch(1, {"SET", "USE"});
  ASSERT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  ASSERT_TRUE(on_disk);
  EXPECT_EQ(on_disk->variables.at("L1500"), 7.0);
  EXPECT_NE(on_disk->tools.Find("4001"), nullptr);
  auto moves = servo_.Ran(1, cell::SEGMENT_RAPID);
  EXPECT_NEAR(Target(moves.back(), 0), 7.0, 1e-9);
  EXPECT_NEAR(Target(moves.back(), 2), 150.0, 1e-9);
}

TEST_F(StationCore, AFailingProgramKeepsWhatItChangedBeforeTheError) {
  Put("FAIL", "G71\n(PAR,L1500=3.,L1501=4.)\n(TLD,T4002P20.)\nG01 X10. F1000.\nG31\nM30\n");
  Dispatch(1, {"FAIL"});
  EXPECT_EQ(RunOne(1).state(), cell::RUN_FAILED);
  Make();
  EXPECT_EQ(Variables().at("L1500"), 3.0);
  EXPECT_EQ(Variables().at("L1501"), 4.0);
  ASSERT_NE(Tool("4002"), nullptr);
  EXPECT_DOUBLE_EQ(Tool("4002")->length, 20.0);
}

TEST_F(StationCore, DeletedParametersAndZtbAreKept) {
  SetVariable("L1500", 1);
  SetVariable("L1600", 2);
  SetVariable("V5", 9);  // a schedule variable: not the program's to delete
  Put("DEL", "G71\n(DLP,L1500)\n(ZTB,T)\n(TLD,T4003P1.)\nM30\n");
  Dispatch(1, {"DEL"});
  ASSERT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  auto v = Variables();
  EXPECT_EQ(v.count("L1500"), 0u);
  EXPECT_EQ(v.at("L1600"), 2.0);
  EXPECT_EQ(v.at("V5"), 9.0);
  auto tools = station_->MemoryState().image.tools;
  ASSERT_EQ(tools.entries().size(), 1u);  // ZTB,T cleared the table, then one TLD
  EXPECT_EQ(tools.entries()[0].tool, "4003");
  Make();
  EXPECT_EQ(Variables().count("L1500"), 0u);
  EXPECT_EQ(station_->MemoryState().image.tools.entries().size(), 1u);
}

TEST_F(StationCore, WhatTheOperatorChangesDuringARunAndTheProgramDoesNotTouchStays) {
  Put("SET", kSetter);
  bool loaded = false;
  script_ = [&] {
    if (loaded) return;
    loaded = true;
    SetVariable("L1700", 5);
    Command(cell::STATION_LOAD_TOOLS, "(TLD,S7T5001P10.)\n");
  };
  Dispatch(1, {"SET"});
  ASSERT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  EXPECT_EQ(Variables().at("L1700"), 5.0);
  EXPECT_EQ(Variables().at("L1500"), 7.0);
  EXPECT_NE(Tool("5001"), nullptr);
  EXPECT_NE(Tool("4001"), nullptr);
  EXPECT_NE(Tool("1001"), nullptr);
}

TEST_F(StationCore, VariablesTheOperatorSetsAreCheckedByTheDialectsRule) {
  EXPECT_GT(SetVariable("L1500", 7).revision(), 0u);
  SetVariable("V200", -1.5);
  EXPECT_THROW(SetVariable("L3000", 1), Error);  // read-only system parameter
  EXPECT_THROW(SetVariable("L999", 1), Error);   // program parameter: cleared by M30
  EXPECT_THROW(SetVariable("L1500", 1e10), Error);
  EXPECT_THROW(SetVariable("V201", 1), Error);
  EXPECT_THROW(SetVariable("E12", 1), Error);  // Balt-System's, not a KT-APL station's
  try {
    SetVariable("L3000", 1);
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("L1000..L2999"), std::string::npos) << e.what();
  }
  EXPECT_EQ(Variables(), (std::map<std::string, double>{{"L1500", 7}, {"V200", -1.5}}));
  Make();
  EXPECT_EQ(Variables(), (std::map<std::string, double>{{"L1500", 7}, {"V200", -1.5}}));
}

TEST_F(StationCore, ToolLoadsKeepEveryTldFieldAcrossARestart) {
  // A manual tool has no socket (tooltable's rule); 7001 has one.
  Command(cell::STATION_LOAD_TOOLS,
          "G71\n(TLD,T33412.5CMP100.D-6.35L0130H7.5)\n(TLD,T33412.5W38P.5D.1)\n(TLD,S9T7001P80.)\n");
  Make();
  auto tools = station_->MemoryState().image.tools;
  const auto* e = tools.Find("33412.5");
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->socket, 0);
  EXPECT_EQ(tools.Find("7001")->socket, 9);
  EXPECT_TRUE(e->check);
  EXPECT_TRUE(e->manual);
  EXPECT_DOUBLE_EQ(e->length, 100.0);
  EXPECT_DOUBLE_EQ(e->diameter, -6.35);
  EXPECT_EQ(e->life_left_min, 90);
  EXPECT_DOUBLE_EQ(e->max_hp, 7.5);
  ASSERT_EQ(tools.process_comps().size(), 1u);
  EXPECT_EQ(tools.process_comps()[0].pallet, 38);
  EXPECT_DOUBLE_EQ(tools.process_comps()[0].length, 0.5);
  // Published with every field.
  const auto& wire = io_.tools.back();
  ASSERT_EQ(wire.process().size(), 1u);
  EXPECT_EQ(wire.process()[0].pallet(), 38);
}

TEST_F(StationCore, ProcessCompensationOfThePalletOnTheTableApplies) {
  // TLD W (manual ln 4060-4080): added to the tool's data while that pallet is on the table.
  Command(cell::STATION_LOAD_TOOLS, "G71\n(TLD,S6T4001P50.)\n(TLD,T4001W38P2.)\n");
  Put("USE", "G71\nT4001 M06\nG90 G01 X0 Y0 Z100. F0\nM30\n");
  Dispatch(1, {"USE"}, 38);
  ASSERT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  EXPECT_NEAR(Target(servo_.Ran(1, cell::SEGMENT_RAPID).back(), 2), 152.0, 1e-9);
  Dispatch(2, {"USE"}, 5);
  ASSERT_EQ(RunOne(2).state(), cell::RUN_COMPLETED);
  EXPECT_NEAR(Target(servo_.Ran(2, cell::SEGMENT_RAPID).back(), 2), 150.0, 1e-9);
}

// A coded-pallet module (KT04: `coded_pallets = true`) has pallets 1-127 (ln 4081-4083): a tool load or a
// program's TLD naming W200 is refused, W127 applies while pallet 127 is on the table (150 + 2 = 152).
TEST_F(StationCore, ACodedPalletModuleTakesProcessCompensationsFor1To127) {
  cfg_.coded_pallets = true;
  Make();
  EXPECT_THROW(Command(cell::STATION_LOAD_TOOLS, "G71\n(TLD,S6T4001P50.)\n(TLD,T4001W200P2.)\n"), Error);
  EXPECT_EQ(station_->MemoryState().image.tools.Find("4001"), nullptr);  // all or nothing
  Command(cell::STATION_LOAD_TOOLS, "G71\n(TLD,S6T4001P50.)\n(TLD,T4001W127P2.)\n");
  Put("USE", "G71\nT4001 M06\nG90 G01 X0 Y0 Z100. F0\nM30\n");
  Dispatch(1, {"USE"}, 127);
  ASSERT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  EXPECT_NEAR(Target(servo_.Ran(1, cell::SEGMENT_RAPID).back(), 2), 152.0, 1e-9);
  Put("TLD", "G71\n(TLD,T4001W200P2.)\nM30\n");
  Dispatch(2, {"TLD"}, 127);
  cell::RunStatus refused = RunOne(2);
  EXPECT_EQ(refused.state(), cell::RUN_FAILED);
  EXPECT_NE(refused.reason().to_string().find("TLD W VALUE 200 OUTSIDE 1-127"), std::string::npos)
      << refused.reason().to_string();
}

// kill -9 at any moment: a copy of the database files taken at every wait of the core is what a killed
// process leaves. Each opens, its variables are those before or after a whole program (never half of a
// program's changes), and a run it shows ACTIVE is reported failed by the next process.
TEST_F(StationCore, ACopyOfTheDatabaseAtAnyMomentOpensConsistent) {
  Put("A", "G71\n(PAR,L1500=1.,L1501=1.)\nG01 X1. F1000.\nX2.\nX3.\nX4.\nX5.\nM30\n");
  Put("B", "G71\n(PAR,L1500=2.,L1501=2.)\n(TLD,S6T4001P50.)\nG01 X4. F1000.\nX5.\nX6.\nX7.\nM30\n");
  servo_.per_wait = 1;
  int copies = 0;
  std::vector<std::filesystem::path> snapshots;
  script_ = [&] {
    auto to = dir_ / ("kill-" + std::to_string(copies++));
    std::filesystem::create_directories(to);
    for (const char* suffix : {"", "-wal"}) {
      auto from = db().string() + suffix;
      if (std::filesystem::exists(from))
        std::filesystem::copy_file(from, to / ("interpreter-KT01.db" + std::string(suffix)));
    }
    snapshots.push_back(to);
  };
  Dispatch(1, {"A", "B"});
  ASSERT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  script_ = nullptr;
  ASSERT_GT(snapshots.size(), 4u);
  bool saw_between = false;
  for (const auto& s : snapshots) {
    FakeIo io;
    FakeServo servo;
    Station restarted(cfg_, s / "interpreter-KT01.db", io, servo, clock_);
    auto v = restarted.MemoryState().image.variables;
    const double l1500 = v.count("L1500") ? v["L1500"] : 0;
    const double l1501 = v.count("L1501") ? v["L1501"] : 0;
    EXPECT_EQ(l1500, l1501) << s;  // both assignments of a program, or neither
    const bool has_tool = restarted.MemoryState().image.tools.Find("4001") != nullptr;
    EXPECT_EQ(has_tool, l1500 == 2.0) << s;
    saw_between |= l1500 == 1.0;
    restarted.Recover();
    auto last = io.LastRun(1);
    ASSERT_TRUE(last) << s;
    EXPECT_EQ(last->state(), cell::RUN_FAILED);
    EXPECT_EQ(last->reason(), "station restarted during the run");
    // It had started: a scheduler waiting for this station's word must not take it for a run that never did
    // and give the part-machined pallet to another run (docs/scheduler.md §5; fms_test found it).
    EXPECT_GT(last->started_ns(), 0) << s;
    // Issue 39 item 7: the lost run has its record too (one per dispatch), saying why it did not complete.
    restarted.FlushOutbox();
    ASSERT_EQ(io.records.size(), 1u) << s;
    EXPECT_FALSE(io.records[0].run().completed());
    EXPECT_EQ(io.records[0].run().reason(), "station restarted during the run");
    EXPECT_EQ(io.records[0].run().dispatch_id(), 1);
    EXPECT_GT(io.records[0].run().started_ns(), 0);
  }
  EXPECT_TRUE(saw_between);  // some copy was taken between the programs
}

TEST_F(StationCore, RecordsWaitInTheOutboxUntilTheWriterTakesThem) {
  Put("P", Moves(1));
  io_.writer_up = false;
  Dispatch(1, {"P"});
  RunOne(1);
  io_.writer_refuses = true;
  io_.writer_up = true;
  station_->FlushOutbox();
  EXPECT_TRUE(io_.records.empty());
  Make();  // kept across a restart
  io_.writer_refuses = false;
  station_->FlushOutbox();
  ASSERT_EQ(io_.records.size(), 1u);
  EXPECT_EQ(io_.records[0].hdr().idempotency_key(), "run-KT01-1");
  station_->FlushOutbox();
  EXPECT_EQ(io_.records.size(), 1u);
}

TEST_F(StationCore, WorkRunsWhatArrivesAndStops) {
  Put("P", Moves(1));
  Dispatch(1, {"P"});
  int idle = 0;
  script_ = [&] {
    if (station_->Status().dispatch_id() == 0 && ++idle == 3) station_->RequestStop();
  };
  station_->Work();
  EXPECT_EQ(io_.LastRun(1)->state(), cell::RUN_COMPLETED);
}

// A pallet map may name the pallet's part model (a file the store keeps as type part_model): the servo gets
// it as the run's workpiece, acknowledged, before the run's first segment; the entry is counted as done so
// that the later programs keep their places in the map.
constexpr const char* kPlate = "[[plane]]\npoint = [0, 0, 50]\nnormal = [0, 0, 1]\n";

TEST_F(StationCore, APalletMapsPartModelGoesToTheServoBeforeAnySegment) {
  io_.part_models["HOST/PLATE7"] = kPlate;
  Put("P", Moves(2));
  Dispatch(1, {"PLATE7", "P"}, 7);
  cell::RunStatus s = RunOne(1);
  EXPECT_EQ(s.state(), cell::RUN_COMPLETED);
  EXPECT_EQ(s.programs_done(), 2);
  ASSERT_EQ(servo_.parts.size(), 1u);
  EXPECT_EQ(servo_.parts[0].station().to_string(), "KT01");
  EXPECT_EQ(servo_.parts[0].run_id(), 1);
  EXPECT_EQ(servo_.parts[0].pallet(), 7);
  EXPECT_EQ(servo_.parts[0].name().to_string(), "PLATE7");
  EXPECT_EQ(servo_.parts[0].text().to_string(), kPlate);
  EXPECT_EQ(servo_.written.size(), 4u);  // P's segments only: the model is not run
  // A program index past the model: P is entry 1 of the map.
  bool saw_p = false;
  for (const auto& r : io_.runs)
    if (r.dispatch_id() == 1 && r.program().to_string() == "P") saw_p = saw_p || r.program_index() == 1;
  EXPECT_TRUE(saw_p);
}

TEST_F(StationCore, AMalformedPartModelFailsTheRunBeforeAnyMotion) {
  io_.part_models["HOST/PLATE7"] = "[[plane]]\npoint = [0, 0\n";
  Put("P", Moves(2));
  Dispatch(1, {"PLATE7", "P"}, 7);
  cell::RunStatus s = RunOne(1);
  EXPECT_EQ(s.state(), cell::RUN_FAILED);
  EXPECT_NE(s.reason().to_string().find("PLATE7:2:"), std::string::npos) << s.reason().to_string();
  EXPECT_TRUE(servo_.parts.empty());
  EXPECT_TRUE(servo_.written.empty());
}

TEST_F(StationCore, AServoThatDoesNotTakeThePartModelFailsTheRun) {
  io_.part_models["HOST/PLATE7"] = kPlate;
  servo_.takes_parts = false;
  Put("P", Moves(2));
  Dispatch(1, {"PLATE7", "P"}, 7);
  cell::RunStatus s = RunOne(1);
  EXPECT_EQ(s.state(), cell::RUN_FAILED);
  EXPECT_NE(s.reason().to_string().find("did not take part model PLATE7"), std::string::npos)
      << s.reason().to_string();
  EXPECT_TRUE(servo_.written.empty());
  // Before failing, the run joined the bus anew once and wrote the part model again on the new participant.
  EXPECT_EQ(servo_.rejoins, 1);
  EXPECT_EQ(servo_.parts.size(), 2u);
}

// M00 (KT-APL ln 2485-2506): the motion before it finishes, then the run waits in PROGRAM_STOPPED, saying why
// and how to go on, until the operator's cycle start; nothing after it is streamed meanwhile. The program's
// last MSG is part of the status text.
TEST_F(StationCore, M00StopsTheRunUntilCycleStart) {
  Put("P", "G71 G90\nG01 X0 Y0 Z100. F1000.\n(MSG,CHECK THE BORE)\nX10. M00\nX20.\nM30\n");
  Dispatch(1, {"P"});
  int stopped_waits = 0;
  std::size_t written_at_stop = 0;
  std::string text;
  script_ = [&] {
    const cell::StationStatus st = station_->Status();
    if (st.execution() != cell::EXECUTION_PROGRAM_STOPPED) return;
    if (++stopped_waits == 1) {
      written_at_stop = servo_.written.size();
      text = st.status_text().to_string();
    }
    if (stopped_waits == 20) {
      EXPECT_EQ(servo_.written.size(), written_at_stop);  // nothing after M00 left while stopped
      Command(cell::STATION_CYCLE_START);
    }
  };
  EXPECT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  EXPECT_GE(stopped_waits, 20);
  EXPECT_EQ(text,
            "M00 program stop at P line 4: press cycle start (cellctl station start KT01) - CHECK THE BORE");
  double last_x = 0;
  for (const auto& seg : servo_.written)
    if (seg.kind() == cell::SEGMENT_LINEAR) last_x = Target(seg, 0);
  EXPECT_DOUBLE_EQ(last_x, 20.0);  // the run went on after the stop
}

// KT-APL M49 (ln 2896-2937, example 5-18 at ln 5095-5133): feed and spindle speed at 100 % whatever the
// selector says, from the M49 block on (the motion before it ran at the operator's 50 %: the station drains
// first); M48 gives the 50 % back after the tapping moves; the operator's setting is kept throughout, and a
// change of it while fixed is recorded and applies after M48. The program's end releases a forgotten M49.
TEST_F(StationCore, M49FixesTheFeedOverrideAt100PercentUntilM48) {
  cell::StationRequest o;
  o.op(cell::STATION_OVERRIDE);
  o.feed_override(0.5);
  o.rapid_override(-1);
  station_->OnCommand(o);
  Put("P", "G71 G90\nG01 X0 Y0 Z206. F500.\nX154. Y305.\nZ184. M49\nZ206.\nX381. Y229. M48\nX0 M49\nM30\n");
  Dispatch(1, {"P"});
  std::vector<std::pair<double, std::size_t>> sent;  // feed override sent, segments the servo had run then
  io_.on_control = [&](const cell::ServoControl& c) {
    sent.emplace_back(c.feed_override(), servo_.ran.size());
  };
  bool pressed = false;
  script_ = [&] {
    if (!pressed && station_->Control().feed_override() == 1.0) {
      pressed = true;
      o.feed_override(0.8);  // the selector turned while fixed: not sent, kept
      station_->OnCommand(o);
      EXPECT_DOUBLE_EQ(station_->Control().feed_override(), 1.0);
    }
  };
  EXPECT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  io_.on_control = nullptr;
  // Fixed once the 2 moves before M49 (Z206, then X154 Y305) had run; the 0.8 press
  // is sent as 100 %; M48 sends 0.8 after the two tapping moves; the last M49 is released at the end.
  ASSERT_EQ(sent.size(), 5u);
  EXPECT_DOUBLE_EQ(sent[0].first, 1.0);
  EXPECT_EQ(sent[0].second, 2u);
  EXPECT_DOUBLE_EQ(sent[1].first, 1.0);
  EXPECT_DOUBLE_EQ(sent[2].first, 0.8);
  EXPECT_EQ(sent[2].second, 4u);
  EXPECT_DOUBLE_EQ(sent[3].first, 1.0);
  EXPECT_DOUBLE_EQ(sent[4].first, 0.8);
  EXPECT_DOUBLE_EQ(station_->Control().feed_override(), 0.8);
}

// Balt-System SA/SK (ln 4108-4138, judgement call 52): a station whose file names no such signal never takes
// the write and drops it; with INTERFACE_LOGIC=0 (BS01) the dialect refuses it (FILMS4 103), and a station
// that left the setting on still stops the run at the block rather than log the signal away.
TEST_F(StationCore, ABaltBufferWriteTheStationDoesNotModelStopsTheRun) {
  cfg_.id = "BS01";
  cfg_.dialect = "balt";
  cfg_.tools = {};
  servo_.station_id = "BS01";
  Make();
  Put("SIG", "G0 X10 Y20 Z30\nSA128=1\nG0 X0\nM30\n", "BS01");
  ASSERT_EQ(Dispatch(1, {"SIG"}).state(), cell::RUN_QUEUED);
  auto run = RunOne(1);
  EXPECT_EQ(run.state(), cell::RUN_FAILED);
  EXPECT_EQ(
      run.reason(),
      "SIG:2: error: output 'SA128=1' is not a signal of station BS01 (its station file has no such output)");
  cfg_.params["INTERFACE_LOGIC"] = "0";
  Make();
  ASSERT_EQ(Dispatch(2, {"SIG"}).state(), cell::RUN_QUEUED);
  auto refused = RunOne(2);
  EXPECT_EQ(refused.state(), cell::RUN_FAILED);
  EXPECT_NE(refused.reason().to_string().find("SIG:2:1: error: [FILMS4 103] FUNCTION NOT CONFIGURED: SA:"),
            std::string::npos)
      << refused.reason();
}

// Balt-System (issue 35 item 4): START on an idle station runs the program SPG selected (ln 8873-8888) as a
// run of the station's own (dispatch id below 1); nothing selected is FILMS4 54 (ln 10079-10080). A map's
// "BS01/MP2:P9" is read from that memory alone, and never from another station's. A KT-APL station's START
// with nothing running starts nothing.
TEST_F(StationCore, BaltStartRunsTheSelectedProgram) {
  Command(cell::STATION_CYCLE_START);
  EXPECT_FALSE(station_->RunNext());
  cfg_.id = "BS01";
  cfg_.dialect = "balt";
  cfg_.tools = {};
  servo_.station_id = "BS01";
  Make();
  try {
    Command(cell::STATION_CYCLE_START);
    ADD_FAILURE() << "START without a selected program was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kFailedPrecondition);
    EXPECT_EQ(std::string(e.what()).rfind("[FILMS4 54] NO PROGRAM HAS BEEN SELECTED", 0), 0u) << e.what();
  }
  EXPECT_FALSE(station_->RunNext());
  Put("P9", "%:P9\nN1 G0 X10 Y20 Z30\nN2 G1 X40 F500\nM30\n", "BS01/MP2");
  io_.selected = "BS01/MP2:P9";
  Command(cell::STATION_CYCLE_START);
  EXPECT_EQ(RunOne(-1).state(), cell::RUN_COMPLETED);
  EXPECT_NE(std::find(io_.fetched.begin(), io_.fetched.end(), "BS01/MP2:P9"),
            io_.fetched.end());  // MP2 alone
  double last_x = 0;
  for (const auto& seg : servo_.written)
    if (seg.kind() == cell::SEGMENT_LINEAR) last_x = Target(seg, 0);
  EXPECT_DOUBLE_EQ(last_x, 40.0);
  Command(cell::STATION_CYCLE_START);  // the next START runs it again, under the next id
  EXPECT_EQ(RunOne(-2).state(), cell::RUN_COMPLETED);
  // A map names a memory's program: read there alone (not HOST's of the same name), never another station's.
  Put("Q1", "%:Q1\nM30\n", "HOST");
  Dispatch(1, {"BS01/MP2:Q1"});
  cell::RunStatus missing = RunOne(1);
  EXPECT_EQ(missing.state(), cell::RUN_FAILED);
  EXPECT_EQ(missing.reason().to_string(), "program 'Q1' is not in BS01/MP2");
  Put("Q1", "%:Q1\nM30\n", "BS02/MP2");
  Dispatch(2, {"BS02/MP2:Q1"});
  EXPECT_EQ(RunOne(2).reason().to_string(), "program 'BS02/MP2:Q1' is in BS02's memory: BS01 cannot read it");
  Dispatch(3, {"BS01/MP2:P9", "HOST:Q1"});
  EXPECT_EQ(RunOne(3).state(), cell::RUN_COMPLETED);
}

TEST_F(StationCore, ACancelEndsAProgramStop) {
  Put("P", "G71 G90\nG01 X0 Y0 Z100. F1000.\nM00\nX20.\nM30\n");
  Dispatch(1, {"P"});
  script_ = [&] {
    if (station_->Status().execution() == cell::EXECUTION_PROGRAM_STOPPED) Cancel(1);
  };
  EXPECT_EQ(RunOne(1).state(), cell::RUN_CANCELLED);
}

// M01 stops only with the optional stop on (the station file's [params] OPTIONAL_STOP = 1), in OPTIONAL_STOP.
TEST_F(StationCore, M01StopsOnlyWithTheOptionalStopOn) {
  Put("P", "G71 G90\nG01 X0 Y0 Z100. F1000.\nM01\nX20.\nM30\n");
  Dispatch(1, {"P"});
  bool stopped = false;
  script_ = [&] { stopped = stopped || station_->Status().execution() == cell::EXECUTION_OPTIONAL_STOP; };
  EXPECT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  EXPECT_FALSE(stopped);

  cfg_.params["OPTIONAL_STOP"] = "1";
  Make();
  Dispatch(2, {"P"});
  script_ = [&] {
    if (station_->Status().execution() != cell::EXECUTION_OPTIONAL_STOP) return;
    stopped = true;
    Command(cell::STATION_CYCLE_START);
  };
  EXPECT_EQ(RunOne(2).state(), cell::RUN_COMPLETED);
  EXPECT_TRUE(stopped);

  // The panel's switch (`cellctl station optional-stop KT01 off`) overrides the station file, and persists.
  cell::StationRequest r;
  r.station("KT01");
  r.op(cell::STATION_OPTIONAL_STOP);
  r.optional_stop(false);
  station_->OnCommand(r);
  Make();
  stopped = false;
  script_ = [&] { stopped = stopped || station_->Status().execution() == cell::EXECUTION_OPTIONAL_STOP; };
  Dispatch(3, {"P"});
  EXPECT_EQ(RunOne(3).state(), cell::RUN_COMPLETED);
  EXPECT_FALSE(stopped);
}

// M99 with M00 on a station (E20, ln 3078-3094): the alarm shows with the block's comment (condition WARNING,
// cleared by reset) and the program stops until cycle start; offline it is the [M99] error (call 10).
TEST_F(StationCore, M99WithM00RaisesTheAlarmAndStops) {
  Put("P", "G71 G90\nG00 X0 Y0 Z100. F0\nN120 M00M99 !GAUGE BORE SIZE\nX20.\nM30\n");
  Dispatch(1, {"P"});
  cell::StationStatus at_stop;
  script_ = [&] {
    const cell::StationStatus st = station_->Status();
    if (st.execution() != cell::EXECUTION_PROGRAM_STOPPED) return;
    at_stop = st;
    Command(cell::STATION_CYCLE_START);
  };
  EXPECT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  EXPECT_EQ(at_stop.condition(), cell::CONDITION_WARNING);
  EXPECT_EQ(at_stop.alarm_text().to_string(), "M99 alarm - see MAIN display: GAUGE BORE SIZE");
  EXPECT_EQ(station_->Status().condition(), cell::CONDITION_WARNING);
  Command(cell::STATION_RESET);
  EXPECT_EQ(station_->Status().condition(), cell::CONDITION_NORMAL);
}

// Tool life (issue 15): the servo's cutting time (feed moves with the spindle turning) is charged to the
// data set that cut, and committed with what the program left; `station tools` shows the life left.
TEST_F(StationCore, CuttingTimeIsChargedToTheToolThatCut) {
  // Three feed moves with the spindle on (10 s each in the fake servo) and one with it off.
  servo_.socket_of = {{"1001", 1}, {"1002", 2}};
  Put("CUT", "G71 G90\nT1001 M6\nS1000 M3\nG01 X0 Y0 Z100. F1000.\nX10.\nX20.\nM5\nX30.\nM30\n");
  Dispatch(1, {"CUT"});
  ASSERT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  ASSERT_NE(Tool("1001"), nullptr);
  EXPECT_NEAR(Tool("1001")->life_left_min, 240 - 30.0 / 60, 1e-9);
  EXPECT_FALSE(Tool("1001")->worn);
  EXPECT_NEAR(Tool("1002")->life_left_min, 180, 1e-9);  // never cut
  // Published, and kept across a restart.
  ASSERT_FALSE(io_.tools.empty());
  EXPECT_NEAR(io_.tools.back().tools()[0].life_left_min(), 239.5, 1e-9);
  Make();
  EXPECT_NEAR(Tool("1001")->life_left_min, 239.5, 1e-9);
}

// A tool that wears out in one program: the next program's M06 of its number takes the alternate in the
// other socket (the servo is told which), and once that wears out too the M06 stops the run.
TEST_F(StationCore, AWornToolGivesWayToItsAlternateThenNoneIsLeft) {
  Command(cell::STATION_LOAD_TOOLS, "(TLD,S1T1001P152.4D25.4L1)\n(TLD,S9T1001P150.D25.4L1)\n");
  const tooltable::ToolTable loaded = station_->MemoryState().image.tools;
  ASSERT_NE(loaded.Find("1001", 9), nullptr);
  ASSERT_NE(loaded.Find("1001", 1), nullptr);
  // 6 feed moves x 10 s = 1 minute: the whole life of one data set.
  Put("CUT", "G71 G90\nT1001 M6\nS1000 M3\nG01 X0 Y0 Z100. F1000.\nX10.\nX20.\nX30.\nX40.\nX50.\nM5\nM30\n");
  Dispatch(1, {"CUT", "CUT"});
  ASSERT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  const auto changes = servo_.Ran(1, cell::SEGMENT_TOOL_CHANGE);
  ASSERT_EQ(changes.size(), 2u);
  EXPECT_EQ(changes[0].tool_socket(), 1);
  EXPECT_EQ(changes[1].tool_socket(), 9);
  const tooltable::ToolTable t = station_->MemoryState().image.tools;
  EXPECT_TRUE(t.Find("1001", 1)->worn);
  EXPECT_EQ(t.Find("1001", 1)->life_left_min, 0);
  EXPECT_TRUE(t.Find("1001", 9)->worn);
  Dispatch(2, {"CUT"});
  const cell::RunStatus failed = RunOne(2);
  EXPECT_EQ(failed.state(), cell::RUN_FAILED);
  EXPECT_NE(failed.reason().to_string().find("CUT:2:7: error: TOOL 1001 IS WORN OR BROKEN"),
            std::string::npos)
      << failed.reason().to_string();
}

// G38 (ln 1583-1593): the servo finds the spindle tool broken; the table says so, the run waits in cycle
// stop with "TOOL BROKEN" until cycle start, and the next M06 takes the alternate.
TEST_F(StationCore, G38FindsTheToolBrokenTheRunStopsAndTheAlternateIsTaken) {
  Command(cell::STATION_LOAD_TOOLS, "(TLD,S1T1001P152.4D25.4L100)\n(TLD,S9T1001P150.D25.4L100)\n");
  servo_.broken_sockets = {1};
  Put("CHK", "G71 G90\nT1001 M6\nG01 X0 Y0 Z100. S30 M3 F1000.\nG38 S16\nT1001 M6\nX10.\nM30\n");
  Dispatch(1, {"CHK"});
  std::string text, code;
  int stopped_waits = 0;
  script_ = [&] {
    const cell::StationStatus st = station_->Status();
    if (st.execution() != cell::EXECUTION_PROGRAM_STOPPED) return;
    if (++stopped_waits == 1) {
      text = st.status_text().to_string();
      code = st.alarm_code().to_string();
    }
    if (stopped_waits == 5) Command(cell::STATION_CYCLE_START);
  };
  EXPECT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  EXPECT_EQ(text, "TOOL BROKEN, cycle stop at CHK line 4: press cycle start (cellctl station start KT01)");
  EXPECT_EQ(code, "TOOL");
  const auto checks = servo_.Ran(1, cell::SEGMENT_PROBE);
  ASSERT_EQ(checks.size(), 1u);
  EXPECT_TRUE(checks[0].tool_check());
  const auto changes = servo_.Ran(1, cell::SEGMENT_TOOL_CHANGE);
  ASSERT_EQ(changes.size(), 2u);
  EXPECT_EQ(changes[1].tool_socket(), 9);
  const tooltable::ToolTable t = station_->MemoryState().image.tools;
  EXPECT_TRUE(t.Find("1001", 1)->broken);
  EXPECT_FALSE(t.Find("1001", 9)->broken);
}

// `cellctl station break ID SOCKET`: the operator's word goes to the servo (ServoControl) and persists.
TEST_F(StationCore, BrokenSocketsGoToTheServoAndPersist) {
  cell::StationRequest r;
  r.station("KT01");
  r.op(cell::STATION_BREAK_TOOL);
  r.socket(5);
  station_->OnCommand(r);
  ASSERT_FALSE(io_.control.empty());
  EXPECT_EQ(io_.control.back().broken_sockets(), (std::vector<int32_t>{5}));
  Make();
  EXPECT_EQ(io_.control.back().broken_sockets(), (std::vector<int32_t>{5}));  // published again at start
  r.mend(true);
  station_->OnCommand(r);
  EXPECT_TRUE(io_.control.back().broken_sockets().empty());
  r.socket(0);
  EXPECT_THROW(station_->OnCommand(r), Error);
}

// USF then ULF on another pallet (issue 15; KT-APL ln 4213-4284, E48): pallet 38's program saves its fixture
// table as PALLET38;FXT in the station's namespace (type fixture_offsets); a later pallet clears its table
// and loads that file by name: the station keeps the loaded lines.
TEST_F(StationCore, UsfThenUlfOnAnotherPalletRestoresTheOffsets) {
  Put("SAVE", "G70\n(FXC,H1X.5Y.25)\n(FXC,H3Z-1.I90.)\n(USF)\nM30\n");
  Dispatch(1, {"SAVE"}, 38);
  ASSERT_EQ(RunOne(1).state(), cell::RUN_COMPLETED);
  ASSERT_TRUE(io_.programs.count("KT01/PALLET38;FXT"));
  EXPECT_EQ(io_.saved_as["KT01/PALLET38;FXT"].file_type, "fixture_offsets");
  const std::string file = io_.programs["KT01/PALLET38;FXT"];
  EXPECT_NE(file.find("(FXC,H1X12.7000Y6.3500Z0.0000A0.0000B0.0000C0.0000)"), std::string::npos) << file;
  EXPECT_NE(file.find("(FXC,H3X0.0000Y0.0000Z-25.4000A0.0000B0.0000C0.0000I90.0000)"), std::string::npos)
      << file;

  Put("LOAD", "G71\n(ZTB,H)\n(FXC,H2X1.)\n(ULF,PALLET38)\nM30\n");
  Dispatch(2, {"LOAD"}, 7);
  ASSERT_EQ(RunOne(2).state(), cell::RUN_COMPLETED);
  const auto vars = Variables();
  ASSERT_TRUE(vars.count("H1.X") && vars.count("H1.Y") && vars.count("H3.Z") && vars.count("H3.I"));
  EXPECT_DOUBLE_EQ(vars.at("H1.X"), 12.7);
  EXPECT_DOUBLE_EQ(vars.at("H1.Y"), 6.35);
  EXPECT_DOUBLE_EQ(vars.at("H3.Z"), -25.4);
  EXPECT_DOUBLE_EQ(vars.at("H3.I"), 90);
  EXPECT_FALSE(vars.count("H2.X"));  // the file replaced the whole table

  // A file that is not there stops the run with the device's message.
  Put("MISS", "G71\n(ULF,NOSUCH)\nM30\n");
  Dispatch(3, {"MISS"}, 7);
  const cell::RunStatus failed = RunOne(3);
  EXPECT_EQ(failed.state(), cell::RUN_FAILED);
  EXPECT_NE(failed.reason().to_string().find("FILE NOSUCH;FXT NOT FOUND"), std::string::npos)
      << failed.reason().to_string();
}

// KT-APL EVT (ln 3430-3434: an event for the supervisory computer): published on cell/station/event with
// the station, dispatch, pallet, program and line.
TEST_F(StationCore, EvtPublishesTheProgramsEvent) {
  Put("EV", "G71 G90\n(EVT,PART 7 DONE)\nM30\n");
  Dispatch(4, {"EV"}, 12);
  ASSERT_EQ(RunOne(4).state(), cell::RUN_COMPLETED);
  ASSERT_EQ(io_.events.size(), 1u);
  const cell::StationEvent& e = io_.events[0];
  EXPECT_EQ(e.station().to_string(), "KT01");
  EXPECT_EQ(e.dispatch_id(), 4);
  EXPECT_EQ(e.pallet(), 12);
  EXPECT_EQ(e.program().to_string(), "EV");
  EXPECT_EQ(e.line(), 2);
  EXPECT_EQ(e.text().to_string(), "PART 7 DONE");
  EXPECT_GT(e.time_ns(), 0);
}

// Okuma READ/WRITE (ln 8075-8109) on a station with a [serial] line: WRITE hands the write area to the line,
// READ waits (asked after at each of the core's waits) until a record arrives, and GET takes it; a cancel
// ends a READ that waits; a line that fails is Alarm B naming the station and line; a station without
// [serial] refuses them with Alarm B (judgement 64 in docs/dialects/okuma.md).
class StationSerial : public StationHarness {
 protected:
  void Okuma(bool serial) {
    cfg_.dialect = "okuma";
    if (serial) {
      cfg_.serial = config::SerialTable{};
      cfg_.serial->device = "/dev/ttyS9";
    }
    Make();
  }
};

TEST_F(StationSerial, WriteSendsAndReadWaitsForTheRecord) {
  Okuma(true);
  Put("P", "V1=7\nPUT 'N='\nPUT V1,3\nWRITE 0\nREAD 0\nGET ,2\nGET V2,5\nG00 X=V2 Z1\nM02\n");
  Dispatch(1, {"P"});
  int waits = 0;
  std::string waiting;
  script_ = [&] {
    if (io_.line_asks == 0) return;
    if (++waits == 5) {  // the READ has waited through five of the core's waits
      waiting = station_->Status().status_text().to_string();
      io_.replies.push_back("X= 12.5");
    }
  };
  const cell::RunStatus st = RunOne(1);
  EXPECT_EQ(st.state(), cell::RUN_COMPLETED) << st.reason().to_string();
  EXPECT_EQ(io_.written, (std::vector<std::string>{"N=  7"}));
  EXPECT_GE(io_.line_asks, 5);
  EXPECT_EQ(io_.line_holders.front(), "dispatch 1");
  EXPECT_EQ(waiting, "READ: waiting for a record on /dev/ttyS9");
  EXPECT_DOUBLE_EQ(Variables().at("V2"), 12.5);
}

TEST_F(StationSerial, ACancelEndsAReadThatWaits) {
  Okuma(true);
  Put("P", "READ 0\nM02\n");
  Dispatch(1, {"P"});
  script_ = [&] {
    if (io_.line_asks == 3) Cancel(1);
  };
  EXPECT_EQ(RunOne(1).state(), cell::RUN_CANCELLED);
}

TEST_F(StationSerial, ALineThatFailsIsAlarmBNamingStationAndLine) {
  Okuma(true);
  io_.line_error = "no DNC process: cell-dnc@KT01 does not answer";
  Put("P", "READ 0\nM02\n");
  Dispatch(1, {"P"});
  const cell::RunStatus st = RunOne(1);
  EXPECT_EQ(st.state(), cell::RUN_FAILED);
  EXPECT_THAT(
      st.reason().to_string(),
      ::testing::HasSubstr("Alarm B RS232C: station KT01 line /dev/ttyS9: no DNC process: cell-dnc@KT01"));
}

TEST_F(StationSerial, WithoutASerialTableReadAndWriteAreAlarmB) {
  Okuma(false);
  std::int32_t id = 0;
  for (const char* text : {"READ 0\nM02\n", "PUT 'A'\nWRITE 0\nM02\n"}) {
    Put("P", text);
    Dispatch(++id, {"P"});
    const cell::RunStatus st = RunOne(id);
    EXPECT_EQ(st.state(), cell::RUN_FAILED);
    EXPECT_THAT(st.reason().to_string(), ::testing::HasSubstr("it has no serial line (no [serial] table"));
  }
  EXPECT_EQ(io_.line_asks, 0);
  EXPECT_TRUE(io_.written.empty());
}

}  // namespace
}  // namespace cell::station::testing
