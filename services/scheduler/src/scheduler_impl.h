// The scheduler's decision core, private to cell_scheduler_lib. Scheduler::Impl changes the State, collects
// what a call produced (Effects) and commits the call's changes through the Store in one transaction.
// scheduler.cpp holds the decision rules and the commands, scheduler_reports.cpp what stations report,
// scheduler_queries.cpp the views.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include "cell/scheduler/estimates.h"
#include "cell/scheduler/program_source.h"
#include "cell/scheduler/route.h"
#include "cell/scheduler/scheduler.h"
#include "scheduler_store.h"
#include "state.h"

namespace cell::scheduler {

struct Scheduler::Impl : State {
  Options opt;
  ProgramSource& programs;
  std::optional<Store> store;                         // none: in memory only
  Effects fx;                                         // what the call in progress produced
  Predictor* predictor = nullptr;                     // none: no predictions, UCY alone
  std::function<void(const PredictionRequest&)> ask;  // queues a prediction (SetPredictor)

  Impl(Options o, ProgramSource& p);

  std::int64_t NowMs() const {
    return std::chrono::duration_cast<std::chrono::milliseconds>(opt.clock().time_since_epoch()).count();
  }
  // Pallet numbers 1-255 (KT-APL seed line 852); a coded-pallet module's 1-127 is a per-station rule
  // (ListedFor).
  static constexpr int kMaxPallet = 255;
  void CheckPallet(int pallet) const;
  // The operation's listed stations that can hold `pallet`: a coded-pallet module takes 1-127 only (KT-APL
  // seed lines 4081-4083), so for pallets 128-255 it is left out (into `scratch`); otherwise op.stations.
  const std::vector<int>& ListedFor(const std::vector<int>& listed, int pallet,
                                    std::vector<int>& scratch) const;
  // Throws kInvalidArgument when an operation lists only stations that cannot hold `pallet`.
  void CheckPalletOnStations(int pallet, const Ops& ops, std::string_view route) const;

  // ---- building operations from specs ----
  std::string DialectClash(const ProgramMeta& meta, const std::vector<std::string>& station_ids) const;
  // Throws when `strict`; otherwise records the problem in Op::blocked.
  Op BuildOp(const OpSpec& spec, bool require_ucy, bool strict, std::string_view where);
  // A map entry's program as the listed stations will read it (docs/scheduler.md, "Program names"); nullopt
  // when one of them would not find it, or (`refused` says why) when one of them may not run it.
  std::optional<ProgramMeta> LookupFor(const std::string& entry, const std::vector<std::string>& station_ids,
                                       std::string* refused);
  // A pallet map's entry, before any station is chosen: in HOST, its own namespace, or some station's.
  bool ProgramExists(const std::string& entry);
  Ops BuildRouteOps(const RouteSpec& spec, bool strict);

  // ---- estimates (docs/scheduler.md "Estimates") ----
  // The program's record on the station for this revision; nullptr without a predictor or a revision, or
  // while the prediction is asked for (never made here: predicting would hold the caller's lock).
  const EstimateRec* EstimateFor(const std::string& program, const std::string& revision, int station);
  // Asks for what an operation's programs lack on its stations, ahead of their allocation.
  void AskEstimates(const Op& op);
  // Seconds of backlog per program of `op` on `station` (stated UCY, else the estimate, else 0), and the
  // prediction behind the visit when every program that runs has one.
  std::vector<std::int64_t> BacklogFor(const Op& op, int station, std::optional<double>& predicted);
  // A visit's machine seconds correct its programs' estimates on its station (LearnEstimate).
  void Learn(const DispatchRec& d, double actual);
  // ---- decisions ----
  void JobChanged(JobRec& j);
  DecisionRec& AddDecision(JobRec& j, std::string trigger);
  void SetWaiting(JobRec& j, std::string reason, std::string_view trigger, const AllocationRec* alloc);
  // Allocates the job's current operation, or makes it wait.
  void Evaluate(JobRec& j, std::string_view trigger);
  // Hands out the station's next pallet when it has none in hand.
  void TrySend(int s);
  DispatchAction Action(const DispatchRec& d, bool resent) const;
  // Schedule jobs: steps the runner to the next PSELECT run, the END, or an alarm.
  void StepSchedule(JobRec& j, int station, std::string_view trigger);
  // Removes a live dispatch from its station (queue or hand) and releases its backlog.
  void Detach(DispatchRec& d, DState end);
  void FinishJob(JobRec& j, JobState state, std::string reason);
  // A schedule job that ended gives its station back: the next schedule waiting for it starts, or the pallets
  // held off it are evaluated again.
  void ReleaseSchedule(const JobRec& j);
  // Re-evaluates waiting jobs whose current operation lists `station` (-1: all).
  void ReevaluateWaiting(int station, std::string_view trigger);
  // A station that vanished or faulted gives up its pallets.
  // A station went offline (cancel = false) or raised a fault (cancel = true: the station is sent a cancel
  // for the dispatch it holds). Its queue is re-queued; the dispatch it holds waits for its report.
  void Interrupt(int s, const std::string& why, bool cancel);
  // What a dispatch puts on the machine, as job reasons name it: "pallet 5", or a schedule run's program.
  static std::string Holding(const DispatchRec& d);
  // Station s answers again (online, no fault): the dispatch it held when it was interrupted is sent again
  // under its id, so the station says what became of it (it re-publishes an ended run's status).
  void AskAgain(int s);
  // An interrupted dispatch the station never started: revoked, and its job allocated again.
  void GiveBack(DispatchRec& d);

  // ---- idempotency ----
  std::optional<std::int64_t> Seen(std::string_view key, const std::string& command);
  void Remember(std::string_view key, const std::string& command, std::int64_t result);

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

  // Back to what the database holds (a failed call may have changed the records).
  void Reload();
  // Commits the call's changes.
  void Flush();
  // Lets go of what the database holds and the cell no longer needs in memory (with a database only).
  void Trim();

  // ---- views ----
  JobView View(const JobRec& j, bool with_decisions) const;
  StationView ViewStation(int s) const;
  RouteView ViewRoute(const std::string& name, const RouteRec& r) const;
};

}  // namespace cell::scheduler
