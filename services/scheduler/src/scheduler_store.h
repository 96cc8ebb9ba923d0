// The scheduler's durable state (docs/scheduler.md §8), private to cell_scheduler_lib: the SQLite schema and
// its migrations, the records loaded at start, and one call's changes written in one transaction.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "cell/scheduler/route.h"
#include "cell/store/sqlite.h"
#include "state.h"

namespace cell::scheduler {

class Store {
 public:
  // Opens (or creates) the database and brings its schema up to date.
  explicit Store(const std::string& path);

  // Reads the records into an empty State: every live job and dispatch, the newest `kept_ended` ended jobs
  // with their decisions and dispatches, no idempotency key (Keyed reads one when asked). Nothing is left
  // marked changed.
  void Load(State& state, std::size_t kept_ended);
  // Writes what `state` marks changed (and the counters) in one transaction.
  void Flush(const State& state);

  // ---- what memory let go of, read back (everything in memory is flushed, so these agree with it) ----
  std::optional<JobView> Job(std::int64_t id, bool with_decisions);
  // `job ls` over every job: each row's id, and how to read its stored view (no decisions) when the caller
  // has none of its own, in id order, until false.
  void ForJobs(const JobQuery& q,
               const std::function<bool(std::int64_t, const std::function<JobView()>&)>& visit);
  std::optional<Keyed> Idempotency(const std::string& key);

 private:
  store::Database db_;
};

// A route's stored form, also the route of a route-define command's fingerprint.
nlohmann::json SpecToJson(const RouteSpec& s);

}  // namespace cell::scheduler
