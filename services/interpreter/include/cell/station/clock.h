// The station core's clock: every timeout and every wait of the core goes through it, so unit tests drive
// the core on a fake clock without DDS and without sleeping (as the scheduler takes Options::clock).
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>

namespace cell::station {

class Clock {
 public:
  using Duration = std::chrono::steady_clock::duration;
  using TimePoint = std::chrono::steady_clock::time_point;
  virtual ~Clock() = default;
  // Monotonic time, for timeouts.
  virtual TimePoint Now() = 0;
  // Wall time in ns since the epoch, for run records and status stamps.
  virtual std::int64_t WallNs() = 0;
  // Releases `lk`, waits until `cv` is notified or `d` has passed (spurious wake-ups allowed: callers
  // re-check their condition), takes `lk` again.
  virtual void Wait(std::unique_lock<std::mutex>& lk, std::condition_variable& cv, Duration d) = 0;
};

// steady_clock, system_clock and the condition variable itself.
class SystemClock final : public Clock {
 public:
  TimePoint Now() override { return std::chrono::steady_clock::now(); }
  std::int64_t WallNs() override;
  void Wait(std::unique_lock<std::mutex>& lk, std::condition_variable& cv, Duration d) override {
    cv.wait_for(lk, d);
  }
};

}  // namespace cell::station
