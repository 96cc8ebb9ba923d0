#include "cell/station/station_db.h"

#include <cstdlib>

#include <nlohmann/json.hpp>

#include "cell/records/names.h"

namespace cell::station {

namespace {

// The station's run states are the wire's (cell/run/status), stored by their records names.
static_assert(static_cast<int>(RunState::kQueued) == static_cast<int>(cell::RUN_QUEUED) &&
              static_cast<int>(RunState::kActive) == static_cast<int>(cell::RUN_ACTIVE) &&
              static_cast<int>(RunState::kCompleted) == static_cast<int>(cell::RUN_COMPLETED) &&
              static_cast<int>(RunState::kFailed) == static_cast<int>(cell::RUN_FAILED) &&
              static_cast<int>(RunState::kCancelled) == static_cast<int>(cell::RUN_CANCELLED));

RunState StateFromText(const std::string& s) {
  for (auto r : {RunState::kActive, RunState::kCompleted, RunState::kFailed, RunState::kCancelled})
    if (RunStateName(r) == s) return r;
  return RunState::kQueued;
}

Dispatch ReadDispatch(store::Statement& q) {
  Dispatch d;
  d.dispatch_id = static_cast<std::int32_t>(q.ColumnInt64(0));
  d.job_id = static_cast<std::int32_t>(q.ColumnInt64(1));
  d.pallet = static_cast<std::int32_t>(q.ColumnInt64(2));
  d.node = q.ColumnText(3);
  for (auto& p : nlohmann::json::parse(q.ColumnText(4))) d.programs.push_back(p.get<std::string>());
  d.repeat = static_cast<int>(q.ColumnInt64(5));
  return d;
}

constexpr const char* kDispatchColumns = "dispatch_id, job_id, pallet, node, programs, repeat";

}  // namespace

std::string_view RunStateName(RunState s) {
  return records::RunStateName(static_cast<cell::RunState>(s));
}

std::vector<store::Migration> StationDb::Migrations() {
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
      store::Migration::Sql(2, "operator panel", "CREATE TABLE panel(name TEXT PRIMARY KEY, value REAL);"),
      // Version 2 kept the tool table in columns without the TLD flags C and M, the horsepower H and the
      // process compensations (W), and discrete inputs among the variables. From 3 the table is one JSON
      // document (common/tooltable's stored form: every field of every dialect, no migration per new field);
      // a database with that row was seeded from the station config. Inputs move to their own table.
      store::Migration{
          3, "tool table as one document, inputs, run progress",
          [](store::Database& db) {
            db.Exec(
                "CREATE TABLE tool_table(id INTEGER PRIMARY KEY CHECK (id = 1), json TEXT NOT NULL);"
                "CREATE TABLE inputs(name TEXT PRIMARY KEY, value REAL);"
                "INSERT INTO inputs(name, value) SELECT name, value FROM variables"
                " WHERE name GLOB 'I[0-9]*';"
                "DELETE FROM variables WHERE name GLOB 'I[0-9]*';"
                "ALTER TABLE runs ADD COLUMN programs_done INTEGER NOT NULL DEFAULT 0;");
            // Version 2 seeded the config's tools at every start while it had neither tools
            // nor runs; either means it was seeded.
            if (db.QueryInt64("SELECT COUNT(*) FROM tools") + db.QueryInt64("SELECT COUNT(*) FROM runs") >
                0) {
              std::vector<tooltable::ToolEntry> entries;
              auto q = db.Prepare(
                  "SELECT tool, socket, length, diameter, life_left_min, worn, broken FROM tools"
                  " ORDER BY ord");
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
              auto ins = db.Prepare("INSERT INTO tool_table(id, json) VALUES(1, ?)");
              ins.BindText(1, tooltable::ToJson(tooltable::ToolTable(std::move(entries))).dump());
              ins.Run();
            }
            db.Exec("DROP TABLE tools;");
          }},
      // Discrete outputs the programs set (KT-APL SET, Okuma VDOUT, the station file's M codes) and their
      // power-up states (KT-APL `(SET)`); inputs stay in `inputs`.
      store::Migration::Sql(4, "discrete outputs",
                            "CREATE TABLE outputs(name TEXT PRIMARY KEY, value INTEGER NOT NULL,"
                            " power_up INTEGER NOT NULL DEFAULT 0);")};
}

StationDb::StationDb(const std::filesystem::path& file) : db_(store::Database::Open(file)) {
  store::Migrate(db_, Migrations());
}

