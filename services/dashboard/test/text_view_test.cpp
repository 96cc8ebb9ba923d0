// `cellctl watch`'s frame from the same snapshot the page renders.
#include <gtest/gtest.h>

#include "cell/dashboard/text_view.h"
#include "test_stations.h"

namespace cell::dashboard {
namespace {

TEST(TextView, StationsBacklogWaitingPalletsAndJobs) {
  CellView v(testing::TwoStations());
  v.Online("KT01", true);
  StatusIn s = testing::Status("KT01", "ACTIVE", "PUMP341", 42, 3);
  s.tool = "1002";
  v.Status(s);
  v.Backlog({{"KT01", 200}});
  JobIn j;
  j.id = 9;
  j.state = "WAITING";
  j.route = "R";
  j.pallet = 7;
  j.decisions = {DecisionIn{1, 0, 1, "operate", "", "x", 0, {{"KT01", true, false, false, 0, {"7777"}}}}};
  v.Job(j);
  std::string f = RenderText(v.Snapshot(), {100, false, 10});
  EXPECT_NE(f.find("KT01   ACTIVE"), std::string::npos) << f;
  EXPECT_NE(f.find("PUMP341"), std::string::npos);
  EXPECT_NE(f.find("3 min 20 s"), std::string::npos);
  EXPECT_NE(f.find("pallet 7 (job 9, route R): KT01 missing tools 7777"), std::string::npos) << f;
  EXPECT_NE(f.find("OK01   UNAVAILABLE"), std::string::npos);
  EXPECT_NE(f.find("WAITING"), std::string::npos);
  EXPECT_EQ(f.find("\x1b["), std::string::npos);  // no colour unless asked
  for (size_t a = 0, b; (b = f.find('\n', a)) != std::string::npos; a = b + 1) {
    size_t columns = 0;  // UTF-8 characters (the bar's blocks are 3 bytes each)
    for (size_t i = a; i < b; ++i) columns += (static_cast<unsigned char>(f[i]) & 0xC0) != 0x80;
    EXPECT_LE(columns, 100u) << f.substr(a, b - a);
  }
  EXPECT_NE(RenderText(v.Snapshot(), {100, true, 10}).find("\x1b[1;32mACTIVE"), std::string::npos);
}

// KT-APL EVT (cell/station/event): the newest events a program recorded, with station, pallet, program and
// line; at most five in the frame.
TEST(TextView, ProgramEventsNewestFirst) {
  CellView v(testing::TwoStations());
  EXPECT_EQ(RenderText(v.Snapshot(), {100, false, 10}).find("EVENTS"), std::string::npos);
  for (int i = 1; i <= 7; ++i) {
    EventIn e;
    e.station = "KT01";
    e.program = "PUMP341";
    e.pallet = 3;
    e.line = 10 * i;
    e.text = "PART " + std::to_string(i) + " DONE";
    e.time_ns = 1'795'000'000'000'000'000 + i;
    v.ProgramEvent(e);
  }
  const auto snap = v.Snapshot();
  ASSERT_EQ(snap["program_events"].size(), 7u);
  EXPECT_EQ(snap["program_events"][0]["text"], "PART 7 DONE");
  const std::string f = RenderText(snap, {100, false, 10});
  EXPECT_NE(f.find("EVENTS"), std::string::npos) << f;
  EXPECT_NE(f.find("KT01 pallet 3 PUMP341 line 70: PART 7 DONE"), std::string::npos) << f;
  EXPECT_NE(f.find("line 30: PART 3 DONE"), std::string::npos) << f;
  EXPECT_EQ(f.find("PART 2 DONE"), std::string::npos) << f;  // five shown
  EXPECT_LT(f.find("PART 7"), f.find("PART 6"));
}

// The serial lines (cell/dnc/status, docs/dnc.md): one row each with state, program and bytes of the total; a
// line in error shows its last error; none without a cell-dnc heard.
TEST(TextView, SerialLines) {
  CellView v(testing::TwoStations());
  EXPECT_EQ(RenderText(v.Snapshot(), {100, false, 10}).find("SERIAL LINES"), std::string::npos);
  DncIn d;
  d.station = "OK01";
  d.device = "/dev/ttyS0";
  d.state = "reading";
  d.program = "dispatch 12";
  v.Dnc(d);
  d.station = "KT01";
  d.state = "sending";
  d.program = "HOST:O1000";
  d.bytes = 300;
  d.total = 1234;
  v.Dnc(d);
  std::string f = RenderText(v.Snapshot(), {100, false, 10});
  EXPECT_NE(f.find("SERIAL LINES"), std::string::npos) << f;
  EXPECT_NE(f.find("  OK01   /dev/ttyS0     reading    dispatch 12          0 bytes"), std::string::npos)
      << f;
  EXPECT_NE(f.find("  KT01   /dev/ttyS0     sending    HOST:O1000           300/1234 bytes"),
            std::string::npos)
      << f;
  d.state = "idle";
  d.failed = true;
  d.last_error = "device /dev/ttyS0: byte 120: parity error (0x32)";
  v.Dnc(d);
  f = RenderText(v.Snapshot(), {160, false, 10});  // wide enough for the whole error
  EXPECT_NE(f.find("KT01   /dev/ttyS0     error      HOST:O1000           300/1234 bytes  device /dev/ttyS0: "
                   "byte 120: parity error (0x32)"),
            std::string::npos)
      << f;
}

}  // namespace
}  // namespace cell::dashboard
