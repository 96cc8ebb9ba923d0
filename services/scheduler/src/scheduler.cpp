#include "cell/scheduler/scheduler.h"

#include <algorithm>
#include <ctime>
#include <memory>
#include <utility>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cell/error/error.h"
#include "cell/interp/interp.h"
#include "cell/names/names.h"
#include "cell/names/program_ref.h"
#include "cell/records/names.h"
#include "scheduler_impl.h"

namespace cell::scheduler {

using json = nlohmann::json;

cell::JobState WireState(JobState s) {
  switch (s) {
    case JobState::kQueued:
      return cell::JOB_QUEUED;
    case JobState::kWaiting:
      return cell::JOB_WAITING;
    case JobState::kDispatched:
      return cell::JOB_DISPATCHED;
    case JobState::kRunning:
      return cell::JOB_RUNNING;
    case JobState::kCompleted:
      return cell::JOB_COMPLETED;
    case JobState::kFailed:
      return cell::JOB_FAILED;
    case JobState::kCancelled:
      return cell::JOB_CANCELLED;
  }
  return cell::JOB_QUEUED;
}

std::string_view JobStateName(JobState s) {
  return records::JobStateName(WireState(s));
}

std::optional<JobState> JobStateFromName(std::string_view name) {
  for (JobState st : {JobState::kQueued, JobState::kWaiting, JobState::kDispatched, JobState::kRunning,
                      JobState::kCompleted, JobState::kFailed, JobState::kCancelled})
    if (JobStateName(st) == name) return st;
  return std::nullopt;
}

bool IsTerminal(JobState s) {
  return s == JobState::kCompleted || s == JobState::kFailed || s == JobState::kCancelled;
}

namespace {

// 64-bit FNV-1a: a stable digest of a schedule's text for its idempotency fingerprint.
std::uint64_t Fnv1a(std::string_view text) {
  std::uint64_t h = 14695981039346656037ull;
  for (unsigned char c : text) h = (h ^ c) * 1099511628211ull;
  return h;
}

// A schedule job's access to its station's common variables: a VSET write is an effect, pending until the
// station shows it back.
struct StationVars : schedule::Variables {
  StationVars(Scheduler::Impl& m, int s) : m(m), s(s) {}
  double Get(int n) override {
    const auto& v = m.stations[static_cast<std::size_t>(s)].vars;
    auto it = v.find(n);
    return it == v.end() ? 0.0 : it->second;
  }
  void Set(int n, double value) override {
    m.stations[static_cast<std::size_t>(s)].vars[n] = value;
    m.stations[static_cast<std::size_t>(s)].pending_vars[n] = value;
    m.dirty_stations.insert(s);
    m.fx.variables.push_back(VariableAction{m.stations[static_cast<std::size_t>(s)].id, n, value});
  }
  Scheduler::Impl& m;
  int s;
};

}  // namespace

// ---------------------------------------------------------------------------------------------------------
// State
int State::StationIndex(std::string_view id, bool create) {
  auto it = station_ids.find(std::string(id));
  if (it != station_ids.end()) return it->second;
  if (!create) return -1;
  if (id.empty()) throw Error(Errc::kInvalidArgument, "empty station id");
  const int idx = static_cast<int>(stations.size());
  stations.push_back(StationRec{});
  stations.back().id = std::string(id);
  states.emplace_back();
  station_ids.emplace(std::string(id), idx);
  dirty_stations.insert(idx);
  return idx;
}
int State::FindStation(std::string_view id) const {
  auto it = station_ids.find(std::string(id));
  return it == station_ids.end() ? -1 : it->second;
}

std::string State::Describe(const AllocationRec& a) const {
  std::string out = "no eligible station: ";
  out.reserve(32 + a.candidates.size() * 24);
  bool first = true;
  const auto part = [&](const std::string& id, std::string_view what) {
    if (!first) out += "; ";
    first = false;
    out += id;
    out += what;
  };
  for (const auto& c : a.candidates) {
    const StationRec& st = stations[static_cast<std::size_t>(c.station)];
    if (!c.online) {
      part(st.id, " offline");
    } else if (c.fault) {
      part(st.id, " in fault");
      if (!st.alarm_code.empty()) out += " (alarm " + st.alarm_code + ")";
    } else if (c.schedule_job != 0) {
      part(st.id, fmt::format(" runs schedule job {}", c.schedule_job));
    }
    if (c.missing_count != 0) {
      part(st.id, " missing tools ");
      bool first_tool = true;
      a.ForMissing(c, [&](int t) {
        if (!first_tool) out += ',';
        first_tool = false;
        out += tool_index.Name(t);
      });
    }
  }
  return out;
}

bool State::Dirty() const {
  return !dirty_jobs.empty() || !dirty_dispatches.empty() || !dirty_stations.empty() ||
         !dirty_pallets.empty() || !dirty_routes.empty() || !dirty_estimates.empty() ||
         !new_decisions.empty() || !new_idem.empty();
}
void State::ClearDirty() {
  dirty_jobs.clear();
  dirty_dispatches.clear();
  dirty_stations.clear();
  dirty_pallets.clear();
  dirty_routes.clear();
  dirty_estimates.clear();
  new_decisions.clear();
  new_idem.clear();
}

// ---------------------------------------------------------------------------------------------------------
// Decision core
Scheduler::Impl::Impl(Options o, ProgramSource& p) : opt(std::move(o)), programs(p) {
  if (!opt.clock) opt.clock = [] { return std::chrono::system_clock::now(); };
  opt.kept_ended_jobs = std::max<std::size_t>(opt.kept_ended_jobs, 1);
  if (!opt.db_path.empty()) {
    store.emplace(opt.db_path);
    store->Load(*this, opt.kept_ended_jobs);
  }
}

void Scheduler::Impl::CheckPallet(int pallet) const {
  if (pallet < 1 || pallet > kMaxPallet) {
    throw Error(Errc::kInvalidArgument, fmt::format("pallet {} outside 1-{}", pallet, kMaxPallet));
  }
}

const std::vector<int>& Scheduler::Impl::ListedFor(const std::vector<int>& listed, int pallet,
                                                   std::vector<int>& scratch) const {
  constexpr int kCodedMax = 127;
  if (pallet <= kCodedMax) return listed;
  scratch.clear();
  for (int s : listed)
    if (!stations[static_cast<std::size_t>(s)].coded_pallets) scratch.push_back(s);
  return scratch.size() == listed.size() ? listed : scratch;
}

void Scheduler::Impl::CheckPalletOnStations(int pallet, const Ops& ops, std::string_view route) const {
  std::vector<int> scratch;
  for (std::size_t i = 0; i < ops->size(); ++i) {
    const std::vector<int>& listed = (*ops)[i].stations;
    if (listed.empty() || !ListedFor(listed, pallet, scratch).empty()) continue;
    std::string ids;
    for (int s : listed) ids += (ids.empty() ? "" : ", ") + stations[static_cast<std::size_t>(s)].id;
    throw Error(
        Errc::kInvalidArgument,
        fmt::format("pallet {} cannot go to {} (operation {} of {}): a coded-pallet module takes pallets "
                    "1-127 only",
                    pallet, ids, i + 1, route));
  }
}

// ---- building operations from specs ----
// A station runs programs of its own controller language only: the dialect the program store recorded
// for the program against each listed station's (its station file's, or what it announced). A station
// whose dialect is not known yet (neither configured nor seen) is not judged. "" when all agree.
std::string Scheduler::Impl::DialectClash(const ProgramMeta& meta,
                                          const std::vector<std::string>& station_ids) const {
  const interp::Dialect* pd = interp::FindDialect(meta.dialect);
  for (const auto& id : station_ids) {
    const int s = FindStation(id);
    if (s < 0) continue;
    const interp::Dialect* sd = interp::FindDialect(stations[static_cast<std::size_t>(s)].dialect);
    if (pd == nullptr || sd == nullptr || pd == sd) continue;
    return fmt::format(
        "program '{}' is {} ({}) but station {} runs {} ({}); a station runs programs of its "
        "own dialect only",
        meta.name, pd->name(), pd->title(), id, sd->name(), sd->title());
  }
  return {};
}

// "NODE:NAME" is read from NODE alone, and a station's namespace (its memories) by that station only. A plain
// NAME is read as the station reads it: its heading from HOST when HOST holds it, else each listed station
// must hold it in its own namespace (a Balt-System program in the control's memory MP1).
std::optional<ProgramMeta> Scheduler::Impl::LookupFor(const std::string& entry,
                                                      const std::vector<std::string>& station_ids,
                                                      std::string* refused) {
  const names::ProgramRef ref = names::SplitProgramRef(entry);
  if (!ref.node.empty()) {
    const std::string owner = names::NodeStation(ref.node);
    for (const auto& id : station_ids) {
      if (owner.empty() || id == owner) continue;
      *refused =
          fmt::format("program '{}' is in {}'s memory: only {} runs it, not {}", entry, owner, owner, id);
      return std::nullopt;
    }
    return programs.Lookup(entry);
  }
  if (auto host = programs.Lookup(entry)) return host;
  std::optional<ProgramMeta> found;
  for (const auto& id : station_ids) {
    auto own = programs.Lookup(id + ":" + entry);
    if (!own) return std::nullopt;
    own->name = entry;
    if (!found) found = std::move(own);
  }
  return found;
}

bool Scheduler::Impl::ProgramExists(const std::string& entry) {
  if (programs.Lookup(entry)) return true;
  if (!names::SplitProgramRef(entry).node.empty()) return false;
  for (const auto& st : stations)
    if (programs.Lookup(st.id + ":" + entry)) return true;
  return false;
}

Op Scheduler::Impl::BuildOp(const OpSpec& spec, bool require_ucy, bool strict, std::string_view where) {
  if (spec.stations.empty()) throw Error(Errc::kInvalidArgument, fmt::format("{}: no station listed", where));
  if (spec.programs.empty() || spec.programs.size() > 75) {
    throw Error(Errc::kInvalidArgument,
                fmt::format("{}: 1-75 programs expected, got {}", where, spec.programs.size()));
  }
  Op op;
  op.programs = spec.programs;
  std::vector<std::string> models;  // part models named among the programs
  for (const auto& name : spec.programs) {
    std::optional<ProgramMeta> meta;
    std::string problem;
    try {
      std::string refused;
      meta = LookupFor(name, spec.stations, &refused);
      if (!refused.empty()) {
        problem = std::move(refused);
        if (strict) throw Error(Errc::kFailedPrecondition, fmt::format("{}: {}", where, problem));
      } else if (meta && meta->part_model) {
        models.push_back(name);
        op.ucy.push_back(0);
        op.revisions.emplace_back();
        op.stated.push_back(1);
        continue;
      } else if (!meta) {
        problem = fmt::format("program '{}' not found", name);
        if (strict) throw Error(Errc::kNotFound, fmt::format("{}: {}", where, problem));
      } else if (std::string clash = DialectClash(*meta, spec.stations); !clash.empty()) {
        problem = std::move(clash);
        if (strict) throw Error(Errc::kFailedPrecondition, fmt::format("{}: {}", where, problem));
      } else if (require_ucy && !meta->ucy_s && (meta->dialect.empty() || meta->dialect == "ktapl")) {
        // UCY is the KT/FMS heading (DESIGN §5); the other dialects' programs have none, and their
        // operations add nothing to the backlog.
        problem = fmt::format(
            "program '{}' has no (UCY,seconds): UCY is required in every KT/FMS part program (KT-APL "
            "manual, "
            "UCY statement)",
            name);
        if (strict) throw Error(Errc::kFailedPrecondition, fmt::format("{}: {}", where, problem));
      }
    } catch (const Error& e) {
      if (strict) throw;
      problem = e.what();
    }
    if (!problem.empty()) {
      if (op.blocked.empty()) op.blocked = fmt::format("{}: {}", where, problem);
      op.ucy.push_back(0);
      op.revisions.emplace_back();
      op.stated.push_back(1);
      continue;
    }
    const std::int64_t u = meta->ucy_s.value_or(0);
    op.ucy.push_back(u);
    op.revisions.push_back(meta->revision);
    op.stated.push_back(meta->ucy_s ? 1 : 0);
    op.ucy_sum += u;
    for (const auto& t : meta->tools) {
      if (std::find(op.tools.begin(), op.tools.end(), t) == op.tools.end()) op.tools.push_back(t);
    }
  }
  // The map's part model is the workpiece of its programs: one at most, and something must run on it.
  if (models.size() > 1)
    throw Error(Errc::kInvalidArgument, fmt::format("{}: names {} part models ({}, {}); a pallet holds one",
                                                    where, models.size(), models[0], models[1]));
  if (!models.empty() && models.size() == spec.programs.size())
    throw Error(Errc::kInvalidArgument,
                fmt::format("{}: names only the part model {}, no program to run", where, models[0]));
  // Stations are registered only once the programs qualify, so a refused route leaves no trace.
  for (auto it = spec.stations.begin(); it != spec.stations.end(); ++it) {
    if (it->empty()) throw Error(Errc::kInvalidArgument, fmt::format("{}: empty station id", where));
    if (std::find(spec.stations.begin(), it, *it) != it) {
      throw Error(Errc::kInvalidArgument, fmt::format("{}: station {} listed twice", where, *it));
    }
  }
  for (const auto& s : spec.stations) op.stations.push_back(StationIndex(s, true));
  for (const auto& t : op.tools) op.tool_ids.push_back(tool_index.Intern(t));
  AskEstimates(op);  // predicted while the route waits for pallets, not at the first allocation
  return op;
}

Ops Scheduler::Impl::BuildRouteOps(const RouteSpec& spec, bool strict) {
  auto ops = std::make_shared<std::vector<Op>>();
  for (std::size_t i = 0; i < spec.ops.size(); ++i) {
    ops->push_back(BuildOp(spec.ops[i], true, strict, fmt::format("route {} op {}", spec.name, i + 1)));
  }
  return ops;
}

void Scheduler::Impl::JobChanged(JobRec& j) {
  dirty_jobs.insert(j.id);
  fx.job_changes.push_back(JobChange{j.id, j.state, j.reason});
}

DecisionRec& Scheduler::Impl::AddDecision(JobRec& j, std::string trigger) {
  DecisionRec& d = j.decisions.emplace_back();
  d.seq = next_seq++;
  d.time_ms = NowMs();
  d.op = j.op;
  d.trigger = std::move(trigger);
  new_decisions.emplace_back(j.id, j.decisions.size() - 1);
  return d;
}

void Scheduler::Impl::SetWaiting(JobRec& j, std::string reason, std::string_view trigger,
                                 const AllocationRec* alloc) {
  if (j.state == JobState::kWaiting && j.reason == reason) return;  // nothing new to log
  DecisionRec& d = AddDecision(j, std::string(trigger));
  if (alloc) {
    d.alloc = *alloc;  // the reason is rendered again from the candidates when the log is read
  } else {
    d.why = reason;
  }
  j.state = JobState::kWaiting;
  j.reason = std::move(reason);
  j.station = -1;
  waiting.insert(j.id);
  JobChanged(j);
}

void Scheduler::Impl::Evaluate(JobRec& j, std::string_view trigger) {
  const Op& op = (*j.ops)[static_cast<std::size_t>(j.op)];
  if (!op.blocked.empty()) {
    SetWaiting(j, op.blocked, trigger, nullptr);
    return;
  }
  AllocationRec alloc;
  alloc.candidates.reserve(op.stations.size());
  alloc.missing.reserve(op.stations.size() * 2);
  std::vector<int> scratch;
  Allocate(ListedFor(op.stations, j.pallet, scratch), op.tool_ids, states, alloc, j.id);
  if (alloc.winner < 0) {
    SetWaiting(j, Describe(alloc), trigger, &alloc);
    return;
  }
  const int w = alloc.winner;
  DecisionRec& d = AddDecision(j, std::string(trigger));
  const std::int64_t backlog = states[static_cast<std::size_t>(w)].backlog_s;
  if (alloc.tied > 1) {
    d.why = fmt::format("tie at backlog {} s between {} stations: {} is listed first", backlog, alloc.tied,
                        stations[static_cast<std::size_t>(w)].id);
  } else {
    d.why = fmt::format("shortest backlog among eligible stations: {} s", backlog);
  }
  std::optional<double> predicted;
  std::vector<std::int64_t> secs = BacklogFor(op, w, predicted);
  std::int64_t added = 0;
  for (auto u : secs) added += u;
  d.added = added;
  d.alloc = std::move(alloc);
  if (predicted) {
    j.predicted[j.op] = *predicted;
  } else {
    j.predicted.erase(j.op);
  }

  DispatchRec disp;
  disp.id = next_dispatch++;
  disp.job = j.id;
  disp.station = w;
  disp.pallet = j.pallet;
  disp.op = j.op;
  disp.programs = op.programs;
  disp.ucy = std::move(secs);
  dirty_dispatches.insert(disp.id);
  states[static_cast<std::size_t>(w)].backlog_s += added;
  stations[static_cast<std::size_t>(w)].queue.push_back(disp.id);
  dirty_stations.insert(w);
  dispatches.emplace(disp.id, std::move(disp));

  waiting.erase(j.id);
  j.state = JobState::kDispatched;
  j.station = w;
  j.reason.clear();
  j.dispatch = next_dispatch - 1;
  JobChanged(j);
  TrySend(w);
}

void Scheduler::Impl::TrySend(int s) {
  StationRec& st = stations[static_cast<std::size_t>(s)];
  const StationState& ss = states[static_cast<std::size_t>(s)];
  if (!ss.online || ss.fault || st.inflight != 0 || st.queue.empty()) return;
  DispatchRec& d = dispatches.at(st.queue.front());
  st.queue.pop_front();
  st.inflight = d.id;
  d.state = DState::kSent;
  d.heard_ms = NowMs();
  dirty_dispatches.insert(d.id);
  dirty_stations.insert(s);
  fx.dispatches.push_back(Action(d, false));
}

DispatchAction Scheduler::Impl::Action(const DispatchRec& d, bool resent) const {
  DispatchAction a{d.id,     stations[static_cast<std::size_t>(d.station)].id,
                   d.pallet, d.programs,
                   d.job,    d.op,
                   resent,   std::nullopt};
  const JobRec& j = jobs.at(d.job);
  if (j.kind == "schedule") a.schedule_run = j.sched_run;
  return a;
}

void Scheduler::Impl::StepSchedule(JobRec& j, int station, std::string_view trigger) {
  // One schedule at a time on a station: a second one waits, not stepped (its first VSET would write the
  // counters the running one loops on), until the first ends (ReleaseSchedule).
  StationState& ss = states[static_cast<std::size_t>(station)];
  if (ss.schedule_job != 0 && ss.schedule_job != j.id) {
    SetWaiting(j,
               fmt::format("{} runs schedule job {}: this schedule starts when that one ends",
                           stations[static_cast<std::size_t>(station)].id, ss.schedule_job),
               trigger, nullptr);
    return;
  }
  ss.schedule_job = j.id;
  StationVars vars(*this, station);
  schedule::Runner runner(j.sched, j.sched_pos);
  const schedule::Step step = runner.Next(vars);
  j.sched_pos = runner.position();
  dirty_jobs.insert(j.id);
  switch (step.kind) {
    case schedule::Step::Kind::kRun: {
      j.sched_run = step.run;
      std::string file = step.run.main_file.substr(step.run.main_file.find(':') + 1);
      auto ops = std::make_shared<std::vector<Op>>(1);
      Op& op = (*ops)[0];
      op.stations = {station};
      op.programs = {file};
      op.ucy = {0};
      j.ops = ops;
      j.op = 0;
      j.state = JobState::kQueued;
      Evaluate(j, fmt::format("{}: PSELECT run {} of {} (line {})", trigger, step.run.index, step.run.count,
                              step.run.line));
      break;
    }
    case schedule::Step::Kind::kEnd:
      j.sched_run.reset();
      FinishJob(j, JobState::kCompleted, "");
      break;
    case schedule::Step::Kind::kAlarm:
      j.sched_run.reset();
      FinishJob(j, JobState::kFailed, step.alarm);
      break;
  }
}

void Scheduler::Impl::Detach(DispatchRec& d, DState end) {
  StationRec& st = stations[static_cast<std::size_t>(d.station)];
  if (st.inflight == d.id) {
    st.inflight = 0;
    st.program.clear();
  }
  st.queue.erase(std::remove(st.queue.begin(), st.queue.end(), d.id), st.queue.end());
  states[static_cast<std::size_t>(d.station)].backlog_s -= d.Remaining();
  // A finished visit has run every program; otherwise `done` keeps the count of programs that really ended.
  if (end == DState::kDone) d.done = static_cast<int>(d.ucy.size());
  d.state = end;
  dirty_dispatches.insert(d.id);
  dirty_stations.insert(d.station);
}

void Scheduler::Impl::FinishJob(JobRec& j, JobState state, std::string reason) {
  j.state = state;
  j.reason = std::move(reason);
  j.finished = NowMs();
  j.dispatch = 0;
  waiting.erase(j.id);
  if (j.pallet != 0) busy_pallets.erase(j.pallet);
  JobChanged(j);
  if (j.kind == "schedule") ReleaseSchedule(j);
}

void Scheduler::Impl::ReleaseSchedule(const JobRec& j) {
  if (j.sched_station < 0) return;
  const int s = j.sched_station;
  StationState& ss = states[static_cast<std::size_t>(s)];
  if (ss.schedule_job != j.id) return;
  ss.schedule_job = 0;
  const std::string trigger =
      fmt::format("schedule job {} ended on {}", j.id, stations[static_cast<std::size_t>(s)].id);
  // The oldest schedule waiting for this station starts; then the pallets held off it are evaluated again
  // (they wait on, for that schedule, or go).
  for (std::int64_t id : waiting) {
    JobRec& next = jobs.at(id);
    if (next.kind == "schedule" && next.ops->empty() && next.sched_station == s) {
      waiting.erase(id);
      next.state = JobState::kQueued;
      StepSchedule(next, s, trigger);
      break;
    }
  }
  ReevaluateWaiting(s, trigger);
}

void Scheduler::Impl::ReevaluateWaiting(int station, std::string_view trigger) {
  const std::vector<std::int64_t> ids(waiting.begin(), waiting.end());
  for (std::int64_t id : ids) {
    JobRec& j = jobs.at(id);
    if (j.state != JobState::kWaiting) continue;
    if (j.ops->empty()) continue;  // a schedule not started: it starts when its station's schedule ends
    const Op& op = (*j.ops)[static_cast<std::size_t>(j.op)];
    if (station >= 0 && std::find(op.stations.begin(), op.stations.end(), station) == op.stations.end()) {
      continue;
    }
    Evaluate(j, trigger);
  }
}

// Health policy (Interrupt): a station that vanished or faulted gives up the pallets allocated to it and not
// yet handed out.
void Scheduler::Impl::Interrupt(int s, const std::string& why, bool cancel) {
  StationRec& st = stations[static_cast<std::size_t>(s)];
  std::vector<std::int64_t> requeue;
  if (st.inflight != 0) {
    // Handed out: only the station knows whether it never received the dispatch, has it queued, is running
    // it or has finished it (its queue and runs are durable). The pallet stays with it until the station's
    // own report settles the dispatch (ReportRun): giving it away ran an operation twice, and failing it at
    // once called finished pallets failed (both found by the chaos test; docs/scheduler.md §5).
    DispatchRec& d = dispatches.at(st.inflight);
    JobRec& j = jobs.at(d.job);
    if (cancel) fx.cancels.push_back(CancelAction{d.id, st.id, j.id});
    if (d.interrupted.empty()) {
      d.interrupted = why;
      dirty_dispatches.insert(d.id);
      j.reason = fmt::format("{} holding {}: waiting for its report on dispatch {} (job cancel releases it)",
                             why, Holding(d), d.id);
      JobChanged(j);
    }
  }
  while (!st.queue.empty()) {
    DispatchRec& d = dispatches.at(st.queue.front());
    Detach(d, DState::kRevoked);
    requeue.push_back(d.job);
  }
  std::sort(requeue.begin(), requeue.end());
  for (std::int64_t id : requeue) {
    JobRec& j = jobs.at(id);
    j.state = JobState::kQueued;
    j.dispatch = 0;
    j.station = -1;
    Evaluate(j, fmt::format("re-queued: {}", why));
  }
}

std::string Scheduler::Impl::Holding(const DispatchRec& d) {
  return d.pallet != 0 ? fmt::format("pallet {}", d.pallet) : d.programs.at(0);
}

void Scheduler::Impl::AskAgain(int s) {
  const StationRec& st = stations[static_cast<std::size_t>(s)];
  if (st.inflight == 0 || states[static_cast<std::size_t>(s)].fault) return;
  DispatchRec& d = dispatches.at(st.inflight);
  if (d.interrupted.empty()) return;
  d.heard_ms = NowMs();
  fx.dispatches.push_back(Action(d, true));
}

void Scheduler::Impl::GiveBack(DispatchRec& d) {
  const int s = d.station;
  JobRec& j = jobs.at(d.job);
  const std::string why = d.interrupted;
  Detach(d, DState::kRevoked);
  j.state = JobState::kQueued;
  j.dispatch = 0;
  j.station = -1;
  j.reason.clear();
  Evaluate(j, fmt::format("re-queued: {} before starting it", why));
  TrySend(s);
}

// ---- idempotency ----
// A key binds the whole command (`command`, a canonical JSON text of the verb and every argument): the same
// command again returns the first outcome; another command under a used key is refused, never taken for a
// replay (docs/scheduler.md §8).
std::optional<std::int64_t> Scheduler::Impl::Seen(std::string_view key, const std::string& command) {
  if (key.empty()) return std::nullopt;
  auto it = idem.find(std::string(key));
  if (it == idem.end() && store) {  // memory keeps the newest keys; the database has every one
    if (auto k = store->Idempotency(std::string(key))) {
      it = idem.emplace(std::string(key), std::move(*k)).first;
      idem_order.emplace_back(key);
    }
  }
  if (it == idem.end()) return std::nullopt;
  if (!it->second.command.empty() && it->second.command != command) {
    throw Error(
        Errc::kFailedPrecondition,
        fmt::format("idempotency key {} was already used for another command ({}); refusing {}",
                    names::Shown(key, 64), names::Fit(it->second.command, 150), names::Fit(command, 150)));
  }
  return it->second.result;
}
void Scheduler::Impl::Remember(std::string_view key, const std::string& command, std::int64_t result) {
  if (key.empty()) return;
  if (idem.emplace(std::string(key), Keyed{result, command}).second) idem_order.emplace_back(key);
  new_idem.emplace_back(std::string(key), Keyed{result, command});
}

void Scheduler::Impl::Reload() {
  fx = Effects{};
  ClearDirty();
  if (!store) return;  // in-memory only: nothing to go back to; state stays as it is
  static_cast<State&>(*this) = State{};
  store->Load(*this, opt.kept_ended_jobs);
}

void Scheduler::Impl::Flush() {
  if (!store) return ClearDirty();
  store->Flush(*this);
  ClearDirty();
  Trim();
}

// Once half `kept_ended_jobs` more jobs are held, the ended jobs past the newest `kept_ended_jobs` go, with
// their ended dispatches and the oldest idempotency keys: all of it is in the database, which the views read
// back (a sweep per kept_ended_jobs / 2 new jobs, so its cost is spread over them).
void Scheduler::Impl::Trim() {
  if (jobs.size() < trim_at) return;
  std::vector<std::int64_t> gone;
  std::size_t ended = 0;
  for (auto it = jobs.rbegin(); it != jobs.rend(); ++it)
    if (IsTerminal(it->second.state) && ++ended > opt.kept_ended_jobs) gone.push_back(it->first);
  for (std::int64_t id : gone) jobs.erase(id);
  if (!gone.empty()) {
    for (auto it = dispatches.begin(); it != dispatches.end();) {
      const bool keep = Live(it->second.state) || jobs.count(it->second.job);
      it = keep ? std::next(it) : dispatches.erase(it);
    }
  }
  while (idem_order.size() > 2 * opt.kept_ended_jobs) {
    idem.erase(idem_order.front());
    idem_order.pop_front();
  }
  trim_at = jobs.size() + std::max<std::size_t>(opt.kept_ended_jobs / 2, 1);
}

// ---------------------------------------------------------------------------------------------------------
// Public API
Scheduler::Scheduler(Options options, ProgramSource& programs)
    : impl_(std::make_unique<Impl>(std::move(options), programs)) {}
Scheduler::~Scheduler() = default;

Effects Scheduler::Recover() {
  Impl& m = *impl_;
  m.Call([&] {
    // VSET writes not shown back yet go out again, ahead of the dispatches (Effects order): setting a value
    // twice is harmless, losing it would run a schedule's loop once more.
    for (const auto& st : m.stations)
      for (const auto& [n, v] : st.pending_vars) m.fx.variables.push_back(VariableAction{st.id, n, v});
    for (std::size_t s = 0; s < m.stations.size(); ++s) {
      const auto& st = m.stations[s];
      if (st.inflight == 0) continue;
      const auto& d = m.dispatches.at(st.inflight);
      if (d.state == DState::kSent) {
        m.fx.dispatches.push_back(m.Action(d, true));
      } else {
        m.AskAgain(static_cast<int>(s));  // a dispatch awaiting its station's word: ask for it
      }
    }
    for (std::size_t s = 0; s < m.stations.size(); ++s) m.TrySend(static_cast<int>(s));
    // What the routes' programs lack (a new station model, a prediction the last process did not finish).
    for (const auto& [name, r] : m.routes)
      for (const Op& op : *r.ops) m.AskEstimates(op);
  });
  return m.TakeEffects();
}

void Scheduler::ConfigureStation(std::string_view id, std::string_view dialect, bool coded_pallets) {
  ConfigureStations({StationSetup{std::string(id), std::string(dialect), coded_pallets}});
}

void Scheduler::ConfigureStations(const std::vector<StationSetup>& stations) {
  Impl& m = *impl_;
  m.Call([&] {
    for (const auto& c : stations) {
      const int s = m.StationIndex(c.id, true);
      m.stations[static_cast<std::size_t>(s)].coded_pallets = c.coded_pallets;
      if (!c.dialect.empty() && m.stations[static_cast<std::size_t>(s)].dialect != c.dialect) {
        m.stations[static_cast<std::size_t>(s)].dialect = c.dialect;
        m.dirty_stations.insert(s);
      }
    }
  });
}

void Scheduler::SetPalletMap(std::string_view key, int pallet, const std::vector<std::string>& programs) {
  Impl& m = *impl_;
  const std::string command = json{{"verb", "pallet-set"}, {"pallet", pallet}, {"programs", programs}}.dump();
  m.Call([&] {
    if (m.Seen(key, command)) return;
    m.CheckPallet(pallet);
    // KT-APL seed line 842: "A Pallet Map consists of from 1 to 75 standard part programs".
    if (programs.empty() || programs.size() > 75) {
      throw Error(Errc::kInvalidArgument, fmt::format("pallet {}: a pallet map holds 1-75 programs, got {}",
                                                      pallet, programs.size()));
    }
    // A map naming a program the store does not hold is refused here, not at `pallet run` (issue 39 item 5).
    for (const auto& p : programs) {
      names::CheckProgramRef(p);
      if (!m.ProgramExists(p)) {
        throw Error(Errc::kNotFound, fmt::format("pallet {}: program {} not found", pallet, names::Shown(p)));
      }
    }
    m.pallet_maps[pallet] = programs;
    m.dirty_pallets.insert(pallet);
    m.Remember(key, command, pallet);
  });
}

RouteView Scheduler::DefineRoute(std::string_view key, const RouteSpec& spec) {
  Impl& m = *impl_;
  const std::string command = json{{"verb", "route-define"}, {"route", SpecToJson(spec)}}.dump();
  return m.Call([&] {
    if (!m.Seen(key, command)) {
      names::CheckRoute(spec.name);
      if (spec.ops.empty()) throw Error(Errc::kInvalidArgument, "route " + spec.name + " has no operation");
      RouteRec r;
      r.spec = spec;
      r.ops = m.BuildRouteOps(spec, true);
      m.routes[spec.name] = std::move(r);
      m.dirty_routes.insert(spec.name);
      m.Remember(key, command, 0);
    }
    auto it = m.routes.find(spec.name);
    if (it == m.routes.end()) throw Error(Errc::kNotFound, "route " + spec.name + " not defined");
    return m.ViewRoute(it->first, it->second);
  });
}

JobResult Scheduler::Operate(std::string_view key, std::string_view route, int pallet) {
  Impl& m = *impl_;
  JobResult res;
  const std::string command = json{{"verb", "route-operate"}, {"route", route}, {"pallet", pallet}}.dump();
  res.job_id = m.Call([&]() -> std::int64_t {
    if (auto seen = m.Seen(key, command)) {
      res.replayed = true;
      return *seen;
    }
    m.CheckPallet(pallet);
    auto it = m.routes.find(route);
    if (it == m.routes.end())
      throw Error(Errc::kNotFound, fmt::format("route {} not defined", names::Shown(route)));
    if (!it->second.valid) {
      throw Error(Errc::kFailedPrecondition,
                  fmt::format("route {} is invalid: {}", route, it->second.invalid_reason));
    }
    if (auto busy = m.busy_pallets.find(pallet); busy != m.busy_pallets.end()) {
      throw Error(Errc::kFailedPrecondition,
                  fmt::format("pallet {} is already in job {}", pallet, busy->second));
    }
    m.CheckPalletOnStations(pallet, it->second.ops, fmt::format("route {}", names::Shown(route)));
    JobRec j;
    j.id = m.next_job++;
    j.kind = "route";
    j.route = std::string(route);
    j.pallet = pallet;
    j.ops = it->second.ops;
    auto& ref = m.jobs.emplace(j.id, std::move(j)).first->second;
    m.busy_pallets[pallet] = ref.id;
    m.JobChanged(ref);
    m.Evaluate(ref, "operate");
    m.Remember(key, command, ref.id);
    return ref.id;
  });
  res.effects = m.TakeEffects();
  return res;
}

JobResult Scheduler::RunPallet(std::string_view key, int pallet, std::string_view station) {
  Impl& m = *impl_;
  JobResult res;
  const std::string command = json{{"verb", "pallet-run"}, {"pallet", pallet}, {"station", station}}.dump();
  res.job_id = m.Call([&]() -> std::int64_t {
    if (auto seen = m.Seen(key, command)) {
      res.replayed = true;
      return *seen;
    }
    m.CheckPallet(pallet);
    auto map = m.pallet_maps.find(pallet);
    if (map == m.pallet_maps.end())
      throw Error(Errc::kNotFound, fmt::format("pallet {} has no pallet map", pallet));
    if (m.FindStation(station) < 0) throw Error(Errc::kNotFound, fmt::format("unknown station {}", station));
    if (auto busy = m.busy_pallets.find(pallet); busy != m.busy_pallets.end()) {
      throw Error(Errc::kFailedPrecondition,
                  fmt::format("pallet {} is already in job {}", pallet, busy->second));
    }
    OpSpec spec{{std::string(station)}, map->second};
    auto ops = std::make_shared<std::vector<Op>>();
    // A direct run is the operator's non-FMS use: UCY is optional (0 s of backlog when absent).
    ops->push_back(m.BuildOp(spec, false, true, fmt::format("pallet {}", pallet)));
    m.CheckPalletOnStations(pallet, ops, "the pallet run");
    JobRec j;
    j.id = m.next_job++;
    j.kind = "pallet";
    j.pallet = pallet;
    j.ops = ops;
    auto& ref = m.jobs.emplace(j.id, std::move(j)).first->second;
    m.busy_pallets[pallet] = ref.id;
    m.JobChanged(ref);
    m.Evaluate(ref, fmt::format("pallet run on {}", station));
    m.Remember(key, command, ref.id);
    return ref.id;
  });
  res.effects = m.TakeEffects();
  return res;
}

JobResult Scheduler::RunSchedule(std::string_view key, std::string_view name, std::string_view text,
                                 std::string_view station) {
  Impl& m = *impl_;
  JobResult res;
  // The schedule's text by length and hash: the command it names, without 64 KiB in every key row.
  const std::string command = json{{"verb", "schedule-run"},
                                   {"schedule", name},
                                   {"station", station},
                                   {"text", fmt::format("{} bytes, fnv1a {:016x}", text.size(), Fnv1a(text))}}
                                  .dump();
  res.job_id = m.Call([&]() -> std::int64_t {
    if (auto seen = m.Seen(key, command)) {
      res.replayed = true;
      return *seen;
    }
    const int s = m.FindStation(station);
    if (s < 0) throw Error(Errc::kNotFound, fmt::format("unknown station {}", station));
    auto program = std::make_shared<schedule::Program>(schedule::Parse(text, name));
    JobRec j;
    j.id = m.next_job++;
    j.kind = "schedule";
    j.sched_station = s;
    j.sched_name = std::string(name);
    j.sched_text = std::string(text);
    j.sched = program;
    j.ops = std::make_shared<std::vector<Op>>();
    auto& ref = m.jobs.emplace(j.id, std::move(j)).first->second;
    m.JobChanged(ref);
    m.StepSchedule(ref, s, fmt::format("schedule {} on {}", name, station));
    m.Remember(key, command, ref.id);
    return ref.id;
  });
  res.effects = m.TakeEffects();
  return res;
}

Effects Scheduler::Cancel(std::string_view key, std::int64_t job_id, std::string_view reason) {
  Impl& m = *impl_;
  const std::string command = json{{"verb", "job-cancel"}, {"job", job_id}}.dump();
  m.Call([&] {
    if (m.Seen(key, command)) return;
    auto already = [&](JobState s) {
      return Error(Errc::kFailedPrecondition, fmt::format("job {} is already {}", job_id, JobStateName(s)));
    };
    auto it = m.jobs.find(job_id);
    if (it == m.jobs.end()) {
      // Only ended jobs leave memory: one the database still has is already over.
      const auto stored = m.store ? m.store->Job(job_id, false) : std::nullopt;
      if (!stored) throw Error(Errc::kNotFound, fmt::format("no job {}", job_id));
      throw already(stored->state);
    }
    JobRec& j = it->second;
    if (IsTerminal(j.state)) throw already(j.state);
    int freed = -1;
    if (j.dispatch != 0) {
      DispatchRec& d = m.dispatches.at(j.dispatch);
      if (Live(d.state)) {
        const bool handed_out = d.state != DState::kQueued;
        freed = handed_out ? d.station : -1;
        m.Detach(d, DState::kRevoked);
        if (handed_out) {
          m.fx.cancels.push_back(
              CancelAction{d.id, m.stations[static_cast<std::size_t>(d.station)].id, j.id});
        }
      }
    }
    m.FinishJob(j, JobState::kCancelled, std::string(reason));
    m.Remember(key, command, job_id);
    if (freed >= 0) m.TrySend(freed);
  });
  return m.TakeEffects();
}

}  // namespace cell::scheduler
