// `job ls` pages (DESIGN §6 `--limit`, `--after`, `--state`, `--station`; issue 39 item 2): the scheduler
// visits jobs by id after a cursor, and records::PageBuilder cuts each page to the reply's bound, as the
// service does. 20,000 jobs (some 50 pages) are made through the scheduler's own API (Operate and Cancel),
// the fastest honest way to a listing of that size; 2,000 more on its SQLite store are listed again after a
// restart (the multi-process test in tests/integration/hardening_test.cpp makes a few hundred through real
// processes).
#include <gtest/gtest.h>

#include <fmt/format.h>

#include "cell/records/page.h"
#include "cell/scheduler/json.h"
#include "cell/scheduler/scheduler.h"
#include "fake_cell.h"

namespace cell::scheduler {
namespace {

using testing::FakeCell;
using testing::TempDir;

// One page as the service answers it (service.cpp ListJobs), and the largest page text seen.
records::Page Fetch(const Scheduler& s, JobQuery q, const std::string& after, std::uint32_t want,
                    std::size_t* largest = nullptr) {
  q.after = after.empty() ? 0 : std::stoll(after);
  records::PageBuilder page(want);
  s.ForJobs(q, [&](const JobView& j) { return page.Add(ToJson(j, false)); });
  if (largest) *largest = std::max(*largest, page.Text().size());
  return {nlohmann::json::parse(page.Text()), page.more()};
}

nlohmann::json List(const Scheduler& s, JobQuery q, std::uint32_t limit, const std::string& after = "",
                    std::size_t* largest = nullptr) {
  return records::CollectPages(limit, after, "id", [&](const std::string& a, std::uint32_t want) {
    return Fetch(s, q, a, want, largest);
  });
}

JobQuery Where(std::optional<JobState> state, std::string station = {}) {
  JobQuery q;
  q.state = state;
  q.station = std::move(station);
  return q;
}

TEST(JobListing, EmptyAndUnknownStationListNothing) {
  FakeCell c;
  EXPECT_TRUE(List(*c.sched, {}, 1000).empty());
  records::Page p = Fetch(*c.sched, {}, "", 10);
  EXPECT_TRUE(p.rows.empty());
  EXPECT_FALSE(p.more);
  c.Program("P1", {}, 60);
  c.Online("KT01");
  c.Route("R", {"KT01:P1"});
  EXPECT_EQ(c.sched->NewestJobId(), 0);
  c.Operate("R", 1);
  EXPECT_EQ(c.sched->NewestJobId(), 1);
  EXPECT_TRUE(List(*c.sched, Where(std::nullopt, "KT09"), 1000).empty());
  EXPECT_EQ(List(*c.sched, Where(std::nullopt, "KT01"), 1000).size(), 1u);
  EXPECT_TRUE(List(*c.sched, Where(JobState::kCompleted), 1000).empty());
  EXPECT_FALSE(JobStateFromName("DONE"));
  EXPECT_EQ(JobStateFromName("CANCELLED"), JobState::kCancelled);
}

// Boundaries: a page ends at its limit exactly, `after` is exclusive, after the last there is nothing.
TEST(JobListing, AfterIsExclusiveAndALimitEndsAPageExactly) {
  FakeCell c;
  c.Program("P1", {}, 60);
  c.Online("KT01");
  c.Route("R", {"KT01:P1"});
  std::vector<std::int64_t> ids;
  for (int p = 1; p <= 5; ++p) ids.push_back(c.Operate("R", p));
  records::Page first = Fetch(*c.sched, {}, "", 2);
  ASSERT_EQ(first.rows.size(), 2u);
  EXPECT_TRUE(first.more);
  EXPECT_EQ(first.rows[1]["id"], ids[1]);
  records::Page rest = Fetch(*c.sched, {}, std::to_string(ids[1]), 3);  // exactly what is left
  ASSERT_EQ(rest.rows.size(), 3u);
  EXPECT_EQ(rest.rows[0]["id"], ids[2]);
  EXPECT_FALSE(rest.more);
  EXPECT_TRUE(Fetch(*c.sched, {}, std::to_string(ids[4]), 3).rows.empty());  // after the last
  EXPECT_EQ(List(*c.sched, {}, 0, std::to_string(ids[4] - 1)).size(), 1u);
}

// Odd jobs on KT01, even ones on KT02; all but the last 200 (one per pallet) cancelled to free the pallet.
void Seed(FakeCell& c, int jobs) {
  constexpr int kPallets = 200;
  c.Program("P1", {}, 60);
  c.Online("KT01");
  c.Online("KT02");
  c.Route("R1", {"KT01:P1"});
  c.Route("R2", {"KT02:P1"});
  for (int i = 1; i <= jobs; ++i) {
    const std::int64_t id = c.Operate(i % 2 ? "R1" : "R2", (i - 1) % kPallets + 1, fmt::format("op-{}", i));
    ASSERT_EQ(id, i);
    if (i <= jobs - kPallets) c.Take(c.sched->Cancel(fmt::format("cancel-{}", i), id));
  }
}

// 20,000 jobs in memory (the same Scheduler without its database); the store's part is the restart test
// below. 100,000 took 5 s here but 34 s under the sanitizers and over 120 s on a loaded CI machine; a page
// costs the same after any cursor, so 50 pages prove what 250 did.
TEST(JobListing, PagesThroughTwentyThousandJobsWithinTheReplyBound) {
  constexpr int kJobs = 20000, kPallets = 200;
  FakeCell c;
  Seed(c, kJobs);
  std::size_t largest = 0;
  nlohmann::json all = List(*c.sched, {}, 0, "", &largest);
  ASSERT_EQ(all.size(), static_cast<std::size_t>(kJobs));
  for (int i = 0; i < kJobs; ++i) ASSERT_EQ(all[static_cast<std::size_t>(i)]["id"], i + 1);
  EXPECT_LE(largest, records::kReplyBytes);
  EXPECT_GT(largest, records::kReplyBytes / 2);  // the pages were cut by the bound, not by chance

  nlohmann::json first = List(*c.sched, {}, 1000);  // the default --limit
  ASSERT_EQ(first.size(), 1000u);
  EXPECT_EQ(first.back()["id"], 1000);
  EXPECT_EQ(List(*c.sched, Where(JobState::kCancelled), 0).size(),
            static_cast<std::size_t>(kJobs - kPallets));
  nlohmann::json kt02 = List(*c.sched, Where(std::nullopt, "KT02"), 0);
  ASSERT_EQ(kt02.size(), static_cast<std::size_t>(kJobs / 2));
  for (const auto& j : kt02) ASSERT_EQ(j["station"], "KT02");
  // Cancelled on KT01 after job 500: 501, 503, 505.
  nlohmann::json some = List(*c.sched, Where(JobState::kCancelled, "KT01"), 3, "500");
  ASSERT_EQ(some.size(), 3u);
  EXPECT_EQ(some[0]["id"], 501);
  EXPECT_EQ(some[2]["id"], 505);
  EXPECT_TRUE(List(*c.sched, {}, 1000, std::to_string(kJobs)).empty());
}

// The listing after a restart is the one recovered from the SQLite store (each command committed on tmpfs).
TEST(JobListing, TheListingSurvivesARestart) {
  TempDir tmp;
  FakeCell c(tmp.db());
  Seed(c, 2000);
  const nlohmann::json before = List(*c.sched, {}, 0);
  ASSERT_EQ(before.size(), 2000u);
  c.Restart();
  EXPECT_EQ(List(*c.sched, {}, 0), before);
  EXPECT_EQ(List(*c.sched, Where(JobState::kCancelled, "KT02"), 0).size(), 900u);  // even ids up to 1800
}

}  // namespace
}  // namespace cell::scheduler
