#include "cell/scheduler/service.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <charconv>

#include "cell/bus/topics.h"
#include "cell/config/config.h"
#include "cell/idl/health.h"
#include "cell/interp/station_rules.h"
#include "cell/names/names.h"
#include "cell/names/program_ref.h"
#include "cell/records/page.h"
#include "cell/scheduler/json.h"
#include "cell/scheduler/route.h"
#include "cell/tooltable/wire.h"

namespace cell::scheduler {

namespace {

// `job show` as a JobInfo sample: the job record's wire form (records::ToWire), in its slot.
cell::JobInfo ToWire(const JobView& v) {
  cell::JobInfo w = records::ToWire(ToRecord(v, true));
  w.slot(static_cast<int32_t>(v.id % bus::topics::kJobSlots));
  w.updated_ns(health::WallNs());
  return w;
}

std::string Key(const cell::SchedulerRequest& r) {
  std::string k = r.hdr().idempotency_key().to_string();
  // Without a key a command is still made unique per request, so it never replays by accident.
  return k.empty() ? r.hdr().client().to_string() + "#" + std::to_string(r.hdr().request_id()) : k;
}

// The audit trail: what a request changes; empty for a query.
std::string Describe(const cell::SchedulerRequest& r) {
  const std::string name = r.name().to_string();
  switch (r.op()) {
    case cell::SCHED_PALLET_SET:
      return fmt::format("pallet set {}", r.pallet());
    case cell::SCHED_PALLET_RUN:
      return fmt::format("pallet run {}{}", r.pallet(),
                         r.station().size() == 0 ? "" : " on " + r.station().to_string());
    case cell::SCHED_ROUTE_DEFINE:
      return fmt::format("route define {}", name);
    case cell::SCHED_ROUTE_OPERATE:
      return fmt::format("route operate {} (pallet {})", name, r.pallet());
    case cell::SCHED_SCHEDULE_RUN:
      return fmt::format("schedule run {}", name);
    case cell::SCHED_JOB_CANCEL:
      return fmt::format("job cancel {}", r.job_id());
    default:
      return {};
  }
}

// The viewer (the dashboard under DDS Security) is granted the request topic for the Gantt chart's plan
// alone (docs/security.md): the topic carries every op, so the scheduler refuses it the rest.
void CheckRequester(const cell::SchedulerRequest& r) {
  const std::string& who = bus::RequesterIdentity();
  if (who == "viewer" && r.op() != cell::SCHED_PLAN)
    throw Error(Errc::kPermissionDenied,
                fmt::format("identity '{}' may ask the scheduler the plan only (SCHED_PLAN), not op {}", who,
                            static_cast<int>(r.op())));
}

}  // namespace

Service::Service(bus::Participant& p, const std::filesystem::path& data_dir)
    : bus_(p),
      programs_(p),
      source_([this](std::string_view name) -> std::optional<StoredProgram> {
        // "BS01/MP2:P9" is P9 in that namespace (names/program_ref.h); a plain name is HOST's.
        const names::ProgramRef ref = names::SplitProgramRef(name);
        auto f = programs_.Fetch(ref.node.empty() ? "HOST" : ref.node, ref.name);
        if (!f) return std::nullopt;
        std::string type = f->info.is_object() ? f->info.value("type", std::string()) : std::string();
        return StoredProgram{std::move(f->content), f->dialect(), std::move(type)};
      }),
      sched_(Options{(data_dir / "scheduler.db").string(), {}}, source_),
      predictor_(p),
      live_(p),
      jobs_w_(p, bus::topics::kJobStatus, bus::QosKind::kEvent),
      state_w_(p, bus::topics::kSchedulerState, bus::QosKind::kState),
      jobinfo_w_(p, bus::topics::kJobState, bus::QosKind::kState),
      alarm_w_(p, bus::topics::kAlarm, bus::QosKind::kEvent) {}

Service::~Service() {
  Stop();
}

void Service::Start() {
  // Answers come back on the queue's worker: mu_ is taken only to keep one (never while predicting).
  predictions_.emplace(predictor_, [this](const PredictionRequest& r, const Predicted& p) {
    std::lock_guard lk(mu_);
    try {
      Apply(sched_.PredictionAnswered(r, p));
    } catch (const std::exception& e) {
      spdlog::warn("prediction of {} on {} not kept: {}", r.program, r.station, e.what());
      throw;  // the queue backs off and it is asked again
    }
  });
  {
    std::lock_guard lk(mu_);
    sched_.SetPredictor(&predictor_, [this](const PredictionRequest& r) { predictions_->Ask(r); });
    std::vector<Scheduler::StationSetup> setup;
    for (auto& id : config::ListStations()) {
      auto cfg = interp::LoadStation(id);
      dialect_[id] = cfg.dialect;
      online_[id] = false;
      setup.push_back({id, cfg.dialect, cfg.coded_pallets});
      predictor_.Basis(id);  // the station file's fingerprint read now, not at the first allocation
    }
    sched_.ConfigureStations(setup);
    Effects e = sched_.Recover();
    if (!e.dispatches.empty())
      spdlog::info("recovery: re-sending {} unacknowledged dispatch(es)", e.dispatches.size());
    Apply(e);
    // After a restart a station keeps its last known online state until the discovery window has passed
    // (Tick), so a station that is still running its pallet is not taken for vanished meanwhile.
    for (auto& v : sched_.Stations())
      if (online_.count(v.id)) online_[v.id] = v.online;
    started_ = std::chrono::steady_clock::now();
    // The job state topic starts empty in a new process: announce the newest jobs again, the last kJobSlots
    // ids (one per slot), visited in place (a view of every job first was 100,000 views for 1024, issue 39).
    JobQuery newest;
    newest.after = std::max<std::int64_t>(0, sched_.NewestJobId() - bus::topics::kJobSlots);
    sched_.ForJobs(newest, [this](const JobView& v) {
      PublishJob(v.id);
      return true;
    });
  }
  // Observations are subscribed only now, with the stations configured and recovery done: samples that
  // arrive at once (state topics are transient-local) are not dropped as coming from unknown stations.
  status_r_.emplace(bus_, bus::topics::kStationStatus, bus::QosKind::kState,
                    [this](const cell::StationStatus& s, const bus::SampleInfo&) {
                      std::lock_guard lk(mu_);
                      const std::string id = s.station().to_string();
                      if (!dialect_.count(id)) return;
                      reported_[id] = {s.condition() == cell::CONDITION_FAULT, s.alarm_code().to_string(),
                                       s.alarm_text().to_string()};
                      UpdateCondition(id);
                    });
  tools_r_.emplace(bus_, bus::topics::kToolTable, bus::QosKind::kState,
                   [this](const cell::ToolTable& t, const bus::SampleInfo&) {
                     std::lock_guard lk(mu_);
                     if (!dialect_.count(t.station().to_string())) return;
                     Apply(sched_.StationTools(t.station().to_string(), tooltable::FromWire(t)));
                   });
  runs_r_.emplace(bus_, bus::topics::kRunStatus, bus::QosKind::kEvent,
                  [this](const cell::RunStatus& s, const bus::SampleInfo&) { OnRun(s); });
  vars_r_.emplace(bus_, bus::topics::kVariables, bus::QosKind::kState,
                  [this](const cell::StationVariables& v, const bus::SampleInfo&) { OnVariables(v); });
  changes_r_.emplace(bus_, bus::topics::kProgramChange, bus::QosKind::kEvent,
                     [this](const cell::ProgramChange& c, const bus::SampleInfo&) {
                       if (c.node() != "HOST") return;
                       std::lock_guard lk(mu_);
                       Apply(sched_.ProgramChanged(c.name().to_string()));
                     });
  sender_ = std::jthread([this](std::stop_token st) { Sender(st); });
  server_ = std::make_unique<bus::Server<cell::SchedulerRequest, cell::SchedulerReply>>(
      bus_, bus::topics::kScheduler, [this](const cell::SchedulerRequest& r) { return Handle(r); }, Describe);
}

void Service::Stop() {
  server_.reset();
  if (predictions_) predictions_->Stop();  // before anything its worker's answers use goes away
  if (sender_.joinable()) {
    sender_.request_stop();
    out_cv_.notify_all();
    sender_.join();
  }
}

void Service::Tick() {
  {
    std::lock_guard lk(mu_);
    for (auto& [id, was] : online_) {
      bool now = live_.StationOnline(id);
      if (now == was) continue;
      // Heartbeats of stations that survived a restart of the scheduler take up to a heartbeat period to
      // arrive: only after the discovery window does a missing one mean "offline".
      if (!now && std::chrono::steady_clock::now() - started_ <
                      std::chrono::milliseconds(bus::topics::kOfflineAfterMs))
        continue;
      was = now;
      spdlog::info("station {} {}", id, now ? "online" : "offline");
      Apply(now ? sched_.StationOnline(id, dialect_[id]) : sched_.StationOffline(id));
    }
    // A run's end travels as an event; should one be lost, the held dispatch would wait for good: a station
    // silent on it for 30 s is asked again, and its reply says how the run stands (issue 43).
    if (const auto t = std::chrono::steady_clock::now(); t - asked_ >= std::chrono::seconds(5)) {
      asked_ = t;
      Apply(sched_.AskSilent(std::chrono::seconds(30)));
    }
  }
  CheckDuplicates();
  PublishBacklog();
}

void Service::CheckDuplicates() {
  std::map<std::string, std::string> now;
  for (auto& c : live_.Conflicts()) now[c.service_id] = c.Describe();
  std::lock_guard lk(mu_);
  if (now == duplicate_) return;
  std::set<std::string> changed;
  for (auto& [id, text] : now)
    if (!duplicate_.count(id) || duplicate_[id] != text) changed.insert(id);
  for (auto& [id, text] : duplicate_)
    if (!now.count(id)) changed.insert(id);
  duplicate_ = now;
  for (auto& id : changed) {
    const bool active = now.count(id) > 0;
    const auto slash = id.find('/');
    const std::string station = slash == std::string::npos ? "" : id.substr(slash + 1);
    const std::string text = active ? now[id] : id + " runs in one process again";
    if (active)
      spdlog::error("FAULT: {}", text);
    else
      spdlog::info("{}", text);
    cell::Alarm a;
    names::AssignText(a.station(), station);
    a.source("cell-scheduler");
    a.code("DUPLICATE");
    names::AssignText(a.text(), text);
    a.active(active);
    a.time_ns(health::WallNs());
    alarm_w_.Write(a);
    if (dialect_.count(station)) UpdateCondition(station);
  }
}

void Service::UpdateCondition(const std::string& station) {
  // A duplicated interpreter or servo of the station outweighs what the station itself reports.
  for (const char* kind : {"cell-interpreter/", "cell-axis-servo/"}) {
    auto it = duplicate_.find(kind + station);
    if (it != duplicate_.end()) {
      Apply(sched_.StationCondition(station, true, "DUPLICATE", it->second));
      return;
    }
  }
  const Condition& c = reported_[station];
  Apply(sched_.StationCondition(station, c.fault, c.code, c.text));
}

void Service::PublishBacklog() {
  cell::SchedulerState s;
  s.scheduler("HOST");
  {
    std::lock_guard lk(mu_);
    for (auto& v : sched_.Stations()) {
      cell::StationBacklog b;
      b.station(v.id);
      b.backlog_s(static_cast<double>(v.backlog_s));
      b.online(v.online);
      s.backlog().push_back(b);
    }
  }
  s.settled(std::chrono::steady_clock::now() - started_ >=
            std::chrono::milliseconds(bus::topics::kOfflineAfterMs));
  s.updated_ns(health::WallNs());
  state_w_.Write(s);
}

cell::SchedulerReply Service::Handle(const cell::SchedulerRequest& r) {
  CheckRequester(r);
  std::lock_guard lk(mu_);
  cell::SchedulerReply rep;
  const std::string key = Key(r), name = r.name().to_string();
  auto info = [&](const nlohmann::json& j) {
    std::string s = j.dump();
    if (s.size() > 65536) throw Error(Errc::kFailedPrecondition, "reply too large; narrow the query");
    rep.info(s);
  };
  switch (r.op()) {
    case cell::SCHED_PALLET_SET: {
      std::vector<std::string> progs;
      for (auto& a : r.args()) progs.push_back(a.to_string());
      sched_.SetPalletMap(key, r.pallet(), progs);
      break;
    }
    case cell::SCHED_PALLET_SHOW: {
      auto m = sched_.PalletMap(r.pallet());
      if (!m) throw Error(Errc::kNotFound, "pallet " + std::to_string(r.pallet()) + " has no map");
      info({{"pallet", r.pallet()}, {"programs", *m}});
      break;
    }
    case cell::SCHED_PALLET_RUN: {
      JobResult j = sched_.RunPallet(key, r.pallet(), r.station().to_string());
      Apply(j.effects);
      rep.job_id(static_cast<int32_t>(j.job_id));
      break;
    }
    case cell::SCHED_ROUTE_DEFINE: {
      RouteSpec spec;
      spec.name = name;
      if (!r.text().to_string().empty()) {
        auto routes = ParseRouteFile(r.text().to_string(), name);
        auto it =
            std::find_if(routes.begin(), routes.end(), [&](const RouteSpec& s) { return s.name == name; });
        if (it == routes.end())
          throw Error(Errc::kNotFound, "the route file defines no route " + names::Shown(name));
        spec = *it;
      }
      for (auto& a : r.args()) spec.ops.push_back(ParseOpSpec(a.to_string()));
      // A station that is not configured can never qualify: refuse the route rather than let pallets wait.
      for (size_t i = 0; i < spec.ops.size(); ++i)
        for (auto& st : spec.ops[i].stations)
          if (!dialect_.count(st))
            throw Error(Errc::kNotFound,
                        fmt::format("route {}: operation {} names unknown station '{}'", name, i + 1, st));
      info(ToJson(sched_.DefineRoute(key, spec)));
      break;
    }
    case cell::SCHED_ROUTE_SHOW: {
      auto v = sched_.Route(name);
      if (!v) throw Error(Errc::kNotFound, "no route " + names::Shown(name));
      info(ToJson(*v));
      break;
    }
    case cell::SCHED_ROUTE_OPERATE: {
      JobResult j = sched_.Operate(key, name, r.pallet());
      Apply(j.effects);
      rep.job_id(static_cast<int32_t>(j.job_id));
      break;
    }
    case cell::SCHED_SCHEDULE_RUN: {
      // FILE's text comes with the request (a local file); otherwise a stored name, looked up in the
      // station's namespace, then HOST.
      const std::string station = r.station().to_string();
      if (!dialect_.count(station)) throw Error(Errc::kNotFound, "unknown station " + station);
      std::string text = r.text().to_string();
      if (text.empty()) {
        auto stored = programs_.GetWithFallback(station, name);
        if (!stored)
          throw Error(Errc::kNotFound, "schedule program '" + name + "' is not in " + station + " or HOST");
        text = std::move(*stored);
      }
      JobResult j = sched_.RunSchedule(key, name, text, station);
      Apply(j.effects);
      rep.job_id(static_cast<int32_t>(j.job_id));
      break;
    }
    case cell::SCHED_JOB_LIST:
      ListJobs(r, rep);
      break;
    case cell::SCHED_JOB_SHOW: {
      auto j = sched_.Job(r.job_id(), true);
      if (!j) throw Error(Errc::kNotFound, "unknown job " + std::to_string(r.job_id()));
      info(FitJobShow(ToJson(*j, true), 65536));
      break;
    }
    case cell::SCHED_JOB_CANCEL:
      if (!sched_.Job(r.job_id(), false))
        throw Error(Errc::kNotFound, "unknown job " + std::to_string(r.job_id()));
      Apply(sched_.Cancel(key, r.job_id()));
      break;
    case cell::SCHED_PROGRAM_SHOW:
      info(ToJson(sched_.Estimates(name)));
      break;
    case cell::SCHED_PLAN:
      info(ToJson(sched_.Plan()));
      break;
  }
  return rep;
}

// `job ls`: one page, by id, within the reply's bound (records::PageBuilder). Called with mu_ held.
void Service::ListJobs(const cell::SchedulerRequest& r, cell::SchedulerReply& rep) const {
  JobQuery q;
  const std::string after = r.page().after().to_string(), state = r.state().to_string();
  if (!after.empty()) {
    const auto [end, ec] = std::from_chars(after.data(), after.data() + after.size(), q.after);
    if (ec != std::errc() || end != after.data() + after.size() || q.after < 0)
      throw Error(Errc::kInvalidArgument,
                  "--after: a job id is a decimal number, not " + names::Shown(after));
  }
  if (!state.empty() && !(q.state = JobStateFromName(state)))
    throw Error(Errc::kInvalidArgument, "--state: no job state " + names::Shown(state));
  q.station = r.station().to_string();
  records::PageBuilder page(r.page().limit());
  sched_.ForJobs(q, [&](const JobView& j) { return page.Add(ToJson(j, false)); });
  rep.info(page.Text());
  rep.more(page.more());
}

// Called with mu_ held.
void Service::Apply(const Effects& e) {
  for (auto& n : e.notes) spdlog::info("{}", n);
  {
    std::lock_guard lk(out_mu_);
    // VSET writes of a schedule program before the dispatches of the same call (the run reads them).
    std::map<std::string, std::vector<VariableAction>> vars;
    for (auto& v : e.variables) vars[v.station].push_back(v);
    for (auto& [station, list] : vars) {
      Outgoing o;
      o.kind = Outgoing::kVariables;
      o.d.station = station;
      o.variables = list;
      outgoing_.push_back(o);
    }
    for (auto& d : e.dispatches) outgoing_.push_back({Outgoing::kDispatch, d, {}});
    for (auto& c : e.cancels) {
      DispatchAction d;
      d.dispatch_id = c.dispatch_id;
      d.station = c.station;
      d.job_id = c.job_id;
      outgoing_.push_back({Outgoing::kCancel, d, {}});
    }
  }
  out_cv_.notify_all();
  std::set<std::int64_t> changed;
  for (auto& c : e.job_changes) changed.insert(c.job_id);
  for (auto id : changed) PublishJob(id);
  for (auto& c : e.job_changes) {
    auto v = sched_.Job(c.job_id, false);
    cell::JobStatus s;
    s.job_id(static_cast<int32_t>(c.job_id));
    s.state(WireState(c.state));
    names::AssignText(s.reason(), c.reason);
    if (v) {
      names::Assign(s.route(), v->route, "route name");
      s.pallet(v->pallet);
      names::Assign(s.station(), v->station, "station id");
      s.started_ns(v->started_ms * 1000000);
      s.finished_ns(v->finished_ms * 1000000);
      s.cycle_s(v->cycle_s.value_or(0));
    }
    spdlog::info("job {} {}{}", c.job_id, JobStateName(c.state), c.reason.empty() ? "" : ": " + c.reason);
    jobs_w_.Write(s);
  }
}

// Called with mu_ held.
void Service::PublishJob(std::int64_t id) {
  auto v = sched_.Job(id, true);
  if (!v) return;
  try {
    jobinfo_w_.Write(ToWire(*v));
  } catch (const Error& e) {  // a view for viewers: never let it stop the scheduler
    spdlog::warn("job {}: state not published: {}", id, e.what());
  }
}

namespace {
RunReport ToReport(const cell::RunStatus& s) {
  RunReport r;
  r.dispatch_id = s.dispatch_id();
  r.programs_done = s.programs_done();
  switch (s.state()) {
    case cell::RUN_QUEUED:
      r.status = RunStatus::kAccepted;
      break;
    case cell::RUN_ACTIVE:
      r.status = RunStatus::kRunning;
      break;
    case cell::RUN_COMPLETED:
      r.status = RunStatus::kCompleted;
      r.cycle_s = s.machine_s();
      break;
    case cell::RUN_FAILED:
    case cell::RUN_CANCELLED:
      r.status = RunStatus::kFailed;
      r.reason = s.reason().to_string().empty() ? "run failed" : s.reason().to_string();
      r.started = s.started_ns() != 0;
      break;
  }
  return r;
}
}  // namespace

void Service::OnRun(const cell::RunStatus& s) {
  // Every sample, re-delivered ones included: the core applies only the steps not yet taken. A station's own
  // runs (Balt-System SPG and START, ids below 1) are none of the scheduler's.
  if (s.dispatch_id() <= 0) return;
  std::lock_guard lk(mu_);
  Apply(sched_.ReportRun(ToReport(s)));
}

void Service::Sender(std::stop_token st) {
  sender_alive_ = true;
  while (!st.stop_requested()) {
    Outgoing o;
    {
      std::unique_lock lk(out_mu_);
      out_cv_.wait_for(lk, std::chrono::milliseconds(500),
                       [&] { return !outgoing_.empty() || st.stop_requested(); });
      if (outgoing_.empty()) continue;
      o = outgoing_.front();
      outgoing_.pop_front();
    }
    if (o.kind == Outgoing::kVariables) {
      SendVariables(o);
      continue;
    }
    const bool cancel = o.kind == Outgoing::kCancel;
    if (!cancel) {
      // A dispatch revoked while it waited here (its station vanished before taking it, and the pallet went
      // elsewhere) is never handed out late: that station would run the pallet a second time.
      std::lock_guard lk(mu_);
      if (!sched_.DispatchLive(o.d.dispatch_id)) {
        spdlog::info("dispatch {} to {} dropped: revoked before the station took it", o.d.dispatch_id,
                     o.d.station);
        continue;
      }
    }
    if (!run_client_)  // one for every station (topics::kStationRun)
      run_client_ =
          std::make_unique<bus::Client<cell::RunRequest, cell::RunReply>>(bus_, bus::topics::kStationRun);
    auto& client = run_client_;
    cell::RunRequest req;
    req.station(o.d.station);
    req.dispatch_id(static_cast<int32_t>(o.d.dispatch_id));
    req.job_id(static_cast<int32_t>(o.d.job_id));
    req.pallet(o.d.pallet);
    req.node(o.d.station);
    req.repeat(1);
    req.cancel(cancel);
    if (o.d.schedule_run) {
      names::Append(req.programs(), schedule::StationEntry(*o.d.schedule_run), "program name");
    } else {
      for (auto& p : o.d.programs) names::Append(req.programs(), p, "program name");
    }
    req.hdr().idempotency_key("dispatch-" + std::to_string(o.d.dispatch_id) + (cancel ? "-cancel" : ""));
    try {
      auto rep = client->Call(req, std::chrono::seconds(5));
      bus::ThrowIfError(rep);
      if (rep.run().dispatch_id() == o.d.dispatch_id) {
        // Asked again (or cancelled): the station's record settles it here, whatever became of its events
        // (a lost end left a pallet RUNNING for good, issue 43).
        std::lock_guard lk(mu_);
        Apply(sched_.ReportRun(ToReport(rep.run())));
      } else if (!cancel) {
        std::lock_guard lk(mu_);
        Apply(sched_.DispatchAcknowledged(o.d.dispatch_id));
      }
      spdlog::info("{} {} to {} acknowledged", cancel ? "cancel of dispatch" : "dispatch", o.d.dispatch_id,
                   o.d.station);
    } catch (const Error& e) {
      if (e.code() == Errc::kInvalidArgument) {
        std::lock_guard lk(mu_);
        Apply(sched_.RunFailed(o.d.dispatch_id, std::string("station rejected the dispatch: ") + e.what()));
        continue;
      }
      // Station not reachable yet: keep it, try again (a dispatch is never dropped silently).
      spdlog::warn("dispatch {} to {} not delivered yet: {}", o.d.dispatch_id, o.d.station, e.what());
      Retry(o);
    }
  }
  sender_alive_ = false;
}

void Service::Retry(const Outgoing& o) {
  // Back into the queue ahead of anything else for the same station (its order is kept: variable writes
  // before the dispatch that reads them), behind other stations' work (a dead station blocks no other).
  std::unique_lock lk(out_mu_);
  auto it = std::find_if(outgoing_.begin(), outgoing_.end(),
                         [&](const Outgoing& x) { return x.d.station == o.d.station; });
  outgoing_.insert(it, o);
  out_cv_.wait_for(lk, std::chrono::seconds(1));
}

void Service::SendVariables(const Outgoing& o) {
  auto& client = command_clients_[o.d.station];
  if (!client)
    client = std::make_unique<bus::Client<cell::StationRequest, cell::StationReply>>(
        bus_, bus::topics::StationCommand(o.d.station));
  cell::StationRequest req;
  req.op(cell::STATION_SET_VARIABLES);
  req.station(o.d.station);
  std::string what;
  for (auto& v : o.variables) {
    cell::Variable x;
    x.name("V" + std::to_string(v.number));
    x.value(v.value);
    req.variables().push_back(x);
    what += fmt::format("{}V{}={}", what.empty() ? "" : " ", v.number, v.value);
  }
  try {
    bus::ThrowIfError(client->Call(req, std::chrono::seconds(5)));
    spdlog::info("variables set on {}: {}", o.d.station, what);
  } catch (const Error& e) {
    if (e.code() == Errc::kInvalidArgument) {
      spdlog::error("station {} refused variables {}: {}", o.d.station, what, e.what());
      return;
    }
    spdlog::warn("variables {} for {} not delivered yet: {}", what, o.d.station, e.what());
    Retry(o);
  }
}

void Service::OnVariables(const cell::StationVariables& v) {
  // Okuma common variables V1-V200 as the station publishes them (IF and VSET of schedule programs).
  std::map<int, double> common;
  for (auto& x : v.variables()) {
    std::string n = x.name().to_string();
    if (n.size() < 2 || (n[0] != 'V' && n[0] != 'v') || n.size() > 4) continue;
    if (!std::all_of(n.begin() + 1, n.end(), [](char c) { return c >= '0' && c <= '9'; })) continue;
    int number = std::stoi(n.substr(1));
    if (number >= 1 && number <= 200) common[number] = x.value();
  }
  std::lock_guard lk(mu_);
  if (!dialect_.count(v.station().to_string())) return;
  Apply(sched_.StationVariables(v.station().to_string(), common));
}

}  // namespace cell::scheduler
