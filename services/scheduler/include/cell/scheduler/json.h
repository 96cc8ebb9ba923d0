// JSON forms of the scheduler's views, with the keys of DESIGN §6 (`job ls`/`job show`, `route show`,
// `station tools`). Keys may be added, never renamed.
#pragma once

#include <nlohmann/json.hpp>

#include "cell/records/job.h"
#include "cell/scheduler/estimates.h"
#include "cell/scheduler/scheduler.h"
#include "cell/tooltable/tooltable.h"

namespace cell::scheduler {

// The job as a record (common/records): 1-based op_index, times in ns. The decisions are copied only when
// with_decisions (job ls leaves them out); decision_count counts them either way.
records::Job ToRecord(const JobView& job, bool with_decisions);
records::Decision ToRecord(const Decision& d);
// records::JobJson of the job: the form the page's job takes too. reason is set only while WAITING and
// when FAILED or CANCELLED.
nlohmann::json ToJson(const JobView& job, bool with_decisions);
nlohmann::json ToJson(const Decision& d);
// `job show` within a reply's bound: a job that waited through many changes of a large cell has a decision
// log past 64 KiB. The first decision and the newest that fit are kept; `decisions_omitted` counts the ones
// between them that were left out (absent when none was). A job whose fields alone do not fit is returned
// as is, for the caller's bound to refuse.
nlohmann::json FitJobShow(nlohmann::json job, std::size_t bound);
nlohmann::json ToJson(const RouteView& r);
// What `program show` adds (DESIGN §6b): {program, ucy_s, predicted_s, predicted_why, estimate_s,
// estimate_runs}, each of the last four an object keyed by station id (predicted_s null and predicted_why the
// reason where the station gives no number; predicted_why null where it does).
nlohmann::json ToJson(const ProgramEstimates& e);
// `plan` (DESIGN §6b): [{job, pallet, route, op (1-based), station, start, end, waiting_for}], ISO-8601 UTC;
// a waiting pallet has station, start and end null and waiting_for the reason (null otherwise).
nlohmann::json ToJson(const std::vector<PlanRow>& plan);
// `station tools ID`: an array of {tool, socket, length, diameter, life_left_min, worn, broken}.
nlohmann::json ToolsJson(const tooltable::ToolTable& t);

}  // namespace cell::scheduler
