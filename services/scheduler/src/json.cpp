#include "cell/scheduler/json.h"

#include "cell/records/time.h"
#include "cell/records/values.h"

namespace cell::scheduler {

using nlohmann::json;

records::Decision ToRecord(const Decision& d) {
  records::Decision r;
  r.seq = d.seq;
  r.time_ns = d.time_ms * 1000000;
  r.op = d.op_index + 1;
  r.trigger = d.trigger;
  r.winner = d.winner;
  r.why = d.why;
  r.added_backlog_s = d.added_backlog_s;
  for (const auto& c : d.considered)
    r.considered.push_back({c.station, c.online, c.fault, c.eligible, c.backlog_s, c.missing_tools});
  return r;
}

records::Job ToRecord(const JobView& j, bool with_decisions) {
  records::Job r;
  r.id = j.id;
  r.state = std::string(JobStateName(j.state));
  r.kind = j.kind;
  r.route = j.route;
  r.schedule = j.schedule;
  r.pallet = j.pallet;
  r.station = j.station;
  r.reason = j.reason;
  r.started_ns = j.started_ms * 1000000;
  r.finished_ns = j.finished_ms * 1000000;
  r.cycle_s = j.cycle_s;
  r.predicted_s = j.predicted_s;
  r.op_index = j.op_index + 1;
  r.op_count = j.op_count;
  r.decision_count = static_cast<std::uint32_t>(j.decision_count);
  if (with_decisions)
    for (const auto& d : j.decisions) r.decisions.push_back(ToRecord(d));
  return r;
}

json ToJson(const JobView& j, bool with_decisions) {
  return records::JobJson(ToRecord(j, with_decisions), with_decisions);
}

json FitJobShow(json job, std::size_t bound) {
  if (job.dump().size() <= bound || !job.contains("decisions")) return job;
  json all = std::move(job["decisions"]);
  job["decisions"] = json::array();
  job["decisions_omitted"] = all.size();
  // The key itself and the array's commas: a margin, so that the sum of the parts bounds the whole.
  std::size_t used = job.dump().size() + 32;
  std::vector<json> kept_tail;
  auto fits = [&](const json& d) {
    const std::size_t n = d.dump().size() + 1;
    if (used + n > bound) return false;
    used += n;
    return true;
  };
  const bool first = !all.empty() && fits(all.front());
  for (std::size_t i = all.size(); i-- > (first ? 1u : 0u);) {
    if (!fits(all[i])) break;
    kept_tail.push_back(std::move(all[i]));
  }
  if (first) job["decisions"].push_back(std::move(all.front()));
  for (auto it = kept_tail.rbegin(); it != kept_tail.rend(); ++it) job["decisions"].push_back(std::move(*it));
  job["decisions_omitted"] = all.size() - job["decisions"].size();
  return job;
}

json ToJson(const Decision& d) {
  return records::DecisionJson(ToRecord(d));
}

json ToJson(const RouteView& r) {
  json ops = json::array();
  for (const auto& op : r.ops) {
    std::int64_t sum = 0;
    for (auto u : op.ucy_s) sum += u;
    ops.push_back({{"stations", op.stations},
                   {"programs", op.programs},
                   {"ucy_s", op.ucy_s},
                   {"ucy_sum_s", sum},
                   {"tools", op.tools}});
  }
  return {{"name", r.name},
          {"valid", r.valid},
          {"invalid_reason", records::TextOrNull(r.invalid_reason)},
          {"ops", ops}};
}

json ToJson(const ProgramEstimates& e) {
  json predicted = json::object(), why = json::object(), estimate = json::object(), runs = json::object();
  for (const auto& s : e.stations) {
    predicted[s.station] = s.predicted_s ? json(*s.predicted_s) : json(nullptr);
    why[s.station] = s.predicted_s ? json(nullptr) : json(s.why);
    estimate[s.station] = s.estimate_s ? json(*s.estimate_s) : json(nullptr);
    runs[s.station] = s.runs;
  }
  return {{"program", e.meta.name},   {"ucy_s", e.meta.ucy_s ? json(*e.meta.ucy_s) : json(nullptr)},
          {"predicted_s", predicted}, {"predicted_why", why},
          {"estimate_s", estimate},   {"estimate_runs", runs}};
}

json ToJson(const std::vector<PlanRow>& plan) {
  json out = json::array();
  for (const auto& r : plan) {
    out.push_back({{"job", r.job},
                   {"pallet", r.pallet},
                   {"route", records::TextOrNull(r.route)},
                   {"op", r.op + 1},
                   {"station", records::TextOrNull(r.station)},
                   {"start", r.start_ms ? records::TimeOrNull(*r.start_ms * 1000000) : json(nullptr)},
                   {"end", r.end_ms ? records::TimeOrNull(*r.end_ms * 1000000) : json(nullptr)},
                   {"waiting_for", records::TextOrNull(r.waiting_for)}});
  }
  return out;
}

json ToolsJson(const tooltable::ToolTable& t) {
  json out = json::array();
  for (const auto& e : t.entries()) out.push_back(tooltable::EntryJson(e));
  return out;
}

}  // namespace cell::scheduler
