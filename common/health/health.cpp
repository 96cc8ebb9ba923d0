#include "cell/health/health.h"

#include "cell/names/names.h"

#include <unistd.h>

#include <algorithm>
#include <random>

#include <fmt/format.h>

namespace cell::health {

int64_t WallNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

uint64_t NewBootId() {
  std::random_device rd;
  uint64_t id = (static_cast<uint64_t>(rd()) << 32) ^ rd() ^ static_cast<uint64_t>(WallNs());
  return id == 0 ? 1 : id;
}

Announcer::Announcer(bus::Participant& p, const std::string& kind, const std::string& station)
    : w_(p, bus::topics::kHealth, bus::QosKind::kState), id_(station.empty() ? kind : kind + "/" + station) {
  names::Assign(h_.service_id(), id_, "service id");
  names::Assign(h_.kind(), kind, "service kind");
  names::Assign(h_.station(), station, "station id");
  h_.pid(getpid());
  h_.started_ns(WallNs());
  h_.boot_id(NewBootId());
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
    names::AssignText(h_.detail(), detail);
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

namespace {
constexpr auto kOffline = std::chrono::milliseconds(bus::topics::kOfflineAfterMs);
}

void Heartbeats::Heard(const cell::ServiceHealth& h, Clock::time_point at) {
  auto& boots = seen_[h.service_id().to_string()];
  auto [it, fresh] = boots.try_emplace(h.boot_id(), Seen{h, at, at});
  it->second.last = h;
  it->second.at = std::max(it->second.at, at);
  // Forget processes not heard for a long while (each restart is a new boot id).
  for (auto b = boots.begin(); b != boots.end();)
    b = at - b->second.at > std::chrono::minutes(1) ? boots.erase(b) : std::next(b);
}

bool Heartbeats::Online(const std::string& service_id, Clock::time_point now) const {
  auto it = seen_.find(service_id);
  if (it == seen_.end() || it->second.empty()) return false;
  // The process heard last speaks for the service.
  auto last = std::max_element(it->second.begin(), it->second.end(),
                               [](auto& a, auto& b) { return a.second.at < b.second.at; });
  if (last->second.last.state() != cell::SERVICE_READY) return false;
  const auto age = now - last->second.at;
  if (age < kOffline) return true;
  return age < kOfflineWhenDeaf && Deaf(now);
}

bool Heartbeats::Deaf(Clock::time_point now) const {
  int heard = 0, silent = 0;
  for (auto& [id, boots] : seen_)
    for (auto& [boot, s] : boots) {
      if (static_cast<int>(s.last.pid()) == own_pid_ || now - s.at > std::chrono::minutes(1)) continue;
      if (s.last.state() == cell::SERVICE_STOPPING) continue;  // said goodbye: its silence is no news
      ++(now - s.at < kOffline ? heard : silent);
    }
  return silent > heard;
}

std::map<std::string, cell::ServiceHealth> Heartbeats::Snapshot() const {
  std::map<std::string, cell::ServiceHealth> out;
  for (auto& [k, boots] : seen_) {
    if (boots.empty()) continue;
    auto last = std::max_element(boots.begin(), boots.end(),
                                 [](auto& a, auto& b) { return a.second.at < b.second.at; });
    out[k] = last->second.last;
  }
  return out;
}

std::vector<Conflict> Heartbeats::Conflicts(Clock::time_point now) const {
  std::vector<Conflict> out;
  for (auto& [id, boots] : seen_) {
    std::vector<const Seen*> live;
    for (auto& [boot, s] : boots)
      if (s.last.state() == cell::SERVICE_READY && now - s.at < kOffline) live.push_back(&s);
    if (live.size() < 2) continue;
    // Both alive at once: each was heard after the other first spoke.
    auto first =
        std::max_element(live.begin(), live.end(), [](auto* a, auto* b) { return a->first < b->first; });
    auto last = std::min_element(live.begin(), live.end(), [](auto* a, auto* b) { return a->at < b->at; });
    if ((*last)->at <= (*first)->first) continue;
    Conflict c;
    c.service_id = id;
    std::sort(live.begin(), live.end(),
              [](auto* a, auto* b) { return a->last.started_ns() < b->last.started_ns(); });
    for (auto* s : live) c.processes.push_back(s->last);
    out.push_back(std::move(c));
  }
  return out;
}

Liveness::Liveness(bus::Participant& p)
    : table_(static_cast<int>(::getpid())),
      r_(p, bus::topics::kHealth, bus::QosKind::kState,
         [this](const cell::ServiceHealth& h, const bus::SampleInfo& si) {
           // When the bus took it in, not when this callback got its turn on the dispatch thread.
           const Heartbeats::Clock::time_point at{std::chrono::nanoseconds(si.received_ns)};
           std::lock_guard lk(mu_);
           table_.Heard(h, si.received_ns != 0 ? at : Heartbeats::Clock::now());
         }) {}

bool Liveness::Online(const std::string& service_id) const {
  std::lock_guard lk(mu_);
  return table_.Online(service_id, Heartbeats::Clock::now());
}

std::map<std::string, cell::ServiceHealth> Liveness::Snapshot() const {
  std::lock_guard lk(mu_);
  return table_.Snapshot();
}

std::vector<Conflict> Liveness::Conflicts() const {
  std::lock_guard lk(mu_);
  return table_.Conflicts(Heartbeats::Clock::now());
}

std::string Conflict::Describe() const {
  std::string who;
  for (auto& h : processes)
    who += fmt::format("{}pid {} (boot {:016x})", who.empty() ? "" : ", ", h.pid(), h.boot_id());
  return fmt::format("{} runs in {} processes at once: {}", service_id, processes.size(), who);
}

}  // namespace cell::health
