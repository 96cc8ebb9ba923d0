// The Gantt chart's data (docs/dashboard.md, "Plan"): the scheduler's plan (its SCHED_PLAN rows, the ones
// `cellctl plan --json` prints) beside what actually ran (CellView::Ran), for /api/plan. Pure: the rows
// come from PlanSource (plan_source.h) or a test.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace cell::dashboard {

// The latest answer to SCHED_PLAN: the rows, when they arrived (0: never), and why the last ask failed.
struct PlanFetch {
  nlohmann::json rows = nlohmann::json::array();
  std::int64_t fetched_ns = 0;
  std::string error;
};

// {now, fetched, error, stations, planned, waiting, ran, current, next}:
//   planned  the rows with a station (job, pallet, route, op, station, start, end), by station and start;
//   waiting  the rows without (job, pallet, route, op, waiting_for);
//   ran      what actually ran (CellView::Ran);
//   current  per station, the planned row in hand at `now` (start <= now < end), else null;
//   next     per station, the first planned row after it (start >= now, not the current one), else null.
// Times are ISO-8601 UTC in whole seconds, so they compare as text.
nlohmann::json GanttJson(const std::vector<std::string>& stations, const PlanFetch& plan,
                         const nlohmann::json& ran, std::int64_t now_ns);

}  // namespace cell::dashboard
