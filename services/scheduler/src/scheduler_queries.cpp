// What the scheduler shows: jobs with their decisions, stations, routes and pallet maps.
#include <algorithm>

#include "cell/scheduler/scheduler.h"
#include "scheduler_impl.h"

namespace cell::scheduler {

JobView Scheduler::Impl::View(const JobRec& j, bool with_decisions) const {
  JobView v;
  v.id = j.id;
  v.state = j.state;
  v.kind = j.kind;
  v.route = j.route;
  v.schedule = j.sched_name;
  v.pallet = j.pallet;
  v.station = j.station < 0 ? std::string() : stations[static_cast<std::size_t>(j.station)].id;
  v.reason = j.reason;
  v.started_ms = j.started;
  v.finished_ms = j.finished;
  v.cycle_s = j.cycle;
  if (!j.predicted.empty()) {
    double sum = 0;
    for (const auto& [op, seconds] : j.predicted) sum += seconds;
    v.predicted_s = sum;
  }
  v.op_index = j.op;
  v.op_count = static_cast<int>(j.ops->size());
  v.decision_count = static_cast<int>(j.decisions.size());
  if (with_decisions) {
    for (const auto& r : j.decisions) {
      Decision d;
      d.seq = r.seq;
      d.time_ms = r.time_ms;
      d.op_index = r.op;
      d.trigger = r.trigger;
      d.why = r.why.empty() && r.alloc.winner < 0 ? Describe(r.alloc) : r.why;
      d.added_backlog_s = r.added;
      d.winner = r.alloc.winner < 0 ? std::string() : stations[static_cast<std::size_t>(r.alloc.winner)].id;
      for (const auto& c : r.alloc.candidates) {
        Candidate cv;
        cv.station = stations[static_cast<std::size_t>(c.station)].id;
        cv.online = c.online;
        cv.fault = c.fault;
        cv.backlog_s = c.backlog_s;
        r.alloc.ForMissing(c, [&](int t) { cv.missing_tools.push_back(tool_index.Name(t)); });
        cv.eligible = c.eligible();
        d.considered.push_back(std::move(cv));
      }
      v.decisions.push_back(std::move(d));
    }
  }
  return v;
}

StationView Scheduler::Impl::ViewStation(int s) const {
  const StationRec& st = stations[static_cast<std::size_t>(s)];
  const StationState& ss = states[static_cast<std::size_t>(s)];
  StationView v;
  v.id = st.id;
  v.dialect = st.dialect;
  v.online = ss.online;
  v.fault = ss.fault;
  v.alarm_code = st.alarm_code;
  v.alarm_text = st.alarm_text;
  v.backlog_s = ss.backlog_s;
  if (st.inflight) {
    v.queue.push_back(st.inflight);
    v.in_hand = st.inflight;
    v.pallet = dispatches.at(st.inflight).pallet;
  }
  v.queue.insert(v.queue.end(), st.queue.begin(), st.queue.end());
  v.program = st.program;
  return v;
}

RouteView Scheduler::Impl::ViewRoute(const std::string& name, const RouteRec& r) const {
  RouteView v;
  v.name = name;
  v.valid = r.valid;
  v.invalid_reason = r.invalid_reason;
  for (const auto& op : *r.ops) {
    OpView o;
    for (int s : op.stations) o.stations.push_back(stations[static_cast<std::size_t>(s)].id);
    o.programs = op.programs;
    o.ucy_s = op.ucy;
    o.tools = op.tools;
    v.ops.push_back(std::move(o));
  }
  return v;
}

std::map<int, double> Scheduler::StationCommonVariables(std::string_view id) const {
  const int s = impl_->FindStation(id);
  if (s < 0) return {};
  return impl_->stations[static_cast<std::size_t>(s)].vars;
}

std::optional<JobView> Scheduler::Job(std::int64_t id, bool with_decisions) const {
  auto it = impl_->jobs.find(id);
  if (it != impl_->jobs.end()) return impl_->View(it->second, with_decisions);
  if (impl_->store) return impl_->store->Job(id, with_decisions);  // an ended job memory let go of
  return std::nullopt;
}

std::vector<JobView> Scheduler::Jobs(bool with_decisions) const {
  std::vector<JobView> out;
  ForJobs({}, [&](const JobView& v) {
    out.push_back(with_decisions ? *Job(v.id, true) : v);
    return true;
  });
  return out;
}

std::int64_t Scheduler::NewestJobId() const {
  return impl_->jobs.empty() ? 0 : impl_->jobs.rbegin()->first;
}

std::size_t Scheduler::HeldJobs() const {
  return impl_->jobs.size();
}

std::size_t Scheduler::HeldDispatches() const {
  return impl_->dispatches.size();
}

void Scheduler::ForJobs(const JobQuery& q, const std::function<bool(const JobView&)>& visit) const {
  if (impl_->store) {
    // The database holds every job, and what memory holds is flushed: the stored rows in order, each seen
    // as memory has it where memory still has it.
    impl_->store->ForJobs(q, [&](std::int64_t id, const std::function<JobView()>& stored) {
      auto it = impl_->jobs.find(id);
      return visit(it == impl_->jobs.end() ? stored() : impl_->View(it->second, false));
    });
    return;
  }
  int station = -1;
  if (!q.station.empty() && (station = impl_->FindStation(q.station)) < 0) return;  // no job was there
  for (auto it = impl_->jobs.upper_bound(q.after); it != impl_->jobs.end(); ++it) {
    const JobRec& j = it->second;
    if ((q.state && j.state != *q.state) || (station >= 0 && j.station != station)) continue;
    if (!visit(impl_->View(j, false))) return;
  }
}

std::vector<StationView> Scheduler::Stations() const {
  std::vector<StationView> out;
  for (std::size_t s = 0; s < impl_->stations.size(); ++s)
    out.push_back(impl_->ViewStation(static_cast<int>(s)));
  std::sort(out.begin(), out.end(), [](const StationView& a, const StationView& b) { return a.id < b.id; });
  return out;
}

bool Scheduler::DispatchLive(std::int64_t dispatch_id) const {
  auto it = impl_->dispatches.find(dispatch_id);
  return it != impl_->dispatches.end() && Live(it->second.state);
}

std::optional<StationView> Scheduler::Station(std::string_view id) const {
  const int s = impl_->FindStation(id);
  if (s < 0) return std::nullopt;
  return impl_->ViewStation(s);
}

std::optional<tooltable::ToolTable> Scheduler::StationToolTable(std::string_view id) const {
  const int s = impl_->FindStation(id);
  if (s < 0) return std::nullopt;
  return impl_->stations[static_cast<std::size_t>(s)].tools;
}

std::optional<RouteView> Scheduler::Route(std::string_view name) const {
  auto it = impl_->routes.find(name);
  if (it == impl_->routes.end()) return std::nullopt;
  return impl_->ViewRoute(it->first, it->second);
}

std::vector<RouteView> Scheduler::Routes() const {
  std::vector<RouteView> out;
  for (const auto& [n, r] : impl_->routes) out.push_back(impl_->ViewRoute(n, r));
  return out;
}

std::optional<std::vector<std::string>> Scheduler::PalletMap(int pallet) const {
  auto it = impl_->pallet_maps.find(pallet);
  if (it == impl_->pallet_maps.end()) return std::nullopt;
  return it->second;
}

}  // namespace cell::scheduler
