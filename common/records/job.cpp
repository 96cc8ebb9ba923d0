#include "cell/records/job.h"

#include "cell/records/names.h"
#include "cell/records/time.h"
#include "cell/records/values.h"

namespace cell::records {

using nlohmann::json;

namespace {

std::vector<std::string> SplitCommas(const std::string& s) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start < s.size()) {
    std::size_t end = s.find(',', start);
    if (end == std::string::npos) end = s.size();
    if (end > start) out.push_back(s.substr(start, end - start));
    start = end + 1;
  }
  return out;
}

std::string Cut(const std::string& s, std::size_t n) {
  return s.size() <= n ? s : s.substr(0, n - 3) + "...";
}

// The wire's comma-separated list within its 256 characters; what does not fit is counted in a last entry.
std::string JoinTools(const std::vector<std::string>& tools) {
  std::string out;
  std::size_t shown = 0;
  for (const auto& t : tools) {
    if (out.size() + t.size() + 16 > 256) break;
    out += (out.empty() ? "" : ",") + t;
    ++shown;
  }
  if (shown < tools.size())
    out += (out.empty() ? "+" : ",+") + std::to_string(tools.size() - shown) + " more";
  return out;
}

}  // namespace

json DecisionJson(const Decision& d) {
  json considered = json::array();
  for (const auto& c : d.considered)
    considered.push_back({{"station", c.station},
                          {"online", c.online},
                          {"fault", c.fault},
                          {"backlog_s", c.backlog_s},
                          {"missing_tools", c.missing_tools},
                          {"eligible", c.eligible}});
  return {{"seq", d.seq},
          {"time", TimeOrNull(d.time_ns)},
          {"op", d.op},
          {"trigger", d.trigger},
          {"considered", considered},
          {"winner", TextOrNull(d.winner)},
          {"why", d.why},
          {"added_backlog_s", d.added_backlog_s}};
}

json JobJson(const Job& j, bool with_decisions) {
  json out = {{"id", j.id},
              {"state", j.state},
              {"kind", j.kind},
              {"route", TextOrNull(j.route)},
              {"schedule", TextOrNull(j.schedule)},
              {"pallet", j.pallet},
              {"station", TextOrNull(j.station)},
              {"reason", TextOrNull(j.reason)},
              {"started", TimeOrNull(j.started_ns)},
              {"finished", TimeOrNull(j.finished_ns)},
              {"cycle_s", j.cycle_s ? json(*j.cycle_s) : json(nullptr)},
              {"op_index", j.op_index},
              {"op_count", j.op_count},
              {"decision_count", j.decision_count}};
  if (with_decisions) {
    // `job show` (DESIGN §6b): the prediction its allocations used, beside cycle_s; null when none had one.
    out["predicted_s"] = j.predicted_s ? json(*j.predicted_s) : json(nullptr);
    json d = json::array();
    for (const auto& x : j.decisions) d.push_back(DecisionJson(x));
    out["decisions"] = d;
  }
  return out;
}

Job FromWire(const cell::JobInfo& w) {
  Job j;
  j.id = w.job_id();
  j.state = std::string(JobStateName(w.state()));
  j.kind = w.kind().to_string();
  j.route = w.route().to_string();
  j.schedule = w.schedule().to_string();
  j.station = w.station().to_string();
  j.reason = w.reason().to_string();
  j.pallet = w.pallet();
  j.started_ns = w.started_ns();
  j.finished_ns = w.finished_ns();
  if (w.cycle_s() >= 0) j.cycle_s = w.cycle_s();  // the wire's -1 is "not yet"
  j.op_index = w.op_index();
  j.op_count = w.op_count();
  j.decision_count = w.decision_count();
  for (const auto& d : w.decisions()) {
    Decision x;
    x.seq = d.seq();
    x.time_ns = d.time_ns();
    x.op = d.op();
    x.trigger = d.trigger().to_string();
    x.winner = d.winner().to_string();
    x.why = d.why().to_string();
    x.added_backlog_s = d.added_backlog_s();
    for (const auto& c : d.considered())
      x.considered.push_back({c.station().to_string(), c.online(), c.fault(), c.eligible(), c.backlog_s(),
                              SplitCommas(c.missing_tools().to_string())});
    j.decisions.push_back(std::move(x));
  }
  return j;
}

cell::JobInfo ToWire(const Job& j) {
  cell::JobInfo w;
  w.job_id(static_cast<std::int32_t>(j.id));
  w.state(JobStateFromName(j.state).value_or(cell::JOB_QUEUED));
  w.kind(Cut(j.kind, 16));
  w.route(Cut(j.route, 64));
  w.schedule(Cut(j.schedule, 64));
  w.pallet(j.pallet);
  w.station(j.station);
  w.reason(Cut(j.reason, 1024));
  w.started_ns(j.started_ns);
  w.finished_ns(j.finished_ns);
  w.cycle_s(j.cycle_s.value_or(-1));
  w.op_index(j.op_index);
  w.op_count(j.op_count);
  w.decision_count(j.decision_count);
  const std::size_t first = j.decisions.size() > 16 ? j.decisions.size() - 16 : 0;
  for (std::size_t i = first; i < j.decisions.size(); ++i) {
    const Decision& d = j.decisions[i];
    cell::JobDecision x;
    x.seq(d.seq);
    x.time_ns(d.time_ns);
    x.op(d.op);
    x.trigger(Cut(d.trigger, 256));
    for (std::size_t c = 0; c < d.considered.size() && c < 16; ++c) {
      const DecisionStation& k = d.considered[c];
      cell::DecisionStation ds;
      ds.station(k.station);
      ds.online(k.online);
      ds.fault(k.fault);
      ds.backlog_s(k.backlog_s);
      ds.missing_tools(JoinTools(k.missing_tools));
      ds.eligible(k.eligible);
      x.considered().push_back(ds);
    }
    x.winner(d.winner);
    x.why(Cut(d.why, 1024));
    x.added_backlog_s(d.added_backlog_s);
    w.decisions().push_back(x);
  }
  return w;
}

}  // namespace cell::records
