#include "cell/store/sqlite.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <limits>
#include <string>

#include <fmt/format.h>

namespace cell::store {
namespace {

namespace fs = std::filesystem;

class TempDir {
 public:
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "cell-store-test-XXXXXX").string();
    if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

TEST(Database, OpenCreatesParentDirectoriesInWalModeWithFullSync) {
  TempDir tmp;
  fs::path file = tmp.path() / "a" / "b" / "c.db";
  Database db = Database::Open(file, {.busy_timeout_ms = 1234});
  EXPECT_TRUE(fs::exists(file));
  EXPECT_EQ(db.JournalMode(), "wal");
  EXPECT_EQ(db.Synchronous(), 2);  // FULL
  EXPECT_EQ(db.QueryInt64("PRAGMA busy_timeout"), 1234);
  EXPECT_EQ(db.QueryInt64("PRAGMA foreign_keys"), 1);
  EXPECT_EQ(db.path(), file);
  EXPECT_EQ(db.QueryInt64("PRAGMA cache_size"), -2000);  // SQLite's default unless asked
  EXPECT_EQ(Database::Open(tmp.path() / "small.db", {.cache_kib = 512}).QueryInt64("PRAGMA cache_size"),
            -512);
}

TEST(Database, OpenFailureIsACellError) {
  TempDir tmp;
  fs::path blocker = tmp.path() / "file";
  { Database::Open(blocker).Exec("CREATE TABLE t(x)"); }
  // A database "inside" a regular file cannot be created.
  try {
    Database::Open(blocker / "sub.db");
    FAIL() << "expected an error";
  } catch (const cell::Error& e) {
    EXPECT_EQ(e.code(), Errc::kIo);
    EXPECT_NE(std::string(e.what()).find("cannot create directory"), std::string::npos) << e.what();
  }
  // A directory is not a database: SQLite's own message comes through.
  try {
    Database::Open(tmp.path());
    FAIL() << "expected an error";
  } catch (const SqliteError& e) {
    EXPECT_EQ(e.code(), Errc::kIo);
    EXPECT_NE(std::string(e.what()).find("unable to open database file"), std::string::npos) << e.what();
  }
  EXPECT_THROW(Database::Open(tmp.path() / "missing.db", {.read_only = true}), SqliteError);
  EXPECT_THROW(Database::Open(""), cell::Error);
}

TEST(Statement, BindsAndReadsEveryType) {
  TempDir tmp;
  Database db = Database::Open(tmp.path() / "t.db");
  db.Exec("CREATE TABLE t(i INTEGER, d REAL, s TEXT, b BLOB, n)");
  const std::string blob("\0\x01\xff;PALLET38;FXT\0", 17);
  Statement ins = db.Prepare("INSERT INTO t VALUES (?, ?, ?, ?, ?)");
  ins.BindInt64(1, std::numeric_limits<std::int64_t>::min())
      .BindDouble(2, 2.5)
      .BindText(3, "PALLET 38;FXT")
      .BindBlob(4, blob)
      .BindNull(5)
      .Run();
  EXPECT_EQ(db.Changes(), 1);
  EXPECT_EQ(db.LastInsertRowId(), 1);
  ins.Reset();
  ins.BindInt64(1, 7).BindBlob(4, std::string_view()).Run();  // unbound params are NULL after Reset

  Statement q = db.Prepare("SELECT i, d, s, b, n FROM t ORDER BY rowid");
  ASSERT_TRUE(q.Step());
  EXPECT_EQ(q.ColumnCount(), 5);
  EXPECT_EQ(q.ColumnName(2), "s");
  EXPECT_EQ(q.Type(0), ColumnType::kInteger);
  EXPECT_EQ(q.Type(1), ColumnType::kFloat);
  EXPECT_EQ(q.Type(2), ColumnType::kText);
  EXPECT_EQ(q.Type(3), ColumnType::kBlob);
  EXPECT_EQ(q.Type(4), ColumnType::kNull);
  EXPECT_EQ(q.ColumnInt64(0), std::numeric_limits<std::int64_t>::min());
  EXPECT_DOUBLE_EQ(q.ColumnDouble(1), 2.5);
  EXPECT_EQ(q.ColumnText(2), "PALLET 38;FXT");
  EXPECT_EQ(q.ColumnBlob(3), blob);
  EXPECT_TRUE(q.IsNull(4));
  ASSERT_TRUE(q.Step());
  EXPECT_EQ(q.ColumnInt64(0), 7);
  EXPECT_TRUE(q.IsNull(2));
  EXPECT_EQ(q.ColumnText(2), "");
  EXPECT_EQ(q.Type(3), ColumnType::kBlob);  // a zero-length blob is not NULL
  EXPECT_EQ(q.ColumnBlob(3), "");
  EXPECT_FALSE(q.Step());
}

TEST(Statement, NamedParameters) {
  TempDir tmp;
  Database db = Database::Open(tmp.path() / "t.db");
  Statement q = db.Prepare("SELECT :a + :b");
  q.BindInt64(q.ParameterIndex(":a"), 40).BindInt64(q.ParameterIndex(":b"), 2);
  ASSERT_TRUE(q.Step());
  EXPECT_EQ(q.ColumnInt64(0), 42);
  EXPECT_THROW(q.ParameterIndex(":c"), cell::Error);
}

TEST(Statement, ErrorsCarryTheSqliteMessage) {
  TempDir tmp;
  Database db = Database::Open(tmp.path() / "t.db");
  try {
    db.Prepare("SELECT * FROM nowhere");
    FAIL();
  } catch (const SqliteError& e) {
    EXPECT_EQ(e.code(), Errc::kIo);
    EXPECT_NE(std::string(e.what()).find("no such table: nowhere"), std::string::npos) << e.what();
  }
  try {
    db.Exec("CREATE TABLE t(x); SELEC 1");
    FAIL();
  } catch (const cell::Error& e) {
    EXPECT_NE(std::string(e.what()).find("syntax error"), std::string::npos) << e.what();
  }
  db.Exec("CREATE TABLE u(k TEXT PRIMARY KEY, v INTEGER NOT NULL)");
  db.Exec("INSERT INTO u VALUES ('a', 1)");
  Statement dup = db.Prepare("INSERT INTO u VALUES ('a', 2)");
  try {
    dup.Run();
    FAIL();
  } catch (const SqliteError& e) {
    EXPECT_EQ(e.code(), Errc::kAlreadyExists);
    EXPECT_EQ(e.sqlite_code(), SQLITE_CONSTRAINT_PRIMARYKEY);
    EXPECT_NE(std::string(e.what()).find("UNIQUE constraint failed: u.k"), std::string::npos) << e.what();
  }
  Statement null = db.Prepare("INSERT INTO u VALUES ('b', NULL)");
  try {
    null.Run();
    FAIL();
  } catch (const SqliteError& e) {
    EXPECT_EQ(e.code(), Errc::kIo);
    EXPECT_EQ(e.sqlite_code(), SQLITE_CONSTRAINT_NOTNULL);
  }
  EXPECT_EQ(db.QueryInt64("SELECT count(*) FROM u"), 1);
}

TEST(Database, BusyTimeoutWaitsThenFails) {
  TempDir tmp;
  Database a = Database::Open(tmp.path() / "t.db");
  a.Exec("CREATE TABLE t(x)");
  Database b = Database::Open(tmp.path() / "t.db", {.busy_timeout_ms = 200});
  Transaction hold(a);
  auto start = std::chrono::steady_clock::now();
  try {
    Transaction tx(b);
    FAIL();
  } catch (const SqliteError& e) {
    EXPECT_EQ(e.sqlite_code() & 0xff, SQLITE_BUSY);
    EXPECT_NE(std::string(e.what()).find("database is locked"), std::string::npos) << e.what();
  }
  EXPECT_GE(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(150));
  hold.Commit();
  Transaction tx(b);
  tx.Commit();
}

TEST(Transaction, CommitRollbackAndDestruction) {
  TempDir tmp;
  Database db = Database::Open(tmp.path() / "t.db");
  db.Exec("CREATE TABLE t(x)");
  {
    Transaction tx(db);
    EXPECT_TRUE(db.InTransaction());
    db.Exec("INSERT INTO t VALUES (1)");
    tx.Commit();
    EXPECT_FALSE(tx.active());
  }
  EXPECT_FALSE(db.InTransaction());
  {
    Transaction tx(db);
    db.Exec("INSERT INTO t VALUES (2)");
  }  // destroyed without commit
  EXPECT_FALSE(db.InTransaction());
  {
    Transaction tx(db, Transaction::Mode::kDeferred);
    db.Exec("INSERT INTO t VALUES (3)");
    tx.Rollback();
    EXPECT_THROW(tx.Commit(), cell::Error);
  }
  try {
    Transaction tx(db);
    db.Exec("INSERT INTO t VALUES (4)");
    throw std::runtime_error("boom");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(db.QueryInt64("SELECT group_concat(x) FROM t"), 1);
  Transaction outer(db);
  EXPECT_THROW(Transaction inner(db), cell::Error);  // no nesting
}

// --- migrations -------------------------------------------------------------------------------------

// The history of a small schema: v1 had programs(name, body); v2 added a size column filled from the
// body; v3 moved bodies into a revisions table.
std::vector<Migration> History() {
  return {
      Migration::Sql(1, "programs", "CREATE TABLE programs(name TEXT PRIMARY KEY, body TEXT NOT NULL)"),
      Migration::Sql(2, "size column",
                     "ALTER TABLE programs ADD COLUMN size INTEGER NOT NULL DEFAULT 0;"
                     "UPDATE programs SET size = length(body)"),
      Migration{3, "revisions table",
                [](Database& db) {
                  db.Exec(
                      "CREATE TABLE revisions(name TEXT NOT NULL REFERENCES programs(name), rev INTEGER NOT "
                      "NULL, body TEXT NOT NULL, PRIMARY KEY(name, rev));"
                      "INSERT INTO revisions SELECT name, 1, body FROM programs;");
                  // A C++ step, to show steps are not only SQL: stamp the count.
                  Statement st = db.Prepare("CREATE TABLE meta(k TEXT PRIMARY KEY, v INTEGER)");
                  st.Run();
                  Statement put = db.Prepare("INSERT INTO meta VALUES ('migrated', ?)");
                  put.BindInt64(1, db.QueryInt64("SELECT count(*) FROM revisions")).Run();
                }},
  };
}

TEST(Migrate, FreshDatabaseReachesLatest) {
  TempDir tmp;
  Database db = Database::Open(tmp.path() / "t.db");
  EXPECT_EQ(SchemaVersion(db), 0);
  EXPECT_EQ(Migrate(db, History()), 3);
  EXPECT_EQ(SchemaVersion(db), 3);
  EXPECT_EQ(db.QueryInt64("SELECT count(*) FROM schema_version"), 3);
  EXPECT_EQ(db.QueryText("SELECT description FROM schema_version WHERE version = 2"), "size column");
  // Running again is a no-op.
  EXPECT_EQ(Migrate(db, History()), 3);
  EXPECT_EQ(db.QueryInt64("SELECT count(*) FROM schema_version"), 3);
}

TEST(Migrate, OlderSchemaFileIsUpgradedKeepingItsData) {
  TempDir tmp;
  fs::path file = tmp.path() / "old.db";
  {
    // A file written by an old build: only the v1 schema and its steps, with data.
    Database old = Database::Open(file);
    std::vector<Migration> v1 = History();
    v1.resize(1);
    EXPECT_EQ(Migrate(old, v1), 1);
    old.Exec("INSERT INTO programs VALUES ('PALLET38;FXT', '(FXT,1)'), ('O1234', 'G0 X0')");
  }
  Database db = Database::Open(file);
  EXPECT_EQ(SchemaVersion(db), 1);
  EXPECT_EQ(Migrate(db, History()), 3);
  EXPECT_EQ(SchemaVersion(db), 3);
  EXPECT_EQ(db.QueryInt64("SELECT size FROM programs WHERE name = 'PALLET38;FXT'"), 7);
  EXPECT_EQ(db.QueryText("SELECT body FROM revisions WHERE name = 'O1234' AND rev = 1"), "G0 X0");
  EXPECT_EQ(db.QueryInt64("SELECT v FROM meta WHERE k = 'migrated'"), 2);
  EXPECT_EQ(db.IntegrityCheck(), "ok");
}

// Every pending step runs in one transaction (one commit, one fsync for a new database): a failing step
// leaves the file where it was, at the version it had before, and a later run starts from there.
TEST(Migrate, FailingStepRollsBackEveryPendingStep) {
  TempDir tmp;
  Database db = Database::Open(tmp.path() / "t.db");
  std::vector<Migration> steps = History();
  steps[2].apply = [](Database& d) {
    d.Exec("CREATE TABLE half(x)");
    d.Exec("INSERT INTO nowhere VALUES (1)");
  };
  try {
    Migrate(db, steps);
    FAIL();
  } catch (const cell::Error& e) {
    EXPECT_NE(std::string(e.what()).find("migration 2 -> 3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("no such table: nowhere"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(db.InTransaction());
  EXPECT_EQ(SchemaVersion(db), 0);
  EXPECT_EQ(db.QueryInt64("SELECT count(*) FROM sqlite_master WHERE name IN ('half', 'programs')"), 0);
  EXPECT_EQ(Migrate(db, History()), 3);
}

TEST(Migrate, RefusesDowngradeAndBadNumbering) {
  TempDir tmp;
  Database db = Database::Open(tmp.path() / "t.db");
  Migrate(db, History());
  std::vector<Migration> older = History();
  older.resize(2);
  try {
    Migrate(db, older);
    FAIL();
  } catch (const cell::Error& e) {
    EXPECT_EQ(e.code(), Errc::kFailedPrecondition);
    EXPECT_NE(std::string(e.what()).find("newer"), std::string::npos) << e.what();
  }
  std::vector<Migration> gap = History();
  gap[1].version = 5;
  EXPECT_THROW(Migrate(db, gap), cell::Error);
  EXPECT_EQ(SchemaVersion(db), 3);
}

// --- crash safety -----------------------------------------------------------------------------------

// A child begins a transaction, writes enough rows that SQLite spills uncommitted pages into the WAL,
// tells the parent, and is SIGKILLed before it commits. The parent must see none of those rows.
TEST(CrashSafety, TransactionInterruptedBySigkillLeavesNoTrace) {
  TempDir tmp;
  fs::path file = tmp.path() / "crash.db";
  {
    Database db = Database::Open(file);
    db.Exec("CREATE TABLE t(id INTEGER PRIMARY KEY, tag TEXT, payload BLOB)");
    Transaction tx(db);
    Statement ins = db.Prepare("INSERT INTO t(tag, payload) VALUES ('committed', zeroblob(1000))");
    for (int i = 0; i < 100; ++i) {
      ins.Run();
      ins.Reset();
    }
    tx.Commit();
  }
  int fds[2];
  ASSERT_EQ(pipe(fds), 0);
  pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    close(fds[0]);
    try {
      Database db = Database::Open(file);
      db.Exec("PRAGMA cache_size = 16");  // small cache: uncommitted pages spill into the WAL file
      Transaction tx(db);
      Statement ins = db.Prepare("INSERT INTO t(tag, payload) VALUES ('doomed', randomblob(4000))");
      for (int i = 0; i < 2000; ++i) {
        ins.Run();
        ins.Reset();
      }
      db.Exec("UPDATE t SET tag = 'doomed' WHERE tag = 'committed' AND id % 2 = 0");
      char ready = 'r';
      if (write(fds[1], &ready, 1) != 1) _exit(3);
      pause();  // killed here, before commit
    } catch (...) {
      _exit(2);
    }
    _exit(1);
  }
  close(fds[1]);
  char ready = 0;
  ASSERT_EQ(read(fds[0], &ready, 1), 1) << "child failed before signalling";
  close(fds[0]);
  // The WAL holds the child's spilled, uncommitted frames now.
  ASSERT_TRUE(fs::exists(fs::path(file.string() + "-wal")));
  EXPECT_GT(fs::file_size(fs::path(file.string() + "-wal")), 1'000'000u);
  ASSERT_EQ(kill(pid, SIGKILL), 0);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(WTERMSIG(status), SIGKILL);

  Database db = Database::Open(file);
  EXPECT_EQ(db.IntegrityCheck(), "ok");
  EXPECT_EQ(db.QueryInt64("SELECT count(*) FROM t"), 100);
  EXPECT_EQ(db.QueryInt64("SELECT count(*) FROM t WHERE tag = 'doomed'"), 0);
  EXPECT_EQ(db.QueryInt64("SELECT count(*) FROM t WHERE tag = 'committed'"), 100);
  // And the database is writable again.
  Transaction tx(db);
  db.Exec("INSERT INTO t(tag) VALUES ('after')");
  tx.Commit();
  EXPECT_EQ(db.QueryInt64("SELECT count(*) FROM t"), 101);
}

}  // namespace
}  // namespace cell::store
