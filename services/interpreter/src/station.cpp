#include "cell/station/station.h"

#include <algorithm>

#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>

#include "cell/error/error.h"
#include "cell/interp/interp.h"
#include "cell/interp/station_rules.h"
#include "cell/names/names.h"
#include "cell/tooltable/wire.h"

namespace cell::station {

namespace {

cell::RunState ToWire(RunState s) {
  switch (s) {
    case RunState::kQueued:
      return cell::RUN_QUEUED;
    case RunState::kActive:
      return cell::RUN_ACTIVE;
    case RunState::kCompleted:
      return cell::RUN_COMPLETED;
    case RunState::kFailed:
      return cell::RUN_FAILED;
    case RunState::kCancelled:
      return cell::RUN_CANCELLED;
  }
  return cell::RUN_QUEUED;
}

cell::StationVariables VariablesToWire(const std::string& station, const std::map<std::string, double>& vars,
                                       std::uint32_t revision) {
  cell::StationVariables v;
  v.station(station);
  v.revision(revision);
  for (const auto& [name, value] : vars) {
    cell::Variable x;
    x.name(name);
    x.value(value);
    v.variables().push_back(x);
  }
  return v;
}

cell::StationIoState IoToWire(const std::string& station, const IoState& io) {
  cell::StationIoState s;
  s.station(station);
  s.revision(io.revision);
  auto point = [&](const std::string& name, int value) {
    cell::IoPoint p;
    p.name(name);
    p.value(value);
    auto it = io.power_up.find(name);
    p.power_up(it == io.power_up.end() ? 0 : it->second);
    return p;
  };
  for (const auto& [n, v] : io.inputs) s.inputs().push_back(point(n, v));
  for (const auto& [n, v] : io.outputs) s.outputs().push_back(point(n, v));
  return s;
}

}  // namespace

std::int64_t SystemClock::WallNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

Station::Station(config::StationConfig cfg, const std::filesystem::path& db_file, StationIo& io,
                 ServoLink& link, Clock& clock, StationOptions options)
    : cfg_(std::move(cfg)),
      options_(options),
      io_(io),
      clock_(clock),
      db_(db_file),
      board_(cfg_.id, cfg_.dialect, clock_, [this](const cell::StationStatus& s) { io_.PublishStatus(s); }),
      panel_(cfg_.id, db_, [this](const cell::ServoControl& c) { io_.PublishControl(c); }),
      memory_(db_, cfg_.dialect, cfg_.tools,
              [this](const MemorySnapshot& now, bool tools, bool vars) { PublishMemory(now, tools, vars); }),
      dio_(db_, cfg_.aux, [this](const IoState& s) { io_.PublishIo(IoToWire(cfg_.id, s)); }),
      stream_(cfg_.id, clock_, link) {
  board_.Queued(db_.Count(RunState::kQueued));
}

void Station::Start() {
  memory_.Announce();
  dio_.Announce();
  panel_.Publish();
  board_.Publish();
}

void Station::PublishMemory(const MemorySnapshot& now, bool tools, bool variables) {
  if (tools) io_.PublishTools(tooltable::ToWire(now.image.tools, cfg_.id, now.tools_revision));
  if (variables) io_.PublishVariables(VariablesToWire(cfg_.id, now.image.variables, now.variables_revision));
}

cell::RunReply Station::OnRun(const cell::RunRequest& r) {
  cell::RunReply rep;
  rep.station(cfg_.id);
  rep.dispatch_id(r.dispatch_id());
  if (r.station() != cfg_.id)
    throw Error(Errc::kInvalidArgument, "run request for " + r.station().to_string() + " reached " + cfg_.id);
  if (r.dispatch_id() <= 0) throw Error(Errc::kInvalidArgument, "dispatch id must be positive");
  const std::optional<RunState> state = db_.FindRun(r.dispatch_id());
  if (r.cancel()) {
    std::optional<RunState> now = state;
    bool say = false;  // on the run topic as well as in the reply
    if (now == RunState::kQueued) {
      if (db_.CancelQueued(r.dispatch_id(), "cancelled by the scheduler", clock_.WallNs())) {
        board_.Queued(db_.Count(RunState::kQueued));
        board_.Publish();
      } else {
        now = db_.FindRun(r.dispatch_id());  // the work thread took it meanwhile: cancelled as running
      }
    }
    if (now == RunState::kActive) {
      cancel_id_ = r.dispatch_id();
      panel_.AbortRun(r.dispatch_id());  // the machine stops too, not only the sending
      stream_.Wake();
    } else if (now) {
      say = true;  // cancelled now, or ended before the cancel came: said (again)
    } else {
      // Never received: kept as cancelled, so that the request itself, arriving late, cannot start it, and
      // said on the run topic, since the scheduler may be waiting for this station's word on it
      // (docs/scheduler.md §5). It never started here (started_ns 0).
      Dispatch d;
      d.dispatch_id = r.dispatch_id();
      d.job_id = r.job_id();
      d.pallet = r.pallet();
      d.node = cfg_.id;
      for (const auto& p : r.programs()) d.programs.push_back(p.to_string());
      db_.EnqueueCancelled(d, "cancelled by the scheduler before the station received it", clock_.WallNs());
      say = true;
    }
    rep.state(state ? ToWire(*state) : cell::RUN_CANCELLED);
    if (const auto run = Recorded(r.dispatch_id())) {
      if (say) io_.PublishRun(*run);
      rep.run(*run);
    }
    return rep;
  }
  if (state) {  // a re-sent dispatch (scheduler restart, station back online): de-duplicated on the id
    // An ended run is said again: its end may have been published by a process that died before anyone read
    // it, and the scheduler asks because it is still waiting for it.
    // The reply says it too: an event lost on the way would otherwise leave the scheduler waiting.
    rep.state(ToWire(*state));
    if (const auto run = Recorded(r.dispatch_id())) {
      if (*state != RunState::kQueued && *state != RunState::kActive) io_.PublishRun(*run);
      rep.run(*run);
    }
    return rep;
  }
  if (r.programs().empty() || r.programs().size() > 75)
    throw Error(Errc::kInvalidArgument, "a pallet map names 1 to 75 programs");
  if (r.repeat() < 0 || r.repeat() > 9999)
    throw Error(Errc::kInvalidArgument, "repeat count must be 1..9999");
  Dispatch d;
  d.dispatch_id = r.dispatch_id();
  d.job_id = r.job_id();
  d.pallet = r.pallet();
  d.node = r.node().to_string().empty() ? cfg_.id : r.node().to_string();
  for (const auto& p : r.programs()) d.programs.push_back(p.to_string());
  d.repeat = r.repeat() == 0 ? 1 : r.repeat();
  db_.Enqueue(d, clock_.WallNs());
  spdlog::info("accepted dispatch {} (job {}, pallet {}, {} program(s))", d.dispatch_id, d.job_id, d.pallet,
               d.programs.size());
  board_.Queued(db_.Count(RunState::kQueued));
  board_.Publish();
  {
    std::lock_guard lk(work_mu_);
    work_pending_ = true;
    work_cv_.notify_all();
  }
  rep.state(cell::RUN_QUEUED);
  return rep;
}

cell::StationReply Station::OnCommand(const cell::StationRequest& r) {
  cell::StationReply rep;
  rep.station(cfg_.id);
  switch (r.op()) {
    case cell::STATION_LOAD_TOOLS: {
      // The station's own tool-table form (KT-APL: a program of TLD statements), on top of the table; a
      // coded-pallet station's pallets are 1-127 (station_rules.h).
      const std::string text = r.text().to_string();
      rep.revision(memory_.ChangeTools(
          [&](tooltable::ToolTable& t) { t = interp::ParseStationTools(cfg_, text, "tools", t); }));
      const auto tools = memory_.Get().image.tools;
      spdlog::info("tool table loaded: {} tools, {} process compensations", tools.entries().size(),
                   tools.process_comps().size());
      return rep;
    }
    case cell::STATION_SET_VARIABLES: {
      std::map<std::string, double> values;
      for (const auto& v : r.variables()) values[v.name().to_string()] = v.value();
      if (values.empty()) throw Error(Errc::kInvalidArgument, "no variable to set");
      rep.revision(memory_.SetVariables(values));
      return rep;
    }
    case cell::STATION_SET_INPUT: {
      std::vector<IoBit> bits;
      for (const auto& v : r.variables()) {
        if (v.value() != 0 && v.value() != 1) throw Error(Errc::kInvalidArgument, "an input is 0 or 1");
        bits.push_back({v.name().to_string(), v.value() == 1 ? 1 : 0});
      }
      rep.revision(dio_.SetInputs(bits));
      stream_.Wake();  // a run waiting in WAI looks again now
      return rep;
    }
    case cell::STATION_RESET:
      board_.Reset();
      board_.Publish();
      return rep;
    case cell::STATION_CYCLE_START:
      rep.revision(panel_.Press(r));
      stream_.Wake();  // a run stopped at M00 looks again now
      StartSelected();
      return rep;
    case cell::STATION_FEED_HOLD:
    case cell::STATION_OVERRIDE:
    case cell::STATION_BREAK_TOOL:
    case cell::STATION_OPTIONAL_STOP:
      rep.revision(panel_.Press(r));
      stream_.Wake();  // a run stopped at M00 looks again now
      return rep;
  }
  throw Error(Errc::kInvalidArgument, "unknown station command");
}

// Balt-System's START with nothing running executes the program SPG selected (manual ln 8873-8888), as a run
// of the station's own: no job, no pallet, a dispatch id below every other (the scheduler's are positive and
// it ignores these). Nothing selected is FILMS4 54 (ln 10079-10080). Other dialects run dispatches only.
bool Station::StartSelected() {
  if (cfg_.dialect != "balt") return false;
  if (db_.Count(RunState::kActive) > 0 || db_.Count(RunState::kQueued) > 0) return false;  // START resumes
  const std::optional<std::string> selected = io_.SelectedProgram(cfg_.id);
  if (!selected)
    throw Error(Errc::kFailedPrecondition,
                "[FILMS4 54] NO PROGRAM HAS BEEN SELECTED: select one with SPG (cellctl program memory " +
                    cfg_.id + " \"SPG,NAME/MPx\")");
  Dispatch d;
  d.dispatch_id = std::min(0, db_.LowestDispatchId()) - 1;
  d.node = cfg_.id;
  d.programs = {*selected};
  d.repeat = 1;
  db_.Enqueue(d, clock_.WallNs());
  spdlog::info("START: run {} of the selected program {}", d.dispatch_id, *selected);
  board_.Queued(db_.Count(RunState::kQueued));
  board_.Publish();
  std::lock_guard lk(work_mu_);
  work_pending_ = true;
  work_cv_.notify_all();
  return true;
}

void Station::OnProgress(const cell::SegmentProgress& p) {
  if (p.station() != cfg_.id) return;
  if (stream_.OnProgress(p)) board_.ServoHeld(p.feed_hold());
}

void Station::OnProbe(const cell::ProbeResult& r) {
  if (r.station() != cfg_.id) return;
  stream_.OnProbe(r);
}

std::optional<cell::RunStatus> Station::Recorded(std::int32_t dispatch_id) {
  const auto v = db_.View(dispatch_id);
  if (!v) return std::nullopt;
  cell::RunStatus s;
  s.dispatch_id(dispatch_id);
  s.station(cfg_.id);
  s.job_id(v->d.job_id);
  s.pallet(v->d.pallet);
  s.state(ToWire(v->state));
  s.programs_done(v->programs_done);
  s.machine_s(v->machine_s);
  s.started_ns(v->started_ns);
  s.finished_ns(v->finished_ns);
  s.reason(v->reason.substr(0, 255));
  return s;
}

void Station::PublishRecorded(std::int32_t dispatch_id) {
  if (auto s = Recorded(dispatch_id)) io_.PublishRun(*s);
}

void Station::Recover() {
  for (const Dispatch& d : db_.Runs(RunState::kActive)) {
    RunProgress end;
    end.dispatch_id = d.dispatch_id;
    end.end = RunState::kFailed;
    end.reason = "station restarted during the run";
    end.finished_ns = clock_.WallNs();
    // One run record per dispatch, a lost run's too (issue 39 item 7: a killed interpreter left none).
    const auto [started_ns, done] = db_.Progress(d.dispatch_id);
    end.programs_done = done;
    end.record = RunRecord(d, cfg_.id, end, started_ns);
    db_.EndRun(end);
    // Said as the database now has it: started (it was active; a run that never started is re-queued by the
    // scheduler, a lost one must not be, docs/scheduler.md §5), with the programs it finished.
    PublishRecorded(d.dispatch_id);
  }
}

bool Station::RunNext() {
  const std::int64_t started_ns = clock_.WallNs();
  auto next = db_.TakeNext(started_ns);
  if (!next) return false;
  Execute(*next, started_ns);
  return true;
}

void Station::FlushOutbox() {
  for (auto& [id, text] : db_.Outbox(16)) {
    auto j = nlohmann::json::parse(text);
    cell::InspectionRequest req;
    req.op(cell::INSPECTION_STORE_RUN);
    req.hdr().idempotency_key("run-" + cfg_.id + "-" + std::to_string(id));
    auto& r = req.run();
    r.dispatch_id(j["dispatch_id"].get<int32_t>());
    r.station(cfg_.id);
    r.job_id(j["job_id"].get<int32_t>());
    r.pallet(j["pallet"].get<int32_t>());
    for (auto& p : j["programs"]) names::Append(r.programs(), p.get<std::string>(), "program name");
    r.completed(j["completed"].get<bool>());
    r.reason(j["reason"].get<std::string>().substr(0, 255));
    r.started_ns(j["started_ns"].get<int64_t>());
    r.finished_ns(j["finished_ns"].get<int64_t>());
    r.machine_s(j["machine_s"].get<double>());
    try {
      if (!io_.StoreRecord(req)) return;  // writer down: keep it, retry later
    } catch (const Error& e) {
      spdlog::warn("run record {} not yet stored: {}", id, e.what());
      return;
    }
    db_.RemoveFromOutbox(id);
  }
}

void Station::Work() {
  Recover();
  while (!stop_) {
    if (RunNext()) continue;
    FlushOutbox();
    std::unique_lock lk(work_mu_);
    if (!work_pending_ && !stop_) clock_.Wait(lk, work_cv_, options_.idle_poll);
    work_pending_ = false;
  }
}

void Station::RequestStop() {
  stop_ = true;
  stream_.Wake();
  std::lock_guard lk(work_mu_);
  work_cv_.notify_all();
}

void Station::Checkpoint(std::int32_t run_id) const {
  if (stop_) throw Error(Errc::kUnavailable, "station stopping");
  if (cancel_id_ == run_id) throw Error(Errc::kFailedPrecondition, "cancelled");
}

}  // namespace cell::station
