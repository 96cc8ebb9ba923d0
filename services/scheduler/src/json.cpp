#include "cell/scheduler/json.h"

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

json ToolsJson(const tooltable::ToolTable& t) {
  json out = json::array();
  for (const auto& e : t.entries()) out.push_back(tooltable::EntryJson(e));
  return out;
}

}  // namespace cell::scheduler
