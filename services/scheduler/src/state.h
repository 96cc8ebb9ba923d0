// The scheduler's in-memory records, private to cell_scheduler_lib: what its decision core (scheduler.cpp)
// changes and its store (scheduler_store.cpp) loads and writes.
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include "cell/scheduler/allocator.h"
#include "cell/scheduler/route.h"
#include "cell/scheduler/schedule_program.h"
#include "cell/scheduler/scheduler.h"
#include "cell/tooltable/tooltable.h"

namespace cell::scheduler {

// A dispatch's life: allocated to a station's queue, handed out, accepted, running, then one of the ends.
enum class DState { kQueued, kSent, kAcked, kRunning, kDone, kFailed, kRevoked };
inline constexpr const char* kDStateNames[] = {"queued", "sent",   "acked",  "running",
                                               "done",   "failed", "revoked"};
inline bool Live(DState s) {
  return s == DState::kQueued || s == DState::kSent || s == DState::kAcked || s == DState::kRunning;
}

struct Op {
  std::vector<int> stations;
  std::vector<std::string> programs;
  std::vector<std::int64_t> ucy;
  std::vector<std::string> tools;
  std::vector<int> tool_ids;
  std::int64_t ucy_sum = 0;
  std::string blocked;  // non-empty: a program no longer qualifies; the pallet waits
  // Per program: its revision (ProgramMeta::revision; "" for a part model or a program that does not
  // qualify: no estimate) and whether its UCY is stated (stated UCY wins over the estimate, scheduler.md).
  // Empty (an operation stored before estimates): UCY alone, as before.
  std::vector<std::string> revisions;
  std::vector<char> stated;
  bool Stated(std::size_t i) const { return i >= stated.size() || stated[i]; }
  const std::string& Revision(std::size_t i) const {
    static const std::string none;
    return i < revisions.size() ? revisions[i] : none;
  }
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
  std::string kind;  // "route" | "pallet" | "schedule"
  std::string route;
  int pallet = 0;
  Ops ops;
  int op = 0;
  JobState state = JobState::kQueued;
  int station = -1;
  std::string reason;
  std::int64_t started = 0, finished = 0;
  std::optional<double> cycle;
  std::map<int, double> predicted;  // per operation: the predicted seconds its last allocation used
  std::int64_t dispatch = 0;        // live dispatch id, 0 = none
  std::vector<DecisionRec> decisions;
  // Schedule jobs: the program, where its runner stands, and the run in progress.
  std::string sched_name, sched_text;
  std::shared_ptr<const schedule::Program> sched;
  schedule::RunnerPosition sched_pos;
  std::optional<schedule::Run> sched_run;
  int sched_station = -1;  // the station it runs on (`schedule run --station`)
};

// A program's prediction and learned estimate on one station, for one revision of the program and of what
// the prediction rests on (Predictor::Basis).
struct EstimateRec {
  std::string revision;  // ProgramMeta::revision + "/" + basis
  std::optional<double> predicted;
  std::string why;
  std::optional<double> estimate;
  int runs = 0;
};
using EstimateKey = std::pair<std::string, std::string>;  // program (map entry), station id

struct DispatchRec {
  std::int64_t id = 0, job = 0;
  int station = 0;
  int pallet = 0;
  int op = 0;
  std::vector<std::string> programs;
  std::vector<std::int64_t> ucy;
  int done = 0;  // programs finished
  DState state = DState::kQueued;
  // Why the scheduler lost sight of the station while this dispatch was in its hands ("station KT01 went
  // offline"); empty otherwise. Only the station's own report settles such a dispatch (docs/scheduler.md §5).
  std::string interrupted;
  // When the scheduler last sent it or heard of it (ms, the scheduler's clock; memory only, 0 after a load):
  // a handed-out dispatch silent for long is asked about again (AskSilent).
  std::int64_t heard_ms = 0;
  std::int64_t Remaining() const {
    std::int64_t r = 0;
    for (std::size_t i = static_cast<std::size_t>(done); i < ucy.size(); ++i) r += ucy[i];
    return r;
  }
};

struct StationRec {
  std::string id, dialect;
  bool coded_pallets = false;  // a coded-pallet FMS module: pallets 1-127 only (KT-APL seed lines 4081-4083)
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

// What an idempotency key gave the first time.
struct Keyed {
  std::int64_t result = 0;
  std::string command;  // the command the key was first used for (Fingerprint); "" for keys stored before v3
};

// Everything the scheduler knows, and what the call in progress changed in it.
struct State {
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
  // With a database, a cache of the keys (the newest, in idem_order); the database holds them all.
  std::unordered_map<std::string, Keyed> idem;
  std::deque<std::string> idem_order;
  std::map<EstimateKey, EstimateRec> estimates;
  std::int64_t next_job = 1, next_dispatch = 1, next_seq = 1;
  std::size_t trim_at = 0;  // jobs.size() at which ended jobs are next let go (Scheduler::Impl::Trim)

  // Changes of the call in progress, flushed in one transaction.
  std::set<std::int64_t> dirty_jobs, dirty_dispatches;
  std::set<int> dirty_stations, dirty_pallets;
  std::set<std::string> dirty_routes;
  std::set<EstimateKey> dirty_estimates;
  std::vector<std::pair<std::int64_t, std::size_t>> new_decisions;  // job, index
  std::vector<std::pair<std::string, Keyed>> new_idem;

  // The station's index; an unknown id is registered (and marked changed) when `create`, else -1.
  int StationIndex(std::string_view id, bool create);
  int FindStation(std::string_view id) const;
  // Why no station is eligible, from an allocation's candidates.
  std::string Describe(const AllocationRec& a) const;
  bool Dirty() const;
  void ClearDirty();
};

}  // namespace cell::scheduler
