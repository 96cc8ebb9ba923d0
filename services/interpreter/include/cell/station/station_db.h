// The station's SQLite database (DESIGN §7): the run queue, the CNC's memory (tool table and the variables
// it keeps between programs), the operator panel, discrete inputs and outputs and the outbox of run records
// for the inspection writer. Schema and stepwise migrations from every released version live here.
//
// Thread-safe: one connection, every call (and every transaction) under one mutex.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "cell/store/sqlite.h"
#include "cell/tooltable/tooltable.h"

namespace cell::station {

// A pallet visit handed to the station by the scheduler: run `programs` in order, `repeat` times.
struct Dispatch {
  std::int32_t dispatch_id = 0;
  std::int32_t job_id = 0;
  std::int32_t pallet = 0;
  std::string node;  // program namespace: the station's, then HOST
  std::vector<std::string> programs;
  int repeat = 1;
};

enum class RunState { kQueued, kActive, kCompleted, kFailed, kCancelled };
std::string_view RunStateName(RunState s);  // "QUEUED", "ACTIVE", ... (as stored)

// What the CNC keeps between programs.
struct MemoryImage {
  tooltable::ToolTable tools;
  std::map<std::string, double> variables;  // by the dialect's own names ("L1500", "V5")
};

// The operator panel as persisted (a held machine stays held across a restart of the interpreter).
struct PanelState {
  bool feed_hold = false;
  double feed_override = 1.0;
  double rapid_override = 1.0;
  std::set<int> broken_sockets;       // the operator says the tools there are broken (cellctl station break)
  std::optional<bool> optional_stop;  // the [ENABLE OPTION STOP] switch; unset: the station file's params
  bool operator==(const PanelState&) const = default;
};

// How far a run got; written in the same transaction as the memory it left behind.
struct RunProgress {
  std::int32_t dispatch_id = 0;
  int programs_done = 0;
  // Set when the run ended: its final state, reason, machine seconds, end time and the run record that goes
  // to the outbox (JSON).
  std::optional<RunState> end;
  std::string reason;
  double machine_s = 0;
  std::int64_t finished_ns = 0;
  std::string record;
};

// The run record the outbox hands to the inspection writer (JSON): one per dispatch that ended, completed or
// not (docs/inspection-writer.md). `end` gives its state, reason, machine seconds and end time.
std::string RunRecord(const Dispatch& d, std::string_view station, const RunProgress& end,
                      std::int64_t started_ns);

class StationDb {
 public:
  // Opens (creating) the file and migrates it to the current schema. Throws cell::Error.
  explicit StationDb(const std::filesystem::path& file);

  // Every schema step since the first release (1: state, 2: panel, 3: the tool table as one document,
  // inputs, run progress, 4: discrete outputs).
  static std::vector<store::Migration> Migrations();
  int SchemaVersion();

  // ---- memory ----
  MemoryImage LoadMemory();
  // True once the tool table was given its initial contents (from the station config), so an operator who
  // emptied it does not get the config's tools back at the next start.
  bool ToolsSeeded();
  // Replaces the stored tool table and variables with `m` (which marks the tools seeded), together with the
  // run's progress when given: one transaction.
  void SaveMemory(const MemoryImage& m, const RunProgress* run = nullptr);

  // ---- run queue ----
  std::optional<RunState> FindRun(std::int32_t dispatch_id);
  void Enqueue(const Dispatch& d, std::int64_t received_ns);
  // A dispatch cancelled before it was received, kept ended so that it can never start here.
  void EnqueueCancelled(const Dispatch& d, const std::string& reason, std::int64_t now_ns);
  // Takes the oldest queued dispatch and marks it active, started at `started_ns`, in one step under the
  // database's lock: a cancel (CancelQueued) either lands before, and the run never starts, or after, and
  // finds it active.
  std::optional<Dispatch> TakeNext(std::int64_t started_ns);
  // Ends a dispatch as cancelled if it is still queued; false when the work thread took it meanwhile (or it
  // has ended).
  bool CancelQueued(std::int32_t dispatch_id, const std::string& reason, std::int64_t finished_ns);
  std::vector<Dispatch> Runs(RunState state);
  int Count(RunState state);
  // The lowest dispatch id kept (0 when none): the operator's own runs take ids below it
  // (Station::OnCommand).
  std::int32_t LowestDispatchId();
  // When the run was marked active (0: never) and how many programs of its map it finished.
  std::pair<std::int64_t, int> Progress(std::int32_t dispatch_id);
  // A run's end without memory changes (cancelled while queued, lost at a restart); a record, when given,
  // goes to the outbox in the same transaction.
  void EndRun(const RunProgress& run);
  // A dispatch as the station last recorded it: its state, how far it got and, once ended, how.
  struct RunView {
    Dispatch d;
    RunState state = RunState::kQueued;
    int programs_done = 0;
    std::string reason;
    double machine_s = 0;
    std::int64_t started_ns = 0, finished_ns = 0;
  };
  std::optional<RunView> View(std::int32_t dispatch_id);

  // ---- outbox: run records until the inspection writer has them ----
  std::vector<std::pair<std::int32_t, std::string>> Outbox(int limit);
  void RemoveFromOutbox(std::int32_t dispatch_id);

  // ---- panel, inputs ----
  PanelState LoadPanel();
  void SavePanel(const PanelState& p);
  void SetInputs(const std::map<std::string, double>& inputs);
  std::map<std::string, double> LoadInputs();
  // Discrete outputs: name -> (value, power-up value). SetOutputs keeps each output's power-up value;
  // SavePowerUp makes every output's value its power-up value (KT-APL `(SET)`).
  void SetOutputs(const std::map<std::string, int>& outputs);
  std::map<std::string, std::pair<int, int>> LoadOutputs();
  void SavePowerUp();

 private:
  void WriteProgress(const RunProgress& run);  // caller holds mu_ inside a transaction
  void Insert(const Dispatch& d, RunState state, const std::string& reason, std::int64_t received_ns,
              std::int64_t finished_ns);

  std::mutex mu_;
  store::Database db_;
};

}  // namespace cell::station
