#include "cell/station/service.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "cell/bus/topics.h"
#include "cell/error/error.h"

namespace cell::station {

Service::Service(bus::Participant& p, config::StationConfig cfg, const std::filesystem::path& data_dir)
    : bus_(p),
      status_w_(p, bus::topics::kStationStatus, bus::QosKind::kState),
      tools_w_(p, bus::topics::kToolTable, bus::QosKind::kState),
      vars_w_(p, bus::topics::kVariables, bus::QosKind::kState),
      io_w_(p, bus::topics::kStationIo, bus::QosKind::kState),
      event_w_(p, bus::topics::kStationEvent, bus::QosKind::kEvent),
      program_w_(p, bus::topics::kStationProgram, bus::QosKind::kState),
      run_w_(p, bus::topics::kRunStatus, bus::QosKind::kEvent),
      seg_w_(p, bus::topics::Segments(cfg.id), bus::QosKind::kStream),
      control_w_(p, bus::topics::ServoControl(cfg.id), bus::QosKind::kState),
      servo_tools_w_(p, bus::topics::ServoTools(cfg.id), bus::QosKind::kState),
      part_w_(p, bus::topics::Part(cfg.id), bus::QosKind::kState),
      programs_(p),
      inspection_(p, bus::topics::kInspection),
      station_(cfg, data_dir / ("interpreter-" + cfg.id + ".db"), *this, *this, clock_),
      progress_r_(p, bus::topics::Progress(cfg.id), bus::QosKind::kState,
                  [this](const cell::SegmentProgress& s, const bus::SampleInfo&) { station_.OnProgress(s); }),
      probe_r_(p, bus::topics::Probe(cfg.id), bus::QosKind::kCommand,
               [this](const cell::ProbeResult& r, const bus::SampleInfo&) { station_.OnProbe(r); }),
      station_id_(cfg.id) {
  if (!cfg.serial || cfg.dialect != "okuma") return;  // READ/WRITE are the Okuma User Task's alone
  dnc_ = std::make_unique<dnc::Client>(p, cfg.id);
  dnc_state_r_ = std::make_unique<bus::Reader<cell::DncStatus>>(
      p, bus::topics::kDncStatus, bus::QosKind::kState,
      [this](const cell::DncStatus& s, const bus::SampleInfo&) {
        if (s.station().to_string() != station_id_) return;
        std::lock_guard lk(dnc_mu_);
        dnc_state_ = s;
      });
}

Service::~Service() {
  Stop();
}

namespace {

// The audit trail: what a dispatch or a panel command asks for (every one changes something).
std::string DescribeRun(const cell::RunRequest& r) {
  return fmt::format("{} {} (job {}, pallet {})", r.cancel() ? "cancel of dispatch" : "dispatch",
                     r.dispatch_id(), r.job_id(), r.pallet());
}

std::string DescribeCommand(const cell::StationRequest& r) {
  switch (r.op()) {
    case cell::STATION_SET_VARIABLES:
      return fmt::format("set {} variable(s)", r.variables().size());
    case cell::STATION_SET_INPUT:
      return fmt::format("set {} input(s)", r.variables().size());
    case cell::STATION_LOAD_TOOLS:
      return "tool load";
    case cell::STATION_RESET:
      return "reset";
    case cell::STATION_FEED_HOLD:
      return "feed hold";
    case cell::STATION_CYCLE_START:
      return "cycle start";
    case cell::STATION_OVERRIDE:
      return fmt::format("override feed {} rapid {}", r.feed_override(), r.rapid_override());
    case cell::STATION_BREAK_TOOL:
      return fmt::format("{} socket {}", r.mend() ? "mend" : "break", r.socket());
    case cell::STATION_OPTIONAL_STOP:
      return fmt::format("optional stop {}", r.optional_stop() ? "on" : "off");
  }
  return "command";
}

}  // namespace

void Service::Start() {
  station_.Start();
  const std::string id = station_.Status().station().to_string();
  run_srv_ = std::make_unique<bus::Server<cell::RunRequest, cell::RunReply>>(
      bus_, bus::topics::kStationRun, [this](const cell::RunRequest& r) { return station_.OnRun(r); },
      DescribeRun, [id](const cell::RunRequest& r) { return r.station() == id; });
  cmd_srv_ = std::make_unique<bus::Server<cell::StationRequest, cell::StationReply>>(
      bus_, bus::topics::StationCommand(id),
      [this](const cell::StationRequest& r) {
        // The scheduler writes this topic to set variables (schedule VSET); the panel verbs are the
        // operator's (docs/security.md, "Partitions").
        if (bus::RequesterIdentity() == "scheduler" && r.op() != cell::STATION_SET_VARIABLES)
          throw Error(Errc::kPermissionDenied, "identity 'scheduler' may only set variables on a station");
        return station_.OnCommand(r);
      },
      DescribeCommand);
  worker_ = std::jthread([this] {
    worker_alive_ = true;
    station_.Work();
    worker_alive_ = false;
  });
}

void Service::Stop() {
  if (worker_.joinable()) {
    station_.RequestStop();
    worker_.join();
  }
  run_srv_.reset();
  cmd_srv_.reset();
}

// The memories MP1 (the station's namespace), MP0, MP2..MP6 (docs/dialects/balt.md, "Memories"), each
// listed for the file SPG flagged; a memory the store has never held is skipped. Asked from a command's
// handler (START), so never through silent_: a rejoin there would remake the server it is running in.
std::optional<std::string> Service::SelectedProgram(const std::string& station) {
  for (const char* memory : {"", "/MP0", "/MP2", "/MP3", "/MP4", "/MP5", "/MP6"}) {
    const std::string node = station + memory;
    nlohmann::json files;
    try {
      files = programs_.List(node, "*");
    } catch (const Error& e) {
      if (e.code() == Errc::kNotFound) continue;
      throw;
    }
    for (const auto& f : files)
      if (f.value("selected", false)) return node + ":" + f.value("name", std::string());
  }
  return std::nullopt;
}

std::optional<std::string> Service::PartModel(const std::string& node, const std::string& name) {
  auto f = silent_.Call(station_id_, [&] { return programs_.FetchWithFallback(node, name); });
  if (!f || !f->info.is_object() || f->info.value("type", std::string()) != "part_model") return std::nullopt;
  return std::move(f->content);
}

bool Service::DeleteFile(const std::string& node, const std::string& name, const std::string& key) {
  try {
    silent_.Call(station_id_, [&] { programs_.Delete(node, name, key); });
    return true;
  } catch (const Error& e) {
    if (e.code() == Errc::kNotFound) return false;
    throw;
  }
}

bool Service::StoreRecord(const cell::InspectionRequest& request) {
  if (!inspection_.WaitForServer(bus::Millis(0))) return false;
  bus::ThrowIfError(
      silent_.Call(station_id_, [&] { return inspection_.Call(request, std::chrono::seconds(5)); }));
  return true;
}

// The Okuma READ/WRITE through the station's cell-dnc (docs/dnc.md "Okuma READ/WRITE"): refused at once
// while the line carries a `cellctl dnc` transfer; one line naming cell-dnc when none answers.
cell::DncReply Service::DncCall(cell::DncOp op, const std::string& holder, const std::string& record,
                                bus::Millis timeout) {
  if (!dnc_) throw Error(Errc::kFailedPrecondition, "no [serial] table");
  auto busy = [&]() -> std::string {
    std::lock_guard lk(dnc_mu_);
    if (!dnc_state_) return "";
    const cell::DncState st = dnc_state_->state();
    if (st != cell::DNC_SENDING && st != cell::DNC_RECEIVING && st != cell::DNC_DRIPPING) return "";
    return fmt::format("busy: cell-dnc@{} is {} {} (cellctl dnc), {} refused", station_id_,
                       dnc::StateName(st), dnc_state_->program().to_string(), dnc::OpName(op));
  };
  if (std::string why = busy(); !why.empty()) throw Error(Errc::kFailedPrecondition, why);
  try {
    return dnc_->Record(op, holder, record, timeout);
  } catch (const Error& e) {
    if (e.code() != Errc::kTimeout && e.code() != Errc::kUnavailable) throw;
    if (std::string why = busy(); !why.empty()) throw Error(Errc::kFailedPrecondition, why);
    const std::string what = e.what();
    if (what.find(" service on DDS domain") != std::string::npos || e.code() == Errc::kTimeout)
      throw Error(e.code(),
                  fmt::format("no DNC process: cell-dnc@{} does not answer ({})", station_id_, what));
    throw;
  }
}

std::optional<std::string> Service::LineRead(const std::string& holder) {
  const cell::DncReply rep = DncCall(cell::DNC_READ, holder, "", bus::Millis(5000));
  if (!nlohmann::json::parse(rep.info().to_string(), nullptr, false).value("done", false))
    return std::nullopt;
  return std::string(rep.data().begin(), rep.data().end());
}

void Service::LineWrite(const std::string& holder, const std::string& record) {
  // The line's own limits end a WRITE the device holds up (XOFF for 30 s); 160 characters at 110 baud is 15
  // s.
  DncCall(cell::DNC_WRITE, holder, record, bus::Millis(60000));
}

bool Service::WaitForServo(Clock::Duration timeout) {
  const auto ms = std::chrono::duration_cast<bus::Millis>(timeout);
  return seg_w_.WaitForMatched(1, ms) && progress_r_.WaitForMatched(1, ms);
}

}  // namespace cell::station
