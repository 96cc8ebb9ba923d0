#include "cell/scheduler/scheduler.h"

#include <algorithm>
#include <ctime>
#include <deque>
#include <map>
#include <set>
#include <unordered_map>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cell/error/error.h"
#include "cell/interp/interp.h"
#include "cell/names/names.h"
#include "cell/scheduler/allocator.h"
#include "cell/store/sqlite.h"

namespace cell::scheduler {

using json = nlohmann::json;

std::string_view JobStateName(JobState s) {
  switch (s) {
    case JobState::kQueued:
      return "QUEUED";
    case JobState::kWaiting:
      return "WAITING";
    case JobState::kDispatched:
      return "DISPATCHED";
    case JobState::kRunning:
      return "RUNNING";
    case JobState::kCompleted:
      return "COMPLETED";
    case JobState::kFailed:
      return "FAILED";
    case JobState::kCancelled:
      return "CANCELLED";
  }
  return "?";
}

bool IsTerminal(JobState s) {
  return s == JobState::kCompleted || s == JobState::kFailed || s == JobState::kCancelled;
}

std::string IsoTime(std::int64_t ms) {
  if (ms == 0) return "";
  const std::time_t t = static_cast<std::time_t>(ms / 1000);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

namespace {

// 64-bit FNV-1a: a stable digest of a schedule's text for its idempotency fingerprint.
std::uint64_t Fnv1a(std::string_view text) {
  std::uint64_t h = 14695981039346656037ull;
  for (unsigned char c : text) h = (h ^ c) * 1099511628211ull;
  return h;
}

JobState ParseJobState(std::string_view s) {
  for (JobState st : {JobState::kQueued, JobState::kWaiting, JobState::kDispatched, JobState::kRunning,
                      JobState::kCompleted, JobState::kFailed, JobState::kCancelled}) {
    if (JobStateName(st) == s) return st;
  }
  throw Error(Errc::kInternal, "scheduler database: unknown job state '" + std::string(s) + "'");
}

// A dispatch's life: allocated to a station's queue, handed out, accepted, running, then one of the ends.
enum class DState { kQueued, kSent, kAcked, kRunning, kDone, kFailed, kRevoked };
constexpr const char* kDStateNames[] = {"queued", "sent", "acked", "running", "done", "failed", "revoked"};
DState ParseDState(std::string_view s) {
  for (int i = 0; i < 7; ++i) {
    if (s == kDStateNames[i]) return static_cast<DState>(i);
  }
  throw Error(Errc::kInternal, "scheduler database: unknown dispatch state '" + std::string(s) + "'");
}
bool Live(DState s) {
  return s == DState::kQueued || s == DState::kSent || s == DState::kAcked || s == DState::kRunning;
}

}  // namespace

// ---------------------------------------------------------------------------------------------------------
struct Scheduler::Impl {
  struct Op {
    std::vector<int> stations;
    std::vector<std::string> programs;
    std::vector<std::int64_t> ucy;
    std::vector<std::string> tools;
    std::vector<int> tool_ids;
    std::int64_t ucy_sum = 0;
    std::string blocked;  // non-empty: a program no longer qualifies; the pallet waits
  };
  using Ops = std::shared_ptr<const std::vector<Op>>;

  struct RouteRec {
    RouteSpec spec;
    Ops ops;
    bool valid = true;
    std::string invalid_reason;
  };

  struct DecisionRec {
    std::int64_t seq = 0;
    std::int64_t time_ms = 0;
    int op = 0;
    std::string trigger;
    AllocationRec alloc;
    std::string why;
    std::int64_t added = 0;
  };

  struct JobRec {
    std::int64_t id = 0;
    std::string kind;  // "route" | "pallet"
    std::string route;
    int pallet = 0;
    Ops ops;
    int op = 0;
    JobState state = JobState::kQueued;
    int station = -1;
    std::string reason;
    std::int64_t started = 0, finished = 0;
    std::optional<double> cycle;
    std::int64_t dispatch = 0;  // live dispatch id, 0 = none
    std::vector<DecisionRec> decisions;
    // Schedule jobs: the program, where its runner stands, and the run in progress.
    std::string sched_name, sched_text;
    std::shared_ptr<const schedule::Program> sched;
    schedule::RunnerPosition sched_pos;
    std::optional<schedule::Run> sched_run;
  };

  struct DispatchRec {
    std::int64_t id = 0, job = 0;
    int station = 0;
    int pallet = 0;
    int op = 0;
    std::vector<std::string> programs;
    std::vector<std::int64_t> ucy;
    int done = 0;  // programs finished
    DState state = DState::kQueued;
    std::int64_t Remaining() const {
      std::int64_t r = 0;
      for (std::size_t i = static_cast<std::size_t>(done); i < ucy.size(); ++i) r += ucy[i];
      return r;
    }
  };

  struct StationRec {
    std::string id, dialect;
    std::string alarm_code, alarm_text;
    tooltable::ToolTable tools;
    std::deque<std::int64_t> queue;  // allocated, not yet handed out
    std::int64_t inflight = 0;       // handed out (sent/acked/running)
    std::string program;
    std::map<int, double> vars;  // common variables V1-V200 (published by the station, plus VSET writes)
    // VSET writes the station has not shown back yet. They survive a restart and are sent again by Recover()
    // (a kill -9 between the commit and the send would lose them), and a station publication from before
    // the write does not roll them back. Cleared by a publication with the value, or by a run's end there
    // (the station had them before that run: writes go out ahead of the dispatch).
    std::map<int, double> pending_vars;
  };

  Options opt;
  ProgramSource& programs;
  std::optional<store::Database> db;

  ToolIndex tool_index;
  std::vector<StationRec> stations;
  std::vector<StationState> states;  // parallel to stations: what Allocate reads
  std::unordered_map<std::string, int> station_ids;
  std::map<std::string, RouteRec, std::less<>> routes;
  std::map<int, std::vector<std::string>> pallet_maps;
  std::map<std::int64_t, JobRec> jobs;
  std::unordered_map<std::int64_t, DispatchRec> dispatches;
  std::set<std::int64_t> waiting;                      // job ids in WAITING
  std::unordered_map<int, std::int64_t> busy_pallets;  // pallet -> live job
  struct Keyed {
    std::int64_t result = 0;
    std::string
        command;  // the command the key was first used for (Fingerprint); "" for keys stored before v3
  };
  std::unordered_map<std::string, Keyed> idem;
  std::int64_t next_job = 1, next_dispatch = 1, next_seq = 1;

  // Changes of the call in progress, flushed in one transaction.
  Effects fx;
  std::set<std::int64_t> dirty_jobs, dirty_dispatches;
  std::set<int> dirty_stations, dirty_pallets;
  std::set<std::string> dirty_routes;
  std::vector<std::pair<std::int64_t, std::size_t>> new_decisions;  // job, index
  std::vector<std::pair<std::string, Keyed>> new_idem;

  Impl(Options o, ProgramSource& p) : opt(std::move(o)), programs(p) {
    if (!opt.clock) opt.clock = [] { return std::chrono::system_clock::now(); };
    if (!opt.db_path.empty()) {
      db.emplace(store::Database::Open(opt.db_path));
      Migrate();
      Load();
    }
  }

  std::int64_t NowMs() const {
    return std::chrono::duration_cast<std::chrono::milliseconds>(opt.clock().time_since_epoch()).count();
  }
  int MaxPallet() const { return opt.coded_pallets ? 127 : 255; }
  void CheckPallet(int pallet) const {
    if (pallet < 1 || pallet > MaxPallet()) {
      throw Error(Errc::kInvalidArgument, fmt::format("pallet {} outside 1-{}{}", pallet, MaxPallet(),
                                                      opt.coded_pallets ? " (coded pallets)" : ""));
    }
  }

  // ---- stations ----
  int StationIndex(std::string_view id, bool create) {
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
  int FindStation(std::string_view id) const {
    auto it = station_ids.find(std::string(id));
    return it == station_ids.end() ? -1 : it->second;
  }

  // ---- building operations from specs ----
  // A station runs programs of its own controller language only: the dialect the program store recorded
  // for the program against each listed station's (its station file's, or what it announced). A station
  // whose dialect is not known yet (neither configured nor seen) is not judged. "" when all agree.
  std::string DialectClash(const ProgramMeta& meta, const std::vector<std::string>& station_ids) const {
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

  // Throws when `strict`; otherwise records the problem in Op::blocked.
  Op BuildOp(const OpSpec& spec, bool require_ucy, bool strict, std::string_view where) {
    if (spec.stations.empty())
      throw Error(Errc::kInvalidArgument, fmt::format("{}: no station listed", where));
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
        meta = programs.Lookup(name);
        if (meta && meta->part_model) {
          models.push_back(name);
          op.ucy.push_back(0);
          continue;
        }
        if (!meta) {
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
        continue;
      }
      const std::int64_t u = meta->ucy_s.value_or(0);
      op.ucy.push_back(u);
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
    return op;
  }

  Ops BuildRouteOps(const RouteSpec& spec, bool strict) {
    auto ops = std::make_shared<std::vector<Op>>();
    for (std::size_t i = 0; i < spec.ops.size(); ++i) {
      ops->push_back(BuildOp(spec.ops[i], true, strict, fmt::format("route {} op {}", spec.name, i + 1)));
    }
    return ops;
  }

  // ---- decisions ----
  std::string Describe(const AllocationRec& a) const {
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

  void JobChanged(JobRec& j) {
    dirty_jobs.insert(j.id);
    fx.job_changes.push_back(JobChange{j.id, j.state, j.reason});
  }

  DecisionRec& AddDecision(JobRec& j, std::string trigger) {
    DecisionRec& d = j.decisions.emplace_back();
    d.seq = next_seq++;
    d.time_ms = NowMs();
    d.op = j.op;
    d.trigger = std::move(trigger);
    new_decisions.emplace_back(j.id, j.decisions.size() - 1);
    return d;
  }

  void SetWaiting(JobRec& j, std::string reason, std::string_view trigger, const AllocationRec* alloc) {
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

  // Allocates the job's current operation, or makes it wait.
  void Evaluate(JobRec& j, std::string_view trigger) {
    const Op& op = (*j.ops)[static_cast<std::size_t>(j.op)];
    if (!op.blocked.empty()) {
      SetWaiting(j, op.blocked, trigger, nullptr);
      return;
    }
    AllocationRec alloc;
    alloc.candidates.reserve(op.stations.size());
    alloc.missing.reserve(op.stations.size() * 2);
    Allocate(op.stations, op.tool_ids, states, alloc);
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
    d.added = op.ucy_sum;
    d.alloc = std::move(alloc);

    DispatchRec disp;
    disp.id = next_dispatch++;
    disp.job = j.id;
    disp.station = w;
    disp.pallet = j.pallet;
    disp.op = j.op;
    disp.programs = op.programs;
    disp.ucy = op.ucy;
    dirty_dispatches.insert(disp.id);
    states[static_cast<std::size_t>(w)].backlog_s += op.ucy_sum;
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

  // Hands out the station's next pallet when it has none in hand.
  void TrySend(int s) {
    StationRec& st = stations[static_cast<std::size_t>(s)];
    const StationState& ss = states[static_cast<std::size_t>(s)];
    if (!ss.online || ss.fault || st.inflight != 0 || st.queue.empty()) return;
    DispatchRec& d = dispatches.at(st.queue.front());
    st.queue.pop_front();
    st.inflight = d.id;
    d.state = DState::kSent;
    dirty_dispatches.insert(d.id);
    dirty_stations.insert(s);
    fx.dispatches.push_back(Action(d, false));
  }

  DispatchAction Action(const DispatchRec& d, bool resent) const {
    DispatchAction a{d.id,     stations[static_cast<std::size_t>(d.station)].id,
                     d.pallet, d.programs,
                     d.job,    d.op,
                     resent,   std::nullopt};
    const JobRec& j = jobs.at(d.job);
    if (j.kind == "schedule") a.schedule_run = j.sched_run;
    return a;
  }

  // Schedule jobs: steps the runner to the next PSELECT run, the END, or an alarm.
  struct StationVars : schedule::Variables {
    StationVars(Impl& m, int s) : m(m), s(s) {}
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
    Impl& m;
    int s;
  };

  void StepSchedule(JobRec& j, int station, std::string_view trigger) {
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

  // Removes a live dispatch from its station (queue or hand) and releases its backlog.
  void Detach(DispatchRec& d, DState end) {
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

  void FinishJob(JobRec& j, JobState state, std::string reason) {
    j.state = state;
    j.reason = std::move(reason);
    j.finished = NowMs();
    j.dispatch = 0;
    waiting.erase(j.id);
    if (j.pallet != 0) busy_pallets.erase(j.pallet);
    JobChanged(j);
  }

  // Re-evaluates waiting jobs whose current operation lists `station` (-1: all).
  void ReevaluateWaiting(int station, std::string_view trigger) {
    const std::vector<std::int64_t> ids(waiting.begin(), waiting.end());
    for (std::int64_t id : ids) {
      JobRec& j = jobs.at(id);
      if (j.state != JobState::kWaiting) continue;
      const Op& op = (*j.ops)[static_cast<std::size_t>(j.op)];
      if (station >= 0 && std::find(op.stations.begin(), op.stations.end(), station) == op.stations.end()) {
        continue;
      }
      Evaluate(j, trigger);
    }
  }

  // Health policy: a station that vanished or faulted gives up its pallets. The dispatch it was handed is
  // cancelled on the station too (delivered when it answers again): a station that comes back must not run a
  // pallet that has been moved on or failed here (the chaos test found a re-queued pallet run twice).
  void Interrupt(int s, const std::string& why) {
    StationRec& st = stations[static_cast<std::size_t>(s)];
    std::vector<std::int64_t> requeue;
    if (st.inflight != 0) {
      DispatchRec& d = dispatches.at(st.inflight);
      JobRec& j = jobs.at(d.job);
      fx.cancels.push_back(CancelAction{d.id, st.id, j.id});
      if (d.state == DState::kRunning) {
        Detach(d, DState::kFailed);
        const std::string what = d.pallet != 0 ? fmt::format("pallet {}", d.pallet) : d.programs.at(0);
        FinishJob(j, JobState::kFailed,
                  fmt::format("{} while running {} (program {} of {}): the {} needs an operator", why, what,
                              d.done + 1, d.programs.size(), d.pallet != 0 ? "pallet" : "part"));
      } else {
        Detach(d, DState::kRevoked);
        requeue.push_back(j.id);
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

  // ---- idempotency ----
  // A key binds the whole command (`command`, a canonical JSON text of the verb and every argument): the same
  // command again returns the first outcome; another command under a used key is refused, never taken for a
  // replay (docs/scheduler.md §8).
  std::optional<std::int64_t> Seen(std::string_view key, const std::string& command) const {
    if (key.empty()) return std::nullopt;
    auto it = idem.find(std::string(key));
    if (it == idem.end()) return std::nullopt;
    if (!it->second.command.empty() && it->second.command != command) {
      throw Error(
          Errc::kFailedPrecondition,
          fmt::format("idempotency key {} was already used for another command ({}); refusing {}",
                      names::Shown(key, 64), names::Fit(it->second.command, 150), names::Fit(command, 150)));
    }
    return it->second.result;
  }
  void Remember(std::string_view key, const std::string& command, std::int64_t result) {
    if (key.empty()) return;
    idem.emplace(std::string(key), Keyed{result, command});
    new_idem.emplace_back(std::string(key), Keyed{result, command});
  }

  // ---- call framing: commit or roll back, then hand out effects ----
  template <typename F>
  auto Call(F&& f) {
    fx = Effects{};
    ClearDirty();
    try {
      if constexpr (std::is_void_v<decltype(f())>) {
        f();
        Flush();
      } else {
        auto r = f();
        Flush();
        return r;
      }
    } catch (...) {
      // In-memory state may be ahead of the database: reload what was committed.
      if (Dirty()) Reload();
      fx = Effects{};
      ClearDirty();
      throw;
    }
  }
  Effects TakeEffects() { return std::exchange(fx, Effects{}); }

  bool Dirty() const {
    return !dirty_jobs.empty() || !dirty_dispatches.empty() || !dirty_stations.empty() ||
           !dirty_pallets.empty() || !dirty_routes.empty() || !new_decisions.empty() || !new_idem.empty();
  }
  void ClearDirty() {
    dirty_jobs.clear();
    dirty_dispatches.clear();
    dirty_stations.clear();
    dirty_pallets.clear();
    dirty_routes.clear();
    new_decisions.clear();
    new_idem.clear();
  }

  void Reload();
  void Migrate();
  void Load();
  void Flush();

  // ---- views ----
  JobView View(const JobRec& j, bool with_decisions) const;
  StationView ViewStation(int s) const;
  RouteView ViewRoute(const std::string& name, const RouteRec& r) const;
  static json OpsToJson(const std::vector<Op>& ops, const std::vector<StationRec>& st);
  Ops OpsFromJson(const json& j);
};

// ---------------------------------------------------------------------------------------------------------
// Persistence
namespace {

const std::vector<store::Migration>& Migrations() {
  static const std::vector<store::Migration> m = {
      store::Migration::Sql(
          1,
          "scheduler: counters, idempotency, stations, pallet maps, routes, jobs, dispatches, "
          "decisions",
          R"sql(
CREATE TABLE counters (name TEXT PRIMARY KEY, value INTEGER NOT NULL);
CREATE TABLE idempotency (key TEXT PRIMARY KEY, result INTEGER NOT NULL);
CREATE TABLE stations (id TEXT PRIMARY KEY, dialect TEXT NOT NULL, online INTEGER NOT NULL,
                       fault INTEGER NOT NULL, alarm_code TEXT NOT NULL, alarm_text TEXT NOT NULL,
                       backlog_s INTEGER NOT NULL, tools TEXT NOT NULL, program TEXT NOT NULL);
CREATE TABLE pallet_maps (pallet INTEGER PRIMARY KEY, programs TEXT NOT NULL);
CREATE TABLE routes (name TEXT PRIMARY KEY, spec TEXT NOT NULL, ops TEXT NOT NULL, valid INTEGER NOT NULL,
                     invalid_reason TEXT NOT NULL);
CREATE TABLE jobs (id INTEGER PRIMARY KEY, state TEXT NOT NULL, kind TEXT NOT NULL, route TEXT NOT NULL,
                   pallet INTEGER NOT NULL, op INTEGER NOT NULL, station TEXT NOT NULL, reason TEXT NOT NULL,
                   started_ms INTEGER NOT NULL, finished_ms INTEGER NOT NULL, cycle_s REAL,
                   dispatch INTEGER NOT NULL, ops TEXT NOT NULL);
CREATE TABLE dispatches (id INTEGER PRIMARY KEY, job INTEGER NOT NULL, station TEXT NOT NULL,
                         pallet INTEGER NOT NULL, op INTEGER NOT NULL, state TEXT NOT NULL,
                         programs TEXT NOT NULL, ucy TEXT NOT NULL, done INTEGER NOT NULL);
CREATE INDEX dispatches_live ON dispatches(state);
CREATE TABLE decisions (seq INTEGER PRIMARY KEY, job INTEGER NOT NULL, body TEXT NOT NULL);
CREATE INDEX decisions_job ON decisions(job);
)sql"),
      store::Migration::Sql(2, "scheduler: station common variables and schedule jobs", R"sql(
ALTER TABLE stations ADD COLUMN vars TEXT NOT NULL DEFAULT '{}';
ALTER TABLE jobs ADD COLUMN schedule TEXT NOT NULL DEFAULT '';
)sql"),
      store::Migration::Sql(3, "scheduler: the command each idempotency key was used for", R"sql(
ALTER TABLE idempotency ADD COLUMN command TEXT NOT NULL DEFAULT '';
)sql"),
      store::Migration::Sql(4, "scheduler: VSET writes a station has not shown back yet", R"sql(
ALTER TABLE stations ADD COLUMN pending_vars TEXT NOT NULL DEFAULT '{}';
)sql"),
  };
  return m;
}

json SpecToJson(const RouteSpec& s) {
  json ops = json::array();
  for (const auto& op : s.ops) ops.push_back({{"stations", op.stations}, {"programs", op.programs}});
  return {{"name", s.name}, {"ops", ops}};
}

RouteSpec SpecFromJson(const json& j) {
  RouteSpec s;
  s.name = j.at("name");
  for (const auto& op : j.at("ops")) s.ops.push_back(OpSpec{op.at("stations"), op.at("programs")});
  return s;
}

}  // namespace

json Scheduler::Impl::OpsToJson(const std::vector<Op>& ops, const std::vector<StationRec>& st) {
  json out = json::array();
  for (const auto& op : ops) {
    std::vector<std::string> names;
    for (int s : op.stations) names.push_back(st[static_cast<std::size_t>(s)].id);
    out.push_back({{"stations", names},
                   {"programs", op.programs},
                   {"ucy", op.ucy},
                   {"tools", op.tools},
                   {"blocked", op.blocked}});
  }
  return out;
}

Scheduler::Impl::Ops Scheduler::Impl::OpsFromJson(const json& j) {
  auto ops = std::make_shared<std::vector<Op>>();
  for (const auto& o : j) {
    Op op;
    for (const auto& s : o.at("stations")) op.stations.push_back(StationIndex(s.get<std::string>(), true));
    op.programs = o.at("programs").get<std::vector<std::string>>();
    op.ucy = o.at("ucy").get<std::vector<std::int64_t>>();
    op.tools = o.at("tools").get<std::vector<std::string>>();
    op.blocked = o.at("blocked");
    for (auto u : op.ucy) op.ucy_sum += u;
    for (const auto& t : op.tools) op.tool_ids.push_back(tool_index.Intern(t));
    ops->push_back(std::move(op));
  }
  return ops;
}

void Scheduler::Impl::Migrate() {
  store::Migrate(*db, Migrations());
}

void Scheduler::Impl::Load() {
  store::Database& d = *db;
  {
    auto q = d.Prepare("SELECT name, value FROM counters");
    while (q.Step()) {
      const std::string n = q.ColumnText(0);
      if (n == "job") next_job = q.ColumnInt64(1);
      if (n == "dispatch") next_dispatch = q.ColumnInt64(1);
      if (n == "decision") next_seq = q.ColumnInt64(1);
    }
  }
  {
    auto q = d.Prepare("SELECT key, result, command FROM idempotency");
    while (q.Step()) idem.emplace(q.ColumnText(0), Keyed{q.ColumnInt64(1), q.ColumnText(2)});
  }
  {
    auto q = d.Prepare(
        "SELECT id, dialect, online, fault, alarm_code, alarm_text, tools, program, vars, pending_vars FROM "
        "stations "
        "ORDER BY rowid");
    while (q.Step()) {
      const int s = StationIndex(q.ColumnText(0), true);
      StationRec& st = stations[static_cast<std::size_t>(s)];
      st.dialect = q.ColumnText(1);
      states[static_cast<std::size_t>(s)].online = q.ColumnInt64(2) != 0;
      states[static_cast<std::size_t>(s)].fault = q.ColumnInt64(3) != 0;
      st.alarm_code = q.ColumnText(4);
      st.alarm_text = q.ColumnText(5);
      st.tools = tooltable::FromJson(json::parse(q.ColumnText(6)));
      st.program = q.ColumnText(7);
      const json vars = json::parse(q.ColumnText(8));
      for (auto it = vars.begin(); it != vars.end(); ++it)
        st.vars[std::stoi(it.key())] = it.value().get<double>();
      const json pending = json::parse(q.ColumnText(9));
      for (auto it = pending.begin(); it != pending.end(); ++it)
        st.pending_vars[std::stoi(it.key())] = it.value().get<double>();
      states[static_cast<std::size_t>(s)].SetTools(st.tools, tool_index);
    }
  }
  {
    auto q = d.Prepare("SELECT pallet, programs FROM pallet_maps");
    while (q.Step()) {
      pallet_maps[static_cast<int>(q.ColumnInt64(0))] =
          json::parse(q.ColumnText(1)).get<std::vector<std::string>>();
    }
  }
  {
    auto q = d.Prepare("SELECT name, spec, ops, valid, invalid_reason FROM routes");
    while (q.Step()) {
      RouteRec r;
      r.spec = SpecFromJson(json::parse(q.ColumnText(1)));
      r.ops = OpsFromJson(json::parse(q.ColumnText(2)));
      r.valid = q.ColumnInt64(3) != 0;
      r.invalid_reason = q.ColumnText(4);
      routes.emplace(q.ColumnText(0), std::move(r));
    }
  }
  {
    auto q = d.Prepare(
        "SELECT id, state, kind, route, pallet, op, station, reason, started_ms, finished_ms, cycle_s, "
        "dispatch, ops, schedule FROM jobs");
    while (q.Step()) {
      JobRec j;
      j.id = q.ColumnInt64(0);
      j.state = ParseJobState(q.ColumnText(1));
      j.kind = q.ColumnText(2);
      j.route = q.ColumnText(3);
      j.pallet = static_cast<int>(q.ColumnInt64(4));
      j.op = static_cast<int>(q.ColumnInt64(5));
      const std::string st = q.ColumnText(6);
      j.station = st.empty() ? -1 : StationIndex(st, true);
      j.reason = q.ColumnText(7);
      j.started = q.ColumnInt64(8);
      j.finished = q.ColumnInt64(9);
      if (!q.IsNull(10)) j.cycle = q.ColumnDouble(10);
      j.dispatch = q.ColumnInt64(11);
      j.ops = OpsFromJson(json::parse(q.ColumnText(12)));
      // Jobs of a route share its current operations when they are the same.
      if (auto r = routes.find(j.route);
          r != routes.end() && OpsToJson(*r->second.ops, stations) == OpsToJson(*j.ops, stations)) {
        j.ops = r->second.ops;
      }
      if (const std::string sched = q.ColumnText(13); !sched.empty()) {
        const json js = json::parse(sched);
        j.sched_name = js.at("name");
        j.sched_text = js.at("text");
        j.sched = std::make_shared<schedule::Program>(schedule::Parse(j.sched_text, j.sched_name));
        j.sched_pos.pc = js.at("pc");
        j.sched_pos.done = js.at("done");
        j.sched_pos.count = js.at("count");
        j.sched_pos.finished = js.at("finished");
        if (const auto& r = js.at("run"); !r.is_null()) {
          j.sched_run = schedule::Run{r.at("main_file"), r.at("program"), r.at("sub_file"),
                                      r.at("index"),     r.at("count"),   r.at("line")};
        }
      }
      if (j.state == JobState::kWaiting) waiting.insert(j.id);
      if (!IsTerminal(j.state) && j.pallet != 0) busy_pallets[j.pallet] = j.id;
      jobs.emplace(j.id, std::move(j));
    }
  }
  {
    auto q = d.Prepare(
        "SELECT id, job, station, pallet, op, state, programs, ucy, done FROM dispatches ORDER BY id");
    while (q.Step()) {
      DispatchRec r;
      r.id = q.ColumnInt64(0);
      r.job = q.ColumnInt64(1);
      r.station = StationIndex(q.ColumnText(2), true);
      r.pallet = static_cast<int>(q.ColumnInt64(3));
      r.op = static_cast<int>(q.ColumnInt64(4));
      r.state = ParseDState(q.ColumnText(5));
      r.programs = json::parse(q.ColumnText(6)).get<std::vector<std::string>>();
      r.ucy = json::parse(q.ColumnText(7)).get<std::vector<std::int64_t>>();
      r.done = static_cast<int>(q.ColumnInt64(8));
      // Backlog and station queues are rebuilt from the live dispatches.
      if (Live(r.state)) {
        StationRec& st = stations[static_cast<std::size_t>(r.station)];
        states[static_cast<std::size_t>(r.station)].backlog_s += r.Remaining();
        if (r.state == DState::kQueued)
          st.queue.push_back(r.id);
        else
          st.inflight = r.id;
      }
      dispatches.emplace(r.id, std::move(r));
    }
  }
  {
    auto q = d.Prepare("SELECT seq, job, body FROM decisions ORDER BY seq");
    while (q.Step()) {
      auto it = jobs.find(q.ColumnInt64(1));
      if (it == jobs.end()) continue;
      const json b = json::parse(q.ColumnText(2));
      DecisionRec r;
      r.seq = q.ColumnInt64(0);
      r.time_ms = b.at("time_ms");
      r.op = b.at("op");
      r.trigger = b.at("trigger");
      r.why = b.at("why");
      r.added = b.at("added");
      const std::string winner = b.at("winner");
      r.alloc.winner = winner.empty() ? -1 : StationIndex(winner, true);
      r.alloc.tied = b.at("tied");
      for (const auto& c : b.at("considered")) {
        CandidateRec cr;
        cr.station = StationIndex(c.at("station").get<std::string>(), true);
        cr.backlog_s = c.at("backlog_s");
        cr.online = c.at("online");
        cr.fault = c.at("fault");
        cr.missing_begin = static_cast<std::uint32_t>(r.alloc.missing.size());
        for (const auto& t : c.at("missing"))
          r.alloc.missing.push_back(tool_index.Intern(t.get<std::string>()));
        cr.missing_count = static_cast<std::uint32_t>(r.alloc.missing.size()) - cr.missing_begin;
        r.alloc.candidates.push_back(std::move(cr));
      }
      it->second.decisions.push_back(std::move(r));
    }
  }
  ClearDirty();
}

void Scheduler::Impl::Reload() {
  fx = Effects{};
  ClearDirty();
  if (!db) return;  // in-memory only: nothing to go back to; state stays as it is
  tool_index = ToolIndex{};
  stations.clear();
  states.clear();
  station_ids.clear();
  routes.clear();
  pallet_maps.clear();
  jobs.clear();
  dispatches.clear();
  waiting.clear();
  busy_pallets.clear();
  idem.clear();
  next_job = next_dispatch = next_seq = 1;
  Load();
}

void Scheduler::Impl::Flush() {
  if (!db) {
    ClearDirty();
    return;
  }
  store::Transaction tx(*db);
  {
    auto q = db->Prepare(
        "INSERT INTO counters(name, value) VALUES (?1, ?2) "
        "ON CONFLICT(name) DO UPDATE SET value = excluded.value");
    for (auto [n, v] : {std::pair<const char*, std::int64_t>{"job", next_job},
                        {"dispatch", next_dispatch},
                        {"decision", next_seq}}) {
      q.BindText(1, n).BindInt64(2, v).Run();
      q.Reset();
    }
  }
  if (!new_idem.empty()) {
    auto q = db->Prepare("INSERT OR IGNORE INTO idempotency(key, result, command) VALUES (?1, ?2, ?3)");
    for (const auto& [k, v] : new_idem) {
      q.BindText(1, k).BindInt64(2, v.result).BindText(3, v.command).Run();
      q.Reset();
    }
  }
  if (!dirty_stations.empty()) {
    auto q = db->Prepare(
        "INSERT INTO stations(id, dialect, online, fault, alarm_code, alarm_text, backlog_s, tools, program, "
        "vars, pending_vars) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11) ON CONFLICT(id) DO UPDATE "
        "SET "
        "dialect = excluded.dialect, online = excluded.online, fault = excluded.fault, "
        "alarm_code = excluded.alarm_code, alarm_text = excluded.alarm_text, backlog_s = excluded.backlog_s, "
        "tools = excluded.tools, program = excluded.program, vars = excluded.vars, "
        "pending_vars = excluded.pending_vars");
    for (int s : dirty_stations) {
      const StationRec& st = stations[static_cast<std::size_t>(s)];
      const StationState& ss = states[static_cast<std::size_t>(s)];
      json vars = json::object();
      for (const auto& [n, v] : st.vars) vars[std::to_string(n)] = v;
      json pending = json::object();
      for (const auto& [n, v] : st.pending_vars) pending[std::to_string(n)] = v;
      q.BindText(11, pending.dump());
      q.BindText(1, st.id).BindText(2, st.dialect).BindInt64(3, ss.online).BindInt64(4, ss.fault);
      q.BindText(5, st.alarm_code).BindText(6, st.alarm_text).BindInt64(7, ss.backlog_s);
      q.BindText(10, vars.dump());
      q.BindText(8, tooltable::ToJson(st.tools).dump()).BindText(9, st.program).Run();
      q.Reset();
    }
  }
  if (!dirty_pallets.empty()) {
    auto q = db->Prepare(
        "INSERT INTO pallet_maps(pallet, programs) VALUES (?1, ?2) "
        "ON CONFLICT(pallet) DO UPDATE SET programs = excluded.programs");
    for (int p : dirty_pallets) {
      q.BindInt64(1, p).BindText(2, json(pallet_maps.at(p)).dump()).Run();
      q.Reset();
    }
  }
  if (!dirty_routes.empty()) {
    auto q = db->Prepare(
        "INSERT INTO routes(name, spec, ops, valid, invalid_reason) VALUES (?1, ?2, ?3, ?4, ?5) "
        "ON CONFLICT(name) DO UPDATE SET spec = excluded.spec, ops = excluded.ops, "
        "valid = excluded.valid, invalid_reason = excluded.invalid_reason");
    for (const auto& n : dirty_routes) {
      const RouteRec& r = routes.at(n);
      q.BindText(1, n).BindText(2, SpecToJson(r.spec).dump()).BindText(3, OpsToJson(*r.ops, stations).dump());
      q.BindInt64(4, r.valid).BindText(5, r.invalid_reason).Run();
      q.Reset();
    }
  }
  if (!dirty_jobs.empty()) {
    auto q = db->Prepare(
        "INSERT INTO jobs(id, state, kind, route, pallet, op, station, reason, started_ms, finished_ms, "
        "cycle_s, "
        "dispatch, ops, schedule) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14) "
        "ON CONFLICT(id) DO UPDATE SET state = excluded.state, op = excluded.op, station = excluded.station, "
        "reason = excluded.reason, started_ms = excluded.started_ms, finished_ms = excluded.finished_ms, "
        "cycle_s = excluded.cycle_s, dispatch = excluded.dispatch, ops = excluded.ops, "
        "schedule = excluded.schedule");
    for (std::int64_t id : dirty_jobs) {
      const JobRec& j = jobs.at(id);
      q.BindInt64(1, j.id).BindText(2, JobStateName(j.state)).BindText(3, j.kind).BindText(4, j.route);
      q.BindInt64(5, j.pallet).BindInt64(6, j.op);
      q.BindText(7, j.station < 0 ? std::string() : stations[static_cast<std::size_t>(j.station)].id);
      q.BindText(8, j.reason).BindInt64(9, j.started).BindInt64(10, j.finished);
      if (j.cycle)
        q.BindDouble(11, *j.cycle);
      else
        q.BindNull(11);
      std::string sched;
      if (j.kind == "schedule") {
        json js = {{"name", j.sched_name},
                   {"text", j.sched_text},
                   {"pc", j.sched_pos.pc},
                   {"done", j.sched_pos.done},
                   {"count", j.sched_pos.count},
                   {"finished", j.sched_pos.finished},
                   {"run", nullptr}};
        if (j.sched_run) {
          const auto& r = *j.sched_run;
          js["run"] = {{"main_file", r.main_file}, {"program", r.program}, {"sub_file", r.sub_file},
                       {"index", r.index},         {"count", r.count},     {"line", r.line}};
        }
        sched = js.dump();
      }
      q.BindText(14, sched);
      q.BindInt64(12, j.dispatch).BindText(13, OpsToJson(*j.ops, stations).dump()).Run();
      q.Reset();
    }
  }
  if (!dirty_dispatches.empty()) {
    auto q = db->Prepare(
        "INSERT INTO dispatches(id, job, station, pallet, op, state, programs, ucy, done) "
        "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9) ON CONFLICT(id) DO UPDATE SET state = excluded.state, "
        "done = excluded.done");
    for (std::int64_t id : dirty_dispatches) {
      const DispatchRec& r = dispatches.at(id);
      q.BindInt64(1, r.id).BindInt64(2, r.job).BindText(3, stations[static_cast<std::size_t>(r.station)].id);
      q.BindInt64(4, r.pallet).BindInt64(5, r.op).BindText(6, kDStateNames[static_cast<int>(r.state)]);
      q.BindText(7, json(r.programs).dump()).BindText(8, json(r.ucy).dump()).BindInt64(9, r.done).Run();
      q.Reset();
    }
  }
  if (!new_decisions.empty()) {
    auto q = db->Prepare("INSERT INTO decisions(seq, job, body) VALUES (?1, ?2, ?3)");
    for (auto [job, idx] : new_decisions) {
      const DecisionRec& r = jobs.at(job).decisions.at(idx);
      json considered = json::array();
      for (const auto& c : r.alloc.candidates) {
        std::vector<std::string> missing;
        r.alloc.ForMissing(c, [&](int t) { missing.push_back(tool_index.Name(t)); });
        considered.push_back({{"station", stations[static_cast<std::size_t>(c.station)].id},
                              {"backlog_s", c.backlog_s},
                              {"online", c.online},
                              {"fault", c.fault},
                              {"missing", missing}});
      }
      const json body = {
          {"time_ms", r.time_ms},
          {"op", r.op},
          {"trigger", r.trigger},
          {"why", r.why.empty() && r.alloc.winner < 0 ? Describe(r.alloc) : r.why},
          {"added", r.added},
          {"winner", r.alloc.winner < 0 ? "" : stations[static_cast<std::size_t>(r.alloc.winner)].id},
          {"tied", r.alloc.tied},
          {"considered", considered}};
      q.BindInt64(1, r.seq).BindInt64(2, job).BindText(3, body.dump()).Run();
      q.Reset();
    }
  }
  tx.Commit();
  ClearDirty();
}

// ---------------------------------------------------------------------------------------------------------
// Views
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
  v.op_index = j.op;
  v.op_count = static_cast<int>(j.ops->size());
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
      }
    }
    for (std::size_t s = 0; s < m.stations.size(); ++s) m.TrySend(static_cast<int>(s));
  });
  return m.TakeEffects();
}

void Scheduler::ConfigureStation(std::string_view id, std::string_view dialect) {
  Impl& m = *impl_;
  m.Call([&] {
    const int s = m.StationIndex(id, true);
    if (!dialect.empty() && m.stations[static_cast<std::size_t>(s)].dialect != dialect) {
      m.stations[static_cast<std::size_t>(s)].dialect = std::string(dialect);
      m.dirty_stations.insert(s);
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
    for (const auto& p : programs) names::CheckProgram(p);
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
      Impl::RouteRec r;
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
    Impl::JobRec j;
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
    auto ops = std::make_shared<std::vector<Impl::Op>>();
    // A direct run is the operator's non-FMS use: UCY is optional (0 s of backlog when absent).
    ops->push_back(m.BuildOp(spec, false, true, fmt::format("pallet {}", pallet)));
    Impl::JobRec j;
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
    Impl::JobRec j;
    j.id = m.next_job++;
    j.kind = "schedule";
    j.sched_name = std::string(name);
    j.sched_text = std::string(text);
    j.sched = program;
    j.ops = std::make_shared<std::vector<Impl::Op>>();
    auto& ref = m.jobs.emplace(j.id, std::move(j)).first->second;
    m.JobChanged(ref);
    m.StepSchedule(ref, s, fmt::format("schedule {} on {}", name, station));
    m.Remember(key, command, ref.id);
    return ref.id;
  });
  res.effects = m.TakeEffects();
  return res;
}

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
      }
      st.vars[n] = v;
    }
    m.dirty_stations.insert(s);
  });
  return m.TakeEffects();
}

std::map<int, double> Scheduler::StationCommonVariables(std::string_view id) const {
  const int s = impl_->FindStation(id);
  if (s < 0) return {};
  return impl_->stations[static_cast<std::size_t>(s)].vars;
}

Effects Scheduler::Cancel(std::string_view key, std::int64_t job_id, std::string_view reason) {
  Impl& m = *impl_;
  const std::string command = json{{"verb", "job-cancel"}, {"job", job_id}}.dump();
  m.Call([&] {
    if (m.Seen(key, command)) return;
    auto it = m.jobs.find(job_id);
    if (it == m.jobs.end()) throw Error(Errc::kNotFound, fmt::format("no job {}", job_id));
    Impl::JobRec& j = it->second;
    if (IsTerminal(j.state)) {
      throw Error(Errc::kFailedPrecondition,
                  fmt::format("job {} is already {}", job_id, JobStateName(j.state)));
    }
    int freed = -1;
    if (j.dispatch != 0) {
      Impl::DispatchRec& d = m.dispatches.at(j.dispatch);
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
    m.Interrupt(s, fmt::format("station {} went offline", id));
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
    st.alarm_code = std::string(code);
    st.alarm_text = std::string(text);
    m.dirty_stations.insert(s);
    if (ss.fault == fault) return;
    ss.fault = fault;
    if (fault) {
      m.Interrupt(s, fmt::format("station {} raised fault{}{}", id, code.empty() ? "" : " ", code));
    } else {
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
Scheduler::Impl::DispatchRec* ForReport(Scheduler::Impl& m, std::int64_t id, std::string_view what) {
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
  return &it->second;
}
}  // namespace

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
void MarkRunning(Scheduler::Impl& m, Scheduler::Impl::DispatchRec& d) {
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
    auto& j = m.jobs.at(d->job);
    if (cycle_s) j.cycle = j.cycle.value_or(0) + *cycle_s;
    j.dispatch = 0;
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
    m.Detach(*d, DState::kFailed);
    auto& j = m.jobs.at(d->job);
    m.FinishJob(j, JobState::kFailed,
                fmt::format("station {}: {}", m.stations[static_cast<std::size_t>(s)].id, reason));
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
    const auto uses = [&](const std::vector<Impl::Op>& ops) {
      for (const auto& op : ops) {
        if (std::find(op.programs.begin(), op.programs.end(), name) != op.programs.end()) return true;
      }
      return false;
    };
    std::map<const std::vector<Impl::Op>*, Impl::Ops> replaced;
    for (auto& [rname, r] : m.routes) {
      if (!uses(*r.ops)) continue;
      Impl::Ops fresh = m.BuildRouteOps(r.spec, false);
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
        auto ops = std::make_shared<std::vector<Impl::Op>>();
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

std::optional<JobView> Scheduler::Job(std::int64_t id, bool with_decisions) const {
  auto it = impl_->jobs.find(id);
  if (it == impl_->jobs.end()) return std::nullopt;
  return impl_->View(it->second, with_decisions);
}

std::vector<JobView> Scheduler::Jobs(bool with_decisions) const {
  std::vector<JobView> out;
  for (const auto& [id, j] : impl_->jobs) out.push_back(impl_->View(j, with_decisions));
  return out;
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
