// Service announcement and liveness: every process publishes ServiceHealth at 1 Hz; readers
// derive "online" from heartbeat age (DESIGN §3: a process not announced is UNAVAILABLE).
#pragma once

#include <chrono>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "cell/bus/bus.h"
#include "cell/bus/topics.h"
#include "cell/idl/health.h"

namespace cell::health {

int64_t WallNs();

// A random id for this process's announcement: two processes under one service id differ in it.
uint64_t NewBootId();

class Announcer {
 public:
  // kind: the executable name; station: empty for cell-wide services. Publishes SERVICE_STARTING at once.
  Announcer(bus::Participant& p, const std::string& kind, const std::string& station = "");
  ~Announcer();
  void Set(cell::ServiceState state, const std::string& detail = "");
  const std::string& service_id() const { return id_; }
  uint64_t boot_id() const { return h_.boot_id(); }
  int64_t started_ns() const { return h_.started_ns(); }

 private:
  void Publish();
  bus::Writer<cell::ServiceHealth> w_;
  std::string id_;
  cell::ServiceHealth h_;
  std::mutex mu_;
  std::jthread beat_;
};

// Two live processes announcing one service id (docs/operations.md, "One process per identity").
struct Conflict {
  std::string service_id;
  std::vector<cell::ServiceHealth> processes;  // their last announcements, oldest start first
  std::string Describe()
      const;  // "cell-interpreter/KT01 runs in 2 processes: pid 12 (boot 3f..), pid 40 (...)"
};

// Every service's last heartbeat, per process (boot id), as heard at given times: the rules of "online"
// without the bus (Liveness feeds it; tests drive it with their own times).
//
// A process whose receive is starved cannot tell its peers are gone from its own deafness: a scheduler on a
// loaded host took its heartbeats in late and in bursts, with datagrams dropped by the hundred thousand, and
// saw twenty stations go offline within 20 ms and come back a second later, each time re-sending what every
// station held, which loaded the bus further (issue 43). So a heartbeat older than topics::kOfflineAfterMs
// means offline only while most processes are still heard; when more than half of those heard in the last
// minute (other than this one) are silent at once, the last word stands for up to kOfflineWhenDeaf.
class Heartbeats {
 public:
  using Clock = std::chrono::steady_clock;
  static constexpr auto kOfflineWhenDeaf = std::chrono::milliseconds(3 * bus::topics::kOfflineAfterMs);

  // own_pid: this process's announcements (delivered locally, never late) say nothing of hearing others.
  explicit Heartbeats(int own_pid) : own_pid_(own_pid) {}
  void Heard(const cell::ServiceHealth& h, Clock::time_point at);
  // Online: announced READY and heard from within topics::kOfflineAfterMs (see above while deaf).
  bool Online(const std::string& service_id, Clock::time_point now) const;
  std::map<std::string, cell::ServiceHealth> Snapshot() const;
  std::vector<Conflict> Conflicts(Clock::time_point now) const;

 private:
  struct Seen {
    cell::ServiceHealth last;
    Clock::time_point first, at;
  };
  bool Deaf(Clock::time_point now) const;  // more than half of the others silent at once
  int own_pid_;
  std::map<std::string, std::map<uint64_t, Seen>> seen_;  // service id -> boot id -> what was heard
};

// Tracks every service's last heartbeat on the bus (Heartbeats, at the time the bus received each).
class Liveness {
 public:
  explicit Liveness(bus::Participant& p);
  // Online: announced READY and heard from within topics::kOfflineAfterMs (Heartbeats says when not).
  bool Online(const std::string& service_id) const;
  bool StationOnline(const std::string& station) const { return Online("cell-interpreter/" + station); }
  // The last announcement heard for each service id (of whichever process spoke last).
  std::map<std::string, cell::ServiceHealth> Snapshot() const;
  // Service ids announced READY by two or more processes that are both alive (heard within
  // topics::kOfflineAfterMs) and each heard again after the other first spoke. A process restarted after a
  // kill -9 is no conflict: the dead one was last heard before the new one first spoke.
  std::vector<Conflict> Conflicts() const;

 private:
  mutable std::mutex mu_;
  Heartbeats table_;
  bus::Reader<cell::ServiceHealth> r_;
};

}  // namespace cell::health
