// The scheduler's decision core (DESIGN §5): pallet maps, routes, OPERATE allocation by tool table and
// backlog, the job lifecycle, station health, and durable state in SQLite. No DDS: the service feeds commands
// and observations in and sends the returned actions out.
//
// Durability: every call that changes state commits one SQLite transaction before it returns, so every action
// it returns is already recorded (write-ahead). After a crash, construct a new Scheduler on the same database
// and call Recover(): it returns again every dispatch that was handed out but not acknowledged by its
// station, with the same dispatch id, so the station can de-duplicate.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cell/idl/scheduler.h"
#include "cell/scheduler/estimates.h"
#include "cell/scheduler/program_source.h"
#include "cell/scheduler/route.h"
#include "cell/scheduler/schedule_program.h"
#include "cell/tooltable/tooltable.h"

namespace cell::scheduler {

enum class JobState { kQueued, kWaiting, kDispatched, kRunning, kCompleted, kFailed, kCancelled };
cell::JobState WireState(JobState s);       // the state on cell/job/state
std::string_view JobStateName(JobState s);  // records::JobStateName: "QUEUED", "WAITING", ...
std::optional<JobState> JobStateFromName(std::string_view name);  // nullopt for a word that is no state
bool IsTerminal(JobState s);

// A pallet visit handed to a station: run `programs` in order on pallet `pallet`.
struct DispatchAction {
  std::int64_t dispatch_id = 0;  // unique, never reused; the station de-duplicates on it
  std::string station;
  int pallet = 0;
  std::vector<std::string> programs;
  std::int64_t job_id = 0;
  int op_index = 0;     // 0-based operation of the route
  bool resent = false;  // true when Recover() offers it again
  // Set for one run of an Okuma schedule program's PSELECT: programs is then {"A.MIN"} (the main program
  // file, looked up in the station's namespace) and pallet 0.
  std::optional<schedule::Run> schedule_run;
};

// VSET of a schedule program: set common variable V<number> on the station. Send these before the
// dispatches of the same Effects.
struct VariableAction {
  std::string station;
  int number = 0;
  double value = 0;
};

// Tells a station to drop a dispatch (job cancelled, or the dispatch revoked or failed because the station
// vanished or faulted while holding it).
struct CancelAction {
  std::int64_t dispatch_id = 0;
  std::string station;
  std::int64_t job_id = 0;
};

struct JobChange {
  std::int64_t job_id = 0;
  JobState state = JobState::kQueued;
  std::string reason;
};

// What one call produced; everything in it is already committed.
struct Effects {
  std::vector<DispatchAction> dispatches;
  std::vector<CancelAction> cancels;
  std::vector<VariableAction> variables;
  std::vector<JobChange> job_changes;
  std::vector<std::string> notes;  // ignored or late reports etc., for the service's log
};

// One station as the decision log saw it.
struct Candidate {
  std::string station;
  bool online = false;
  bool fault = false;
  std::int64_t backlog_s = 0;
  std::vector<std::string> missing_tools;
  bool eligible = false;
};

struct Decision {
  std::int64_t seq = 0;  // global order of decisions
  std::int64_t time_ms = 0;
  int op_index = 0;
  std::string trigger;  // "operate", "station KT01 online", "tools KT02", "op 1 completed", ...
  std::vector<Candidate> considered;
  std::string winner;  // empty when the pallet waits
  std::string why;     // "shortest backlog 120 s", "tie at 0 s: listed first", or the waiting reason
  std::int64_t added_backlog_s = 0;
};

struct JobView {
  std::int64_t id = 0;
  JobState state = JobState::kQueued;
  std::string kind;      // "route", "pallet" or "schedule"
  std::string route;     // empty unless a route job
  std::string schedule;  // the schedule program's name for a schedule job
  int pallet = 0;
  std::string station;  // the station of the current or last visit; empty if none
  // Set while WAITING, when FAILED or CANCELLED, and while the scheduler waits for the word of a station that
  // went offline or faulted holding the job's pallet (DISPATCHED or RUNNING; docs/scheduler.md §5).
  std::string reason;
  std::int64_t started_ms = 0;    // first run start reported by a station; 0 = not yet
  std::int64_t finished_ms = 0;   // terminal time; 0 = not yet
  std::optional<double> cycle_s;  // sum of the stations' reported machine seconds
  // Sum of the predictions its allocations used (one per operation allocated; estimates.h), when every one
  // had one.
  std::optional<double> predicted_s;
  int op_index = 0;
  int op_count = 0;
  int decision_count = 0;           // all of the job's decisions, listed in `decisions` or not
  std::vector<Decision> decisions;  // filled only when asked for (job ls leaves them out)
};

// `job ls` (DESIGN §6): the jobs after `after` (exclusive) in id order, only those in `state` and those whose
// current or last visit is on `station`, when given.
struct JobQuery {
  std::int64_t after = 0;
  std::optional<JobState> state;
  std::string station;  // "" any
};

struct StationView {
  std::string id;
  std::string dialect;
  bool online = false;
  bool fault = false;
  std::string alarm_code;
  std::string alarm_text;
  std::int64_t backlog_s = 0;
  std::vector<std::int64_t> queue;  // dispatch ids allocated to it, in run order (the first may be in hand)
  std::int64_t in_hand = 0;  // the dispatch handed out to the station (sent, accepted or running), 0 = none
  int pallet = 0;            // pallet of the running or handed-out dispatch, 0 = none
  std::string program;       // its current program, if reported
};

// A route as defined: each operation with the UTL/UCY data DEFINE extracted.
struct OpView {
  std::vector<std::string> stations;
  std::vector<std::string> programs;
  std::vector<std::int64_t> ucy_s;  // per program
  std::vector<std::string> tools;   // union of the programs' UTL lists
};
struct RouteView {
  std::string name;
  std::vector<OpView> ops;
  bool valid = true;
  std::string invalid_reason;  // when a program it uses changed and no longer qualifies
};

// What a station says it did with a dispatch (its run-status sample). After a restart of either side the
// latest sample tells the scheduler what actually ran.
enum class RunStatus { kAccepted, kRunning, kCompleted, kFailed };
struct RunReport {
  std::int64_t dispatch_id = 0;
  RunStatus status = RunStatus::kAccepted;
  int programs_done = 0;          // programs of the dispatch that reached their end
  std::optional<double> cycle_s;  // kCompleted: machine seconds of the visit
  std::string reason;             // kFailed
  // kFailed: whether the station had started the run (its status's started_ns). A dispatch the station
  // cancelled, or never received, before starting it goes back to the allocator when the scheduler was
  // waiting for the station's word on it (docs/scheduler.md §5).
  bool started = true;
};

struct Options {
  std::string db_path;  // SQLite file; empty = in memory only (tests, benchmarks)
  std::function<std::chrono::system_clock::time_point()> clock;  // default: system_clock::now
  // With a database, the ended jobs kept in memory beyond the live ones (the newest, by id); the others are
  // read back from the database when asked for, so memory stays flat over months of pallets (issue 39).
  // Idempotency keys are kept twice as many. At least 1. Without a database everything stays.
  std::size_t kept_ended_jobs = 512;
};

// The outcome of a job-creating command.
struct JobResult {
  std::int64_t job_id = 0;
  bool replayed = false;  // the idempotency key was seen before: nothing new happened
  Effects effects;
};

// One visit of the plan (docs/scheduler.md §15): a pallet's operation on a station, projected.
struct PlanRow {
  std::int64_t job = 0;
  int pallet = 0;
  std::string route;                             // "" for a pallet run or a schedule
  int op = 0;                                    // 0-based
  std::string station;                           // "" while the pallet waits
  std::optional<std::int64_t> start_ms, end_ms;  // wall clock, ms since the epoch; none while waiting
  std::string waiting_for;                       // why it waits
};

class Scheduler {
 public:
  // Opens (or creates) the database and loads its state. `programs` must outlive the Scheduler.
  Scheduler(Options options, ProgramSource& programs);
  ~Scheduler();
  Scheduler(const Scheduler&) = delete;
  Scheduler& operator=(const Scheduler&) = delete;

