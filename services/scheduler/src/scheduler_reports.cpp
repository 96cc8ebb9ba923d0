// What stations and the program store report: health, tools, variables, and the runs of dispatches.
#include <algorithm>
#include <map>

#include <fmt/format.h>

#include "cell/error/error.h"
#include "cell/scheduler/scheduler.h"
#include "scheduler_impl.h"

namespace cell::scheduler {

Effects Scheduler::StationVariables(std::string_view id, const std::map<int, double>& common) {
  Impl& m = *impl_;
  m.Call([&] {
    const int s = m.StationIndex(id, true);
    auto& st = m.stations[static_cast<std::size_t>(s)];
    for (const auto& [n, v] : common) {
      if (n < 1 || n > 200)
        throw Error(Errc::kInvalidArgument, fmt::format("V{} is not a common variable", n));
      if (auto p = st.pending_vars.find(n); p != st.pending_vars.end()) {
        if (p->second != v) continue;  // from before our write: the write wins until the station shows it
        st.pending_vars.erase(p);
        m.dirty_stations.insert(s);
      }
      auto [it, added] = st.vars.try_emplace(n, v);
      if (!added && it->second == v) continue;
      it->second = v;
      m.dirty_stations.insert(s);
    }
  });
  return m.TakeEffects();
}

Effects Scheduler::StationOnline(std::string_view id, std::string_view dialect) {
  Impl& m = *impl_;
  m.Call([&] {
    const int s = m.StationIndex(id, true);
    auto& st = m.stations[static_cast<std::size_t>(s)];
    if (!dialect.empty() && st.dialect != dialect) {
      st.dialect = std::string(dialect);
      m.dirty_stations.insert(s);
    }
    if (m.states[static_cast<std::size_t>(s)].online) return;
    m.states[static_cast<std::size_t>(s)].online = true;
    m.dirty_stations.insert(s);
    m.AskAgain(s);
    m.ReevaluateWaiting(s, fmt::format("station {} online", id));
    m.TrySend(s);
  });
  return m.TakeEffects();
}

Effects Scheduler::StationOffline(std::string_view id) {
  Impl& m = *impl_;
  m.Call([&] {
    const int s = m.FindStation(id);
    if (s < 0 || !m.states[static_cast<std::size_t>(s)].online) return;
    m.states[static_cast<std::size_t>(s)].online = false;
    m.dirty_stations.insert(s);
    m.Interrupt(s, fmt::format("station {} went offline", id), false);
    m.ReevaluateWaiting(s, fmt::format("station {} offline", id));
  });
  return m.TakeEffects();
}

Effects Scheduler::StationCondition(std::string_view id, bool fault, std::string_view code,
                                    std::string_view text) {
  Impl& m = *impl_;
  m.Call([&] {
    const int s = m.StationIndex(id, true);
    auto& st = m.stations[static_cast<std::size_t>(s)];
    auto& ss = m.states[static_cast<std::size_t>(s)];
    // A station's status comes several times a second while it runs; only a change is a write (each was a
    // transaction with the station's whole row, tool table included, issue 43).
    if (ss.fault == fault && st.alarm_code == code && st.alarm_text == text) return;
    st.alarm_code = std::string(code);
    st.alarm_text = std::string(text);
    m.dirty_stations.insert(s);
    if (ss.fault == fault) return;
    ss.fault = fault;
    if (fault) {
      m.Interrupt(s, fmt::format("station {} raised fault{}{}", id, code.empty() ? "" : " ", code), true);
    } else {
      // A station that came back while in fault was not asked about the dispatch it holds: it is now.
      if (ss.online) m.AskAgain(s);
      m.ReevaluateWaiting(s, fmt::format("station {} fault cleared", id));
      m.TrySend(s);
    }
  });
  return m.TakeEffects();
}

Effects Scheduler::StationTools(std::string_view id, const tooltable::ToolTable& table) {
  Impl& m = *impl_;
  m.Call([&] {
    const int s = m.StationIndex(id, true);
    m.stations[static_cast<std::size_t>(s)].tools = table;
    m.states[static_cast<std::size_t>(s)].SetTools(table, m.tool_index);
    m.dirty_stations.insert(s);
    // Pallets allocated here but not yet handed out that now lack a tool are allocated again.
    std::vector<std::int64_t> requeue;
    for (std::int64_t did : m.stations[static_cast<std::size_t>(s)].queue) {
      const auto& d = m.dispatches.at(did);
      const auto& j = m.jobs.at(d.job);
      for (int t : (*j.ops)[static_cast<std::size_t>(j.op)].tool_ids) {
        if (!m.states[static_cast<std::size_t>(s)].Holds(t)) {
          requeue.push_back(did);
          break;
        }
      }
    }
    for (std::int64_t did : requeue) {
      auto& d = m.dispatches.at(did);
      m.Detach(d, DState::kRevoked);
      auto& j = m.jobs.at(d.job);
      j.state = JobState::kQueued;
      j.dispatch = 0;
      j.station = -1;
      m.Evaluate(j, fmt::format("re-queued: tool table of {} changed", id));
    }
    m.ReevaluateWaiting(s, fmt::format("tool table of {} changed", id));
  });
  return m.TakeEffects();
}

namespace {
// Looks up a live dispatch for a station report; nullptr (and a note) when the report is stale.
DispatchRec* ForReport(Scheduler::Impl& m, std::int64_t id, std::string_view what) {
  auto it = m.dispatches.find(id);
  if (it == m.dispatches.end()) {
    m.fx.notes.push_back(fmt::format("{} for unknown dispatch {} ignored", what, id));
    return nullptr;
  }
  if (!Live(it->second.state) || it->second.state == DState::kQueued) {
    m.fx.notes.push_back(fmt::format("{} for dispatch {} ({}) ignored", what, id,
                                     kDStateNames[static_cast<int>(it->second.state)]));
    return nullptr;
  }
  it->second.heard_ms = m.NowMs();
  return &it->second;
}
}  // namespace

Effects Scheduler::AskSilent(std::chrono::milliseconds quiet) {
  // Changes nothing the database keeps (heard_ms is memory only): no transaction, every few seconds.
  Impl& m = *impl_;
  Effects fx;
  const std::int64_t now = m.NowMs();
  for (std::size_t s = 0; s < m.stations.size(); ++s) {
    const auto& ss = m.states[s];
    const std::int64_t id = m.stations[s].inflight;
    if (id == 0 || !ss.online || ss.fault) continue;
    DispatchRec& d = m.dispatches.at(id);
    // A dispatch still being delivered is the sender's (it retries until answered).
    if (d.state == DState::kSent || now - d.heard_ms < quiet.count()) continue;
    d.heard_ms = now;
    fx.dispatches.push_back(m.Action(d, true));
  }
  return fx;
}

Effects Scheduler::DispatchAcknowledged(std::int64_t dispatch_id) {
  Impl& m = *impl_;
  m.Call([&] {
    auto* d = ForReport(m, dispatch_id, "acknowledgement");
    if (!d || d->state != DState::kSent) return;
    d->state = DState::kAcked;
    m.dirty_dispatches.insert(d->id);
  });
  return m.TakeEffects();
}

namespace {
void MarkRunning(Scheduler::Impl& m, DispatchRec& d) {
  const auto& ss = m.states[static_cast<std::size_t>(d.station)];
  if (!d.interrupted.empty() && ss.online && !ss.fault) {
    // The station is back and says it holds the run: nothing is left to wait for.
    d.interrupted.clear();
    m.dirty_dispatches.insert(d.id);
    auto& j = m.jobs.at(d.job);
    j.reason.clear();
    m.JobChanged(j);
  }
  if (d.state == DState::kRunning) return;
  d.state = DState::kRunning;
  m.dirty_dispatches.insert(d.id);
  auto& j = m.jobs.at(d.job);
  if (j.started == 0) j.started = m.NowMs();
  j.state = JobState::kRunning;
  m.JobChanged(j);
}
}  // namespace

Effects Scheduler::RunStarted(std::int64_t dispatch_id) {
  Impl& m = *impl_;
  m.Call([&] {
    auto* d = ForReport(m, dispatch_id, "run start");
    if (!d) return;
    MarkRunning(m, *d);
    auto& st = m.stations[static_cast<std::size_t>(d->station)];
    if (d->done < static_cast<int>(d->programs.size()))
      st.program = d->programs[static_cast<std::size_t>(d->done)];
    m.dirty_stations.insert(d->station);
  });
  return m.TakeEffects();
}

Effects Scheduler::ProgramFinished(std::int64_t dispatch_id, int program_index,
                                   std::string_view next_program) {
  Impl& m = *impl_;
  m.Call([&] {
    auto* d = ForReport(m, dispatch_id, "program end");
    if (!d) return;
    if (program_index < 0 || program_index >= static_cast<int>(d->programs.size())) {
      m.fx.notes.push_back(
          fmt::format("program end {} outside dispatch {} ignored", program_index, dispatch_id));
      return;
    }
    MarkRunning(m, *d);
    if (program_index + 1 <= d->done) return;  // duplicate report
    std::int64_t freed = 0;
    for (int i = d->done; i <= program_index; ++i) freed += d->ucy[static_cast<std::size_t>(i)];
    d->done = program_index + 1;
    m.states[static_cast<std::size_t>(d->station)].backlog_s -= freed;
    auto& st = m.stations[static_cast<std::size_t>(d->station)];
    st.program = next_program.empty() && d->done < static_cast<int>(d->programs.size())
                     ? d->programs[static_cast<std::size_t>(d->done)]
                     : std::string(next_program);
    m.dirty_dispatches.insert(d->id);
    m.dirty_stations.insert(d->station);
  });
  return m.TakeEffects();
}

Effects Scheduler::RunFinished(std::int64_t dispatch_id, std::optional<double> cycle_s) {
  Impl& m = *impl_;
  m.Call([&] {
    auto* d = ForReport(m, dispatch_id, "run end");
    if (!d) return;
    MarkRunning(m, *d);
    const int s = d->station;
    m.stations[static_cast<std::size_t>(s)].pending_vars.clear();  // the station had them before this run
    m.Detach(*d, DState::kDone);
    if (cycle_s) m.Learn(*d, *cycle_s);
    auto& j = m.jobs.at(d->job);
    if (cycle_s) j.cycle = j.cycle.value_or(0) + *cycle_s;
    j.dispatch = 0;
    j.reason.clear();  // an interruption the station's report has settled
    ++j.op;
    if (j.kind == "schedule") {
      j.op = 0;
      const auto& run = *j.sched_run;
      m.StepSchedule(j, s, fmt::format("run {} of {} finished", run.index, run.count));
    } else if (j.op < static_cast<int>(j.ops->size())) {
      // The pallet moves on to its next operation.
      j.state = JobState::kQueued;
      j.dispatch = 0;
      m.Evaluate(
          j, fmt::format("operation {} completed on {}", j.op, m.stations[static_cast<std::size_t>(s)].id));
    } else {
      --j.op;  // keep op_index on the last operation
      m.FinishJob(j, JobState::kCompleted, "");
    }
    m.TrySend(s);
  });
  return m.TakeEffects();
}

Effects Scheduler::RunFailed(std::int64_t dispatch_id, std::string_view reason) {
  Impl& m = *impl_;
  m.Call([&] {
    auto* d = ForReport(m, dispatch_id, "run failure");
    if (!d) return;
    const int s = d->station;
    m.stations[static_cast<std::size_t>(s)].pending_vars.clear();  // as at a run's end
    auto& j = m.jobs.at(d->job);
    std::string why =
        d->interrupted.empty()
            ? fmt::format("station {}: {}", m.stations[static_cast<std::size_t>(s)].id, reason)
            : fmt::format("{} while running {} (program {} of {}): {}; the {} needs an operator",
                          d->interrupted, Impl::Holding(*d), d->done + 1, d->programs.size(), reason,
                          d->pallet != 0 ? "pallet" : "part");
    m.Detach(*d, DState::kFailed);
    m.FinishJob(j, JobState::kFailed, std::move(why));
    m.TrySend(s);
  });
  return m.TakeEffects();
}

Effects Scheduler::ReportRun(const RunReport& report) {
  // Each step is its own transaction; every step is idempotent, so a crash between them is repaired by the
  // station's next (or re-delivered) report.
  Effects all;
  const auto add = [&](Effects fx) {
    for (auto& d : fx.dispatches) all.dispatches.push_back(std::move(d));
    for (auto& c : fx.cancels) all.cancels.push_back(std::move(c));
    for (auto& v : fx.variables) all.variables.push_back(std::move(v));
    for (auto& j : fx.job_changes) all.job_changes.push_back(std::move(j));
    for (auto& n : fx.notes) all.notes.push_back(std::move(n));
  };
  const std::int64_t id = report.dispatch_id;
  auto live = [&] {
    auto it = impl_->dispatches.find(id);
    return it != impl_->dispatches.end() && Live(it->second.state) && it->second.state != DState::kQueued;
  };
  if (!live()) {
    add(DispatchAcknowledged(id));  // records the note about the stale report
    return all;
  }
  add(DispatchAcknowledged(id));
  if (report.status == RunStatus::kAccepted) return all;
  if (report.status == RunStatus::kFailed && !report.started && report.programs_done == 0 &&
      !impl_->dispatches.at(id).interrupted.empty()) {
    // The station never started it (cancelled from its queue, or never received): the pallet is free.
    Impl& m = *impl_;
    m.Call([&] { m.GiveBack(m.dispatches.at(id)); });
    add(m.TakeEffects());
    return all;
  }
  if (report.status != RunStatus::kFailed || report.programs_done > 0) add(RunStarted(id));
  const int programs = static_cast<int>(impl_->dispatches.at(id).programs.size());
  const int done = std::min(report.programs_done, programs);
  if (done > 0 && impl_->dispatches.at(id).done < done) add(ProgramFinished(id, done - 1));
  if (report.status == RunStatus::kCompleted) add(RunFinished(id, report.cycle_s));
  if (report.status == RunStatus::kFailed)
    add(RunFailed(id, report.reason.empty() ? "run failed" : report.reason));
  return all;
}

Effects Scheduler::ProgramChanged(std::string_view name) {
  Impl& m = *impl_;
  m.Call([&] {
    const auto uses = [&](const std::vector<Op>& ops) {
      for (const auto& op : ops) {
        if (std::find(op.programs.begin(), op.programs.end(), name) != op.programs.end()) return true;
      }
      return false;
    };
    std::map<const std::vector<Op>*, Ops> replaced;
    for (auto& [rname, r] : m.routes) {
      if (!uses(*r.ops)) continue;
      Ops fresh = m.BuildRouteOps(r.spec, false);
      std::string problem;
      for (const auto& op : *fresh) {
        if (!op.blocked.empty() && problem.empty()) problem = op.blocked;
      }
      r.valid = problem.empty();
      r.invalid_reason = problem;
      replaced[r.ops.get()] = fresh;
      r.ops = fresh;
      m.dirty_routes.insert(rname);
    }
    for (auto& [id, j] : m.jobs) {
      if (j.state != JobState::kQueued && j.state != JobState::kWaiting) continue;
      if (auto it = replaced.find(j.ops.get()); it != replaced.end()) {
        j.ops = it->second;
      } else if (j.kind == "pallet" && uses(*j.ops)) {
        const auto& old = (*j.ops)[0];
        OpSpec spec{{m.stations[static_cast<std::size_t>(old.stations[0])].id}, old.programs};
        auto ops = std::make_shared<std::vector<Op>>();
        ops->push_back(m.BuildOp(spec, false, false, fmt::format("pallet {}", j.pallet)));
        j.ops = ops;
      } else {
        continue;
      }
      m.dirty_jobs.insert(id);
    }
    m.ReevaluateWaiting(-1, fmt::format("program {} changed", name));
  });
  return m.TakeEffects();
}

}  // namespace cell::scheduler
