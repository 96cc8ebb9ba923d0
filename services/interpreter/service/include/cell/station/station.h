// The station side of the interpreter (`cell-interpreter --station ID`): the CNC of one machine.
// It owns the station's tool table and variables (persisted), accepts run requests, runs each
// dispatch's programs through the interpreter library, streams the canonical commands as motion
// segments under the servo's credits, and reports status, run progress and run records.
#pragma once

#include <atomic>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "cell/bus/bus.h"
#include "cell/config/config.h"
#include "cell/idl/inspection.h"
#include "cell/idl/motion.h"
#include "cell/idl/run.h"
#include "cell/idl/station.h"
#include "cell/interp/interp.h"
#include "cell/program_store/client.h"
#include "cell/store/sqlite.h"
#include "cell/tooltable/tooltable.h"

namespace cell::station {

// Maps one canonical command to a servo segment; nullopt for commands the CNC handles itself
// (messages, outputs, tool pre-selection, unit changes, ...). Exposed for tests.
std::optional<cell::MotionSegment> ToSegment(const interp::Canon& c);

class Station {
 public:
  Station(bus::Participant& p, config::StationConfig cfg, const std::filesystem::path& data_dir);
  ~Station();
  void Start();
  void Stop();
  // For the watchdog: the worker thread is alive.
  bool Healthy() const { return worker_alive_.load(); }

 private:
  struct Dispatch {
    int32_t dispatch_id = 0;
    int32_t job_id = 0;
    int32_t pallet = 0;
    std::string node;
    std::vector<std::string> programs;
    int repeat = 1;
  };
  class Env;

  cell::RunReply OnRun(const cell::RunRequest& r);
  cell::StationReply OnCommand(const cell::StationRequest& r);
  void OnProgress(const cell::SegmentProgress& p);
  void Worker(std::stop_token st);
  void Execute(const Dispatch& d, std::stop_token st);
  void RunProgram(const Dispatch& d, const std::string& name, std::stop_token st);
  void Send(cell::MotionSegment seg, std::stop_token st);
  void WaitDrained(std::stop_token st);
  void CheckServo(std::unique_lock<std::mutex>& lk, std::stop_token st);
  void ResendMissing(std::unique_lock<std::mutex>& lk);
  cell::StationReply SetPanel(const cell::StationRequest& r);
  void PublishControl();
  void SetExecution(cell::Execution base);
  void PublishStatus();
  void PublishTools();
  void PublishVariables();
  void PublishRun(const Dispatch& d, cell::RunState state, const std::string& reason = "");
  void SaveRun(int32_t id, const std::string& state, const std::string& reason);
  void SaveTools();
  void FlushOutbox();

  bus::Participant& bus_;
  config::StationConfig cfg_;
  mutable std::mutex db_mu_;
  store::Database db_;
  tooltable::ToolTable tools_;
  uint32_t tools_rev_ = 0, vars_rev_ = 0;
  std::map<std::string, double> vars_;

  // Status (guarded by status_mu_).
  std::mutex status_mu_;
  cell::StationStatus status_;

  // Motion flow control (guarded by motion_mu_).
  std::mutex motion_mu_;
  std::condition_variable motion_cv_;
  int32_t run_id_ = 0;
  uint64_t sent_seq_ = 0, completed_seq_ = 0, credit_seq_ = 0;
  double run_machine_s_ = 0;
  bool servo_alarm_ = false;
  std::string servo_alarm_code_, servo_alarm_text_;
  std::chrono::steady_clock::time_point last_progress_;
  // Written, not yet completed: what the servo has not received is sent again (ResendMissing).
  std::deque<cell::MotionSegment> unacked_;
  uint64_t received_seq_ = 0;  // the servo holds 1..received_seq_ of this run (its last progress)
  uint64_t seg_matches_ = 0;   // seg_w_.TotalMatched() at the last check
  std::chrono::steady_clock::time_point last_report_, last_resend_;  // progress of this run; re-send
  uint64_t run_boot_ = 0;                                            // the servo this run started on
  bool servo_restarted_ = false;         // progress came from another servo process mid-run
  std::atomic<bool> servo_held_{false};  // the servo reports the operator's feed hold in effect

  // The operator's panel (guarded by status_mu_, persisted): feed hold and overrides for the servo.
  cell::ServoControl control_;
  cell::Execution base_execution_ = cell::EXECUTION_READY;  // what the run state alone says

  // Current run bookkeeping.
  int64_t run_started_ns_ = 0;
  int32_t programs_done_ = 0;
  std::string program_;
  std::atomic<int32_t> cancel_id_{0};
  double probe_feed_ = 500.0;  // mm/min for probe moves the program does not feed itself

  std::mutex queue_mu_;
  std::condition_variable queue_cv_;

  std::atomic<bool> worker_alive_{false};

  bus::Writer<cell::StationStatus> status_w_;
  bus::Writer<cell::ToolTable> tools_w_;
  bus::Writer<cell::StationVariables> vars_w_;
  bus::Writer<cell::RunStatus> run_w_;
  bus::Writer<cell::MotionSegment> seg_w_;
  bus::Writer<cell::ServoControl> control_w_;
  bus::Reader<cell::SegmentProgress> progress_r_;
  bus::Reader<cell::ProbeResult> probe_r_;
  program_store::Client programs_;
  bus::Client<cell::InspectionRequest, cell::InspectionReply> inspection_;
  std::unique_ptr<bus::Server<cell::RunRequest, cell::RunReply>> run_srv_;
  std::unique_ptr<bus::Server<cell::StationRequest, cell::StationReply>> cmd_srv_;
  std::jthread worker_;
};

}  // namespace cell::station