  // After a restart: every dispatch handed out and not yet acknowledged, again with the same id
  // (resent = true), plus anything the loaded state can now send.
  Effects Recover();

  // ---- commands (each carries an idempotency key; a repeated key returns the first outcome) ----
  // Station registration from configuration (offline until announced).
  // `coded_pallets`: a coded-pallet FMS module (station file `coded_pallets = true`) holds pallets 1-127 only
  // (KT-APL seed lines 4081-4083): it is no candidate for pallets 128-255, and an operation listing only such
  // modules refuses them at OPERATE / `pallet run`.
  void ConfigureStation(std::string_view id, std::string_view dialect, bool coded_pallets = false);
  // Every station of the configuration at once: one commit, where a commit each made a new 32-station
  // cell's scheduler wait on 32 fsyncs while every other process of the cell started (docs/operations.md
  // §9.4).
  struct StationSetup {
    std::string id, dialect;
    bool coded_pallets = false;
  };
  void ConfigureStations(const std::vector<StationSetup>& stations);
  void SetPalletMap(std::string_view key, int pallet, const std::vector<std::string>& programs);
  // DEFINE ROUTE: opens each program, extracts UTL and UCY. Throws cell::Error: kNotFound for a missing
  // program, kFailedPrecondition for a program without UCY, kInvalidArgument for a malformed spec.
  RouteView DefineRoute(std::string_view key, const RouteSpec& spec);
  // OPERATE: a new job for the pallet on the route; allocates its first operation at once.
  JobResult Operate(std::string_view key, std::string_view route, int pallet);
  // `pallet run P --station ID`: the pallet's map on one station.
  JobResult RunPallet(std::string_view key, int pallet, std::string_view station);
  // `schedule run FILE --station ID`: runs Okuma schedule program `text` (named `name`) on a station. Each
  // PSELECT run becomes a dispatch (one after another); IF and VSET use the station's common variables.
  // Throws cell::Error kInvalidArgument with the schedule's alarm when it does not parse, kNotFound for an
  // unknown station. An alarm while running fails the job with the alarm as its reason.
  JobResult RunSchedule(std::string_view key, std::string_view name, std::string_view text,
                        std::string_view station);
  Effects Cancel(std::string_view key, std::int64_t job_id,
                 std::string_view reason = "cancelled by operator");

