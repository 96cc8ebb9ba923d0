// The cut-division laws of the EMCO cycles against the manual's stated numbers.
#include <gtest/gtest.h>

#include "cycles.h"

namespace cell::interp::emco::cyc {
namespace {

TEST(Cycles, EqualCutsAsTheManualCountsThem) {
  EXPECT_EQ(EqualCuts(7, 2), 4);      // G84 D3 = 2 mm over 7 mm: 4 cuts of 1.75 (ln 3263-3281)
  EXPECT_EQ(EqualCuts(29, 6), 5);     // G87 D3 = 6 mm over 29 mm: 5 pecks of 5.8 (ln 4746-4761)
  EXPECT_EQ(EqualCuts(-7, 1.75), 4);  // exact multiples do not get an extra cut
  EXPECT_EQ(EqualCuts(5, 0), 1);
}

TEST(Cycles, DecrementalThreadDepthsKeepTheChipSection) {
  // M30x2 (ln 4176-4188), D3 = 600 first depth, D6 = 1227 (the printed 1277 is a typo: 30 - 2 x 1.227 =
  // 27.546): cumulative depths 600 sqrt(k) until D6.
  std::vector<double> d = ThreadDepths(1.227, 0.6, false, false, 0.1);
  ASSERT_EQ(d.size(), 5u);
  EXPECT_NEAR(d[0], 0.6, 1e-9);
  EXPECT_NEAR(d[1], 0.848528, 1e-6);
  EXPECT_NEAR(d[2], 1.039230, 1e-6);
  EXPECT_NEAR(d[3], 1.2, 1e-9);
  EXPECT_NEAR(d[4], 1.227, 1e-9);
}

TEST(Cycles, TheMonitorMinimumRaisesSmallInfeeds) {
  // ln 3907-3917: "D3 = 120 ... with the second infeed this value would be fallen short of ... the
  // subsequent infeeds are executed at 100".
  std::vector<double> d = ThreadDepths(0.5, 0.12, false, false, 0.1);
  ASSERT_GE(d.size(), 3u);
  EXPECT_NEAR(d[0], 0.12, 1e-9);
  EXPECT_NEAR(d[1], 0.22, 1e-9);
  EXPECT_NEAR(d[2], 0.32, 1e-9);
  // "D6 is 0.75 mm, D3 = 15 cuts ... the thread is cut in 8 infeeds": 7 of 100 um and the last 50 um with
  // constant infeed; decremental the first cut is 193.6 um and six more reach 0.75 mm.
  EXPECT_EQ(ThreadDepths(0.75, 15, true, true, 0.1).size(), 8u);
  EXPECT_EQ(ThreadDepths(0.75, 15, true, false, 0.1).size(), 7u);
  // Constant infeed by number of cuts: 6 equal cuts (ln 4215-4235).
  std::vector<double> six = ThreadDepths(1.227, 6, true, true, 0.1);
  ASSERT_EQ(six.size(), 6u);
  EXPECT_NEAR(six[0], 0.2045, 1e-9);
  EXPECT_NEAR(six[5], 1.227, 1e-9);
}

TEST(Cycles, DrillPecksWithReductionAndResidue) {
  // ln 4796-4807: D3 = 7 mm, D5 = 80 %, D6 = 3 mm over 29 mm: 7, 5.6, 4.48, 3.584, then the residual
  // 8.336 mm in 3 pecks.
  std::vector<double> p = DrillPecks(29, 7, 80, 3);
  ASSERT_EQ(p.size(), 7u);
  EXPECT_NEAR(p[0], 7, 1e-9);
  EXPECT_NEAR(p[1], 5.6, 1e-9);
  EXPECT_NEAR(p[2], 4.48, 1e-9);
  EXPECT_NEAR(p[3], 3.584, 1e-9);
  EXPECT_NEAR(p[4], 8.336 / 3, 1e-9);
  EXPECT_NEAR(p[6], 8.336 / 3, 1e-9);
  // Without reduction: equal pecks below D3; without D3 one pass.
  std::vector<double> q = DrillPecks(29, 6, 0, 0.1);
  ASSERT_EQ(q.size(), 5u);
  EXPECT_NEAR(q[0], 5.8, 1e-9);
  EXPECT_EQ(DrillPecks(29, 0, 0, 0.1).size(), 1u);
}

}  // namespace
}  // namespace cell::interp::emco::cyc
