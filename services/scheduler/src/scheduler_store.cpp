#include "scheduler_store.h"

#include <cstdint>
#include <utility>
#include <vector>

#include "cell/error/error.h"
#include "cell/scheduler/scheduler.h"

namespace cell::scheduler {

using json = nlohmann::json;

namespace {

const std::vector<store::Migration>& Migrations() {
  static const std::vector<store::Migration> m = {
      store::Migration::Sql(
          1,
          "scheduler: counters, idempotency, stations, pallet maps, routes, jobs, dispatches, "
          "decisions",
          R"sql(
CREATE TABLE counters (name TEXT PRIMARY KEY, value INTEGER NOT NULL);
CREATE TABLE idempotency (key TEXT PRIMARY KEY, result INTEGER NOT NULL);
CREATE TABLE stations (id TEXT PRIMARY KEY, dialect TEXT NOT NULL, online INTEGER NOT NULL,
                       fault INTEGER NOT NULL, alarm_code TEXT NOT NULL, alarm_text TEXT NOT NULL,
                       backlog_s INTEGER NOT NULL, tools TEXT NOT NULL, program TEXT NOT NULL);
CREATE TABLE pallet_maps (pallet INTEGER PRIMARY KEY, programs TEXT NOT NULL);
CREATE TABLE routes (name TEXT PRIMARY KEY, spec TEXT NOT NULL, ops TEXT NOT NULL, valid INTEGER NOT NULL,
                     invalid_reason TEXT NOT NULL);
CREATE TABLE jobs (id INTEGER PRIMARY KEY, state TEXT NOT NULL, kind TEXT NOT NULL, route TEXT NOT NULL,
                   pallet INTEGER NOT NULL, op INTEGER NOT NULL, station TEXT NOT NULL, reason TEXT NOT NULL,
                   started_ms INTEGER NOT NULL, finished_ms INTEGER NOT NULL, cycle_s REAL,
                   dispatch INTEGER NOT NULL, ops TEXT NOT NULL);
CREATE TABLE dispatches (id INTEGER PRIMARY KEY, job INTEGER NOT NULL, station TEXT NOT NULL,
                         pallet INTEGER NOT NULL, op INTEGER NOT NULL, state TEXT NOT NULL,
                         programs TEXT NOT NULL, ucy TEXT NOT NULL, done INTEGER NOT NULL);
CREATE INDEX dispatches_live ON dispatches(state);
CREATE TABLE decisions (seq INTEGER PRIMARY KEY, job INTEGER NOT NULL, body TEXT NOT NULL);
CREATE INDEX decisions_job ON decisions(job);
)sql"),
      store::Migration::Sql(2, "scheduler: station common variables and schedule jobs", R"sql(
ALTER TABLE stations ADD COLUMN vars TEXT NOT NULL DEFAULT '{}';
ALTER TABLE jobs ADD COLUMN schedule TEXT NOT NULL DEFAULT '';
)sql"),
      store::Migration::Sql(3, "scheduler: the command each idempotency key was used for", R"sql(
ALTER TABLE idempotency ADD COLUMN command TEXT NOT NULL DEFAULT '';
)sql"),
      store::Migration::Sql(4, "scheduler: VSET writes a station has not shown back yet", R"sql(
ALTER TABLE stations ADD COLUMN pending_vars TEXT NOT NULL DEFAULT '{}';
)sql"),
      store::Migration::Sql(5, "scheduler: predicted and learned cycle times, a job's predictions", R"sql(
CREATE TABLE estimates (program TEXT NOT NULL, station TEXT NOT NULL, revision TEXT NOT NULL,
                        predicted_s REAL, why TEXT NOT NULL, estimate_s REAL, runs INTEGER NOT NULL,
                        PRIMARY KEY (program, station));
ALTER TABLE jobs ADD COLUMN predicted TEXT NOT NULL DEFAULT '{}';
)sql"),
      store::Migration::Sql(6, "scheduler: why a station's word is awaited on a dispatch it holds", R"sql(
ALTER TABLE dispatches ADD COLUMN interrupted TEXT NOT NULL DEFAULT '';
)sql"),
  };
  return m;
}

JobState ParseJobState(std::string_view s) {
  if (auto st = JobStateFromName(s)) return *st;
  throw Error(Errc::kInternal, "scheduler database: unknown job state '" + std::string(s) + "'");
}

DState ParseDState(std::string_view s) {
  for (int i = 0; i < 7; ++i) {
    if (s == kDStateNames[i]) return static_cast<DState>(i);
  }
  throw Error(Errc::kInternal, "scheduler database: unknown dispatch state '" + std::string(s) + "'");
}

}  // namespace

json SpecToJson(const RouteSpec& s) {
  json ops = json::array();
  for (const auto& op : s.ops) ops.push_back({{"stations", op.stations}, {"programs", op.programs}});
  return {{"name", s.name}, {"ops", ops}};
}

namespace {

RouteSpec SpecFromJson(const json& j) {
  RouteSpec s;
  s.name = j.at("name");
  for (const auto& op : j.at("ops")) s.ops.push_back(OpSpec{op.at("stations"), op.at("programs")});
  return s;
}

json OpsToJson(const std::vector<Op>& ops, const std::vector<StationRec>& st) {
  json out = json::array();
  for (const auto& op : ops) {
    std::vector<std::string> names;
    for (int s : op.stations) names.push_back(st[static_cast<std::size_t>(s)].id);
    out.push_back({{"stations", names},
                   {"programs", op.programs},
                   {"ucy", op.ucy},
                   {"tools", op.tools},
                   {"blocked", op.blocked},
                   {"revisions", op.revisions},
                   {"stated", op.stated}});
  }
  return out;
}

Ops OpsFromJson(State& state, const json& j) {
  auto ops = std::make_shared<std::vector<Op>>();
  for (const auto& o : j) {
    Op op;
    for (const auto& s : o.at("stations"))
      op.stations.push_back(state.StationIndex(s.get<std::string>(), true));
    op.programs = o.at("programs").get<std::vector<std::string>>();
    op.ucy = o.at("ucy").get<std::vector<std::int64_t>>();
    op.tools = o.at("tools").get<std::vector<std::string>>();
    op.blocked = o.at("blocked");
    // Operations stored before estimates have neither: UCY alone, as then.
    if (o.contains("revisions")) op.revisions = o.at("revisions").get<std::vector<std::string>>();
    if (o.contains("stated")) op.stated = o.at("stated").get<std::vector<char>>();
    for (auto u : op.ucy) op.ucy_sum += u;
    for (const auto& t : op.tools) op.tool_ids.push_back(state.tool_index.Intern(t));
    ops->push_back(std::move(op));
  }
  return ops;
}

// ---- load, one table each, in the order of the schema ----
void LoadCounters(store::Database& db, State& state) {
  auto q = db.Prepare("SELECT name, value FROM counters");
  while (q.Step()) {
    const std::string n = q.ColumnText(0);
    if (n == "job") state.next_job = q.ColumnInt64(1);
    if (n == "dispatch") state.next_dispatch = q.ColumnInt64(1);
    if (n == "decision") state.next_seq = q.ColumnInt64(1);
  }
}

void LoadStations(store::Database& db, State& state) {
  auto q = db.Prepare(
      "SELECT id, dialect, online, fault, alarm_code, alarm_text, tools, program, vars, pending_vars FROM "
      "stations "
      "ORDER BY rowid");
  while (q.Step()) {
    const int s = state.StationIndex(q.ColumnText(0), true);
    StationRec& st = state.stations[static_cast<std::size_t>(s)];
    st.dialect = q.ColumnText(1);
    state.states[static_cast<std::size_t>(s)].online = q.ColumnInt64(2) != 0;
    state.states[static_cast<std::size_t>(s)].fault = q.ColumnInt64(3) != 0;
    st.alarm_code = q.ColumnText(4);
    st.alarm_text = q.ColumnText(5);
    st.tools = tooltable::FromJson(json::parse(q.ColumnText(6)));
    st.program = q.ColumnText(7);
    const json vars = json::parse(q.ColumnText(8));
    for (auto it = vars.begin(); it != vars.end(); ++it)
      st.vars[std::stoi(it.key())] = it.value().get<double>();
    const json pending = json::parse(q.ColumnText(9));
    for (auto it = pending.begin(); it != pending.end(); ++it)
      st.pending_vars[std::stoi(it.key())] = it.value().get<double>();
    state.states[static_cast<std::size_t>(s)].SetTools(st.tools, state.tool_index);
  }
}

void LoadPalletMaps(store::Database& db, State& state) {
  auto q = db.Prepare("SELECT pallet, programs FROM pallet_maps");
  while (q.Step()) {
    state.pallet_maps[static_cast<int>(q.ColumnInt64(0))] =
        json::parse(q.ColumnText(1)).get<std::vector<std::string>>();
  }
}

void LoadRoutes(store::Database& db, State& state) {
  auto q = db.Prepare("SELECT name, spec, ops, valid, invalid_reason FROM routes");
  while (q.Step()) {
    RouteRec r;
    r.spec = SpecFromJson(json::parse(q.ColumnText(1)));
    r.ops = OpsFromJson(state, json::parse(q.ColumnText(2)));
    r.valid = q.ColumnInt64(3) != 0;
    r.invalid_reason = q.ColumnText(4);
    state.routes.emplace(q.ColumnText(0), std::move(r));
  }
}

// The states a job ends in, as stored.
constexpr const char* kEndedStates = "('COMPLETED', 'FAILED', 'CANCELLED')";

void LoadJobs(store::Database& db, State& state, std::size_t kept_ended) {
  auto q = db.Prepare(
      std::string("SELECT id, state, kind, route, pallet, op, station, reason, started_ms, finished_ms, "
                  "cycle_s, dispatch, ops, schedule, predicted FROM jobs WHERE state NOT IN ") +
      kEndedStates + " OR id IN (SELECT id FROM jobs WHERE state IN " + kEndedStates +
      " ORDER BY id DESC LIMIT ?1)");
  q.BindInt64(1, static_cast<std::int64_t>(kept_ended));
  while (q.Step()) {
    JobRec j;
    j.id = q.ColumnInt64(0);
    j.state = ParseJobState(q.ColumnText(1));
    j.kind = q.ColumnText(2);
    j.route = q.ColumnText(3);
    j.pallet = static_cast<int>(q.ColumnInt64(4));
    j.op = static_cast<int>(q.ColumnInt64(5));
    const std::string st = q.ColumnText(6);
    j.station = st.empty() ? -1 : state.StationIndex(st, true);
    j.reason = q.ColumnText(7);
    j.started = q.ColumnInt64(8);
    j.finished = q.ColumnInt64(9);
    if (!q.IsNull(10)) j.cycle = q.ColumnDouble(10);
    j.dispatch = q.ColumnInt64(11);
    j.ops = OpsFromJson(state, json::parse(q.ColumnText(12)));
    // Jobs of a route share its current operations when they are the same.
    if (auto r = state.routes.find(j.route);
        r != state.routes.end() &&
        OpsToJson(*r->second.ops, state.stations) == OpsToJson(*j.ops, state.stations)) {
      j.ops = r->second.ops;
    }
    if (const std::string sched = q.ColumnText(13); !sched.empty()) {
      const json js = json::parse(sched);
      j.sched_name = js.at("name");
      j.sched_text = js.at("text");
      j.sched = std::make_shared<schedule::Program>(schedule::Parse(j.sched_text, j.sched_name));
      j.sched_pos.pc = js.at("pc");
      j.sched_pos.done = js.at("done");
      j.sched_pos.count = js.at("count");
      j.sched_pos.finished = js.at("finished");
      // Stored since the one-schedule-a-station rule; before it, the station of its run (if any).
      if (auto it = js.find("station"); it != js.end() && it->is_string()) {
        j.sched_station = state.StationIndex(it->get<std::string>(), true);
      } else if (!j.ops->empty() && !(*j.ops)[0].stations.empty()) {
        j.sched_station = (*j.ops)[0].stations[0];
      }
      // A schedule that has stepped has its station to itself (StationState::schedule_job).
      if (!IsTerminal(j.state) && !j.ops->empty() && j.sched_station >= 0)
        state.states[static_cast<std::size_t>(j.sched_station)].schedule_job = j.id;
      if (const auto& r = js.at("run"); !r.is_null()) {
        j.sched_run = schedule::Run{r.at("main_file"), r.at("program"), r.at("sub_file"),
                                    r.at("index"),     r.at("count"),   r.at("line")};
      }
    }
    const json predicted = json::parse(q.ColumnText(14));
    for (const auto& [op, v] : predicted.items()) j.predicted[std::stoi(op)] = v.get<double>();
    if (j.state == JobState::kWaiting) state.waiting.insert(j.id);
    if (!IsTerminal(j.state) && j.pallet != 0) state.busy_pallets[j.pallet] = j.id;
    state.jobs.emplace(j.id, std::move(j));
  }
}

void LoadDispatches(store::Database& db, State& state) {
  auto q = db.Prepare(
      "SELECT id, job, station, pallet, op, state, programs, ucy, done, interrupted FROM dispatches "
      "ORDER BY id");
  while (q.Step()) {
    DispatchRec r;
    r.id = q.ColumnInt64(0);
    r.job = q.ColumnInt64(1);
    r.station = state.StationIndex(q.ColumnText(2), true);
    r.pallet = static_cast<int>(q.ColumnInt64(3));
    r.op = static_cast<int>(q.ColumnInt64(4));
    r.state = ParseDState(q.ColumnText(5));
    r.programs = json::parse(q.ColumnText(6)).get<std::vector<std::string>>();
    r.ucy = json::parse(q.ColumnText(7)).get<std::vector<std::int64_t>>();
    r.done = static_cast<int>(q.ColumnInt64(8));
    r.interrupted = q.ColumnText(9);
    if (!Live(r.state) && !state.jobs.count(r.job)) continue;  // its job's record is read when asked for
    // Backlog and station queues are rebuilt from the live dispatches.
    if (Live(r.state)) {
      StationRec& st = state.stations[static_cast<std::size_t>(r.station)];
      state.states[static_cast<std::size_t>(r.station)].backlog_s += r.Remaining();
      if (r.state == DState::kQueued)
        st.queue.push_back(r.id);
      else
        st.inflight = r.id;
    }
    state.dispatches.emplace(r.id, std::move(r));
  }
}

void LoadDecisions(store::Database& db, State& state) {
  if (state.jobs.empty()) return;
  auto q = db.Prepare("SELECT seq, job, body FROM decisions WHERE job >= ?1 ORDER BY seq");
  q.BindInt64(1, state.jobs.begin()->first);
  while (q.Step()) {
    auto it = state.jobs.find(q.ColumnInt64(1));
    if (it == state.jobs.end()) continue;
    const json b = json::parse(q.ColumnText(2));
    DecisionRec r;
    r.seq = q.ColumnInt64(0);
    r.time_ms = b.at("time_ms");
    r.op = b.at("op");
    r.trigger = b.at("trigger");
    r.why = b.at("why");
    r.added = b.at("added");
    const std::string winner = b.at("winner");
    r.alloc.winner = winner.empty() ? -1 : state.StationIndex(winner, true);
    r.alloc.tied = b.at("tied");
    for (const auto& c : b.at("considered")) {
      CandidateRec cr;
      cr.station = state.StationIndex(c.at("station").get<std::string>(), true);
      cr.backlog_s = c.at("backlog_s");
      cr.online = c.at("online");
      cr.fault = c.at("fault");
      cr.missing_begin = static_cast<std::uint32_t>(r.alloc.missing.size());
      for (const auto& t : c.at("missing"))
        r.alloc.missing.push_back(state.tool_index.Intern(t.get<std::string>()));
      cr.missing_count = static_cast<std::uint32_t>(r.alloc.missing.size()) - cr.missing_begin;
      r.alloc.candidates.push_back(std::move(cr));
    }
    it->second.decisions.push_back(std::move(r));
  }
}

// ---- read back what memory let go of ----
// The columns StoredJob reads, in its order.
constexpr const char* kJobViewColumns =
    "id, state, kind, route, pallet, op, station, reason, started_ms, finished_ms, cycle_s, ops, schedule, "
    "(SELECT COUNT(*) FROM decisions WHERE decisions.job = jobs.id), predicted";

JobView StoredJob(store::Statement& q) {
  JobView v;
  v.id = q.ColumnInt64(0);
  v.state = ParseJobState(q.ColumnText(1));
  v.kind = q.ColumnText(2);
  v.route = q.ColumnText(3);
  v.pallet = static_cast<int>(q.ColumnInt64(4));
  v.op_index = static_cast<int>(q.ColumnInt64(5));
  v.station = q.ColumnText(6);
  v.reason = q.ColumnText(7);
  v.started_ms = q.ColumnInt64(8);
  v.finished_ms = q.ColumnInt64(9);
  if (!q.IsNull(10)) v.cycle_s = q.ColumnDouble(10);
  v.op_count = static_cast<int>(json::parse(q.ColumnText(11)).size());
  if (const std::string sched = q.ColumnText(12); !sched.empty()) v.schedule = json::parse(sched).at("name");
  v.decision_count = static_cast<int>(q.ColumnInt64(13));
  // As Scheduler::Impl::View: the sum of the predictions each operation's allocation used.
  if (const json predicted = json::parse(q.ColumnText(14)); !predicted.empty()) {
    double sum = 0;
    for (const auto& [op, seconds] : predicted.items()) sum += seconds.get<double>();
    v.predicted_s = sum;
  }
  return v;
}

// A decision as FlushDecisions stored it, in the view's form.
Decision StoredDecision(std::int64_t seq, const json& b) {
  Decision d;
  d.seq = seq;
  d.time_ms = b.at("time_ms");
  d.op_index = b.at("op");
  d.trigger = b.at("trigger");
  d.why = b.at("why");
  d.added_backlog_s = b.at("added");
  d.winner = b.at("winner");
  for (const auto& c : b.at("considered")) {
    Candidate cv;
    cv.station = c.at("station");
    cv.online = c.at("online");
    cv.fault = c.at("fault");
    cv.backlog_s = c.at("backlog_s");
    cv.missing_tools = c.at("missing").get<std::vector<std::string>>();
    cv.eligible = cv.online && !cv.fault && cv.missing_tools.empty();  // CandidateRec::eligible
    d.considered.push_back(std::move(cv));
  }
  return d;
}

// ---- flush, one table each; Store::Flush calls them in this order ----
void FlushCounters(store::Database& db, const State& state) {
  auto q = db.Prepare(
      "INSERT INTO counters(name, value) VALUES (?1, ?2) "
      "ON CONFLICT(name) DO UPDATE SET value = excluded.value");
  for (auto [n, v] : {std::pair<const char*, std::int64_t>{"job", state.next_job},
                      {"dispatch", state.next_dispatch},
                      {"decision", state.next_seq}}) {
    q.BindText(1, n).BindInt64(2, v).Run();
    q.Reset();
  }
}

void FlushIdempotency(store::Database& db, const State& state) {
  if (state.new_idem.empty()) return;
  auto q = db.Prepare("INSERT OR IGNORE INTO idempotency(key, result, command) VALUES (?1, ?2, ?3)");
  for (const auto& [k, v] : state.new_idem) {
    q.BindText(1, k).BindInt64(2, v.result).BindText(3, v.command).Run();
    q.Reset();
  }
}

void FlushStations(store::Database& db, const State& state) {
  if (state.dirty_stations.empty()) return;
  auto q = db.Prepare(
      "INSERT INTO stations(id, dialect, online, fault, alarm_code, alarm_text, backlog_s, tools, program, "
      "vars, pending_vars) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11) ON CONFLICT(id) DO UPDATE "
      "SET "
      "dialect = excluded.dialect, online = excluded.online, fault = excluded.fault, "
      "alarm_code = excluded.alarm_code, alarm_text = excluded.alarm_text, backlog_s = excluded.backlog_s, "
      "tools = excluded.tools, program = excluded.program, vars = excluded.vars, "
      "pending_vars = excluded.pending_vars");
  for (int s : state.dirty_stations) {
    const StationRec& st = state.stations[static_cast<std::size_t>(s)];
    const StationState& ss = state.states[static_cast<std::size_t>(s)];
    json vars = json::object();
    for (const auto& [n, v] : st.vars) vars[std::to_string(n)] = v;
    json pending = json::object();
    for (const auto& [n, v] : st.pending_vars) pending[std::to_string(n)] = v;
    q.BindText(11, pending.dump());
    q.BindText(1, st.id).BindText(2, st.dialect).BindInt64(3, ss.online).BindInt64(4, ss.fault);
    q.BindText(5, st.alarm_code).BindText(6, st.alarm_text).BindInt64(7, ss.backlog_s);
    q.BindText(10, vars.dump());
    q.BindText(8, tooltable::ToJson(st.tools).dump()).BindText(9, st.program).Run();
    q.Reset();
  }
}

void FlushPalletMaps(store::Database& db, const State& state) {
  if (state.dirty_pallets.empty()) return;
  auto q = db.Prepare(
      "INSERT INTO pallet_maps(pallet, programs) VALUES (?1, ?2) "
      "ON CONFLICT(pallet) DO UPDATE SET programs = excluded.programs");
  for (int p : state.dirty_pallets) {
    q.BindInt64(1, p).BindText(2, json(state.pallet_maps.at(p)).dump()).Run();
    q.Reset();
  }
}

void FlushRoutes(store::Database& db, const State& state) {
  if (state.dirty_routes.empty()) return;
  auto q = db.Prepare(
      "INSERT INTO routes(name, spec, ops, valid, invalid_reason) VALUES (?1, ?2, ?3, ?4, ?5) "
      "ON CONFLICT(name) DO UPDATE SET spec = excluded.spec, ops = excluded.ops, "
      "valid = excluded.valid, invalid_reason = excluded.invalid_reason");
  for (const auto& n : state.dirty_routes) {
    const RouteRec& r = state.routes.at(n);
    q.BindText(1, n)
        .BindText(2, SpecToJson(r.spec).dump())
        .BindText(3, OpsToJson(*r.ops, state.stations).dump());
    q.BindInt64(4, r.valid).BindText(5, r.invalid_reason).Run();
    q.Reset();
  }
}

void FlushJobs(store::Database& db, const State& state) {
  if (state.dirty_jobs.empty()) return;
  auto q = db.Prepare(
      "INSERT INTO jobs(id, state, kind, route, pallet, op, station, reason, started_ms, finished_ms, "
      "cycle_s, "
      "dispatch, ops, schedule, predicted) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, "
      "?14, "
      "?15) "
      "ON CONFLICT(id) DO UPDATE SET state = excluded.state, op = excluded.op, station = excluded.station, "
      "reason = excluded.reason, started_ms = excluded.started_ms, finished_ms = excluded.finished_ms, "
      "cycle_s = excluded.cycle_s, dispatch = excluded.dispatch, ops = excluded.ops, "
      "schedule = excluded.schedule, predicted = excluded.predicted");
  for (std::int64_t id : state.dirty_jobs) {
    const JobRec& j = state.jobs.at(id);
    q.BindInt64(1, j.id).BindText(2, JobStateName(j.state)).BindText(3, j.kind).BindText(4, j.route);
    q.BindInt64(5, j.pallet).BindInt64(6, j.op);
    q.BindText(7, j.station < 0 ? std::string() : state.stations[static_cast<std::size_t>(j.station)].id);
    q.BindText(8, j.reason).BindInt64(9, j.started).BindInt64(10, j.finished);
    if (j.cycle)
      q.BindDouble(11, *j.cycle);
    else
      q.BindNull(11);
    std::string sched;
    if (j.kind == "schedule") {
      json js = {{"name", j.sched_name},
                 {"text", j.sched_text},
                 {"pc", j.sched_pos.pc},
                 {"done", j.sched_pos.done},
                 {"count", j.sched_pos.count},
                 {"finished", j.sched_pos.finished},
                 {"station", j.sched_station >= 0
                                 ? json(state.stations[static_cast<std::size_t>(j.sched_station)].id)
                                 : json(nullptr)},
                 {"run", nullptr}};
      if (j.sched_run) {
        const auto& r = *j.sched_run;
        js["run"] = {{"main_file", r.main_file}, {"program", r.program}, {"sub_file", r.sub_file},
                     {"index", r.index},         {"count", r.count},     {"line", r.line}};
      }
      sched = js.dump();
    }
    q.BindText(14, sched);
    json predicted = json::object();
    for (const auto& [op, v] : j.predicted) predicted[std::to_string(op)] = v;
    q.BindText(15, predicted.dump());
    q.BindInt64(12, j.dispatch).BindText(13, OpsToJson(*j.ops, state.stations).dump()).Run();
    q.Reset();
  }
}

void FlushDispatches(store::Database& db, const State& state) {
  if (state.dirty_dispatches.empty()) return;
  auto q = db.Prepare(
      "INSERT INTO dispatches(id, job, station, pallet, op, state, programs, ucy, done, interrupted) "
      "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10) ON CONFLICT(id) DO UPDATE SET state = "
      "excluded.state, "
      "done = excluded.done, interrupted = excluded.interrupted");
  for (std::int64_t id : state.dirty_dispatches) {
    const DispatchRec& r = state.dispatches.at(id);
    q.BindInt64(1, r.id).BindInt64(2, r.job).BindText(3,
                                                      state.stations[static_cast<std::size_t>(r.station)].id);
    q.BindInt64(4, r.pallet).BindInt64(5, r.op).BindText(6, kDStateNames[static_cast<int>(r.state)]);
    q.BindText(7, json(r.programs).dump())
        .BindText(8, json(r.ucy).dump())
        .BindInt64(9, r.done)
        .BindText(10, r.interrupted)
        .Run();
    q.Reset();
  }
}

void FlushDecisions(store::Database& db, const State& state) {
  if (state.new_decisions.empty()) return;
  auto q = db.Prepare("INSERT INTO decisions(seq, job, body) VALUES (?1, ?2, ?3)");
  for (auto [job, idx] : state.new_decisions) {
    const DecisionRec& r = state.jobs.at(job).decisions.at(idx);
    json considered = json::array();
    for (const auto& c : r.alloc.candidates) {
      std::vector<std::string> missing;
      r.alloc.ForMissing(c, [&](int t) { missing.push_back(state.tool_index.Name(t)); });
      considered.push_back({{"station", state.stations[static_cast<std::size_t>(c.station)].id},
                            {"backlog_s", c.backlog_s},
                            {"online", c.online},
                            {"fault", c.fault},
                            {"missing", missing}});
    }
    const json body = {
        {"time_ms", r.time_ms},
        {"op", r.op},
        {"trigger", r.trigger},
        {"why", r.why.empty() && r.alloc.winner < 0 ? state.Describe(r.alloc) : r.why},
        {"added", r.added},
        {"winner", r.alloc.winner < 0 ? "" : state.stations[static_cast<std::size_t>(r.alloc.winner)].id},
        {"tied", r.alloc.tied},
        {"considered", considered}};
    q.BindInt64(1, r.seq).BindInt64(2, job).BindText(3, body.dump()).Run();
    q.Reset();
  }
}

}  // namespace

// 512 KiB of page cache: the scheduler writes each decision once and reads back only what memory let go of
// (Impl::Trim), so SQLite's default 2 MB cache only delayed the point where its memory stops growing.
Store::Store(const std::string& path) : db_(store::Database::Open(path, {.cache_kib = 512})) {
  store::Migrate(db_, Migrations());
}

void LoadEstimates(store::Database& db, State& state) {
  auto q = db.Prepare("SELECT program, station, revision, predicted_s, why, estimate_s, runs FROM estimates");
  while (q.Step()) {
    EstimateRec& r = state.estimates[{q.ColumnText(0), q.ColumnText(1)}];
    r.revision = q.ColumnText(2);
    if (!q.IsNull(3)) r.predicted = q.ColumnDouble(3);
    r.why = q.ColumnText(4);
    if (!q.IsNull(5)) r.estimate = q.ColumnDouble(5);
    r.runs = static_cast<int>(q.ColumnInt64(6));
  }
}

void FlushEstimates(store::Database& db, const State& state) {
  if (state.dirty_estimates.empty()) return;
  auto q = db.Prepare(
      "INSERT OR REPLACE INTO estimates(program, station, revision, predicted_s, why, estimate_s, runs) "
      "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)");
  for (const EstimateKey& k : state.dirty_estimates) {
    const EstimateRec& r = state.estimates.at(k);
    q.BindText(1, k.first).BindText(2, k.second).BindText(3, r.revision).BindText(5, r.why);
    if (r.predicted)
      q.BindDouble(4, *r.predicted);
    else
      q.BindNull(4);
    if (r.estimate)
      q.BindDouble(6, *r.estimate);
    else
      q.BindNull(6);
    q.BindInt64(7, r.runs).Run();
    q.Reset();
  }
}

void Store::Load(State& state, std::size_t kept_ended) {
  LoadCounters(db_, state);
  LoadStations(db_, state);
  LoadPalletMaps(db_, state);
  LoadRoutes(db_, state);
  LoadJobs(db_, state, kept_ended);
  LoadDispatches(db_, state);
  LoadDecisions(db_, state);
  LoadEstimates(db_, state);
  state.ClearDirty();
}

std::optional<JobView> Store::Job(std::int64_t id, bool with_decisions) {
  auto q = db_.Prepare(std::string("SELECT ") + kJobViewColumns + " FROM jobs WHERE id = ?1");
  q.BindInt64(1, id);
  if (!q.Step()) return std::nullopt;
  JobView v = StoredJob(q);
  if (with_decisions) {
    auto d = db_.Prepare("SELECT seq, body FROM decisions WHERE job = ?1 ORDER BY seq");
    d.BindInt64(1, id);
    while (d.Step()) v.decisions.push_back(StoredDecision(d.ColumnInt64(0), json::parse(d.ColumnText(1))));
  }
  return v;
}

void Store::ForJobs(const JobQuery& q,
                    const std::function<bool(std::int64_t, const std::function<JobView()>&)>& visit) {
  auto s = db_.Prepare(std::string("SELECT ") + kJobViewColumns +
                       " FROM jobs WHERE id > ?1 AND (?2 = '' OR state = ?2) AND (?3 = '' OR station = ?3) "
                       "ORDER BY id");
  s.BindInt64(1, q.after)
      .BindText(2, q.state ? std::string(JobStateName(*q.state)) : std::string())
      .BindText(3, q.station);
  const std::function<JobView()> stored = [&s] { return StoredJob(s); };
  while (s.Step())
    if (!visit(s.ColumnInt64(0), stored)) return;
}

std::optional<Keyed> Store::Idempotency(const std::string& key) {
  auto q = db_.Prepare("SELECT result, command FROM idempotency WHERE key = ?1");
  q.BindText(1, key);
  if (!q.Step()) return std::nullopt;
  return Keyed{q.ColumnInt64(0), q.ColumnText(1)};
}

void Store::Flush(const State& state) {
  store::Transaction tx(db_);
  FlushCounters(db_, state);
  FlushIdempotency(db_, state);
  FlushStations(db_, state);
  FlushPalletMaps(db_, state);
  FlushRoutes(db_, state);
  FlushJobs(db_, state);
  FlushDispatches(db_, state);
  FlushDecisions(db_, state);
  FlushEstimates(db_, state);
  tx.Commit();
}

}  // namespace cell::scheduler
