#include "cell/servo/runner.h"

#include <chrono>
#include <vector>

namespace cell::servo {

using machine::MachineConfig;

Runner::Runner(MachineConfig config, ClockKind clock, EventSink sink)
    : machine_(std::move(config), clock), sink_(std::move(sink)) {}

Runner::~Runner() {
  Stop();
}

void Runner::Start() {
  std::lock_guard lock(mu_);
  if (running_) return;
  running_ = true;
  thread_ = std::thread([this] { Loop(); });
}

void Runner::Stop() {
  {
    std::lock_guard lock(mu_);
    if (!running_) return;
    running_ = false;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

std::size_t Runner::credits() const {
  std::lock_guard lock(mu_);
  return machine_.credits();
}

void Runner::Push(const Segment& segment) {
  {
    std::lock_guard lock(mu_);
    machine_.Push(segment);
    idle_ = false;
  }
  cv_.notify_all();
}

AxisState Runner::State() const {
  std::lock_guard lock(mu_);
  return machine_.State();
}

double Runner::machine_time() const {
  std::lock_guard lock(mu_);
  return machine_.machine_time();
}

bool Runner::WaitIdle(double timeout_s) {
  std::unique_lock lock(mu_);
  return cv_.wait_for(lock, std::chrono::duration<double>(timeout_s),
                      [&] { return idle_ && machine_.credits() == machine_.capacity(); });
}

void Runner::Loop() {
  const bool real = machine_.clock() == ClockKind::kReal;
  std::vector<Event> events;
  std::unique_lock lock(mu_);
  while (running_) {
    if (real) {
      const auto deadline = machine_.NextDeadline();
      lock.unlock();
      std::this_thread::sleep_until(deadline);
      lock.lock();
      if (!running_) break;
    }
    const bool ran = machine_.StepNow();
    if (machine_.HasEvents()) machine_.TakeEvents(events);
    if (!events.empty()) {
      lock.unlock();
      for (const auto& e : events) sink_(e);
      events.clear();
      lock.lock();
    }
    idle_ = !ran || machine_.Idle();
    if (idle_) cv_.notify_all();  // WaitIdle()
    if (!ran) {                   // virtual clock, nothing to do: sleep until woken
      cv_.wait(lock, [&] { return !running_ || !machine_.Idle(); });
      idle_ = false;
    }
  }
}

}  // namespace cell::servo
