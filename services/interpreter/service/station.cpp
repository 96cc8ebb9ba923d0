#include "cell/station/station.h"

#include <cmath>

#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>

#include "cell/bus/topics.h"
#include "cell/health/health.h"
#include "cell/interp/interp.h"
#include "cell/tooltable/wire.h"

namespace cell::station {

namespace {

constexpr uint64_t kInitialCredit = 4;  // segments sent before the servo has spoken for a run
constexpr auto kServoWait = std::chrono::seconds(10);
// A run fails when its servo has been unmatched and silent this long. A servo that comes back sooner (a
// process stopped past the 3 s DDS lease and continued, a network cut) gets the missing segments again; one
// that restarted is told apart by its boot_id and fails the run at once.
constexpr auto kServoGone = std::chrono::seconds(10);

std::vector<store::Migration> Migrations() {
  return {
      store::Migration::Sql(
          1, "station state",
          "CREATE TABLE tools(tool TEXT PRIMARY KEY, socket INTEGER, length REAL, diameter REAL,"
          " life_left_min INTEGER, worn INTEGER, broken INTEGER, ord INTEGER);"
          "CREATE TABLE variables(name TEXT PRIMARY KEY, value REAL);"
          "CREATE TABLE runs(dispatch_id INTEGER PRIMARY KEY, job_id INTEGER, pallet INTEGER,"
          " node TEXT, programs TEXT, repeat INTEGER, state TEXT, reason TEXT,"
          " machine_s REAL, started_ns INTEGER, finished_ns INTEGER, received_ns INTEGER);"
          "CREATE TABLE outbox(dispatch_id INTEGER PRIMARY KEY, record TEXT);"),
      // The operator's panel survives a restart of this process: a held machine must not start moving
      // because its interpreter was restarted.
      store::Migration::Sql(2, "operator panel", "CREATE TABLE panel(name TEXT PRIMARY KEY, value REAL);")};
}

cell::RunState StateFromText(const std::string& s) {
  if (s == "ACTIVE") return cell::RUN_ACTIVE;
  if (s == "COMPLETED") return cell::RUN_COMPLETED;
  if (s == "FAILED") return cell::RUN_FAILED;
  if (s == "CANCELLED") return cell::RUN_CANCELLED;
  return cell::RUN_QUEUED;
}

void SetTarget(cell::MotionSegment& s, const interp::Target& t) {
  uint16_t mask = 0;
  for (int i = 0; i < interp::kAxisCount; ++i) {
    s.target()[static_cast<size_t>(i)] = t.pos[static_cast<size_t>(i)];
    if (t.used & (1u << i)) mask = static_cast<uint16_t>(mask | (1u << i));
  }
  s.axis_mask(mask);
}

void SetFeed(cell::MotionSegment& s, const interp::Feed& f) {
  s.feed(f.rate);
  s.feed_mode(f.mode == interp::FeedMode::kPerRev ? 1 : f.mode == interp::FeedMode::kInverseTime ? 2 : 0);
  s.exact_stop(f.exact_stop);
}

cell::ArcPlane PlaneOf(const interp::PlaneAxes& p) {
  auto base = [](int a) {
    return a >= interp::kU ? a - interp::kU : a;
  };  // a co-axis moves like its parallel
  int first = base(p.first);
  if (first == interp::kZ) return cell::PLANE_ZX;
  if (first == interp::kY) return cell::PLANE_YZ;
  return cell::PLANE_XY;
}

}  // namespace

std::optional<cell::MotionSegment> ToSegment(const interp::Canon& c) {
  cell::MotionSegment s;
  s.line(c.line);
  switch (c.op()) {
    case interp::Op::kRapid:
      s.kind(cell::SEGMENT_RAPID);
      SetTarget(s, c.As<interp::RapidOp>().to);
      s.exact_stop(true);
      return s;
    case interp::Op::kLinear: {
      const auto& l = c.As<interp::LinearOp>();
      s.kind(cell::SEGMENT_LINEAR);
      SetTarget(s, l.to);
      SetFeed(s, l.feed);
      return s;
    }
    case interp::Op::kArc: {
      const auto& a = c.As<interp::ArcOp>();
      s.kind(cell::SEGMENT_ARC);
      SetTarget(s, a.to);
      SetFeed(s, a.feed);
      s.center({a.center[0], a.center[1], a.center[2]});
      s.plane(PlaneOf(a.plane));
      s.ccw(!a.cw);
      // A one-block full circle sweeps 360 degrees with end == start: no extra turn.
      s.turns(a.angle > 360.0 + 1e-6 ? static_cast<int32_t>(std::floor((a.angle - 1e-6) / 360.0)) : 0);
      return s;
    }
    case interp::Op::kThread: {
      // Spindle-synchronised: the lead along the major axis, from the start angle (docs/axis-servo.md).
      const auto& t = c.As<interp::ThreadOp>();
      s.kind(cell::SEGMENT_THREAD);
      SetTarget(s, t.to);
      s.exact_stop(false);
      s.thread_lead(t.lead);
      s.thread_lead_change(t.lead_change);
      s.thread_start_angle(t.start_angle);
      return s;
    }
    case interp::Op::kDwell:
      s.kind(cell::SEGMENT_DWELL);
      s.dwell_s(c.As<interp::DwellOp>().seconds);
      return s;
    case interp::Op::kSpindle: {
      const auto& sp = c.As<interp::SpindleOp>();
      s.kind(cell::SEGMENT_SPINDLE);
      s.spindle_rpm(sp.rpm);
      s.spindle_mode(sp.dir == interp::SpindleDir::kCw       ? 1
                     : sp.dir == interp::SpindleDir::kCcw    ? 2
                     : sp.dir == interp::SpindleDir::kOrient ? 3
                                                             : 0);
      // The whole spindle state on every spindle segment: constant surface speed and the spindle limit.
      s.css_surface_speed(sp.css);
      s.spindle_max_rpm(sp.max_rpm);
      return s;
    }
    case interp::Op::kCoolant: {
      interp::CoolantMode m = c.As<interp::CoolantOp>().mode;
      s.kind(cell::SEGMENT_COOLANT);
      s.coolant(m == interp::CoolantMode::kOff ? 0 : m == interp::CoolantMode::kMist ? 2 : 1);
      return s;
    }
    case interp::Op::kToolChange:
      s.kind(cell::SEGMENT_TOOL_CHANGE);
      s.tool(c.As<interp::ToolChangeOp>().tool);
      return s;
    case interp::Op::kPallet:
      s.kind(cell::SEGMENT_PALLET);
      return s;
    case interp::Op::kEnd:
      s.kind(cell::SEGMENT_END);
      return s;
    default:
      return std::nullopt;
  }
}

// Queue busters answered by the machine: the run's Next() blocks here until the servo reports.
class Station::Env : public interp::Environment {
 public:
  Env(Station& s, std::stop_token st) : s_(s), st_(std::move(st)) {}
  interp::ProbeResult Probe(bool contact, const interp::AxisArray& from,
                            const interp::AxisArray& to) override {
    (void)from;
    cell::MotionSegment seg;
    seg.kind(cell::SEGMENT_PROBE);
    for (size_t i = 0; i < to.size(); ++i) seg.target()[i] = to[i];
    seg.axis_mask(0x3f);
    seg.exact_stop(true);
    seg.feed(s_.probe_feed_);
    s_.Send(seg, st_);
    uint64_t want = s_.sent_seq_;
    int32_t run = s_.run_id_;
    interp::ProbeResult r;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
    std::optional<cell::ProbeResult> got;
    while (!(got = s_.probe_r_.WaitFor(
                 [&](const cell::ProbeResult& p) { return p.run_id() == run && p.seq() == want; },
                 std::chrono::milliseconds(200)))) {
      {
        std::unique_lock lk(s_.motion_mu_);
        s_.CheckServo(lk, st_);  // alarms, a lost servo, and the re-send after it matched again
      }
      if (std::chrono::steady_clock::now() > deadline)
        throw Error(Errc::kTimeout, "no probe result from the axis servo");
    }
    r.event = got->contact() == contact;
    for (size_t i = 0; i < r.at.size(); ++i) r.at[i] = got->position()[i];
    return r;
  }

