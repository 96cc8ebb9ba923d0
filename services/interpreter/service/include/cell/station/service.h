// cell-interpreter's bus binding: the station core (cell/station/station.h) on DDS. Run requests and station
// commands are served, servo progress and probe results fed in, the core's publications written to their
// topics, segments to cell/station/<ID>/segments, and one worker thread runs the dispatches.
#pragma once

#include <atomic>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "cell/bus/bus.h"
#include "cell/config/config.h"
#include "cell/dnc/client.h"
#include "cell/idl/dnc.h"
#include "cell/idl/inspection.h"
#include "cell/idl/motion.h"
#include "cell/idl/run.h"
#include "cell/idl/station.h"
#include "cell/program_store/client.h"
#include "cell/station/silent_service.h"
#include "cell/station/station.h"

namespace cell::station {

class Service final : public StationIo, public ServoLink {
 public:
  Service(bus::Participant& p, config::StationConfig cfg, const std::filesystem::path& data_dir);
  ~Service() override;
  void Start();
  void Stop();
  // For the watchdog: the worker thread is alive.
  bool Healthy() const { return worker_alive_.load(); }

  // StationIo
  void PublishStatus(const cell::StationStatus& s) override { status_w_.Write(s); }
  void PublishTools(const cell::ToolTable& t) override {
    tools_w_.Write(t);        // the cell's view: scheduler, cellctl, dashboard
    servo_tools_w_.Write(t);  // this station's axis servo only (topics::ServoTools)
  }
  void PublishVariables(const cell::StationVariables& v) override { vars_w_.Write(v); }
  void PublishIo(const cell::StationIoState& s) override { io_w_.Write(s); }
  void PublishEvent(const cell::StationEvent& e) override { event_w_.Write(e); }
  void PublishProgram(const cell::StationProgram& p) override { program_w_.Write(p); }
  void PublishRun(const cell::RunStatus& r) override { run_w_.Write(r); }
  void PublishControl(const cell::ServoControl& c) override { control_w_.Write(c); }
  bool WaitForProgramStore(Clock::Duration timeout) override {
    return programs_.WaitForServer(std::chrono::duration_cast<bus::Millis>(timeout));
  }
  std::optional<std::string> Program(const std::string& node, const std::string& name) override {
    return silent_.Call(station_id_, [&] { return programs_.GetWithFallback(node, name); });
  }
  std::optional<std::string> SelectedProgram(const std::string& station) override;
  std::optional<std::string> ProgramIn(const std::string& node, const std::string& name) override {
    return silent_.Call(station_id_, [&] { return programs_.Get(node, name); });
  }
  std::optional<std::string> PartModel(const std::string& node, const std::string& name) override;
  bool DeleteFile(const std::string& node, const std::string& name, const std::string& key) override;
  void SaveFile(const std::string& node, const std::string& name, const std::string& text,
                const SaveAs& as) override {
    program_store::Client::PutOptions o;
    o.node = node;
    o.force = true;
    o.dialect = as.dialect;
    o.file_type = as.file_type;
    o.idempotency_key = as.idempotency_key;
    silent_.Call(station_id_, [&] { programs_.Put(name, text, o); });
  }
  bool StoreRecord(const cell::InspectionRequest& request) override;
  std::optional<std::string> LineRead(const std::string& holder) override;
  void LineWrite(const std::string& holder, const std::string& record) override;
  // ServoLink
  void Write(const cell::MotionSegment& segment) override { seg_w_.Write(segment); }
  std::size_t Matched() override { return static_cast<std::size_t>(seg_w_.Matched()); }
  std::uint64_t TotalMatched() override { return seg_w_.TotalMatched(); }
  bool WaitForServo(Clock::Duration timeout) override;
  void WritePart(const cell::PartModel& part) override { part_w_.Write(part); }
  void Rejoin() override { bus_.Rejoin(); }

 private:
  bus::Participant& bus_;
  SystemClock clock_;
  // Around the worker thread's calls to a host service (never a command handler's: SelectedProgram).
  SilentServiceRejoin silent_{clock_, [this] { bus_.Rejoin(); }};
  bus::Writer<cell::StationStatus> status_w_;
  bus::Writer<cell::ToolTable> tools_w_;
  bus::Writer<cell::StationVariables> vars_w_;
  bus::Writer<cell::StationIoState> io_w_;
  bus::Writer<cell::StationEvent> event_w_;
  bus::Writer<cell::StationProgram> program_w_;
  bus::Writer<cell::RunStatus> run_w_;
  bus::Writer<cell::MotionSegment> seg_w_;
  bus::Writer<cell::ServoControl> control_w_;
  bus::Writer<cell::ToolTable> servo_tools_w_;
  bus::Writer<cell::PartModel> part_w_;
  program_store::Client programs_;
  bus::Client<cell::InspectionRequest, cell::InspectionReply> inspection_;
  Station station_;  // after the endpoints it uses, before the readers that feed it
  bus::Reader<cell::SegmentProgress> progress_r_;
  bus::Reader<cell::ProbeResult> probe_r_;
  // A station with a [serial] line: its cell-dnc, for the Okuma READ/WRITE, and the line's state, so that a
  // READ/WRITE while `cellctl dnc` transfers is refused at once (cell-dnc answers requests one at a time).
  std::string station_id_;
  std::mutex dnc_mu_;
  std::optional<cell::DncStatus> dnc_state_;  // under dnc_mu_
  std::unique_ptr<dnc::Client> dnc_;
  std::unique_ptr<bus::Reader<cell::DncStatus>> dnc_state_r_;
  cell::DncReply DncCall(cell::DncOp op, const std::string& holder, const std::string& record, bus::Millis t);
  std::unique_ptr<bus::Server<cell::RunRequest, cell::RunReply>> run_srv_;
  std::unique_ptr<bus::Server<cell::StationRequest, cell::StationReply>> cmd_srv_;
  std::atomic<bool> worker_alive_{false};
  std::jthread worker_;
};

}  // namespace cell::station
