// JSON forms of the scheduler's views, with the keys of DESIGN §6 (`job ls`/`job show`, `station ls`,
// `station tools`). Keys may be added, never renamed.
#pragma once

#include <nlohmann/json.hpp>

#include "cell/scheduler/scheduler.h"
#include "cell/tooltable/tooltable.h"

namespace cell::scheduler {

// {id, state, route, pallet, station, reason, started, finished, cycle_s, kind, op_index, op_count}
// plus `decisions` when with_decisions. route/station/reason/started/finished/cycle_s are null when unset
// (reason is set only while WAITING and when FAILED or CANCELLED).
nlohmann::json ToJson(const JobView& job, bool with_decisions);
nlohmann::json ToJson(const Decision& d);
// The scheduler's share of a `station ls` row: {id, dialect, online, condition, alarm_code, alarm_text,
// backlog_s, pallet, program, queue}. execution and line come from the station's own state topic.
nlohmann::json ToJson(const StationView& s);
nlohmann::json ToJson(const RouteView& r);
// `station tools ID`: an array of {tool, socket, length, diameter, life_left_min, worn, broken}.
nlohmann::json ToolsJson(const tooltable::ToolTable& t);

}  // namespace cell::scheduler