int StationDb::SchemaVersion() {
  std::lock_guard lk(mu_);
  return store::SchemaVersion(db_);
}

MemoryImage StationDb::LoadMemory() {
  std::lock_guard lk(mu_);
  MemoryImage m;
  const std::string tools = db_.QueryText("SELECT json FROM tool_table WHERE id=1");
  if (!tools.empty()) m.tools = tooltable::FromJson(nlohmann::json::parse(tools));
  auto v = db_.Prepare("SELECT name, value FROM variables");
  while (v.Step()) m.variables[v.ColumnText(0)] = v.ColumnDouble(1);
  return m;
}

bool StationDb::ToolsSeeded() {
  std::lock_guard lk(mu_);
  return db_.QueryInt64("SELECT COUNT(*) FROM tool_table") > 0;
}

void StationDb::SaveMemory(const MemoryImage& m, const RunProgress* run) {
  const std::string tools = tooltable::ToJson(m.tools).dump();
  std::lock_guard lk(mu_);
  store::Transaction tx(db_);
  auto t = db_.Prepare("INSERT OR REPLACE INTO tool_table(id, json) VALUES(1, ?)");
  t.BindText(1, tools);
  t.Run();
  db_.Exec("DELETE FROM variables;");
  auto var = db_.Prepare("INSERT INTO variables(name, value) VALUES(?,?)");
  for (const auto& [name, value] : m.variables) {
    var.BindText(1, name).BindDouble(2, value);
    var.Run();
    var.Reset();
  }
  if (run) WriteProgress(*run);
  tx.Commit();
}

std::optional<RunState> StationDb::FindRun(std::int32_t dispatch_id) {
  std::lock_guard lk(mu_);
  auto q = db_.Prepare("SELECT state FROM runs WHERE dispatch_id=?");
  q.BindInt64(1, dispatch_id);
  if (!q.Step()) return std::nullopt;
  return StateFromText(q.ColumnText(0));
}

void StationDb::Enqueue(const Dispatch& d, std::int64_t received_ns) {
  Insert(d, RunState::kQueued, "", received_ns, 0);
}

void StationDb::EnqueueCancelled(const Dispatch& d, const std::string& reason, std::int64_t now_ns) {
  Insert(d, RunState::kCancelled, reason, now_ns, now_ns);
}

void StationDb::Insert(const Dispatch& d, RunState state, const std::string& reason, std::int64_t received_ns,
                       std::int64_t finished_ns) {
  nlohmann::json progs = d.programs;
  std::lock_guard lk(mu_);
  auto ins = db_.Prepare(
      "INSERT INTO runs(dispatch_id, job_id, pallet, node, programs, repeat, state, reason, received_ns, "
      "finished_ns) VALUES(?,?,?,?,?,?,?,?,?,?)");
  ins.BindInt64(1, d.dispatch_id).BindInt64(2, d.job_id).BindInt64(3, d.pallet).BindText(4, d.node);
  ins.BindText(5, progs.dump()).BindInt64(6, d.repeat).BindText(7, RunStateName(state)).BindText(8, reason);
  ins.BindInt64(9, received_ns).BindInt64(10, finished_ns);
  ins.Run();
}

std::optional<Dispatch> StationDb::TakeNext(std::int64_t started_ns) {
  std::lock_guard lk(mu_);
  store::Transaction tx(db_);
  Dispatch d;
  {
    auto q = db_.Prepare(std::string("SELECT ") + kDispatchColumns +
                         " FROM runs WHERE state='QUEUED' ORDER BY received_ns, dispatch_id LIMIT 1");
    if (!q.Step()) return std::nullopt;
    d = ReadDispatch(q);
  }
  auto u = db_.Prepare("UPDATE runs SET state='ACTIVE', started_ns=? WHERE dispatch_id=?");
  u.BindInt64(1, started_ns).BindInt64(2, d.dispatch_id);
  u.Run();
  tx.Commit();
  return d;
}

bool StationDb::CancelQueued(std::int32_t dispatch_id, const std::string& reason, std::int64_t finished_ns) {
  std::lock_guard lk(mu_);
  auto u = db_.Prepare(
      "UPDATE runs SET state='CANCELLED', reason=?, finished_ns=? WHERE dispatch_id=? AND state='QUEUED'");
  u.BindText(1, reason).BindInt64(2, finished_ns).BindInt64(3, dispatch_id);
  u.Run();
  return db_.Changes() > 0;
}

