// Predictions off the scheduler's lock (issue 40; docs/scheduler.md "Estimates"): the scheduler's `ask`
// queues a PredictionRequest here and returns at once; one worker thread runs the Predictor on one request
// at a time, each within a time limit, and hands every answer to `post` (the service takes its lock there and
// gives it to Scheduler::PredictionAnswered). A request already queued or running is not queued again; one
// that just failed transiently is not asked again before its back-off has passed (30 s, doubling up to an
// hour), so a program store that does not answer costs one bounded try now and then, not one per allocation.
//
//   PredictionQueue q(predictor, [&](const PredictionRequest& r, const Predicted& p) {
//     std::lock_guard lk(mu);
//     Apply(sched.PredictionAnswered(r, p));
//   });
//   sched.SetPredictor(&predictor, [&](const PredictionRequest& r) { q.Ask(r); });
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <set>
#include <thread>

#include "cell/scheduler/estimates.h"

namespace cell::scheduler {

class PredictionQueue {
 public:
  using Post = std::function<void(const PredictionRequest&, const Predicted&)>;
  struct Options {
    std::chrono::milliseconds time_limit{10'000};   // wall clock per prediction (Predictor::Predict's limit)
    std::chrono::milliseconds retry_after{30'000};  // after a transient failure; doubles each time
    std::chrono::milliseconds retry_max{3'600'000};
    std::size_t max_queued = 4096;  // beyond: dropped (the scheduler asks again at its next need)
    std::function<std::chrono::steady_clock::time_point()> clock;  // default: steady_clock::now
  };

  // Starts the worker. `predictor` and whatever `post` uses must outlive the queue (or its Stop()).
  PredictionQueue(Predictor& predictor, Post post, Options options);
  PredictionQueue(Predictor& predictor, Post post) : PredictionQueue(predictor, std::move(post), Options{}) {}
  ~PredictionQueue();
  PredictionQueue(const PredictionQueue&) = delete;
  PredictionQueue& operator=(const PredictionQueue&) = delete;

  // Queues `r` unless it is queued, running, backing off or the queue is full. Never waits on a prediction.
  void Ask(const PredictionRequest& r);
  // Asks the running prediction to give up, and joins the worker; later Asks are dropped.
  void Stop();

  std::size_t Queued() const;    // waiting, not counting the one running
  std::size_t Answered() const;  // predictions run to an answer (posted), transient ones included

 private:
  void Run(std::stop_token st);
  // Records a transient failure's back-off (with mu_ held).
  void BackOff(const PredictionRequest& r);
  std::chrono::steady_clock::time_point Now() const;

  Predictor& predictor_;
  Post post_;
  Options opt_;
  mutable std::mutex mu_;
  std::condition_variable_any cv_;
  std::deque<PredictionRequest> queue_;
  std::set<PredictionRequest> pending_;  // queued or running
  struct Retry {
    std::chrono::steady_clock::time_point at;
    std::chrono::milliseconds wait{0};
  };
  std::map<PredictionRequest, Retry> retry_;
  std::size_t answered_ = 0;
  bool stopped_ = false;
  std::jthread worker_;  // last: started when everything above exists
};

}  // namespace cell::scheduler
