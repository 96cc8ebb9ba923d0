#include "cell/dashboard/plan_source.h"

#include "cell/bus/topics.h"
#include "cell/error/error.h"
#include "cell/records/time.h"

namespace cell::dashboard {

namespace {
// A job event comes in bursts (dispatch, start, end of several pallets): one request after the burst.
constexpr auto kSettle = std::chrono::milliseconds(200);
constexpr auto kTimeout = bus::Millis(5000);
}  // namespace

PlanSource::PlanSource(bus::Participant& p, std::chrono::milliseconds period)
    : p_(p), period_(period), thread_([this] { Loop(); }) {}

PlanSource::~PlanSource() {
  {
    std::lock_guard lk(mu_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

PlanFetch PlanSource::Latest() const {
  std::lock_guard lk(mu_);
  return latest_;
}

void PlanSource::Poke() {
  {
    std::lock_guard lk(mu_);
    poked_ = true;
  }
  cv_.notify_all();
}

void PlanSource::Loop() {
  std::unique_lock lk(mu_);
  while (!stop_) {
    cv_.wait_for(lk, period_, [this] { return stop_ || poked_; });
    if (stop_) break;
    if (poked_) cv_.wait_for(lk, kSettle, [this] { return stop_; });
    poked_ = false;
    lk.unlock();
    Ask();
    lk.lock();
  }
}

void PlanSource::Ask() {
  PlanFetch got;
  try {
    // Made here, not in the constructor: a viewer the permissions did not grant the request topic (an
    // older cell's governance) gets the reason on the page instead of a dashboard that does not start.
    if (!client_)
      client_ = std::make_unique<bus::Client<cell::SchedulerRequest, cell::SchedulerReply>>(
          p_, bus::topics::kScheduler);
    cell::SchedulerRequest r;
    r.op(cell::SCHED_PLAN);
    auto rep = client_->Call(std::move(r), kTimeout);
    bus::ThrowIfError(rep);
    got.rows = nlohmann::json::parse(rep.info().to_string());
    got.fetched_ns = records::NowNs();
  } catch (const std::exception& e) {
    got.error = std::string("the scheduler's plan: ") + e.what();
  }
  std::lock_guard lk(mu_);
  if (got.error.empty()) {
    latest_ = std::move(got);
  } else {
    latest_.error = got.error;  // the last plan stays, with when it came and why it is not newer
  }
}

}  // namespace cell::dashboard