  // ---- observations ----
  Effects StationOnline(std::string_view id, std::string_view dialect);
  Effects StationOffline(std::string_view id);  // liveliness lost
  // condition FAULT (fault = true) or back to NORMAL/WARNING (fault = false).
  Effects StationCondition(std::string_view id, bool fault, std::string_view alarm_code = {},
                           std::string_view alarm_text = {});
  // The station's common variables V1-V200 as it publishes them (all of them, or those that changed).
  Effects StationVariables(std::string_view id, const std::map<int, double>& common);
  // The station's published tool table (the whole table).
  Effects StationTools(std::string_view id, const tooltable::ToolTable& table);
  // The station accepted dispatch `dispatch_id` (reply to the run request).
  Effects DispatchAcknowledged(std::int64_t dispatch_id);
  Effects RunStarted(std::int64_t dispatch_id);
  // Program `program_index` (0-based in the dispatch's list) reached its end: its UCY leaves the backlog.
  Effects ProgramFinished(std::int64_t dispatch_id, int program_index, std::string_view next_program = {});
  // The whole visit ended (last M30). cycle_s: the machine seconds the station measured, if any.
  Effects RunFinished(std::int64_t dispatch_id, std::optional<double> cycle_s = std::nullopt);
  Effects RunFailed(std::int64_t dispatch_id, std::string_view reason);
  // Applies a station's run report: acknowledgement, start, program ends up to programs_done, then the end or
  // the failure, each step only if it has not happened yet (a repeated or older report changes nothing).
  Effects ReportRun(const RunReport& report);
  // The dispatches held by online stations (no fault) that nothing was heard of for `quiet` are sent again
  // (the same id): the station answers with the run as recorded, so an end whose event was lost still
  // settles it (issue 43). The service calls it every few seconds.
  Effects AskSilent(std::chrono::milliseconds quiet);
  // A program changed (or vanished) in the store: routes using it are re-validated.
  Effects ProgramChanged(std::string_view name);

  // ---- estimates (estimates.h; docs/scheduler.md "Estimates") ----
  // Predictions: `predictor` (not owned; nullptr: none, and the backlog counts UCY alone) gives each
  // station's Basis; `ask` queues a prediction the scheduler has no record for and must return at once
  // (PredictionQueue::Ask): it is called with the caller's lock held. Until the answer comes back through
  // PredictionAnswered(), the backlog counts UCY, or nothing, as without a predictor.
  void SetPredictor(Predictor* predictor, std::function<void(const PredictionRequest&)> ask);
  // An answer to a request `ask` was given: kept with the request's revision unless it is transient.
  Effects PredictionAnswered(const PredictionRequest& request, const Predicted& answer);
  // A program's prediction and estimate on every known station; where one is missing it is asked for and
  // shown as not predicted yet. Throws cell::Error(kNotFound) for a program the source does not have.
  ProgramEstimates Estimates(std::string_view program);
  // The projected schedule: every live job's visits from the stations' state now and the allocation rule
  // run forward on the backlog seconds (UCY or estimates); waiting jobs without times.
  std::vector<PlanRow> Plan();

  // ---- queries ----
  std::optional<JobView> Job(std::int64_t id, bool with_decisions = true) const;
  std::vector<JobView> Jobs(bool with_decisions = false) const;  // every job, in id order (tests)
  std::int64_t NewestJobId() const;                              // 0 when there is no job
  // Jobs and dispatches held in memory (tests and the memory benchmark: bounded with a database).
  std::size_t HeldJobs() const;
  std::size_t HeldDispatches() const;
  // The jobs of q without their decisions, one at a time, until visit returns false (a page is full): a
  // listing of any size costs only the page it shows.
  void ForJobs(const JobQuery& q, const std::function<bool(const JobView&)>& visit) const;
  std::vector<StationView> Stations() const;
  std::optional<StationView> Station(std::string_view id) const;
  // False once a dispatch was revoked or ended: the service drops it instead of handing it out late.
  bool DispatchLive(std::int64_t dispatch_id) const;
  std::optional<tooltable::ToolTable> StationToolTable(std::string_view id) const;
  // The scheduler's view of a station's common variables (published values plus VSET writes).
  std::map<int, double> StationCommonVariables(std::string_view id) const;
  std::optional<RouteView> Route(std::string_view name) const;
  std::vector<RouteView> Routes() const;
  std::optional<std::vector<std::string>> PalletMap(int pallet) const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace cell::scheduler
