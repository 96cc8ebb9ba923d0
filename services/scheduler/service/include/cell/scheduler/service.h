// Binds the scheduler's decision core to the bus: cellctl commands in, station observations in,
// dispatches out (retried until each station acknowledges), job events and backlog out.
#pragma once

#include <chrono>
#include <condition_variable>
#include <deque>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <thread>

#include "cell/bus/bus.h"
#include "cell/health/health.h"
#include "cell/idl/program_store.h"
#include "cell/idl/run.h"
#include "cell/idl/scheduler.h"
#include "cell/idl/station.h"
#include "cell/program_store/client.h"
#include "cell/scheduler/prediction_queue.h"
#include "cell/scheduler/scheduler.h"
#include "cell/scheduler/station_predictor.h"

namespace cell::scheduler {

class Service {
 public:
  Service(bus::Participant& p, const std::filesystem::path& data_dir);
  ~Service();
  // Registers the configured stations and re-sends unacknowledged dispatches (after a restart).
  void Start();
  void Stop();
  // Main loop: station liveness (heartbeats) and the backlog state topic.
  void Tick();
  bool Healthy() const { return sender_alive_.load(); }

 private:
  cell::SchedulerReply Handle(const cell::SchedulerRequest& r);
  void ListJobs(const cell::SchedulerRequest& r, cell::SchedulerReply& rep) const;
  void Apply(const Effects& e);
  void OnRun(const cell::RunStatus& s);
  void Sender(std::stop_token st);
  void PublishBacklog();
  void PublishJob(std::int64_t id);  // JobInfo on cell/job/state, for viewers
  // Two live processes under one identity (health::Liveness::Conflicts): a FAULT condition naming both, on
  // cell/alarm and, for a station's service, on the station (nothing is dispatched to it until one is gone).
  void CheckDuplicates();
  void UpdateCondition(const std::string& station);  // with mu_ held

  bus::Participant& bus_;
  program_store::Client programs_;
  TextProgramSource source_;
  std::mutex mu_;  // guards sched_ and the bookkeeping below
  Scheduler sched_;
  StationPredictor predictor_;  // predicted cycle times (docs/scheduler.md "Estimates")
  // Its worker predicts off mu_ and takes mu_ only to hand an answer to sched_ (created by Start()).
  std::optional<PredictionQueue> predictions_;
  std::map<std::string, std::string> dialect_;  // configured stations
  std::map<std::string, bool> online_;
  struct Condition {
    bool fault = false;
    std::string code, text;
  };
  std::map<std::string, Condition> reported_;     // the condition each station publishes
  std::map<std::string, std::string> duplicate_;  // service id -> Conflict::Describe(), while it lasts

  struct Outgoing {
    enum Kind { kDispatch, kCancel, kVariables } kind = kDispatch;
    DispatchAction d;                       // kVariables: only d.station
    std::vector<VariableAction> variables;  // kVariables
  };
  void Retry(const Outgoing& o);
  void SendVariables(const Outgoing& o);
  void OnVariables(const cell::StationVariables& v);
  std::mutex out_mu_;
  std::condition_variable out_cv_;
  std::deque<Outgoing> outgoing_;
  std::unique_ptr<bus::Client<cell::RunRequest, cell::RunReply>> run_client_;
  std::map<std::string, std::unique_ptr<bus::Client<cell::StationRequest, cell::StationReply>>>
      command_clients_;
  std::atomic<bool> sender_alive_{false};

  health::Liveness live_;
  bus::Writer<cell::JobStatus> jobs_w_;
  bus::Writer<cell::SchedulerState> state_w_;
  bus::Writer<cell::JobInfo> jobinfo_w_;
  bus::Writer<cell::Alarm> alarm_w_;
  std::chrono::steady_clock::time_point started_;
  std::chrono::steady_clock::time_point asked_;  // the last AskSilent
  // Created by Start(), after the stations are configured and recovery has run.
  std::optional<bus::Reader<cell::StationStatus>> status_r_;
  std::optional<bus::Reader<cell::ToolTable>> tools_r_;
  std::optional<bus::Reader<cell::RunStatus>> runs_r_;
  std::optional<bus::Reader<cell::ProgramChange>> changes_r_;
  std::optional<bus::Reader<cell::StationVariables>> vars_r_;
  std::unique_ptr<bus::Server<cell::SchedulerRequest, cell::SchedulerReply>> server_;
  std::jthread sender_;
};

}  // namespace cell::scheduler
