// Runner: the machine on its own thread, fed from another thread on credit.
#include "cell/servo/runner.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <thread>
#include <vector>

#include "test_util.h"

namespace cell::servo {
namespace {

using machine::DefaultMachineConfig;
using machine::MachineConfig;

TEST(Runner, FeedsOnCreditAndDeliversEventsInOrder) {
  for (ClockKind clock : {ClockKind::kVirtual, ClockKind::kReal}) {
    MachineConfig c = DefaultMachineConfig("hmc");
    c.queue_capacity = 3;
    std::mutex mu;
    std::vector<std::uint64_t> completed;
    double last_time = 0;
    Runner r(c, clock, [&](const Event& e) {
      std::lock_guard lock(mu);
      if (e.kind == EventKind::kCompleted) {
        completed.push_back(e.segment_id);
        last_time = e.machine_time;
      }
    });
    r.Start();
    const int n = clock == ClockKind::kVirtual ? 30 : 6;
    const auto w0 = std::chrono::steady_clock::now();
    for (int i = 1; i <= n;) {
      if (r.credits() > 0) {
        r.Push(testing::Line(i, 10.0 * i, (i % 2) * 5.0, 0, 6000));
        ++i;
      } else {
        std::this_thread::sleep_for(std::chrono::microseconds(200));
      }
    }
    ASSERT_TRUE(r.WaitIdle(30));
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
    r.Control([](Machine& m) { m.FeedHold(); });
    EXPECT_EQ(r.State().execution, Execution::kFeedHold);
    r.Stop();
    std::lock_guard lock(mu);
    ASSERT_EQ(completed.size(), static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) EXPECT_EQ(completed[i], static_cast<std::uint64_t>(i + 1));
    if (clock == ClockKind::kReal) {
      EXPECT_GE(wall, 0.95 * last_time);  // paced by the wall clock
    }
    EXPECT_NEAR(r.State().actual[kX], 10.0 * n, 1e-3);
  }
}

}  // namespace
}  // namespace cell::servo
