// The scheduler's plan for the Gantt chart (docs/dashboard.md, "Plan"): the dashboard asks SCHED_PLAN, the
// request `cellctl plan` sends, on its own thread every few seconds and soon after a job changes (Poke:
// cell-dashboard's Feed calls it for each job state sample, so the dashboard reads the job topic once), and
// keeps the answer. Every browser's /api/plan reads the kept answer: many browsers
// cost the scheduler one request per period, and no page request waits on the bus or on another lock.
#pragma once

#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <thread>

#include "cell/bus/bus.h"
#include "cell/dashboard/gantt.h"
#include "cell/idl/scheduler.h"

namespace cell::dashboard {

class PlanSource {
 public:
  explicit PlanSource(bus::Participant& p, std::chrono::milliseconds period = std::chrono::seconds(3));
  ~PlanSource();
  PlanSource(const PlanSource&) = delete;
  PlanSource& operator=(const PlanSource&) = delete;

  PlanFetch Latest() const;  // the kept answer; never blocks on the bus
  void Poke();               // ask again soon (a job changed)

 private:
  void Loop();
  void Ask();  // one SCHED_PLAN, on the thread

  bus::Participant& p_;
  const std::chrono::milliseconds period_;
  std::unique_ptr<bus::Client<cell::SchedulerRequest, cell::SchedulerReply>> client_;
  mutable std::mutex mu_;  // latest_, poked_, stop_ only: held for a copy, never across a request
  std::condition_variable cv_;
  bool poked_ = true, stop_ = false;
  PlanFetch latest_;
  std::thread thread_;
};

}  // namespace cell::dashboard
