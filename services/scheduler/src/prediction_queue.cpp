// One worker, one prediction at a time, off the scheduler's lock (prediction_queue.h).
#include "cell/scheduler/prediction_queue.h"

#include <algorithm>
#include <exception>
#include <utility>

namespace cell::scheduler {

PredictionQueue::PredictionQueue(Predictor& predictor, Post post, Options options)
    : predictor_(predictor), post_(std::move(post)), opt_(std::move(options)) {
  worker_ = std::jthread([this](std::stop_token st) { Run(st); });
}

PredictionQueue::~PredictionQueue() {
  Stop();
}

std::chrono::steady_clock::time_point PredictionQueue::Now() const {
  return opt_.clock ? opt_.clock() : std::chrono::steady_clock::now();
}

void PredictionQueue::Ask(const PredictionRequest& r) {
  std::lock_guard lk(mu_);
  if (stopped_ || pending_.count(r) || queue_.size() >= opt_.max_queued) return;
  if (auto it = retry_.find(r); it != retry_.end() && Now() < it->second.at) return;
  pending_.insert(r);
  queue_.push_back(r);
  cv_.notify_one();
}

void PredictionQueue::Stop() {
  {
    std::lock_guard lk(mu_);
    stopped_ = true;
    queue_.clear();
  }
  if (worker_.joinable()) {
    worker_.request_stop();  // wakes the wait below and ends a running prediction (Predictor's stop)
    worker_.join();
  }
}

std::size_t PredictionQueue::Queued() const {
  std::lock_guard lk(mu_);
  return queue_.size();
}

std::size_t PredictionQueue::Answered() const {
  std::lock_guard lk(mu_);
  return answered_;
}

void PredictionQueue::BackOff(const PredictionRequest& r) {
  if (retry_.size() >=
      opt_.max_queued) {  // bounded: forget the back-offs that have passed, else the oldest key
    std::erase_if(retry_, [&](const auto& kv) { return kv.second.at <= Now(); });
    if (retry_.size() >= opt_.max_queued) retry_.erase(retry_.begin());
  }
  Retry& x = retry_[r];
  x.wait = x.wait.count() == 0 ? opt_.retry_after : std::min(opt_.retry_max, x.wait * 2);
  x.at = Now() + x.wait;
}

void PredictionQueue::Run(std::stop_token st) {
  for (;;) {
    PredictionRequest r;
    {
      std::unique_lock lk(mu_);
      if (!cv_.wait(lk, st, [&] { return !queue_.empty(); })) return;
      r = std::move(queue_.front());
      queue_.pop_front();
    }
    Predicted p;
    try {
      p = predictor_.Predict(r.program, r.station, opt_.time_limit, st);
    } catch (const std::exception& e) {
      p = Predicted{std::nullopt, e.what(), true};  // what failed may answer next time
    }
    if (st.stop_requested()) return;  // stopping: an answer cut short is no answer
    try {
      post_(r, p);
    } catch (...) {
      p.transient = true;  // not kept: asked again after the back-off
    }
    std::lock_guard lk(mu_);
    if (p.transient)
      BackOff(r);
    else
      retry_.erase(r);
    pending_.erase(r);
    ++answered_;
  }
}

}  // namespace cell::scheduler
