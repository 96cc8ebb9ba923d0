#include "cell/store/sqlite.h"

#include <sqlite3.h>

#include <fmt/format.h>
#include <fmt/std.h>

#include <system_error>
#include <utility>

namespace cell::store {
namespace {

Errc ErrcFor(int rc) {
  switch (rc) {
    case SQLITE_CONSTRAINT_UNIQUE:
    case SQLITE_CONSTRAINT_PRIMARYKEY:
      return Errc::kAlreadyExists;
    case SQLITE_READONLY:
    case SQLITE_PERM:
      return Errc::kPermissionDenied;
    default:
      return Errc::kIo;
  }
}

[[noreturn]] void Throw(int rc, std::string_view what, std::string_view message,
                        const std::filesystem::path& path) {
  throw SqliteError(
      ErrcFor(rc), rc,
      fmt::format("sqlite: {}: {} ({}) [{}]", what, message, sqlite3_errstr(rc), path.string()));
}

}  // namespace

// ---------------------------------------------------------------------------------------------------------
// Statement

Statement::Statement(sqlite3_stmt* stmt, std::string sql) : stmt_(stmt), sql_(std::move(sql)) {}

Statement::Statement(Statement&& other) noexcept
    : stmt_(std::exchange(other.stmt_, nullptr)), sql_(std::move(other.sql_)) {}

Statement& Statement::operator=(Statement&& other) noexcept {
  if (this != &other) {
    if (stmt_ != nullptr) sqlite3_finalize(stmt_);
    stmt_ = std::exchange(other.stmt_, nullptr);
    sql_ = std::move(other.sql_);
  }
  return *this;
}

Statement::~Statement() {
  if (stmt_ != nullptr) sqlite3_finalize(stmt_);
}

void Statement::Check(int rc, const char* what) const {
  if (rc == SQLITE_OK) return;
  Fail(rc, what);
}

void Statement::Fail(int rc, std::string_view what) const {
  if (stmt_ == nullptr) throw cell::Error(Errc::kInternal, "sqlite: use of an empty statement");
  sqlite3* db = sqlite3_db_handle(stmt_);
  const char* file = sqlite3_db_filename(db, "main");
  Throw(rc, fmt::format("{} \"{}\"", what, sql_), sqlite3_errmsg(db), file != nullptr ? file : "");
}

void Statement::RequireStatement() const {
  if (stmt_ == nullptr) throw cell::Error(Errc::kInternal, "sqlite: use of an empty statement");
}

Statement& Statement::BindInt64(int index, std::int64_t value) {
  Check(sqlite3_bind_int64(stmt_, index, value), "bind");
  return *this;
}

Statement& Statement::BindDouble(int index, double value) {
  Check(sqlite3_bind_double(stmt_, index, value), "bind");
  return *this;
}

Statement& Statement::BindText(int index, std::string_view value) {
  Check(sqlite3_bind_text64(stmt_, index, value.data(), value.size(), SQLITE_TRANSIENT, SQLITE_UTF8), "bind");
  return *this;
}

Statement& Statement::BindBlob(int index, std::string_view bytes) {
  return BindBlob(index, bytes.data(), bytes.size());
}

Statement& Statement::BindBlob(int index, const void* data, std::size_t size) {
  if (size == 0) {
    Check(sqlite3_bind_zeroblob(stmt_, index, 0), "bind");
  } else {
    Check(sqlite3_bind_blob64(stmt_, index, data, size, SQLITE_TRANSIENT), "bind");
  }
  return *this;
}

Statement& Statement::BindNull(int index) {
  Check(sqlite3_bind_null(stmt_, index), "bind");
  return *this;
}

int Statement::ParameterIndex(const char* name) const {
  int index = sqlite3_bind_parameter_index(stmt_, name);
  if (index == 0) {
    throw cell::Error(Errc::kInvalidArgument, fmt::format("sqlite: no parameter {} in \"{}\"", name, sql_));
  }
  return index;
}

bool Statement::Step() {
  RequireStatement();
  int rc = sqlite3_step(stmt_);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  // Report, then reset so the statement can run again (the reset would overwrite the message).
  try {
    Fail(rc, "step");
  } catch (...) {
    sqlite3_reset(stmt_);
    throw;
  }
}

void Statement::Run() {
  while (Step()) {
  }
}

void Statement::Reset() {
  sqlite3_reset(stmt_);
  sqlite3_clear_bindings(stmt_);
}

int Statement::ColumnCount() const {
  return sqlite3_column_count(stmt_);
}

ColumnType Statement::Type(int column) const {
  switch (sqlite3_column_type(stmt_, column)) {
    case SQLITE_INTEGER:
      return ColumnType::kInteger;
    case SQLITE_FLOAT:
      return ColumnType::kFloat;
    case SQLITE_TEXT:
      return ColumnType::kText;
    case SQLITE_BLOB:
      return ColumnType::kBlob;
    default:
      return ColumnType::kNull;
  }
}

std::int64_t Statement::ColumnInt64(int column) const {
  return sqlite3_column_int64(stmt_, column);
}

double Statement::ColumnDouble(int column) const {
  return sqlite3_column_double(stmt_, column);
}

std::string Statement::ColumnText(int column) const {
  const unsigned char* text = sqlite3_column_text(stmt_, column);
  if (text == nullptr) return {};
  return std::string(reinterpret_cast<const char*>(text), sqlite3_column_bytes(stmt_, column));
}

std::string Statement::ColumnBlob(int column) const {
  return std::string(ColumnBlobView(column));
}

std::string_view Statement::ColumnBlobView(int column) const {
  const void* data = sqlite3_column_blob(stmt_, column);
  int size = sqlite3_column_bytes(stmt_, column);
  if (data == nullptr || size <= 0) return {};
  return std::string_view(static_cast<const char*>(data), static_cast<std::size_t>(size));
}

std::string Statement::ColumnName(int column) const {
  const char* name = sqlite3_column_name(stmt_, column);
  return name == nullptr ? std::string() : std::string(name);
}

// ---------------------------------------------------------------------------------------------------------
// Database

Database Database::Open(const std::filesystem::path& file, const OpenOptions& options) {
  if (file.empty()) throw cell::Error(Errc::kInvalidArgument, "sqlite: empty database path");
  if (!options.read_only && file.has_parent_path()) {
    std::error_code ec;
    std::filesystem::create_directories(file.parent_path(), ec);
    if (ec) {
      throw cell::Error(Errc::kIo, fmt::format("sqlite: cannot create directory {}: {}",
                                               file.parent_path().string(), ec.message()));
    }
  }
  int flags = options.read_only ? SQLITE_OPEN_READONLY : (SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE);
  // Serialized mode: a connection shared between threads (e.g. DDS callbacks) cannot corrupt SQLite's state.
  // Transactions are per connection, so threads sharing one must still take turns around a Transaction.
  flags |= SQLITE_OPEN_FULLMUTEX;
  sqlite3* raw = nullptr;
  int rc = sqlite3_open_v2(file.c_str(), &raw, flags, nullptr);
  if (rc != SQLITE_OK) {
    std::string message = raw != nullptr ? sqlite3_errmsg(raw) : "out of memory";
    sqlite3_close_v2(raw);
    Throw(rc, "open", message, file);
  }
  Database db(raw, file);
  sqlite3_extended_result_codes(raw, 1);
  sqlite3_busy_timeout(raw, options.busy_timeout_ms);
  if (!options.read_only) {
    std::string mode = db.QueryText("PRAGMA journal_mode=WAL");
    if (mode != "wal") {
      throw cell::Error(Errc::kIo,
                        fmt::format("sqlite: cannot switch {} to WAL mode (got '{}')", file.string(), mode));
    }
  }
  db.Exec("PRAGMA synchronous=FULL; PRAGMA foreign_keys=ON");
  if (options.cache_kib > 0) db.Exec(fmt::format("PRAGMA cache_size=-{}", options.cache_kib));
  return db;
}

Database::Database(Database&& other) noexcept
    : db_(std::exchange(other.db_, nullptr)), path_(std::move(other.path_)) {}

Database& Database::operator=(Database&& other) noexcept {
  if (this != &other) {
    Close();
    db_ = std::exchange(other.db_, nullptr);
    path_ = std::move(other.path_);
  }
  return *this;
}

Database::~Database() {
  Close();
}

void Database::Close() noexcept {
  if (db_ != nullptr) {
    // close_v2 defers the close until every statement is finalized.
    sqlite3_close_v2(db_);
    db_ = nullptr;
  }
}

void Database::Fail(int rc, std::string_view what) const {
  Throw(rc, what, db_ != nullptr ? sqlite3_errmsg(db_) : "closed connection", path_);
}

void Database::Exec(std::string_view sql) {
  std::string owned(sql);
  char* message = nullptr;
  int rc = sqlite3_exec(db_, owned.c_str(), nullptr, nullptr, &message);
  if (rc != SQLITE_OK) {
    std::string text = message != nullptr ? message : sqlite3_errmsg(db_);
    sqlite3_free(message);
    Throw(sqlite3_extended_errcode(db_), fmt::format("exec \"{}\"", sql), text, path_);
  }
}

Statement Database::Prepare(std::string_view sql) {
  sqlite3_stmt* stmt = nullptr;
  const char* tail = nullptr;
  int rc = sqlite3_prepare_v3(db_, sql.data(), static_cast<int>(sql.size()), 0, &stmt, &tail);
  if (rc != SQLITE_OK) Fail(rc, fmt::format("prepare \"{}\"", sql));
  if (stmt == nullptr) {
    throw cell::Error(Errc::kInvalidArgument, fmt::format("sqlite: no statement in \"{}\"", sql));
  }
  return Statement(stmt, std::string(sql));
}

std::int64_t Database::QueryInt64(std::string_view sql, std::int64_t fallback) {
  Statement st = Prepare(sql);
  if (!st.Step() || st.IsNull(0)) return fallback;
  return st.ColumnInt64(0);
}

std::string Database::QueryText(std::string_view sql) {
  Statement st = Prepare(sql);
  if (!st.Step()) return {};
  return st.ColumnText(0);
}

std::int64_t Database::LastInsertRowId() const {
  return sqlite3_last_insert_rowid(db_);
}

int Database::Changes() const {
  return sqlite3_changes(db_);
}

bool Database::InTransaction() const {
  return sqlite3_get_autocommit(db_) == 0;
}

std::string Database::JournalMode() {
  return QueryText("PRAGMA journal_mode");
}

int Database::Synchronous() {
  return static_cast<int>(QueryInt64("PRAGMA synchronous", -1));
}

std::string Database::IntegrityCheck() {
  Statement st = Prepare("PRAGMA integrity_check");
  std::string result;
  while (st.Step()) {
    if (!result.empty()) result += "\n";
    result += st.ColumnText(0);
  }
  return result;
}

// ---------------------------------------------------------------------------------------------------------
// Transaction

Transaction::Transaction(Database& db, Mode mode) : db_(db) {
  db_.Exec(mode == Mode::kImmediate ? "BEGIN IMMEDIATE" : "BEGIN DEFERRED");
  active_ = true;
}

Transaction::~Transaction() {
  if (active_) {
    // Never throws: a failed COMMIT may already have rolled back; ROLLBACK then reports "no transaction".
    sqlite3_exec(db_.handle(), "ROLLBACK", nullptr, nullptr, nullptr);
  }
}

void Transaction::Commit() {
  if (!active_) throw cell::Error(Errc::kFailedPrecondition, "sqlite: commit of a finished transaction");
  db_.Exec("COMMIT");
  active_ = false;
}

void Transaction::Rollback() {
  if (!active_) return;
  active_ = false;
  if (db_.InTransaction()) db_.Exec("ROLLBACK");
}

// ---------------------------------------------------------------------------------------------------------
// Migrations

Migration Migration::Sql(int version, std::string description, std::string sql) {
  return Migration{version, std::move(description), [sql = std::move(sql)](Database& db) { db.Exec(sql); }};
}

namespace {

constexpr const char* kCreateSchemaVersion =
    "CREATE TABLE IF NOT EXISTS schema_version ("
    " version INTEGER PRIMARY KEY,"
    " description TEXT NOT NULL DEFAULT '',"
    " applied_at TEXT NOT NULL DEFAULT (strftime('%Y-%m-%dT%H:%M:%fZ','now')))";

bool HasSchemaVersionTable(Database& db) {
  return db.QueryInt64("SELECT count(*) FROM sqlite_master WHERE type='table' AND name='schema_version'") > 0;
}

}  // namespace

int SchemaVersion(Database& db) {
  if (!HasSchemaVersionTable(db)) return 0;
  return static_cast<int>(db.QueryInt64("SELECT max(version) FROM schema_version", 0));
}

int Migrate(Database& db, const std::vector<Migration>& migrations) {
  for (std::size_t i = 0; i < migrations.size(); ++i) {
    if (migrations[i].version != static_cast<int>(i) + 1) {
      throw cell::Error(Errc::kInvalidArgument,
                        fmt::format("migration #{} is numbered {}; steps must be numbered 1, 2, 3, ...",
                                    i + 1, migrations[i].version));
    }
    if (!migrations[i].apply) {
      throw cell::Error(Errc::kInvalidArgument, fmt::format("migration {} has no body", i + 1));
    }
  }
  const int target = static_cast<int>(migrations.size());
  // Every pending step in one transaction: all or none, and one commit (one fsync of the WAL) where a step
  // each made a new station's database cost four while 32 stations started at once.
  Transaction tx(db);
  db.Exec(kCreateSchemaVersion);
  // Read inside the write lock: another process may have migrated meanwhile.
  int current = SchemaVersion(db);
  if (current > target) {
    throw cell::Error(Errc::kFailedPrecondition,
                      fmt::format("database {} has schema version {}, newer than this program's {}; "
                                  "refusing to downgrade",
                                  db.path().string(), current, target));
  }
  for (; current < target; ++current) {
    const Migration& step = migrations[static_cast<std::size_t>(current)];
    try {
      step.apply(db);
    } catch (const cell::Error& e) {
      throw cell::Error(e.code(), fmt::format("migration {} -> {} ({}) failed: {}", current, step.version,
                                              step.description, e.what()));
    }
    Statement record = db.Prepare("INSERT INTO schema_version(version, description) VALUES (?, ?)");
    record.BindInt64(1, step.version).BindText(2, step.description).Run();
  }
  tx.Commit();
  return current;
}

}  // namespace cell::store