 private:
  Station& s_;
  std::stop_token st_;
};

Station::Station(bus::Participant& p, config::StationConfig cfg, const std::filesystem::path& data_dir)
    : bus_(p),
      cfg_(std::move(cfg)),
      db_(store::Database::Open(data_dir / ("interpreter-" + cfg_.id + ".db"))),
      tools_(std::vector<tooltable::ToolEntry>{}),
      status_w_(p, bus::topics::kStationStatus, bus::QosKind::kState),
      tools_w_(p, bus::topics::kToolTable, bus::QosKind::kState),
      vars_w_(p, bus::topics::kVariables, bus::QosKind::kState),
      run_w_(p, bus::topics::kRunStatus, bus::QosKind::kEvent),
      seg_w_(p, bus::topics::Segments(cfg_.id), bus::QosKind::kStream),
      control_w_(p, bus::topics::kServoControl, bus::QosKind::kState),
      progress_r_(p, bus::topics::kProgress, bus::QosKind::kState,
                  [this](const cell::SegmentProgress& s, const bus::SampleInfo&) { OnProgress(s); }),
      probe_r_(p, bus::topics::Probe(cfg_.id), bus::QosKind::kCommand),
      programs_(p),
      inspection_(p, bus::topics::kInspection) {
  store::Migrate(db_, Migrations());
  // Tool table: persisted; seeded once from the station config's initial tools.
  std::vector<tooltable::ToolEntry> entries;
  auto q = db_.Prepare(
      "SELECT tool, socket, length, diameter, life_left_min, worn, broken FROM tools ORDER BY ord");
  while (q.Step()) {
    tooltable::ToolEntry e;
    e.tool = q.ColumnText(0);
    e.socket = static_cast<int>(q.ColumnInt64(1));
    e.length = q.ColumnDouble(2);
    e.diameter = q.ColumnDouble(3);
    e.life_left_min = q.ColumnDouble(4);
    e.worn = q.ColumnInt64(5) != 0;
    e.broken = q.ColumnInt64(6) != 0;
    entries.push_back(e);
  }
  if (entries.empty() && db_.QueryInt64("SELECT COUNT(*) FROM runs") == 0) {
    entries = cfg_.tools;
  }
  tools_ = tooltable::ToolTable(entries);
  auto v = db_.Prepare("SELECT name, value FROM variables");
  while (v.Step()) vars_[v.ColumnText(0)] = v.ColumnDouble(1);

  control_.station(cfg_.id);
  control_.feed_override(1.0);
  control_.rapid_override(1.0);
  auto pq = db_.Prepare("SELECT name, value FROM panel");
  while (pq.Step()) {
    const std::string n = pq.ColumnText(0);
    if (n == "feed_hold") control_.feed_hold(pq.ColumnDouble(1) != 0);
    if (n == "feed_override") control_.feed_override(pq.ColumnDouble(1));
    if (n == "rapid_override") control_.rapid_override(pq.ColumnDouble(1));
  }

  status_.station(cfg_.id);
  status_.dialect(cfg_.dialect);
  SetExecution(cell::EXECUTION_READY);
  status_.condition(cell::CONDITION_NORMAL);
  status_.queued(static_cast<int32_t>(db_.QueryInt64("SELECT COUNT(*) FROM runs WHERE state='QUEUED'")));
}

Station::~Station() {
  Stop();
}

// The whole table replaces the stored one in one transaction (caller holds db_mu_).
void Station::SaveTools() {
  store::Transaction tx(db_);
  db_.Exec("DELETE FROM tools");
  auto save = db_.Prepare(
      "INSERT INTO tools(tool, socket, length, diameter, life_left_min, worn, broken, ord) "
      "VALUES(?,?,?,?,?,?,?,?)");
  int ord = 0;
  for (auto& e : tools_.entries()) {
    save.BindText(1, e.tool).BindInt64(2, e.socket).BindDouble(3, e.length).BindDouble(4, e.diameter);
    save.BindInt64(5, e.life_left_min).BindInt64(6, e.worn).BindInt64(7, e.broken).BindInt64(8, ord++);
    save.Run();
    save.Reset();
  }
  tx.Commit();
}

void Station::Start() {
  {
    std::lock_guard lk(db_mu_);
    SaveTools();
  }
  PublishTools();
  PublishVariables();
  PublishControl();
  PublishStatus();
  run_srv_ = std::make_unique<bus::Server<cell::RunRequest, cell::RunReply>>(
      bus_, bus::topics::StationRun(cfg_.id), [this](const cell::RunRequest& r) { return OnRun(r); });
  cmd_srv_ = std::make_unique<bus::Server<cell::StationRequest, cell::StationReply>>(
      bus_, bus::topics::StationCommand(cfg_.id),
      [this](const cell::StationRequest& r) { return OnCommand(r); });
  worker_ = std::jthread([this](std::stop_token st) { Worker(st); });
}

void Station::Stop() {
  if (worker_.joinable()) {
    worker_.request_stop();
    queue_cv_.notify_all();
    motion_cv_.notify_all();
    worker_.join();
  }
  run_srv_.reset();
  cmd_srv_.reset();
}

cell::RunReply Station::OnRun(const cell::RunRequest& r) {
  cell::RunReply rep;
  rep.station(cfg_.id);
  rep.dispatch_id(r.dispatch_id());
  if (r.station() != cfg_.id)
    throw Error(Errc::kInvalidArgument, "run request for " + r.station().to_string() + " reached " + cfg_.id);
  if (r.dispatch_id() <= 0) throw Error(Errc::kInvalidArgument, "dispatch id must be positive");
  std::lock_guard lk(db_mu_);
  auto find = db_.Prepare("SELECT state FROM runs WHERE dispatch_id=?");
  find.BindInt64(1, r.dispatch_id());
  bool known = find.Step();
  std::string state = known ? find.ColumnText(0) : "";
  if (r.cancel()) {
    if (state == "QUEUED") SaveRun(r.dispatch_id(), "CANCELLED", "cancelled by the scheduler");
    if (state == "ACTIVE") {
      cancel_id_ = r.dispatch_id();
      {
        std::lock_guard s(status_mu_);
        control_.abort_run(r.dispatch_id());  // the machine stops too, not only the sending (not persisted)
        control_.revision(control_.revision() + 1);
      }
      PublishControl();
      motion_cv_.notify_all();
    }
    rep.state(known ? StateFromText(state) : cell::RUN_CANCELLED);
    return rep;
  }
  if (known) {  // a re-sent dispatch (scheduler restart): the station de-duplicates on the id
    rep.state(StateFromText(state));
    return rep;
  }
  if (r.programs().empty() || r.programs().size() > 75)
    throw Error(Errc::kInvalidArgument, "a pallet map names 1 to 75 programs");
  if (r.repeat() < 0 || r.repeat() > 9999)
    throw Error(Errc::kInvalidArgument, "repeat count must be 1..9999");
  nlohmann::json progs = nlohmann::json::array();
  for (auto& p : r.programs()) progs.push_back(p.to_string());
  auto ins = db_.Prepare(
      "INSERT INTO runs(dispatch_id, job_id, pallet, node, programs, repeat, state, received_ns) "
      "VALUES(?,?,?,?,?,?,'QUEUED',?)");
  ins.BindInt64(1, r.dispatch_id()).BindInt64(2, r.job_id()).BindInt64(3, r.pallet());
  ins.BindText(4, r.node().to_string().empty() ? cfg_.id : r.node().to_string()).BindText(5, progs.dump());
  ins.BindInt64(6, r.repeat() == 0 ? 1 : r.repeat()).BindInt64(7, health::WallNs());
  ins.Run();
  spdlog::info("accepted dispatch {} (job {}, pallet {}, {} program(s))", r.dispatch_id(), r.job_id(),
               r.pallet(), r.programs().size());
  {
    std::lock_guard s(status_mu_);
    status_.queued(static_cast<int32_t>(db_.QueryInt64("SELECT COUNT(*) FROM runs WHERE state='QUEUED'")));
  }
  PublishStatus();
  queue_cv_.notify_all();
  rep.state(cell::RUN_QUEUED);
  return rep;
}

cell::StationReply Station::OnCommand(const cell::StationRequest& r) {
  cell::StationReply rep;
  rep.station(cfg_.id);
  switch (r.op()) {
    case cell::STATION_LOAD_TOOLS: {
      // The station's own tool-table form (KT-APL: a program of TLD statements), on top of the table.
      const interp::Dialect& dialect = interp::DialectOrThrow(cfg_.dialect);
      std::lock_guard lk(db_mu_);
      tools_ = dialect.ParseToolTable(r.text().to_string(), "tools", tools_);
      SaveTools();
      spdlog::info("tool table loaded: {} tools, {} process compensations", tools_.entries().size(),
                   tools_.process_comps().size());
      PublishTools();
      rep.revision(tools_rev_);
      return rep;
    }
    case cell::STATION_SET_VARIABLES:
    case cell::STATION_SET_INPUT: {
      std::lock_guard lk(db_mu_);
      store::Transaction tx(db_);
      auto save = db_.Prepare("INSERT OR REPLACE INTO variables(name, value) VALUES(?,?)");
      for (auto& v : r.variables()) {
        std::string n = v.name().to_string();
        if (n.empty()) throw Error(Errc::kInvalidArgument, "variable without a name");
        vars_[n] = v.value();
        save.BindText(1, n).BindDouble(2, v.value());
        save.Run();
        save.Reset();
      }
      tx.Commit();
      PublishVariables();
      rep.revision(vars_rev_);
      return rep;
    }
    case cell::STATION_RESET: {
      std::lock_guard s(status_mu_);
      status_.condition(cell::CONDITION_NORMAL);
      status_.alarm_code("");
      status_.alarm_text("");
    }
      PublishStatus();
      return rep;
    case cell::STATION_FEED_HOLD:
    case cell::STATION_CYCLE_START:
    case cell::STATION_OVERRIDE:
      return SetPanel(r);
  }
  throw Error(Errc::kInvalidArgument, "unknown station command");
}

// Feed hold, feed and rapid override: recorded, persisted, published to the servo (ServoControl). The servo
// reports the hold in its progress, which turns the station's execution to FEED_HOLD and back (OnProgress);
// the reply does not wait for that: this handler runs on the bus thread that delivers the progress.
cell::StationReply Station::SetPanel(const cell::StationRequest& r) {
  cell::StationReply rep;
  rep.station(cfg_.id);
  cell::ServoControl c;
  {
    std::lock_guard s(status_mu_);
    c = control_;
  }
  if (r.op() == cell::STATION_OVERRIDE) {
    if (r.feed_override() > 2.0 || r.rapid_override() > 1.0)
      throw Error(Errc::kInvalidArgument, "feed override is 0..200 %, rapid override 0..100 %");
    if (r.feed_override() >= 0) c.feed_override(r.feed_override());
    if (r.rapid_override() >= 0) c.rapid_override(r.rapid_override());
  } else {
    c.feed_hold(r.op() == cell::STATION_FEED_HOLD);
  }
  c.revision(c.revision() + 1);
  {
    std::lock_guard lk(db_mu_);
    store::Transaction tx(db_);
    auto save = db_.Prepare("INSERT OR REPLACE INTO panel(name, value) VALUES(?,?)");
    for (auto [n, v] : {std::pair<const char*, double>{"feed_hold", c.feed_hold() ? 1.0 : 0.0},
                        {"feed_override", c.feed_override()},
                        {"rapid_override", c.rapid_override()}}) {
      save.BindText(1, n).BindDouble(2, v);
      save.Run();
      save.Reset();
    }
    tx.Commit();
    std::lock_guard s(status_mu_);
    control_ = c;
  }
  PublishControl();
  spdlog::info("panel: feed hold {}, feed override {:.0f} %, rapid override {:.0f} %",
               c.feed_hold() ? "on" : "off", c.feed_override() * 100, c.rapid_override() * 100);
  rep.revision(c.revision());
  return rep;
}

void Station::OnProgress(const cell::SegmentProgress& p) {
  if (p.station() != cfg_.id) return;
  bool held_changed;
  {
    std::lock_guard lk(motion_mu_);
    held_changed = servo_held_ != p.feed_hold();
    servo_held_ = p.feed_hold();
    // Progress from another servo process than the one this run started on: the servo restarted and the
    // segments it had are gone (it refuses to join a run in the middle).
    if (run_id_ != 0 && run_boot_ != 0 && p.boot_id() != run_boot_) servo_restarted_ = true;
    if (p.run_id() == run_id_ && run_id_ != 0) {
      if (run_boot_ == 0) run_boot_ = p.boot_id();
      completed_seq_ = std::max(completed_seq_, p.completed_seq());
      credit_seq_ = std::max(credit_seq_, p.credit_seq());
      received_seq_ = p.received_seq();
      last_report_ = std::chrono::steady_clock::now();
      while (!unacked_.empty() && unacked_.front().seq() <= completed_seq_) unacked_.pop_front();
      run_machine_s_ = p.run_machine_s();
      last_progress_ = std::chrono::steady_clock::now();
      if (p.alarm()) {
        servo_alarm_ = true;
        servo_alarm_code_ = p.alarm_code().to_string();
        servo_alarm_text_ = p.alarm_text().to_string();
      }
    }
    motion_cv_.notify_all();
  }
  if (held_changed) {
    {
      std::lock_guard s(status_mu_);
      SetExecution(base_execution_);  // the hold shown, or what the run state says
    }
    PublishStatus();
  }
}

void Station::Worker(std::stop_token st) {
  worker_alive_ = true;
  {
    // A run that was ACTIVE when the process died did not finish: report it failed, never silently.
    std::lock_guard lk(db_mu_);
    auto q = db_.Prepare("SELECT dispatch_id, job_id, pallet FROM runs WHERE state='ACTIVE'");
    std::vector<Dispatch> lost;
    while (q.Step()) {
      Dispatch d;
      d.dispatch_id = static_cast<int32_t>(q.ColumnInt64(0));
      d.job_id = static_cast<int32_t>(q.ColumnInt64(1));
      d.pallet = static_cast<int32_t>(q.ColumnInt64(2));
      lost.push_back(d);
    }
    for (auto& d : lost) {
      SaveRun(d.dispatch_id, "FAILED", "station restarted during the run");
      PublishRun(d, cell::RUN_FAILED, "station restarted during the run");
    }
  }
  while (!st.stop_requested()) {
    std::optional<Dispatch> next;
    {
      std::lock_guard lk(db_mu_);
      auto q = db_.Prepare(
          "SELECT dispatch_id, job_id, pallet, node, programs, repeat FROM runs WHERE state='QUEUED' "
          "ORDER BY received_ns, dispatch_id LIMIT 1");
      if (q.Step()) {
        Dispatch d;
        d.dispatch_id = static_cast<int32_t>(q.ColumnInt64(0));
        d.job_id = static_cast<int32_t>(q.ColumnInt64(1));
        d.pallet = static_cast<int32_t>(q.ColumnInt64(2));
        d.node = q.ColumnText(3);
        for (auto& p : nlohmann::json::parse(q.ColumnText(4))) d.programs.push_back(p.get<std::string>());
        d.repeat = static_cast<int>(q.ColumnInt64(5));
        next = d;
      }
    }
    if (next) {
      Execute(*next, st);
      continue;
    }
    FlushOutbox();
    std::unique_lock lk(queue_mu_);
    queue_cv_.wait_for(lk, std::chrono::milliseconds(500));
  }
  worker_alive_ = false;
}

void Station::Execute(const Dispatch& d, std::stop_token st) {
  run_started_ns_ = health::WallNs();
  programs_done_ = 0;
  {
    std::lock_guard lk(db_mu_);
    auto u = db_.Prepare("UPDATE runs SET state='ACTIVE', started_ns=? WHERE dispatch_id=?");
    u.BindInt64(1, run_started_ns_).BindInt64(2, d.dispatch_id);
    u.Run();
  }
  {
    std::lock_guard lk(motion_mu_);
    run_id_ = d.dispatch_id;
    sent_seq_ = completed_seq_ = run_machine_s_ = 0;
    credit_seq_ = kInitialCredit;
    servo_alarm_ = false;
    servo_restarted_ = false;
    run_boot_ = 0;
    unacked_.clear();
    received_seq_ = 0;
    seg_matches_ = seg_w_.TotalMatched();
    last_report_ = last_resend_ = std::chrono::steady_clock::now();
  }
  {
    std::lock_guard s(status_mu_);
    SetExecution(cell::EXECUTION_ACTIVE);
    status_.pallet(d.pallet);
    status_.dispatch_id(d.dispatch_id);
  }
  PublishStatus();  // ACTIVE with its pallet now, not only once the run has made 100 ms of progress
  spdlog::info("dispatch {}: pallet {} running {} program(s)", d.dispatch_id, d.pallet, d.programs.size());
  std::string reason;
  bool ok = true;
  try {
    if (!seg_w_.WaitForMatched(1, kServoWait) || !progress_r_.WaitForMatched(1, kServoWait))
      throw Error(Errc::kUnavailable, "no axis servo for station " + cfg_.id + " on the bus");
    for (int rep = 0; rep < d.repeat; ++rep) {
      for (size_t i = 0; i < d.programs.size(); ++i) {
        program_ = d.programs[i];
        PublishRun(d, cell::RUN_ACTIVE);
        RunProgram(d, d.programs[i], st);
        WaitDrained(st);
        ++programs_done_;
        PublishRun(d, cell::RUN_ACTIVE);  // a program finished: its UCY leaves the backlog
      }
    }
  } catch (const Error& e) {
    ok = false;
    reason = e.what();
  }
  double machine_s;
  {
    std::lock_guard lk(motion_mu_);
    machine_s = run_machine_s_;
  }
  const std::string state = ok ? "COMPLETED" : (cancel_id_ == d.dispatch_id ? "CANCELLED" : "FAILED");
  int64_t finished = health::WallNs();
  {
    std::lock_guard lk(db_mu_);
    store::Transaction tx(db_);
    auto u = db_.Prepare("UPDATE runs SET state=?, reason=?, machine_s=?, finished_ns=? WHERE dispatch_id=?");
    u.BindText(1, state).BindText(2, reason).BindDouble(3, machine_s).BindInt64(4, finished);
    u.BindInt64(5, d.dispatch_id);
    u.Run();
    nlohmann::json rec = {{"dispatch_id", d.dispatch_id},
                          {"station", cfg_.id},
                          {"job_id", d.job_id},
                          {"pallet", d.pallet},
                          {"programs", d.programs},
                          {"completed", ok},
                          {"reason", reason},
                          {"started_ns", run_started_ns_},
                          {"finished_ns", finished},
                          {"machine_s", machine_s}};
    auto o = db_.Prepare("INSERT OR REPLACE INTO outbox(dispatch_id, record) VALUES(?,?)");
    o.BindInt64(1, d.dispatch_id).BindText(2, rec.dump());
    o.Run();
    tx.Commit();
  }
  if (ok) {
    spdlog::info("dispatch {} completed: {:.3f} machine seconds", d.dispatch_id, machine_s);
  } else {
    spdlog::error("dispatch {} {}: {}", d.dispatch_id, state, reason);
  }
  int32_t queued;
  {
    std::lock_guard lk(db_mu_);  // lock order everywhere: db_mu_ before status_mu_
    queued = static_cast<int32_t>(db_.QueryInt64("SELECT COUNT(*) FROM runs WHERE state='QUEUED'"));
  }
  {
    std::lock_guard s(status_mu_);
    SetExecution(ok ? cell::EXECUTION_PROGRAM_COMPLETED : cell::EXECUTION_STOPPED);
    status_.part_count(status_.part_count() + (ok ? 1 : 0));
    status_.dispatch_id(0);
    status_.queued(queued);
  }
  PublishRun(d,
             ok                     ? cell::RUN_COMPLETED
             : state == "CANCELLED" ? cell::RUN_CANCELLED
                                    : cell::RUN_FAILED,
             reason);
  PublishStatus();
  FlushOutbox();
}

void Station::RunProgram(const Dispatch& d, const std::string& name, std::stop_token st) {
  auto text = programs_.GetWithFallback(d.node, name);
  if (!text) throw Error(Errc::kNotFound, "program '" + name + "' is not in " + d.node + " or HOST");
  interp::RunOptions opt;
  opt.dialect = cfg_.dialect;
  opt.program_name = name;
  opt.program_text = std::move(*text);
  opt.library = [this, node = d.node](const std::string& lib) {
    return programs_.GetWithFallback(node, lib);
  };
  opt.params = cfg_.params;  // the station config's [params]: the dialect's machine settings (EMCO's monitor)
  opt.params["PALLET"] = std::to_string(d.pallet);
  {
    std::lock_guard lk(db_mu_);
    opt.tools = tools_;
    opt.variables = vars_;
  }
  Env env(*this, st);
  opt.env = &env;
  auto run = interp::StartRun(opt);
  auto last_status = std::chrono::steady_clock::now();
  while (true) {
    if (st.stop_requested()) throw Error(Errc::kUnavailable, "station stopping");
    if (cancel_id_ == d.dispatch_id) throw Error(Errc::kFailedPrecondition, "cancelled");
    interp::Step s = run->Next();
    if (s.kind == interp::Step::kEnd) break;
    if (s.kind == interp::Step::kError) {
      std::lock_guard lk(status_mu_);
      status_.condition(cell::CONDITION_WARNING);
      status_.alarm_code(s.diag.alarm.substr(0, 16));
      status_.alarm_text(s.diag.Format().substr(0, 255));
      throw Error(Errc::kInvalidArgument, s.diag.Format());
    }
    const interp::Canon& c = s.canon;
    {
      std::lock_guard lk(status_mu_);
      status_.program(name.substr(0, 64));
      status_.line(c.line);
      if (auto* t = c.If<interp::ToolChangeOp>()) status_.tool(t->tool.substr(0, 16));
    }
    if (auto seg = ToSegment(c)) Send(*seg, st);
    if (auto* m = c.If<interp::MessageOp>()) spdlog::info("{} line {}: {}", name, c.line, m->text);
    if (std::chrono::steady_clock::now() - last_status > std::chrono::milliseconds(100)) {
      PublishStatus();
      last_status = std::chrono::steady_clock::now();
    }
  }
  PublishStatus();
}

void Station::Send(cell::MotionSegment seg, std::stop_token st) {
  std::unique_lock lk(motion_mu_);
  seg.station(cfg_.id);
  seg.run_id(run_id_);
  seg.seq(++sent_seq_);
  last_progress_ = std::chrono::steady_clock::now();
  // Credit-based flow control: never more segments in flight than the servo granted.
  while (seg.seq() > credit_seq_) {
    CheckServo(lk, st);
    motion_cv_.wait_for(lk, std::chrono::milliseconds(200));
  }
  ResendMissing(lk);  // the earlier segments first: the servo takes them in seq order only
  unacked_.push_back(seg);
  lk.unlock();
  seg_w_.Write(seg);
}

void Station::WaitDrained(std::stop_token st) {
  std::unique_lock lk(motion_mu_);
  while (completed_seq_ < sent_seq_) {
    CheckServo(lk, st);
    motion_cv_.wait_for(lk, std::chrono::milliseconds(200));
  }
}

// While waiting on the servo (lk holds motion_mu_): stop on an alarm, a stop request, a restarted or
// vanished servo; re-send what it may have missed when it matched again.
void Station::CheckServo(std::unique_lock<std::mutex>& lk, std::stop_token st) {
  if (cancel_id_ == run_id_) throw Error(Errc::kFailedPrecondition, "cancelled");
  if (servo_alarm_)
    throw Error(Errc::kFailedPrecondition, "[" + servo_alarm_code_ + "] " + servo_alarm_text_);
  if (st.stop_requested()) throw Error(Errc::kUnavailable, "station stopping");
  if (servo_restarted_)
    throw Error(Errc::kUnavailable, "axis servo of " + cfg_.id + " restarted during the run");
  const auto now = std::chrono::steady_clock::now();
  if (seg_w_.Matched() == 0 && now - last_progress_ > kServoGone)
    throw Error(Errc::kUnavailable, "axis servo of " + cfg_.id + " vanished during the run");
  // Matched on this side but deaf on the other (Fast DDS 2.9 may not re-exchange endpoints after only one
  // side let the lease run out, docs/operations.md): segments are missing and nothing comes back.
  if (!unacked_.empty() && received_seq_ < unacked_.back().seq() && now - last_report_ > kServoGone)
    throw Error(Errc::kUnavailable, "axis servo of " + cfg_.id + " has taken no segment for " +
                                        std::to_string(kServoGone.count()) + " s");
  ResendMissing(lk);
}

// The segment stream is volatile: what is written while the servo is unmatched (its process stopped past the
// DDS lease, a network cut) never arrives, and a servo that dropped the match on its side may miss samples
// the writer still thinks delivered. So segments are kept until completed and sent again, in order, from
// the first one the servo has not reported (received_seq), when the writer matches a servo again or when
// the servo has been silent for a second with segments missing. The servo drops what it already holds.
void Station::ResendMissing(std::unique_lock<std::mutex>& lk) {
  if (unacked_.empty() || seg_w_.Matched() == 0) return;
  const auto now = std::chrono::steady_clock::now();
  const uint64_t matches = seg_w_.TotalMatched();
  const bool rematched = matches != seg_matches_;
  const bool silent = received_seq_ < unacked_.back().seq() && now - last_report_ > std::chrono::seconds(1) &&
                      now - last_resend_ > std::chrono::seconds(1);
  seg_matches_ = matches;
  if (!rematched && !silent) return;
  last_resend_ = now;
  std::vector<cell::MotionSegment> again;
  for (auto& seg : unacked_)
    if (seg.seq() > received_seq_) again.push_back(seg);
  if (again.empty()) return;
  spdlog::warn("axis servo of {} {}: re-sending seq {}..{} of run {}", cfg_.id,
               rematched ? "matched again" : "reported nothing for 1 s", again.front().seq(),
               again.back().seq(), run_id_);
  lk.unlock();  // never write under motion_mu_: the progress callback takes it on the DDS thread
  for (auto& seg : again) seg_w_.Write(seg);
  lk.lock();
}

void Station::SetExecution(cell::Execution base) {
  base_execution_ = base;
  status_.execution(servo_held_ ? cell::EXECUTION_FEED_HOLD : base);
}

void Station::PublishControl() {
  std::lock_guard s(status_mu_);
  control_w_.Write(control_);
}

void Station::SaveRun(int32_t id, const std::string& state, const std::string& reason) {
  auto u = db_.Prepare("UPDATE runs SET state=?, reason=?, finished_ns=? WHERE dispatch_id=?");
  u.BindText(1, state).BindText(2, reason).BindInt64(3, health::WallNs()).BindInt64(4, id);
  u.Run();
}

void Station::FlushOutbox() {
  std::vector<std::pair<int64_t, std::string>> rows;
  {
    std::lock_guard lk(db_mu_);
    auto q = db_.Prepare("SELECT dispatch_id, record FROM outbox ORDER BY dispatch_id LIMIT 16");
    while (q.Step()) rows.emplace_back(q.ColumnInt64(0), q.ColumnText(1));
  }
  for (auto& [id, text] : rows) {
    if (!inspection_.WaitForServer(std::chrono::milliseconds(0))) return;  // writer down: keep, retry later
    auto j = nlohmann::json::parse(text);
    cell::InspectionRequest req;
    req.op(cell::INSPECTION_STORE_RUN);
    req.hdr().idempotency_key("run-" + cfg_.id + "-" + std::to_string(id));
    auto& r = req.run();
    r.dispatch_id(j["dispatch_id"].get<int32_t>());
    r.station(cfg_.id);
    r.job_id(j["job_id"].get<int32_t>());
    r.pallet(j["pallet"].get<int32_t>());
    for (auto& p : j["programs"]) r.programs().push_back(p.get<std::string>());
    r.completed(j["completed"].get<bool>());
    r.reason(j["reason"].get<std::string>().substr(0, 255));
    r.started_ns(j["started_ns"].get<int64_t>());
    r.finished_ns(j["finished_ns"].get<int64_t>());
    r.machine_s(j["machine_s"].get<double>());
    try {
      bus::ThrowIfError(inspection_.Call(req, std::chrono::seconds(5)));
    } catch (const Error& e) {
      spdlog::warn("run record {} not yet stored: {}", id, e.what());
      return;
    }
    std::lock_guard lk(db_mu_);
    auto del = db_.Prepare("DELETE FROM outbox WHERE dispatch_id=?");
    del.BindInt64(1, id);
    del.Run();
  }
}

void Station::PublishStatus() {
  std::lock_guard lk(status_mu_);
  status_.updated_ns(health::WallNs());
  status_w_.Write(status_);
}

void Station::PublishTools() {
  tools_w_.Write(tooltable::ToWire(tools_, cfg_.id, ++tools_rev_));
}

void Station::PublishVariables() {
  cell::StationVariables v;
  v.station(cfg_.id);
  v.revision(++vars_rev_);
  for (auto& [k, val] : vars_) {
    cell::Variable x;
    x.name(k);
    x.value(val);
    v.variables().push_back(x);
  }
  vars_w_.Write(v);
}

void Station::PublishRun(const Dispatch& d, cell::RunState state, const std::string& reason) {
  cell::RunStatus s;
  s.dispatch_id(d.dispatch_id);
  s.station(cfg_.id);
  s.job_id(d.job_id);
  s.pallet(d.pallet);
  s.state(state);
  s.program(program_.substr(0, 64));
  s.programs_done(programs_done_);
  s.program_index(
      static_cast<int32_t>(d.programs.empty() ? 0 : programs_done_ % static_cast<int>(d.programs.size())));
  {
    std::lock_guard lk(motion_mu_);
    s.machine_s(run_machine_s_);
  }
  s.started_ns(run_started_ns_);
  if (state == cell::RUN_COMPLETED || state == cell::RUN_FAILED || state == cell::RUN_CANCELLED)
    s.finished_ns(health::WallNs());
  s.reason(reason.substr(0, 255));
  run_w_.Write(s);
}

}  // namespace cell::station
