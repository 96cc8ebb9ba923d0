#include "cell/station/silent_service.h"

#include <spdlog/spdlog.h>

namespace cell::station {

bool SilentServiceRejoin::MayRejoin() {
  std::lock_guard lk(mu_);
  const auto now = clock_.Now();
  if (last_ && now - *last_ < min_gap_) return false;
  last_ = now;
  ++rejoins_;
  return true;
}

void SilentServiceRejoin::Warn(const std::string& station, const std::string& what) {
  spdlog::warn("{}: {} though matched: joining the bus anew and asking once more", station, what);
}

}  // namespace cell::station
