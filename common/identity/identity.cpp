#include "cell/identity/identity.h"

#include <ctime>
#include <thread>

#include <fmt/format.h>

#include "cell/bus/topics.h"
#include "cell/error/error.h"
#include "cell/records/time.h"

namespace cell::identity {

Claim::Claim(bus::Participant& p, const health::Announcer& me)
    : id_(me.service_id()),
      boot_(me.boot_id()),
      started_ns_(me.started_ns()),
      deadline_(std::chrono::steady_clock::now() + kClaimWindow) {
  r_.emplace(p, bus::topics::kHealth, bus::QosKind::kState,
             [this](const cell::ServiceHealth& h, const bus::SampleInfo&) {
               if (h.service_id() != id_ || h.boot_id() == boot_ || h.state() == cell::SERVICE_STOPPING)
                 return;
               // The younger of two refuses: a later start, or at the same instant the larger boot id.
               const bool older =
                   h.started_ns() < started_ns_ || (h.started_ns() == started_ns_ && h.boot_id() < boot_);
               if (!older) return;
               std::lock_guard lk(mu_);
               rival_ = h;
             });
}

void Claim::Confirm() {
  for (;;) {
    {
      std::lock_guard lk(mu_);
      if (rival_) {
        const auto& h = *rival_;
        const std::string when = records::IsoTime(h.started_ns());
        throw Error(
            Errc::kAlreadyExists,
            fmt::format("another live process is {}: pid {} (boot {:016x}, started {}); refusing to start a "
                        "second one (stop it first, or wait for its lease to run out if it was killed)",
                        id_, h.pid(), h.boot_id(), when));
      }
    }
    auto left = deadline_ - std::chrono::steady_clock::now();
    if (left <= std::chrono::steady_clock::duration::zero()) {
      r_.reset();
      return;
    }
    std::this_thread::sleep_for(
        std::min<std::chrono::steady_clock::duration>(left, std::chrono::milliseconds(50)));
  }
}

}  // namespace cell::identity
