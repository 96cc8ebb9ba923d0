// cell_store: a thin, exception-based wrapper over SQLite for the cell's services.
//
// Every service keeps its state in one SQLite database (DESIGN §7): WAL mode, synchronous=FULL (a commit
// is on disk when Commit() returns), a busy timeout so two connections wait instead of failing, a
// `schema_version` table and stepwise migrations. Errors are cell::Error (Errc::kIo, or
// Errc::kAlreadyExists for a UNIQUE/PRIMARY KEY violation) carrying SQLite's own message; the subclass
// SqliteError also carries the extended SQLite result code.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "cell/error/error.h"

struct sqlite3;
struct sqlite3_stmt;

namespace cell::store {

// A cell::Error raised by SQLite; code() is Errc::kIo unless the failure is a constraint violation.
class SqliteError : public cell::Error {
 public:
  SqliteError(Errc code, int sqlite_code, const std::string& what)
      : cell::Error(code, what), sqlite_code_(sqlite_code) {}
  // The extended SQLite result code (SQLITE_BUSY, SQLITE_CONSTRAINT_UNIQUE, ...).
  int sqlite_code() const noexcept { return sqlite_code_; }

 private:
  int sqlite_code_;
};

struct OpenOptions {
  int busy_timeout_ms = 10000;  // how long a statement waits for another connection's lock
  bool read_only = false;       // open an existing file read-only (no parent dirs, no WAL switch)
  // The connection's page cache in KiB (PRAGMA cache_size=-N); 0 keeps SQLite's default (2,000 KiB). A
  // service that runs for months and seldom reads back what it wrote bounds it smaller, so that its memory is
  // flat early (issue 39: the page cache was what grew between pallets 1,000 and 5,000).
  int cache_kib = 0;
};

// SQLite's fundamental column types.
enum class ColumnType { kInteger, kFloat, kText, kBlob, kNull };

class Database;

// A prepared statement. Parameters and columns are numbered as SQLite numbers them: parameters from 1,
// result columns from 0. Move-only; finalized on destruction. A statement does not refer to its Database
// object, so moving the Database is safe; it must not outlive the connection's use.
class Statement {
 public:
  Statement() = default;
  Statement(Statement&& other) noexcept;
  Statement& operator=(Statement&& other) noexcept;
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;
  ~Statement();

  Statement& BindInt64(int index, std::int64_t value);
  Statement& BindDouble(int index, double value);
  Statement& BindText(int index, std::string_view value);  // copied by SQLite
  Statement& BindBlob(int index, std::string_view bytes);  // copied by SQLite; empty -> zero-length blob
  Statement& BindBlob(int index, const void* data, std::size_t size);
  Statement& BindNull(int index);
  // Index of a named parameter (":name", "@name", "$name"); throws if the statement has no such parameter.
  int ParameterIndex(const char* name) const;

  // Runs one step: true when a result row is available, false when the statement is done.
  bool Step();
  // Runs the statement to completion, ignoring any rows.
  void Run();
  // Makes the statement runnable again and clears all bindings.
  void Reset();

  int ColumnCount() const;
  ColumnType Type(int column) const;
  bool IsNull(int column) const { return Type(column) == ColumnType::kNull; }
  std::int64_t ColumnInt64(int column) const;
  double ColumnDouble(int column) const;
  std::string ColumnText(int column) const;  // NULL -> ""
  std::string ColumnBlob(int column) const;  // the bytes; NULL -> ""
  // The bytes without a copy; valid until the next Step(), Reset() or destruction.
  std::string_view ColumnBlobView(int column) const;
  std::string ColumnName(int column) const;

  const std::string& sql() const { return sql_; }

 private:
  friend class Database;
  Statement(sqlite3_stmt* stmt, std::string sql);
  void Check(int rc, const char* what) const;
  [[noreturn]] void Fail(int rc, std::string_view what) const;
  void RequireStatement() const;

  sqlite3_stmt* stmt_ = nullptr;
  std::string sql_;
};

// One connection to one database file. Move-only; closed on destruction. Opened in SQLite's serialized
// mode, so calls from several threads are safe, but a transaction belongs to the connection: threads that
// share one must serialize their transactions (or open a connection each; WAL lets readers and one writer
// work at once, and the busy timeout makes writers wait for each other).
class Database {
 public:
  // Opens (creating it and its parent directories) the database at `file`, switches it to WAL mode with
  // synchronous=FULL, foreign_keys=ON and the busy timeout. Throws SqliteError (Errc::kIo) on failure.
  static Database Open(const std::filesystem::path& file, const OpenOptions& options = {});

  Database(Database&& other) noexcept;
  Database& operator=(Database&& other) noexcept;
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;
  ~Database();

  // Runs one or more SQL statements separated by ';' (no parameters, rows ignored).
  void Exec(std::string_view sql);
  Statement Prepare(std::string_view sql);
  // Convenience: runs a query whose first row's first column is an integer (NULL or no row -> fallback).
  std::int64_t QueryInt64(std::string_view sql, std::int64_t fallback = 0);
  // Convenience: first row's first column as text (no row -> "").
  std::string QueryText(std::string_view sql);

  std::int64_t LastInsertRowId() const;
  int Changes() const;         // rows changed by the most recent INSERT/UPDATE/DELETE
  bool InTransaction() const;  // false in autocommit mode
  std::string JournalMode();   // "wal" after Open (unless read_only on a non-WAL file)
  int Synchronous();           // 2 == FULL
  // Runs PRAGMA integrity_check; returns "ok" or SQLite's list of problems.
  std::string IntegrityCheck();

  const std::filesystem::path& path() const { return path_; }
  sqlite3* handle() const { return db_; }

  // Throws SqliteError for `rc` with this connection's error message, prefixed by `what`.
  [[noreturn]] void Fail(int rc, std::string_view what) const;

 private:
  Database(sqlite3* db, std::filesystem::path path) : db_(db), path_(std::move(path)) {}
  void Close() noexcept;

  sqlite3* db_ = nullptr;
  std::filesystem::path path_;
};

// RAII transaction. The constructor runs BEGIN IMMEDIATE (takes the write lock up front, so a
// read-then-write transaction never fails with SQLITE_BUSY half way) or BEGIN DEFERRED; Commit() commits;
// the destructor rolls back if neither Commit() nor Rollback() ran. Transactions do not nest.
class Transaction {
 public:
  enum class Mode { kImmediate, kDeferred };
  explicit Transaction(Database& db, Mode mode = Mode::kImmediate);
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;
  ~Transaction();

  void Commit();
  void Rollback();
  bool active() const { return active_; }

 private:
  Database& db_;
  bool active_ = false;
};

// One schema step: moves the database from version `version - 1` to `version`.
struct Migration {
  int version = 0;
  std::string description;
  std::function<void(Database&)> apply;

  // A step that is plain SQL (one or more statements).
  static Migration Sql(int version, std::string description, std::string sql);
};

// The schema version recorded in the `schema_version` table (0 when the table is absent or empty).
int SchemaVersion(Database& db);

// Brings the database up to the last migration's version. `migrations` must be numbered 1, 2, 3, ... in
// order (the list of every step since the first schema). Every pending step, each with its
// `schema_version` row, runs in one BEGIN IMMEDIATE transaction (one commit: a new database costs one fsync,
// not one per step), so a crash or a failing step leaves the database at the version it had, never between.
// Throws cell::Error (kFailedPrecondition) if the file's version is newer than the newest migration (a
// downgrade), kInvalidArgument for a badly numbered list. Returns the version.
int Migrate(Database& db, const std::vector<Migration>& migrations);

}  // namespace cell::store
