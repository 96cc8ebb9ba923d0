// The station core: one station's CNC without DDS (DESIGN §2, "every service keeps its logic in a library
// that tests use without DDS"). It owns the run queue, the CNC's memory (tool table and variables), the
// operator panel and the station's status; it runs each dispatch's programs through the interpreter library
// and streams the canonical commands to the axis servo as motion segments under the servo's credits.
//
// The service (services/interpreter/service) binds it to the bus: requests and samples go in through the
// On* calls (from any thread), publications and program fetches go out through StationIo, segments through
// ServoLink, and a worker thread calls Work(). Tests drive it the same way with fakes and a fake Clock.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <optional>
#include <string>

#include "cell/config/config.h"
#include "cell/error/error.h"
#include "cell/idl/inspection.h"
#include "cell/idl/motion.h"
#include "cell/idl/run.h"
#include "cell/idl/station.h"
#include "cell/interp/serial.h"
#include "cell/station/clock.h"
#include "cell/station/io.h"
#include "cell/station/memory.h"
#include "cell/station/panel.h"
#include "cell/station/segment_stream.h"
#include "cell/station/station_db.h"
#include "cell/station/to_segment.h"

namespace cell::station {

// Everything the core says or asks outside of the servo link.
class StationIo {
 public:
  virtual ~StationIo() = default;
  virtual void PublishStatus(const cell::StationStatus& s) = 0;
  virtual void PublishTools(const cell::ToolTable& t) = 0;
  virtual void PublishVariables(const cell::StationVariables& v) = 0;
  virtual void PublishIo(const cell::StationIoState& s) = 0;
  virtual void PublishEvent(const cell::StationEvent& e) = 0;      // what a program records (KT-APL EVT)
  virtual void PublishProgram(const cell::StationProgram& p) = 0;  // the text a run's program starts with
  virtual void PublishRun(const cell::RunStatus& r) = 0;
  virtual void PublishControl(const cell::ServoControl& c) = 0;
  // True once a program store answers on the bus (within `timeout`): a run does not start, and lose its
  // pallet, while the store is restarting.
  virtual bool WaitForProgramStore(Clock::Duration timeout) = 0;
  // A program's text from the program store: namespace `node`, then HOST; nullopt when in neither.
  virtual std::optional<std::string> Program(const std::string& node, const std::string& name) = 0;
  // The program selected for execution in one of `station`'s memories (Balt-System SPG), as a map entry
  // "BS01/MP2:P9" ("BS01:P9" for MP1); nullopt when none is. Throws cell::Error when the store did not
  // answer.
  virtual std::optional<std::string> SelectedProgram(const std::string& station) = 0;
  // A program's text from namespace `node` alone (a pallet map's "BS01/MP2:P9"); nullopt when not there.
  virtual std::optional<std::string> ProgramIn(const std::string& node, const std::string& name) = 0;
  // The text of `name` when the store keeps it as a part model (type part_model), `node` then HOST; nullopt
  // for any other file or none (a pallet map's entries: docs/station.md, "Part models").
  virtual std::optional<std::string> PartModel(const std::string& node, const std::string& name) = 0;
  // Deletes a file a program names (KT-APL DLF) from namespace `node`; false when it was not there. Throws
  // cell::Error when the store refused (a protected file) or did not answer.
  virtual bool DeleteFile(const std::string& node, const std::string& name, const std::string& key) = 0;
  // How a saved file is declared to the program store ("" = detected from name and content) and the key that
  // makes a retried save one revision ("" = none).
  struct SaveAs {
    std::string dialect, file_type, idempotency_key;
  };
  // Stores a file a program saved (a new revision over an existing one): Balt-System's origins and tool life
  // files (FILEOR, GE1TOL on MP3), KT-APL's inspection and data files. Throws cell::Error when the store
  // refused it or did not answer.
  virtual void SaveFile(const std::string& node, const std::string& name, const std::string& text,
                        const SaveAs& as) = 0;
  // Hands a run record to the inspection writer: false when no writer is there (the record stays in the
  // outbox); throws cell::Error when the writer refused it or did not answer.
  virtual bool StoreRecord(const cell::InspectionRequest& request) = 0;
  // The station's serial line through its cell-dnc (Okuma READ/WRITE, docs/dnc.md "Okuma READ/WRITE"), for
  // the run `holder` ("dispatch 12"). LineRead starts a READ of one record, or asks after the one started:
  // the record once it has arrived, nullopt while it has not. LineWrite returns when the record and its end
  // code are on the line. Both throw cell::Error with the one-line reason: refused (the line is busy with a
  // transfer), the line failed, no cell-dnc answering.
  virtual std::optional<std::string> LineRead(const std::string& holder) {
    (void)holder;
    throw Error(Errc::kUnavailable, "no DNC link in this process");
  }
  virtual void LineWrite(const std::string& holder, const std::string& record) {
    (void)holder;
    (void)record;
    throw Error(Errc::kUnavailable, "no DNC link in this process");
  }
};

struct StationOptions {
  double probe_feed = 500.0;  // mm/min for probe moves the program does not feed itself
  Clock::Duration writer_wait = std::chrono::seconds(60);      // for an inspection writer at a file's close
  Clock::Duration servo_wait = std::chrono::seconds(10);       // for a servo on the bus at a run's start
  Clock::Duration store_wait = std::chrono::seconds(30);       // for the program store at a run's start
  Clock::Duration idle_poll = std::chrono::milliseconds(500);  // outbox retries while idle
  Clock::Duration status_period = std::chrono::milliseconds(100);  // status while a run goes on
};

class Station {
 public:
  Station(config::StationConfig cfg, const std::filesystem::path& db_file, StationIo& io, ServoLink& link,
          Clock& clock, StationOptions options = {});
  Station(const Station&) = delete;
  Station& operator=(const Station&) = delete;

