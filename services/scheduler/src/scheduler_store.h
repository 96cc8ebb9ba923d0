// The scheduler's durable state (docs/scheduler.md §8), private to cell_scheduler_lib: the SQLite schema and
// its migrations, the records loaded at start, and one call's changes written in one transaction.
#pragma once

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

  // Reads every record into an empty State; nothing is left marked changed.
  void Load(State& state);
  // Writes what `state` marks changed (and the counters) in one transaction.
  void Flush(const State& state);

 private:
  store::Database db_;
};

// A route's stored form, also the route of a route-define command's fingerprint.
nlohmann::json SpecToJson(const RouteSpec& s);

}  // namespace cell::scheduler
