// Predictions off the scheduler's lock (prediction_queue.h): a prediction that hangs holds up no dispatch,
// one runs at a time, a request is queued once, a transient failure backs off on the queue's clock, the
// time limit reaches the predictor, and Stop ends a prediction that hangs.
#include "cell/scheduler/prediction_queue.h"

#include <gtest/gtest.h>

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "cell/scheduler/scheduler.h"
#include "fake_cell.h"

namespace cell::scheduler {
namespace {

using namespace std::chrono_literals;
using testing::FakeCell;

// Hangs in Predict until released (or stopped). A call on `forbidden` (the thread that holds the
// scheduler, as the old EstimateFor made it) returns at once and is counted, so such a test fails, not hangs.
class HangingPredictor : public Predictor {
 public:
  Predicted Predict(std::string_view, std::string_view, std::chrono::milliseconds limit,
                    std::stop_token stop) override {
    std::unique_lock lk(mu_);
    if (std::this_thread::get_id() == forbidden) {
      ++on_scheduler_thread;
      return {seconds, ""};
    }
    ++running_;
    ++calls_;
    max_running_ = std::max(max_running_, running_);
    last_limit_ = limit;
    cv_.notify_all();
    cv_.wait(lk, stop, [&] { return released_; });
    --running_;
    if (!released_) return {std::nullopt, "stopped", true};
    return {seconds, ""};
  }
  std::string Basis(std::string_view) override { return "b"; }

  void Release() {
    std::lock_guard lk(mu_);
    released_ = true;
    cv_.notify_all();
  }
  bool WaitCalls(int n) {
    std::unique_lock lk(mu_);
    return cv_.wait_for(lk, 10s, [&] { return calls_ >= n; });
  }
  int calls() {
    std::lock_guard lk(mu_);
    return calls_;
  }
  int max_running() {
    std::lock_guard lk(mu_);
    return max_running_;
  }
  std::chrono::milliseconds last_limit() {
    std::lock_guard lk(mu_);
    return last_limit_;
  }

  std::thread::id forbidden = std::this_thread::get_id();
  std::optional<double> seconds = 95.0;
  int on_scheduler_thread = 0;

