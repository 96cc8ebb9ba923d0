#include "cell/health/health.h"

#include <unistd.h>

namespace cell::health {

int64_t WallNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

Announcer::Announcer(bus::Participant& p, const std::string& kind, const std::string& station)
    : w_(p, bus::topics::kHealth, bus::QosKind::kState), id_(station.empty() ? kind : kind + "/" + station) {
  h_.service_id(id_);
  h_.kind(kind);
  h_.station(station);
  h_.pid(getpid());
  h_.started_ns(WallNs());
  h_.state(cell::SERVICE_STARTING);
  Publish();
  beat_ = std::jthread([this](std::stop_token st) {
    std::mutex m;
    std::condition_variable_any cv;
    std::unique_lock lk(m);
    // wait_for returns at once once a stop is requested, so the stop must end the loop itself.
    while (!st.stop_requested()) {
      cv.wait_for(lk, st, std::chrono::milliseconds(bus::topics::kHeartbeatMs), [] { return false; });
      if (!st.stop_requested()) Publish();
    }
  });
}

Announcer::~Announcer() {
  beat_.request_stop();
  if (beat_.joinable()) beat_.join();
  Set(cell::SERVICE_STOPPING, "stopped");
}

void Announcer::Set(cell::ServiceState state, const std::string& detail) {
  {
    std::lock_guard lk(mu_);
    h_.state(state);
    h_.detail(detail.substr(0, 255));
  }
  Publish();
}

void Announcer::Publish() {
  std::lock_guard lk(mu_);
  h_.heartbeat_ns(WallNs());
  try {
    w_.Write(h_);
  } catch (const std::exception&) {
    // A heartbeat that cannot go out is the same as a missed one; readers time it out.
  }
}

Liveness::Liveness(bus::Participant& p)
    : r_(p, bus::topics::kHealth, bus::QosKind::kState,
         [this](const cell::ServiceHealth& h, const bus::SampleInfo&) {
           std::lock_guard lk(mu_);
           seen_[h.service_id().to_string()] = {h, std::chrono::steady_clock::now()};
         }) {}

bool Liveness::Online(const std::string& service_id) const {
  std::lock_guard lk(mu_);
  auto it = seen_.find(service_id);
  if (it == seen_.end()) return false;
  auto age = std::chrono::steady_clock::now() - it->second.second;
  return it->second.first.state() == cell::SERVICE_READY &&
         age < std::chrono::milliseconds(bus::topics::kOfflineAfterMs);
}

std::map<std::string, cell::ServiceHealth> Liveness::Snapshot() const {
  std::lock_guard lk(mu_);
  std::map<std::string, cell::ServiceHealth> out;
  for (auto& [k, v] : seen_) out[k] = v.first;
  return out;
}

}  // namespace cell::health
