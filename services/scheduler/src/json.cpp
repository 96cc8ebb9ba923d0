#include "cell/scheduler/json.h"

namespace cell::scheduler {

using nlohmann::json;

namespace {
json OrNull(const std::string& s) {
  return s.empty() ? json(nullptr) : json(s);
}
json TimeOrNull(std::int64_t ms) {
  return ms == 0 ? json(nullptr) : json(IsoTime(ms));
}
}  // namespace

json ToJson(const Decision& d) {
  json considered = json::array();
  for (const auto& c : d.considered) {
    considered.push_back({{"station", c.station},
                          {"online", c.online},
                          {"fault", c.fault},
                          {"backlog_s", c.backlog_s},
                          {"missing_tools", c.missing_tools},
                          {"eligible", c.eligible}});
  }
  return {{"seq", d.seq},
          {"time", TimeOrNull(d.time_ms)},
          {"op", d.op_index + 1},
          {"trigger", d.trigger},
          {"considered", considered},
          {"winner", OrNull(d.winner)},
          {"why", d.why},
          {"added_backlog_s", d.added_backlog_s}};
}

json ToJson(const JobView& j, bool with_decisions) {
  json out = {{"id", j.id},
              {"state", std::string(JobStateName(j.state))},
              {"route", OrNull(j.route)},
              {"pallet", j.pallet},
              {"station", OrNull(j.station)},
              {"reason", OrNull(j.reason)},
              {"started", TimeOrNull(j.started_ms)},
              {"finished", TimeOrNull(j.finished_ms)},
              {"cycle_s", j.cycle_s ? json(*j.cycle_s) : json(nullptr)},
              {"kind", j.kind},
              {"schedule", OrNull(j.schedule)},
              {"op_index", j.op_index + 1},
              {"op_count", j.op_count}};
  if (with_decisions) {
    json d = json::array();
    for (const auto& x : j.decisions) d.push_back(ToJson(x));
    out["decisions"] = d;
  }
  return out;
}

json ToJson(const StationView& s) {
  return {{"id", s.id},
          {"dialect", s.dialect},
          {"online", s.online},
          {"condition", s.fault ? "FAULT" : "NORMAL"},
          {"alarm_code", OrNull(s.alarm_code)},
          {"alarm_text", OrNull(s.alarm_text)},
          {"backlog_s", s.backlog_s},
          {"pallet", s.pallet == 0 ? json(nullptr) : json(s.pallet)},
          {"program", OrNull(s.program)},
          {"queue", s.queue}};
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
  return {{"name", r.name}, {"valid", r.valid}, {"invalid_reason", OrNull(r.invalid_reason)}, {"ops", ops}};
}

json ToolsJson(const tooltable::ToolTable& t) {
  json out = json::array();
  for (const auto& e : t.entries()) out.push_back(tooltable::EntryJson(e));
  return out;
}

}  // namespace cell::scheduler