 private:
  std::mutex mu_;
  std::condition_variable_any cv_;
  bool released_ = false;
  int calls_ = 0, running_ = 0, max_running_ = 0;
  std::chrono::milliseconds last_limit_{0};
};

bool WaitAnswered(const PredictionQueue& q, std::size_t n) {
  const auto until = std::chrono::steady_clock::now() + 10s;
  while (q.Answered() < n) {
    if (std::chrono::steady_clock::now() > until) return false;
    std::this_thread::sleep_for(1ms);
  }
  return true;
}

const char* kEmco = "%\nN0010 G00 X50. Z10.\nN0020 M30\n";

// The chaos test's failure (issue 40): the old EstimateFor predicted under the service's lock, so a slow
// prediction stalled every allocation and report. Now a prediction that hangs holds up nothing.
TEST(PredictionQueue, DispatchProceedsWhileAPredictionHangs) {
  FakeCell c;
  HangingPredictor p;
  std::mutex mu;  // the service's lock
  PredictionQueue q(p, [&](const PredictionRequest& r, const Predicted& a) {
    std::lock_guard lk(mu);
    c.Take(c.sched->PredictionAnswered(r, a));
  });
  std::unique_lock lk(mu);
  c.sched->SetPredictor(&p, [&](const PredictionRequest& r) { q.Ask(r); });
  c.programs.Put("TURN", kEmco, "emco");
  c.Take(c.sched->StationOnline("EM01", "emco"));
  c.Take(c.sched->StationTools("EM01", testing::Tools({})));
  c.Route("R", {"EM01:TURN"});
  lk.unlock();
  ASSERT_TRUE(p.WaitCalls(1));  // the worker is in Predict, and stays there
  lk.lock();
  const std::int64_t j1 = c.Operate("R", 1);
  EXPECT_EQ(c.State(j1), JobState::kDispatched);
  ASSERT_EQ(c.received["EM01"].size(), 1u);  // handed out at once
  EXPECT_EQ(c.Backlog("EM01"), 0);           // an EMCO program without UCY: nothing, as before predictions
  EXPECT_FALSE(c.sched->Job(j1)->predicted_s);
  EXPECT_EQ(c.sched->Estimates("TURN").stations[0].why, "not predicted yet: asked for");
  EXPECT_EQ(q.Queued(), 0u);  // asked again by the allocation and program show: it is already running
  EXPECT_EQ(p.on_scheduler_thread, 0) << "predicted on the scheduler's thread, under its lock";
  lk.unlock();
  p.Release();
  ASSERT_TRUE(WaitAnswered(q, 1));
  lk.lock();
  const std::int64_t j2 = c.Operate("R", 2);
  EXPECT_EQ(c.Backlog("EM01"), 95);  // the next allocation uses the answer
  EXPECT_DOUBLE_EQ(c.sched->Job(j2)->predicted_s.value(), 95.0);
  EXPECT_EQ(p.calls(), 1);
}

TEST(PredictionQueue, OneAtATimeAndEachRequestOnce) {
  HangingPredictor p;
  std::mutex mu;
  std::vector<PredictionRequest> posted;
  PredictionQueue::Options o;
  o.time_limit = 1234ms;
  PredictionQueue q(
      p,
      [&](const PredictionRequest& r, const Predicted&) {
        std::lock_guard lk(mu);
        posted.push_back(r);
      },
      o);
  const PredictionRequest a{"A", "EM01", "r1/b"}, b{"B", "EM01", "r1/b"};
  q.Ask(a);
  ASSERT_TRUE(p.WaitCalls(1));
  q.Ask(a);  // running
  q.Ask(b);
  q.Ask(b);  // queued
  EXPECT_EQ(q.Queued(), 1u);
  p.Release();
  ASSERT_TRUE(WaitAnswered(q, 2));
  EXPECT_EQ(p.calls(), 2);
  EXPECT_EQ(p.max_running(), 1);
  EXPECT_EQ(p.last_limit(), 1234ms);  // the time limit reaches the predictor
  std::lock_guard lk(mu);
  EXPECT_EQ(posted, (std::vector<PredictionRequest>{a, b}));
}

class TransientPredictor : public Predictor {
 public:
  Predicted Predict(std::string_view, std::string_view, std::chrono::milliseconds, std::stop_token) override {
    ++calls;
    return {std::nullopt, "the program store did not answer", true};
  }
  std::string Basis(std::string_view) override { return "b"; }
  std::atomic<int> calls{0};
};

// A transient failure is asked again only after its back-off (30 s, then 60 s, ...), on the queue's clock.
TEST(PredictionQueue, TransientFailureBacksOff) {
  TransientPredictor p;
  std::atomic<std::int64_t> now_s{0};
  PredictionQueue::Options o;
  o.clock = [&] { return std::chrono::steady_clock::time_point(std::chrono::seconds(now_s.load())); };
  PredictionQueue q(
      p, [](const PredictionRequest&, const Predicted&) {}, o);
  const PredictionRequest a{"A", "EM01", "r1/b"};
  q.Ask(a);
  ASSERT_TRUE(WaitAnswered(q, 1));
  q.Ask(a);  // backing off: dropped
  now_s = 29;
  q.Ask(a);
  EXPECT_EQ(q.Queued(), 0u);
  EXPECT_EQ(p.calls, 1);
  now_s = 30;
  q.Ask(a);
  ASSERT_TRUE(WaitAnswered(q, 2));
  EXPECT_EQ(p.calls, 2);
  now_s = 60;  // the second back-off is 60 s: until 90
  q.Ask(a);
  EXPECT_EQ(p.calls, 2);
  now_s = 90;
  q.Ask(a);
  ASSERT_TRUE(WaitAnswered(q, 3));
  EXPECT_EQ(p.calls, 3);
  q.Ask({"B", "EM01", "r1/b"});  // another request is not held up by A's back-off
  ASSERT_TRUE(WaitAnswered(q, 4));
}

TEST(PredictionQueue, StopEndsAPredictionThatHangs) {
  HangingPredictor p;
  int posted = 0;
  PredictionQueue q(p, [&](const PredictionRequest&, const Predicted&) { ++posted; });
  q.Ask({"A", "EM01", "r1/b"});
  ASSERT_TRUE(p.WaitCalls(1));
  q.Ask({"B", "EM01", "r1/b"});
  q.Stop();  // returns: the hanging prediction saw the stop
  EXPECT_EQ(posted, 0);
  q.Ask({"C", "EM01", "r1/b"});  // dropped after Stop
  EXPECT_EQ(q.Queued(), 0u);
  EXPECT_EQ(p.calls(), 1);
}

}  // namespace
}  // namespace cell::scheduler
