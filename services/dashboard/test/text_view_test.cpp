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
  j.decisions = {DecisionIn{1, 0, 1, "operate", "", "x", 0, {{"KT01", true, false, false, 0, "7777"}}}};
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

}  // namespace
}  // namespace cell::dashboard
