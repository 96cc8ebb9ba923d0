// Service announcement and liveness: every process publishes ServiceHealth at 1 Hz; readers
// derive "online" from heartbeat age (DESIGN §3: a process not announced is UNAVAILABLE).
#pragma once

#include <chrono>
#include <map>
#include <mutex>
#include <string>
#include <thread>

#include "cell/bus/bus.h"
#include "cell/bus/topics.h"
#include "cell/idl/health.h"

namespace cell::health {

int64_t WallNs();

class Announcer {
 public:
  // kind: the executable name; station: empty for cell-wide services.
  Announcer(bus::Participant& p, const std::string& kind, const std::string& station = "");
  ~Announcer();
  void Set(cell::ServiceState state, const std::string& detail = "");
  const std::string& service_id() const { return id_; }

 private:
  void Publish();
  bus::Writer<cell::ServiceHealth> w_;
  std::string id_;
  cell::ServiceHealth h_;
  std::mutex mu_;
  std::jthread beat_;
};

// Tracks every service's last heartbeat.
class Liveness {
 public:
  explicit Liveness(bus::Participant& p);
  // Online: announced READY and heard from within topics::kOfflineAfterMs.
  bool Online(const std::string& service_id) const;
  bool StationOnline(const std::string& station) const { return Online("cell-interpreter/" + station); }
  std::map<std::string, cell::ServiceHealth> Snapshot() const;

 private:
  mutable std::mutex mu_;
  std::map<std::string, std::pair<cell::ServiceHealth, std::chrono::steady_clock::time_point>> seen_;
  bus::Reader<cell::ServiceHealth> r_;
};

}  // namespace cell::health
