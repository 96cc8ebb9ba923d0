// One process per identity (a station's interpreter or axis servo, each host service): a process that hears
// its own service id announced by another live process refuses to start.
//
//   cell::bus::Participant bus("cell-interpreter/" + station);
//   cell::health::Announcer health(bus, "cell-interpreter", station);   // announces STARTING
//   cell::identity::Claim claim(bus, health);                          // listens on cell/health
//   ... read configuration, open the database ...
//   claim.Confirm();   // before anything is served: throws if this identity is taken
//
// The rule: during the claim window (kClaimWindow, the DDS liveliness lease, from the Claim's construction)
// every announcement of the same service id by another boot id counts, unless it says STOPPING or comes
// from a younger process (started later; equal start: the larger boot id is younger) — the younger of two
// that start together refuses, so one of them runs. A process killed with -9 announces nothing any more (a
// dead writer delivers no samples to a newcomer), so its restart is not refused. Should two run at once
// anyway (a discovery slower than the window, a process stopped past its lease), the scheduler raises a FAULT
// condition naming both (health::Liveness::Conflicts).
#pragma once

#include <chrono>
#include <mutex>
#include <optional>
#include <string>

#include "cell/bus/bus.h"
#include "cell/health/health.h"
#include "cell/idl/health.h"

namespace cell::identity {

inline constexpr std::chrono::milliseconds kClaimWindow{3000};

class Claim {
 public:
  // Starts listening for `me`'s service id announced by another process.
  Claim(bus::Participant& p, const health::Announcer& me);
  Claim(const Claim&) = delete;
  Claim& operator=(const Claim&) = delete;

  // Waits until the claim window has passed since construction (returns at once after that). Throws
  // cell::Error(kAlreadyExists) as soon as an older live process with this identity is heard: "another live
  // process is cell-interpreter/KT01: pid 1234 (boot 3f.., started ..., heard 0.4 s ago); refusing to start a
  // second one". Then stops listening: a cell-wide heartbeat read by every process was N x N samples a
  // second (a 24-station cell's 52 processes: 2,700), for a check that is over.
  void Confirm();

 private:
  std::string id_;
  uint64_t boot_;
  int64_t started_ns_;
  std::chrono::steady_clock::time_point deadline_;
  std::mutex mu_;
  std::optional<cell::ServiceHealth> rival_;
  std::optional<bus::Reader<cell::ServiceHealth>> r_;
};

}  // namespace cell::identity
