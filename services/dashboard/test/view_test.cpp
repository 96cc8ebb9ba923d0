// The dashboard's view of the cell without DDS: station cards, waiting reasons, jobs, cycle times, the
// event log, and the MTConnect sequence buffer.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "cell/config/config.h"
#include "cell/dashboard/cell_view.h"
#include "cell/machine/machine_config.h"
#include "test_stations.h"

namespace cell::dashboard {
namespace {

using testing::Status;
using testing::TwoStations;

JobIn WaitingJob(int id, int pallet) {
  JobIn j;
  j.id = id;
  j.state = "WAITING";
  j.kind = "route";
  j.route = "R";
  j.pallet = pallet;
  j.reason = "no eligible station: KT01 missing tools 7777; OK01 offline";
  DecisionIn d;
  d.trigger = "operate";
  d.why = j.reason;
  d.considered = {{"KT01", true, false, false, 0, {"7777"}}, {"OK01", false, false, false, 0, {}}};
  j.decisions = {d};
  j.decision_count = 1;
  return j;
}

TEST(SequenceBuffer, NumbersEveryObservationAndKeepsTheLastN) {
  SequenceBuffer b(4, 2);
  EXPECT_EQ(b.first(), 1u);
  EXPECT_EQ(b.next(), 1u);
  for (int i = 0; i < 6; ++i) b.Add({0, 0, i % 2, std::to_string(i), "", ""});
  EXPECT_EQ(b.first(), 3u);
  EXPECT_EQ(b.last(), 6u);
  EXPECT_EQ(b.next(), 7u);
  auto r = b.Range(1, 10);  // from before the buffer: what is there
  ASSERT_EQ(r.size(), 4u);
  EXPECT_EQ(r.front().sequence, 3u);
  EXPECT_EQ(b.Latest()[0].value, "4");  // the latest of item 0, also once it left the ring
  EXPECT_EQ(b.Latest()[1].value, "5");
  std::uint64_t next = 0;
  auto odd = b.Scan(
      3, 1, [](const Observation& o) { return o.item == 1; }, &next);
  ASSERT_EQ(odd.size(), 1u);
  EXPECT_EQ(odd[0]->sequence, 4u);
  EXPECT_EQ(next, 5u);
}

TEST(CellView, StationCardsSpeakMtconnectAndShowWhyAPalletWaits) {
  CellView v(TwoStations());
  auto snap = v.Snapshot();
  ASSERT_EQ(snap["stations"].size(), 2u);
  EXPECT_EQ(snap["stations"][0]["execution"], "UNAVAILABLE");  // not announced yet (DESIGN §3)
  v.Online("KT01", true);
  v.Status(Status("KT01", "ACTIVE", "PUMP341", 42, 3));
  v.Job(WaitingJob(9, 7));
  snap = v.Snapshot();
  const auto& kt = snap["stations"][0];
  EXPECT_EQ(kt["execution"], "ACTIVE");
  EXPECT_EQ(kt["condition"], "NORMAL");
  EXPECT_EQ(kt["program"], "PUMP341");
  EXPECT_EQ(kt["line"], 42);
  EXPECT_EQ(kt["pallet"], 3);
  EXPECT_EQ(kt["axes"], nlohmann::json({"X", "Y", "Z", "B"}));
  ASSERT_EQ(kt["waiting"].size(), 1u);
  EXPECT_EQ(kt["waiting"][0]["pallet"], 7);
  EXPECT_EQ(kt["waiting"][0]["why"], "missing tools 7777");
  EXPECT_EQ(snap["stations"][1]["waiting"][0]["why"], "station offline");
  EXPECT_EQ(snap["stations"][1]["axes"], nlohmann::json({"X (dia)", "Z"}));
  // The job leaves WAITING: no station shows it any more.
  JobIn j = WaitingJob(9, 7);
  j.state = "DISPATCHED";
  j.station = "KT01";
  v.Job(j);
  snap = v.Snapshot();
  EXPECT_TRUE(snap["stations"][0]["waiting"].empty());
  EXPECT_EQ(snap["stations"][0]["queue"][0]["pallet"], 7);
  // Offline: the station's values are unavailable, as MTConnect has it.
  v.Online("KT01", false);
  EXPECT_EQ(v.Snapshot()["stations"][0]["execution"], "UNAVAILABLE");
}

// The station row is records::StationRow: not announced, condition is UNAVAILABLE too (DESIGN §3), and an
// alarm raised on the station (the scheduler's DUPLICATE) is its condition, on the page and in MTConnect.
TEST(CellView, StationRowsFollowTheRecordsRules) {
  ViewOptions o;
  o.vocabulary = {{"dialects", {{"ktapl", "Kearney & Trecker KT-APL"}}}};
  CellView v(TwoStations(), o);
  auto kt = v.Snapshot()["stations"][0];
  EXPECT_EQ(kt["condition"], "UNAVAILABLE");
  EXPECT_TRUE(kt["part_count"].is_null());
  EXPECT_EQ(v.Snapshot()["vocabulary"]["dialects"]["ktapl"], "Kearney & Trecker KT-APL");
  EXPECT_EQ(kt["axis_defs"][3],
            nlohmann::json({{"name", "B"}, {"label", "B"}, {"rotary", true}, {"diameter", false}}));
  v.Online("KT01", true);
  v.Status(Status("KT01", "READY"));
  EXPECT_EQ(v.Snapshot()["stations"][0]["condition"], "NORMAL");
  v.Alarm("KT01", {true, "DUPLICATE", "cell-interpreter/KT01 runs in 2 processes", 5});
  kt = v.Snapshot()["stations"][0];
  EXPECT_EQ(kt["condition"], "FAULT");
  EXPECT_EQ(kt["alarm_code"], "DUPLICATE");
  EXPECT_NE(v.Current(0).find("nativeCode=\"DUPLICATE\""), std::string::npos);
  v.Alarm("KT01", {false, "DUPLICATE", "", 4});  // older than the raise: ignored
  EXPECT_EQ(v.Snapshot()["stations"][0]["condition"], "FAULT");
  v.Alarm("KT01", {false, "DUPLICATE", "", 6});
  EXPECT_EQ(v.Snapshot()["stations"][0]["condition"], "NORMAL");
  v.Online("KT01", false);
  EXPECT_EQ(v.Snapshot()["stations"][0]["condition"], "UNAVAILABLE");
  EXPECT_NE(v.Current(0).find("<Unavailable "), std::string::npos);
}

TEST(CellView, EventsCarryEachChangeOnceAndResyncWhenTooOld) {
  ViewOptions o;
  o.event_log = 8;
  CellView v(TwoStations(), o);
  const auto start = v.LastEvent();
  v.Online("KT01", true);
  v.Status(Status("KT01", "READY"));
  v.Status(Status("KT01", "READY"));  // no change: no event
  auto evs = v.EventsAfter(start, 100);
  ASSERT_TRUE(evs);
  ASSERT_EQ(evs->size(), 2u);  // online, then READY
  auto last = nlohmann::json::parse(evs->back().data);
  EXPECT_EQ(last["type"], "station");
  EXPECT_EQ(last["station"]["execution"], "READY");
  EXPECT_EQ(last["id"], evs->back().id);
  EXPECT_FALSE(v.WaitEvent(v.LastEvent(), std::chrono::milliseconds(10)));
  for (int i = 1; i <= 20; ++i) v.Status(Status("KT01", "ACTIVE", "P", i));
  EXPECT_FALSE(v.EventsAfter(start, 100)) << "events that left the log must make the browser resync";
  EXPECT_TRUE(v.EventsAfter(v.LastEvent() - 3, 100));
}

// The default sequence buffer is the dashboard's largest container (issue 39: its RSS still grew at pallet
// 10,000 while the old 131,072 filled): 16,384 observations at most, so after 20,000 `from` may go back
// exactly 16,384 from nextSequence and no further.
TEST(CellView, DefaultSequenceBufferKeeps16384Observations) {
  CellView v(TwoStations());
  v.Online("KT01", true);
  for (int i = 1; i <= 20000; ++i) v.Status(Status("KT01", "ACTIVE", "P", i));  // a new line each time
  const auto next = static_cast<std::int64_t>(v.NextSequence());
  ASSERT_GT(next, 20000);
  EXPECT_EQ(v.Sample(next - 16384, 1, -1).status, 200);
  EXPECT_EQ(v.Sample(next - 16385, 1, -1).status, 404) << "older observations must have left the buffer";
}

TEST(CellView, CycleTimesPerProgramFromProgramEnds) {
  CellView v(TwoStations());
  // Two programs on one visit: ends at 100 s and 160 s of machine time; a repeated sample changes nothing.
  v.Run({7, "KT01", "ROUGH", "ACTIVE", 1, 3, 1, 100.0, 0});
  v.Run({7, "KT01", "ROUGH", "ACTIVE", 1, 3, 1, 100.0, 0});
  v.Run({7, "KT01", "FINISH", "ACTIVE", 1, 3, 2, 160.0, 0});
  auto c = v.Snapshot()["cycles"];
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c[0]["program"], "ROUGH");
  EXPECT_DOUBLE_EQ(c[0]["s"].get<double>(), 100.0);
  EXPECT_EQ(c[1]["program"], "FINISH");
  EXPECT_DOUBLE_EQ(c[1]["s"].get<double>(), 60.0);
}

TEST(CellView, JobDetailHasTheDecisionLogAndInspectionsAreNewestFirst) {
  CellView v(TwoStations());
  v.Job(WaitingJob(3, 1));
  auto d = v.JobDetail(3);
  ASSERT_TRUE(d);
  ASSERT_EQ((*d)["decisions"].size(), 1u);
  EXPECT_EQ((*d)["decisions"][0]["considered"][0]["missing_tools"], nlohmann::json::array({"7777"}));
  EXPECT_FALSE(v.JobDetail(4));
  StoredIn a{"run", "run-KT01-1.json", "KT01", 3, 1, 1, {"P1"}, true, "", 12.5, "", 0};
  StoredIn b = a;
  b.name = "run-KT01-2.json";
  v.Stored(a);
  v.Stored(b);
  v.Stored(a);  // re-delivered: moves to the front, not twice
  auto ins = v.Snapshot()["inspections"];
  ASSERT_EQ(ins.size(), 2u);
  EXPECT_EQ(ins[0]["name"], "run-KT01-1.json");
}

TEST(StationDefs, AxesComeFromTheStationFiles) {
  setenv("CELL_CONFIG_DIR", (cell::testing::SourceDir() + "/deploy").c_str(), 1);
  auto defs = LoadStationDefs();
  unsetenv("CELL_CONFIG_DIR");
  std::map<std::string, StationDef> by;
  for (auto& d : defs) by[d.id] = d;
  ASSERT_TRUE(by.count("KT01"));
  ASSERT_TRUE(by.count("OK01"));
  auto names = [](const StationDef& d) {
    std::string s;
    for (auto& a : d.axes) s += a.name;
    return s;
  };
  EXPECT_EQ(names(by["KT01"]), "XYZB");  // deploy/stations/KT01.toml: [axes.x] [axes.y] [axes.z] [axes.b]
  EXPECT_TRUE(by["KT01"].axes[3].rotary);
  EXPECT_EQ(names(by["OK01"]), "XZC");  // the lathe: X (diameter), Z and the C axis
  EXPECT_TRUE(by["OK01"].axes[0].diameter);
  EXPECT_TRUE(by["OK01"].axes[2].rotary);
  EXPECT_EQ(by["OK01"].kind, "lathe");
}

TEST(StationDefs, AConfiguredUHeadIsListedAsALinearAxis) {
  // A KT station with the U-head ([axes.u], KT-APL manual ln 7128): U after X Y Z B, at its index 6.
  cell::machine::MachineConfig m = cell::machine::DefaultMachineConfig("hmc");
  m.axes[cell::machine::kU] = m.axes[cell::machine::kZ];
  cell::config::StationConfig st;
  st.id = "KT09";
  const StationDef d = MakeStationDef(st, m);
  std::string names;
  for (auto& a : d.axes) names += a.name;
  EXPECT_EQ(names, "XYZBU");
  EXPECT_EQ(d.axes.back().index, cell::machine::kU);
  EXPECT_FALSE(d.axes.back().rotary);
}

}  // namespace
}  // namespace cell::dashboard