std::vector<Dispatch> StationDb::Runs(RunState state) {
  std::lock_guard lk(mu_);
  auto q = db_.Prepare(std::string("SELECT ") + kDispatchColumns +
                       " FROM runs WHERE state=? ORDER BY received_ns, dispatch_id");
  q.BindText(1, RunStateName(state));
  std::vector<Dispatch> out;
  while (q.Step()) out.push_back(ReadDispatch(q));
  return out;
}

std::int32_t StationDb::LowestDispatchId() {
  std::lock_guard lk(mu_);
  auto q = db_.Prepare("SELECT COALESCE(MIN(dispatch_id), 0) FROM runs");
  q.Step();
  return static_cast<std::int32_t>(q.ColumnInt64(0));
}

int StationDb::Count(RunState state) {
  std::lock_guard lk(mu_);
  auto q = db_.Prepare("SELECT COUNT(*) FROM runs WHERE state=?");
  q.BindText(1, RunStateName(state));
  q.Step();
  return static_cast<int>(q.ColumnInt64(0));
}

std::pair<std::int64_t, int> StationDb::Progress(std::int32_t dispatch_id) {
  std::lock_guard lk(mu_);
  auto q = db_.Prepare("SELECT started_ns, programs_done FROM runs WHERE dispatch_id=?");
  q.BindInt64(1, dispatch_id);
  if (!q.Step()) return {0, 0};
  return {q.ColumnInt64(0), static_cast<int>(q.ColumnInt64(1))};
}

std::string RunRecord(const Dispatch& d, std::string_view station, const RunProgress& end,
                      std::int64_t started_ns) {
  return nlohmann::json{{"dispatch_id", d.dispatch_id},
                        {"station", station},
                        {"job_id", d.job_id},
                        {"pallet", d.pallet},
                        {"programs", d.programs},
                        {"completed", end.end == RunState::kCompleted},
                        {"reason", end.reason},
                        {"started_ns", started_ns},
                        {"finished_ns", end.finished_ns},
                        {"machine_s", end.machine_s}}
      .dump();
}

void StationDb::WriteProgress(const RunProgress& run) {
  if (run.end) {
    auto u = db_.Prepare(
        "UPDATE runs SET programs_done=?, state=?, reason=?, machine_s=?, finished_ns=? WHERE dispatch_id=?");
    u.BindInt64(1, run.programs_done).BindText(2, RunStateName(*run.end)).BindText(3, run.reason);
    u.BindDouble(4, run.machine_s).BindInt64(5, run.finished_ns).BindInt64(6, run.dispatch_id);
    u.Run();
  } else {
    auto u = db_.Prepare("UPDATE runs SET programs_done=? WHERE dispatch_id=?");
    u.BindInt64(1, run.programs_done).BindInt64(2, run.dispatch_id);
    u.Run();
  }
  if (!run.record.empty()) {
    auto o = db_.Prepare("INSERT OR REPLACE INTO outbox(dispatch_id, record) VALUES(?,?)");
    o.BindInt64(1, run.dispatch_id).BindText(2, run.record);
    o.Run();
  }
}

void StationDb::EndRun(const RunProgress& run) {
  std::lock_guard lk(mu_);
  store::Transaction tx(db_);
  WriteProgress(run);
  tx.Commit();
}

std::optional<StationDb::RunView> StationDb::View(std::int32_t dispatch_id) {
  std::lock_guard lk(mu_);
  auto q = db_.Prepare(std::string("SELECT ") + kDispatchColumns +
                       ", state, COALESCE(programs_done, 0), COALESCE(reason, ''), COALESCE(machine_s, 0),"
                       " COALESCE(started_ns, 0), COALESCE(finished_ns, 0) FROM runs WHERE dispatch_id=?");
  q.BindInt64(1, dispatch_id);
  if (!q.Step()) return std::nullopt;
  RunView v;
  v.d = ReadDispatch(q);
  v.state = StateFromText(q.ColumnText(6));
  v.programs_done = static_cast<int>(q.ColumnInt64(7));
  v.reason = q.ColumnText(8);
  v.machine_s = q.ColumnDouble(9);
  v.started_ns = q.ColumnInt64(10);
  v.finished_ns = q.ColumnInt64(11);
  return v;
}

