// The page's DNC lines (docs/dashboard.md "DNC lines") without DDS: a transfer under way with its figures, a
// failed one shown as an error until the next transfer, a cell-dnc gone.
#include <gtest/gtest.h>

#include "cell/dashboard/cell_view.h"
#include "test_stations.h"

namespace cell::dashboard {
namespace {

DncIn Line(const std::string& state, std::uint64_t bytes) {
  DncIn d;
  d.station = "KT01";
  d.device = "/dev/ttyS0";
  d.state = state;
  d.program = "HOST:PART-A";
  d.bytes = bytes;
  d.total = 5000;
  d.seconds = 2;
  d.rate = bytes / 2.0;
  d.stalls = 3;
  d.stopped_s = 0.4;
  d.transfers = 1;
  return d;
}

// The newest "dnc" event after `after`.
nlohmann::json LastDncEvent(const CellView& v, std::uint64_t after) {
  nlohmann::json last;
  const auto events = v.EventsAfter(after, 1000);
  if (!events) return last;
  for (auto& e : *events) {
    auto j = nlohmann::json::parse(e.data);
    if (j["type"] == "dnc") last = j["dnc"];
  }
  return last;
}

TEST(DncView, ATransferUnderWayShowsItsFiguresOnThePage) {
  CellView v(testing::TwoStations());
  EXPECT_TRUE(v.Snapshot()["dnc"].empty());  // no station has a line: the page hides the panel
  const auto start = v.LastEvent();
  v.Dnc(Line("sending", 1200));
  auto row = LastDncEvent(v, start);
  EXPECT_EQ(row["station"], "KT01");
  EXPECT_EQ(row["state"], "sending");
  EXPECT_EQ(row["bytes"], 1200);
  EXPECT_EQ(row["total"], 5000);
  EXPECT_DOUBLE_EQ(row["rate"].get<double>(), 600.0);
  EXPECT_EQ(row["stalls"], 3);
  EXPECT_DOUBLE_EQ(row["stopped_s"].get<double>(), 0.4);
  EXPECT_EQ(row["device"], "/dev/ttyS0");
  auto snap = v.Snapshot()["dnc"];
  ASSERT_EQ(snap.size(), 1u);
  EXPECT_EQ(snap[0], row);  // one rendering for the snapshot and the stream
}

TEST(DncView, AFailedTransferIsAnErrorUntilTheNextOneBegins) {
  CellView v(testing::TwoStations());
  DncIn d = Line("idle", 830);
  d.failed = true;
  d.errors = 1;
  d.last_error = "device /dev/ttyS0: byte 830: hang-up";
  v.Dnc(d);
  auto row = v.Snapshot()["dnc"][0];
  EXPECT_EQ(row["state"], "error");
  EXPECT_EQ(row["transfer_state"], "idle");
  EXPECT_EQ(row["last_error"], "device /dev/ttyS0: byte 830: hang-up");
  // The next transfer: the line works again, the old error is still there to read but not the state.
  d = Line("sending", 10);
  d.errors = 1;
  d.last_error = "device /dev/ttyS0: byte 830: hang-up";
  v.Dnc(d);
  row = v.Snapshot()["dnc"][0];
  EXPECT_EQ(row["state"], "sending");
  EXPECT_EQ(row["errors"], 1);
  EXPECT_FALSE(row["failed"].get<bool>());
}

TEST(DncView, ALineWhoseProcessIsGoneIsOfflineNotStuckSending) {
  ViewOptions o;
  o.dnc_grace_s = 0;
  CellView v(testing::TwoStations(), o);
  v.DncOnline("KT01", false);  // no line heard: nothing to show
  EXPECT_TRUE(v.Snapshot()["dnc"].empty());
  v.Dnc(Line("sending", 400));
  const auto start = v.LastEvent();
  v.DncOnline("KT01", true);  // no change: no event
  EXPECT_EQ(v.LastEvent(), start);
  v.DncOnline("KT01", false);  // killed mid-send: its last sample says "sending"
  EXPECT_EQ(LastDncEvent(v, start)["state"], "offline");
  EXPECT_EQ(v.Snapshot()["dnc"][0]["transfer_state"], "sending");
  v.Dnc(Line("idle", 0));  // restarted: it writes again
  EXPECT_EQ(v.Snapshot()["dnc"][0]["state"], "idle");

  CellView fresh(testing::TwoStations());  // default grace: a sample just heard outweighs a missing heartbeat
  fresh.Dnc(Line("idle", 0));
  fresh.DncOnline("KT01", false);
  EXPECT_EQ(fresh.Snapshot()["dnc"][0]["state"], "idle");
}

}  // namespace
}  // namespace cell::dashboard