  // Publishes tools, variables, the I/O, the panel and the status once (state topics: late joiners get them).
  void Start();

  // ---- from the bus (any thread) ----
  // A dispatch (queued once per dispatch id: a re-sent request gets the state it has) or a cancel.
  cell::RunReply OnRun(const cell::RunRequest& r);
  // Tool loads, variables, inputs (a run waiting for them goes on), reset and the panel's buttons. Throws
  // cell::Error for a bad request.
  cell::StationReply OnCommand(const cell::StationRequest& r);
  void OnProgress(const cell::SegmentProgress& p);
  void OnProbe(const cell::ProbeResult& r);

  // ---- the worker ----
  // Runs that were ACTIVE when the process died did not finish: each is reported FAILED, never silently.
  void Recover();
  // Executes the next queued dispatch to its end; false when none is queued.
  bool RunNext();
  // Hands stored run records to the inspection writer (until it is missing or refuses one).
  void FlushOutbox();
  // Recover(), then runs dispatches as they come and flushes the outbox while idle, until RequestStop().
  void Work();
  void RequestStop();

  // ---- views (tests, the service's health) ----
  MemorySnapshot MemoryState() const { return memory_.Get(); }
  IoState Io() const { return dio_.Get(); }
  cell::StationStatus Status() const { return board_.Get(); }
  cell::ServoControl Control() const { return panel_.Get(); }

 private:
  struct ActiveRun;
  class RunEnvironment;

  void Execute(const Dispatch& d, std::int64_t started_ns);  // taken from the queue, marked active
  void RunProgram(ActiveRun& run, const std::string& entry);
  bool StartSelected();
  std::optional<std::string> ReadProgram(const std::string& node, const std::string& entry);
  void PublishProgram(const Dispatch& d, const std::string& name, const std::string& text);
  std::vector<bool> SendPartModel(const Dispatch& d);
  void ProgramStop(const std::string& program, int line, const interp::StopOp& stop);
  // KT-APL WAI (interp::Environment::WaitInputs): after the motion before it, until the inputs match.
  void WaitInputs(const std::string& spec);
  // Okuma READ/WRITE (interp::SerialChannel) on the station's [serial] line, after the motion before them; a
  // READ waits until a record arrives or the run ends (a cancel, the station's stop).
  interp::SerialChannel::Result SerialRead(std::int32_t dispatch_id);
  interp::SerialChannel::Result SerialWrite(std::int32_t dispatch_id, const std::string& record);
  // OutputOp and the station file's M codes; throws cell::Error to stop the run.
  void ExecuteIo(const std::string& program, const interp::Canon& c, AuxIo& aux);
  void Checkpoint(std::int32_t run_id) const;  // throws when the run was cancelled or the station stops
  void PublishRun(const ActiveRun& run, cell::RunState state, const std::string& reason = "");
  // The dispatch's status as the database has it (none for an unknown id); PublishRecorded says it again on
  // the run topic (a scheduler waiting for its end).
  std::optional<cell::RunStatus> Recorded(std::int32_t dispatch_id);
  void PublishRecorded(std::int32_t dispatch_id);
  void PublishMemory(const MemorySnapshot& now, bool tools, bool variables);

  const config::StationConfig cfg_;
  const StationOptions options_;
  StationIo& io_;
  Clock& clock_;
  StationDb db_;
  StatusBoard board_;
  Panel panel_;
  Memory memory_;
  DiscreteIo dio_;
  SegmentStream stream_;
  RotaryUnwrap unwrap_;  // A and C as the servo runs them, within a run (from the zero: ToArrival)
  std::atomic<std::int32_t> cancel_id_{0};
  std::atomic<bool> stop_{false};
  std::mutex work_mu_;  // for work_cv_ and work_pending_ only: the queue itself is in db_
  std::condition_variable work_cv_;
  bool work_pending_ = false;  // a dispatch was queued since the worker last looked
};

}  // namespace cell::station