std::vector<std::pair<std::int32_t, std::string>> StationDb::Outbox(int limit) {
  std::lock_guard lk(mu_);
  auto q = db_.Prepare("SELECT dispatch_id, record FROM outbox ORDER BY dispatch_id LIMIT ?");
  q.BindInt64(1, limit);
  std::vector<std::pair<std::int32_t, std::string>> out;
  while (q.Step()) out.emplace_back(static_cast<std::int32_t>(q.ColumnInt64(0)), q.ColumnText(1));
  return out;
}

void StationDb::RemoveFromOutbox(std::int32_t dispatch_id) {
  std::lock_guard lk(mu_);
  auto del = db_.Prepare("DELETE FROM outbox WHERE dispatch_id=?");
  del.BindInt64(1, dispatch_id);
  del.Run();
}

PanelState StationDb::LoadPanel() {
  std::lock_guard lk(mu_);
  PanelState p;
  auto q = db_.Prepare("SELECT name, value FROM panel");
  while (q.Step()) {
    const std::string n = q.ColumnText(0);
    if (n == "feed_hold") p.feed_hold = q.ColumnDouble(1) != 0;
    if (n == "feed_override") p.feed_override = q.ColumnDouble(1);
    if (n == "rapid_override") p.rapid_override = q.ColumnDouble(1);
    if (n == "optional_stop") p.optional_stop = q.ColumnDouble(1) != 0;
    if (n.rfind("broken_socket.", 0) == 0 && q.ColumnDouble(1) != 0)
      p.broken_sockets.insert(std::atoi(n.c_str() + 14));
  }
  return p;
}

void StationDb::SavePanel(const PanelState& p) {
  std::lock_guard lk(mu_);
  store::Transaction tx(db_);
  auto save = db_.Prepare("INSERT OR REPLACE INTO panel(name, value) VALUES(?,?)");
  for (auto [n, v] : {std::pair<const char*, double>{"feed_hold", p.feed_hold ? 1.0 : 0.0},
                      {"feed_override", p.feed_override},
                      {"rapid_override", p.rapid_override}}) {
    save.BindText(1, n).BindDouble(2, v);
    save.Run();
    save.Reset();
  }
  if (p.optional_stop) {
    save.BindText(1, "optional_stop").BindDouble(2, *p.optional_stop ? 1.0 : 0.0);
    save.Run();
    save.Reset();
  }
  db_.Prepare("DELETE FROM panel WHERE name LIKE 'broken_socket.%'").Run();
  for (int sock : p.broken_sockets) {
    save.BindText(1, "broken_socket." + std::to_string(sock)).BindDouble(2, 1.0);
    save.Run();
    save.Reset();
  }
  tx.Commit();
}

void StationDb::SetInputs(const std::map<std::string, double>& inputs) {
  std::lock_guard lk(mu_);
  store::Transaction tx(db_);
  auto save = db_.Prepare("INSERT OR REPLACE INTO inputs(name, value) VALUES(?,?)");
  for (const auto& [n, v] : inputs) {
    save.BindText(1, n).BindDouble(2, v);
    save.Run();
    save.Reset();
  }
  tx.Commit();
}

std::map<std::string, double> StationDb::LoadInputs() {
  std::lock_guard lk(mu_);
  std::map<std::string, double> out;
  auto q = db_.Prepare("SELECT name, value FROM inputs");
  while (q.Step()) out[q.ColumnText(0)] = q.ColumnDouble(1);
  return out;
}

void StationDb::SetOutputs(const std::map<std::string, int>& outputs) {
  std::lock_guard lk(mu_);
  store::Transaction tx(db_);
  auto save = db_.Prepare(
      "INSERT INTO outputs(name, value) VALUES(?,?) ON CONFLICT(name) DO UPDATE SET value=excluded.value");
  for (const auto& [n, v] : outputs) {
    save.BindText(1, n).BindInt64(2, v);
    save.Run();
    save.Reset();
  }
  tx.Commit();
}

std::map<std::string, std::pair<int, int>> StationDb::LoadOutputs() {
  std::lock_guard lk(mu_);
  std::map<std::string, std::pair<int, int>> out;
  auto q = db_.Prepare("SELECT name, value, power_up FROM outputs");
  while (q.Step())
    out[q.ColumnText(0)] = {static_cast<int>(q.ColumnInt64(1)), static_cast<int>(q.ColumnInt64(2))};
  return out;
}

void StationDb::SavePowerUp() {
  std::lock_guard lk(mu_);
  db_.Exec("UPDATE outputs SET power_up = value;");
}

}  // namespace cell::station
