// A host service (the program store, the inspection writer) matched on the bus yet silent for a whole call is
// most often DDS discovery broken one way since this process or the service restarted: in the 32-station Fast
// DDS week (2026-12-04) an interpreter started again after a kill had every program fetch time out for nine
// minutes, failing ten dispatches, until a rejoin for its servo healed it. The answer is the servo's
// (SegmentStream::RejoinOnce): join the bus anew, so discovery starts clean, and ask once more.
#pragma once

#include <chrono>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <utility>

#include "cell/error/error.h"
#include "cell/station/clock.h"

namespace cell::station {

class SilentServiceRejoin {
 public:
  // A rejoin costs the whole cell a discovery round, so it comes at most once per `min_gap`, however many
  // calls time out (a service that is down for a while, a caller that retries every few seconds).
  static constexpr std::chrono::seconds kMinGap{60};

  SilentServiceRejoin(Clock& clock, std::function<void()> rejoin, Clock::Duration min_gap = kMinGap)
      : clock_(clock), rejoin_(std::move(rejoin)), min_gap_(min_gap) {}

  // Calls `ask`. When it throws kTimeout (the service was matched: an unmatched one is kUnavailable) and no
  // rejoin came within min_gap, joins the bus anew and calls `ask` once more; its outcome is the answer.
  // Any other error, or a timeout within min_gap of the last rejoin, is thrown as it came.
  template <class Ask>
  auto Call(const std::string& station, Ask&& ask) -> decltype(ask()) {
    try {
      return ask();
    } catch (const Error& e) {
      if (e.code() != Errc::kTimeout || !MayRejoin()) throw;
      Warn(station, e.what());
      rejoin_();
      return ask();
    }
  }

  int rejoins() const {
    std::lock_guard lk(mu_);
    return rejoins_;
  }

 private:
  bool MayRejoin();
  static void Warn(const std::string& station, const std::string& what);

  Clock& clock_;
  std::function<void()> rejoin_;
  Clock::Duration min_gap_;
  mutable std::mutex mu_;
  std::optional<Clock::TimePoint> last_;
  int rejoins_ = 0;
};

}  // namespace cell::station
