// The job record (DESIGN §6 `job ls` / `job show`, and the page's jobs): one struct, one JSON form. The
// scheduler fills it from its own state, the dashboard from the job state topic (FromWire); both print
// JobJson, so `cellctl job show --json` and the page's job agree key by key.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cell/idl/scheduler.h"

namespace cell::records {

struct DecisionStation {  // one station as a decision weighed it
  std::string station;
  bool online = false, fault = false, eligible = false;
  std::int64_t backlog_s = 0;
  std::vector<std::string> missing_tools;
};

struct Decision {  // DESIGN §5: every allocation decision with its inputs
  std::int64_t seq = 0;
  std::int64_t time_ns = 0;
  int op = 1;  // 1-based operation of the route
  std::string trigger, winner, why;
  std::int64_t added_backlog_s = 0;
  std::vector<DecisionStation> considered;
};

struct Job {
  std::int64_t id = 0;
  std::string state;  // JobStateName: QUEUED, WAITING, DISPATCHED, RUNNING, COMPLETED, FAILED, CANCELLED
  std::string kind;   // "route", "pallet" or "schedule"
  std::string route, schedule, station, reason;  // "" when unset (printed as null)
  int pallet = 0;
  std::int64_t started_ns = 0, finished_ns = 0;  // 0 = not yet
  std::optional<double> cycle_s;                 // machine seconds, once known
  std::optional<double> predicted_s;             // job show: what its allocations predicted (not on the wire)
  int op_index = 1, op_count = 1;                // 1-based
  std::uint32_t decision_count = 0;              // all decisions, even when `decisions` holds the latest only
  std::vector<Decision> decisions;
};

// {id, state, route, pallet, station, reason, started, finished, cycle_s, kind, schedule, op_index, op_count,
// decision_count}, plus `decisions` and `predicted_s` when with_decisions. Empty strings and unset times are
// null.
nlohmann::json JobJson(const Job& job, bool with_decisions);
nlohmann::json DecisionJson(const Decision& d);

// From cell/job/state (the scheduler's JobInfo sample): comma-separated missing tools become a list.
Job FromWire(const cell::JobInfo& w);
// The sample the scheduler publishes: within the IDL bounds (long texts cut with "...", the latest 16
// decisions with 16 stations each, a missing-tool list cut at 256 characters with a last "+N more" entry).
// The slot and the update time are the publisher's to set.
cell::JobInfo ToWire(const Job& j);

}  // namespace cell::records
