#include "cell/program_store/program_store.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>
#include <thread>

#include <fmt/format.h>

#include "cell/error/error.h"
#include "cell/program_store/sha256.h"
#include "cell/store/sqlite.h"

namespace cell::program_store {
namespace {

const Dialect kNoDialect = nullptr;
const Dialect kKtapl = interp::FindDialect("ktapl");
const Dialect kOkuma = interp::FindDialect("okuma");
const Dialect kBalt = interp::FindDialect("balt");

namespace fs = std::filesystem;
using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::IsEmpty;

class TempDir {
 public:
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "cell-program-store-test-XXXXXX").string();
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

template <typename Fn>
void ExpectError(Fn fn, Errc code, const std::string& needle) {
  try {
    fn();
    ADD_FAILURE() << "expected an error containing '" << needle << "'";
  } catch (const cell::Error& e) {
    EXPECT_EQ(e.code(), code) << e.what();
    EXPECT_THAT(e.what(), HasSubstr(needle));
  }
}

constexpr const char* kGear = "%\n(NAM,GEAR HOUSING)\n(UTL,12,T3)\n(UCY,840)\nN10 G0 X0 Y0 F0 M3\nN20 M30\n";
constexpr const char* kGear2 =
    "%\n(NAM,GEAR HOUSING)\n(UTL,12,T3,44)\n(UCY,900)\nN10 G0 X1 Y0 F0 M3\nN20 M30\n";

StoreOptions Options(const fs::path& dir) {
  StoreOptions o;
  o.data_dir = dir / "data";
  o.namespaces = {"KT01", "KT02", "OK01"};
  return o;
}

PutRequest Req(std::string node, std::string name, std::string content, bool force = false,
               std::string key = "") {
  PutRequest r;
  r.node = std::move(node);
  r.name = std::move(name);
  r.content = std::move(content);
  r.force = force;
  r.idempotency_key = std::move(key);
  return r;
}

// Everything the store holds, as text, through a separate connection: "left exactly as it was" means equal.
std::string Snapshot(const fs::path& db_path) {
  store::Database db = store::Database::Open(db_path);
  std::string out;
  for (const char* sql :
       {"SELECT id, node, name, head, protected, created_at FROM files ORDER BY id",
        "SELECT file_id, rev, sha256, size, lines, type, dialect, nam, utl, ucy, warnings FROM revisions "
        "ORDER BY "
        "file_id, rev",
        "SELECT sha256, size, length(data) FROM blobs ORDER BY sha256",
        "SELECT seq, kind, node, name, rev FROM events",
        "SELECT key, fingerprint FROM idempotency ORDER BY key"}) {
    store::Statement st = db.Prepare(sql);
    while (st.Step()) {
      for (int i = 0; i < st.ColumnCount(); ++i) out += st.ColumnText(i) + "|";
      out += "\n";
    }
    out += "--\n";
  }
  return out;
}

// Staging files of chunk streams.
int StagedFiles(const fs::path& db_path) {
  int n = 0;
  for (const auto& entry : fs::directory_iterator(db_path.parent_path() / "program-store-streams")) {
    (void)entry;
    ++n;
  }
  return n;
}

TEST(ProgramStore, PutGetShowRoundTrip) {
  TempDir tmp;
  ProgramStore ps(Options(tmp.path()));
  EXPECT_TRUE(fs::exists(ps.database_path()));
  PutResult put = ps.Put(Req("HOST", "GEAR HOUSING", kGear));
  EXPECT_TRUE(put.created);
  EXPECT_FALSE(put.replayed);
  EXPECT_EQ(put.file.revision, 1u);
  EXPECT_EQ(put.file.head_revision, 1u);
  EXPECT_EQ(put.file.sha256, Sha256Hex(kGear));
  EXPECT_EQ(put.file.metadata.type, FileType::kPartProgram);
  EXPECT_EQ(put.file.metadata.dialect, kKtapl);
  EXPECT_EQ(put.file.metadata.nam, "GEAR HOUSING");
  EXPECT_THAT(put.file.metadata.utl, ElementsAre("12", "3"));
  EXPECT_EQ(put.file.metadata.lines, 6u);
  EXPECT_THAT(put.warnings(), IsEmpty());
  ASSERT_EQ(put.events.size(), 1u);
  EXPECT_EQ(put.events[0].kind, ChangeEvent::Kind::kCreated);
  EXPECT_EQ(put.events[0].revision, 1u);

  GetResult got = ps.Get("HOST", "GEAR HOUSING");
  EXPECT_EQ(got.content, kGear);
  EXPECT_EQ(got.file.sha256, Sha256Hex(got.content));
  ShowResult shown = ps.Show("HOST", "GEAR HOUSING");
  EXPECT_DOUBLE_EQ(shown.file.metadata.ucy_s.value_or(0), 840);
  ASSERT_EQ(shown.revisions.size(), 1u);
  EXPECT_EQ(shown.revisions[0].size, std::string(kGear).size());
  EXPECT_THAT(shown.revisions[0].created_at, testing::MatchesRegex("20[0-9-]+T[0-9:.]+Z"));

  ExpectError([&] { ps.Get("HOST", "NOPE"); }, Errc::kNotFound, "no file 'NOPE' in HOST");
  ExpectError([&] { ps.Get("KT01", "GEAR HOUSING"); }, Errc::kNotFound, "no file 'GEAR HOUSING' in KT01");
}

TEST(ProgramStore, ExistingNameNeedsForceAndKeepsEveryRevision) {
  TempDir tmp;
  ProgramStore ps(Options(tmp.path()));
  ps.Put(Req("HOST", "GEAR HOUSING", kGear));
  std::string before = Snapshot(ps.database_path());
  ExpectError([&] { ps.Put(Req("HOST", "GEAR HOUSING", kGear2)); }, Errc::kAlreadyExists,
              "'GEAR HOUSING' in HOST already exists (revision 1); use --force");
  EXPECT_EQ(Snapshot(ps.database_path()), before);

  PutResult second = ps.Put(Req("HOST", "GEAR HOUSING", kGear2, /*force=*/true));
  EXPECT_FALSE(second.created);
  EXPECT_EQ(second.file.revision, 2u);
  EXPECT_EQ(second.events.at(0).kind, ChangeEvent::Kind::kUpdated);
  EXPECT_THAT(second.file.metadata.utl, ElementsAre("12", "3", "44"));
  EXPECT_EQ(ps.Get("HOST", "GEAR HOUSING").content, kGear2);
  GetResult first = ps.Get("HOST", "GEAR HOUSING", 1);
  EXPECT_EQ(first.content, kGear);
  EXPECT_EQ(first.file.revision, 1u);
  EXPECT_EQ(first.file.head_revision, 2u);
  EXPECT_THAT(first.file.metadata.utl, ElementsAre("12", "3"));  // metadata is per revision
  EXPECT_EQ(ps.Show("HOST", "GEAR HOUSING").revisions.size(), 2u);
  ExpectError([&] { ps.Get("HOST", "GEAR HOUSING", 3); }, Errc::kNotFound, "has no revision 3");
  // The same content again is still a new revision.
  EXPECT_EQ(ps.Put(Req("HOST", "GEAR HOUSING", kGear2, true)).file.revision, 3u);
}

TEST(ProgramStore, NamespacesAndDialectNames) {
  TempDir tmp;
  ProgramStore ps(Options(tmp.path()));
  EXPECT_THAT(ps.namespaces(), ElementsAre("HOST", "KT01", "KT02", "OK01"));
  PutRequest fxt = Req("KT01", "PALLET38;FXT", "(FXC,H1 I0 X-.0012 Y.0030)\n");
  PutResult r = ps.Put(fxt);
  EXPECT_EQ(r.file.metadata.type, FileType::kFixtureOffsets);
  EXPECT_EQ(r.file.metadata.dialect, kKtapl);
  EXPECT_EQ(ps.Get("KT01", "PALLET38;FXT").content, fxt.content);

  PutResult okuma = ps.Put(Req("OK01", "SHAFT-1.SDF", "N010 PSELECT A.MIN,O100,,Q=20\nEND\n"));
  EXPECT_EQ(okuma.file.metadata.type, FileType::kSchedule);
  PutResult omin = ps.Put(Req("OK01", "A.MIN", "O100\nN100 G00 X100 Z100\nVSET V1=V1+1\nN150 M02\n"));
  EXPECT_THAT(omin.file.metadata.program_names, ElementsAre("O100"));

  std::string before = Snapshot(ps.database_path());
  ExpectError([&] { ps.Put(Req("KT09", "X", kGear)); }, Errc::kNotFound,
              "unknown namespace 'KT09' (configured: HOST, KT01, KT02, OK01)");
  ExpectError([&] { ps.List("KT09"); }, Errc::kNotFound, "unknown namespace");
  ExpectError([&] { ps.Put(Req("", "X", kGear)); }, Errc::kInvalidArgument, "no namespace");
  EXPECT_EQ(Snapshot(ps.database_path()), before);
  StoreOptions spaced = Options(tmp.path());
  spaced.namespaces = {"KT 01"};
  ExpectError([&] { ProgramStore x(spaced); }, Errc::kInvalidArgument, "bad namespace 'KT 01'");
}

TEST(ProgramStore, StationNamespacesLendTheirDialect) {
  TempDir tmp;
  StoreOptions opts = Options(tmp.path());
  opts.namespace_dialects = {{"KT01", kKtapl}, {"OK01", kOkuma}};
  ProgramStore ps(opts);
  EXPECT_EQ(ps.NamespaceDialect("KT01"), kKtapl);
  EXPECT_EQ(ps.NamespaceDialect("HOST"), kNoDialect);
  const std::string plain = "N10 G0 X1. F0\nN20 M30\n";
  PutResult kt = ps.Put(Req("KT01", "PLAIN", plain));
  EXPECT_EQ(kt.file.metadata.dialect, kKtapl);
  EXPECT_EQ(ps.Put(Req("OK01", "PLAIN", plain)).file.metadata.dialect, kOkuma);
  ExpectError([&] { ps.Put(Req("HOST", "PLAIN", plain)); }, Errc::kInvalidArgument,
              "cannot tell the dialect");
  // Copying to HOST keeps the dialect the file was stored with.
  EXPECT_EQ(ps.Copy({.from_node = "KT01",
                     .from_name = "PLAIN",
                     .from_revision = 0,
                     .to_node = "HOST",
                     .to_name = "",
                     .force = false,
                     .idempotency_key = ""})
                .file.metadata.dialect,
            kKtapl);
  StoreOptions bad = Options(tmp.path());
  bad.namespace_dialects = {{"KT07", kKtapl}};
  ExpectError([&] { ProgramStore x(bad); }, Errc::kInvalidArgument, "not a configured station namespace");
}

// A Balt-System memory holds 64,000 characters (manual ln 223): a put, a copy or a move that would overfill
// one is FILMS3 15 NO FREE SECTORS (ln 9758-9759) and stores nothing; MP1 is the station's own namespace.
// Other stations' namespaces and HOST are not bounded. Sizes: 40,000 + 24,000 = 64,000 fits exactly; one
// character more does not, nor does replacing the 24,000 file by 24,001.
TEST(ProgramStore, BaltMemoriesHoldSixtyFourThousandCharacters) {
  TempDir tmp;
  StoreOptions opts = Options(tmp.path());
  opts.namespaces = {"BS01", "BS01/MP2", "KT01"};
  opts.namespace_dialects = {{"BS01", kBalt}, {"BS01/MP2", kBalt}, {"KT01", kKtapl}};
  ProgramStore ps(opts);
  EXPECT_TRUE(ps.IsMemory("BS01"));
  EXPECT_TRUE(ps.IsMemory("BS01/MP2"));
  EXPECT_FALSE(ps.IsMemory("KT01"));
  EXPECT_FALSE(ps.IsMemory("HOST"));
  // A Balt-System program of n characters: comment blocks after a G0 block.
  auto text = [](std::size_t n) {
    std::string t = "G0 X0\n";
    while (t.size() < n) t += std::string(std::min<std::size_t>(79, n - t.size() - 1), ';') + "\n";
    return t;
  };
  auto put = [&](const std::string& node, const std::string& name, std::size_t n, bool force = false) {
    PutRequest r = Req(node, name, text(n), force);
    r.dialect = kBalt;
    return ps.Put(r);
  };
  put("BS01/MP2", "BIG", 40000);
  put("BS01/MP2", "MID", 24000);
  const std::string before = Snapshot(ps.database_path());
  ExpectError([&] { put("BS01/MP2", "ONE", 6); }, Errc::kFailedPrecondition,
              "[FILMS3 15] NO FREE SECTORS: BS01/MP2 would hold 64006 characters, 64000 at most");
  ExpectError([&] { put("BS01/MP2", "MID", 24001, true); }, Errc::kFailedPrecondition,
              "[FILMS3 15] NO FREE SECTORS");
  EXPECT_EQ(Snapshot(ps.database_path()), before);
  put("BS01/MP2", "MID", 23000, true);  // a smaller revision frees room
  put("BS01", "P1", 64000);
  ExpectError([&] { put("BS01", "P2", 10); }, Errc::kFailedPrecondition, "NO FREE SECTORS");
  put("HOST", "P3", 2000);
  ExpectError(
      [&] {
        ps.Copy({.from_node = "HOST",
                 .from_name = "P3",
                 .from_revision = 0,
                 .to_node = "BS01/MP2",
                 .to_name = "",
                 .force = false,
                 .idempotency_key = ""});
      },
      Errc::kFailedPrecondition, "NO FREE SECTORS");
  ExpectError(
      [&] {
        ps.Rename({.node = "HOST", .name = "P3", .to_node = "BS01", .to_name = "", .idempotency_key = ""});
      },
      Errc::kFailedPrecondition, "NO FREE SECTORS");
  std::string kt;
  while (kt.size() < 70000) kt += "N10 G0 X1. F0\n";
  ps.Put(Req("KT01", "LONG", kt));  // not a memory: only the store's file size bounds it
}

TEST(ProgramStore, BadInputGetsAClearErrorAndChangesNothing) {
  TempDir tmp;
  ProgramStore ps(Options(tmp.path()));
  ps.Put(Req("HOST", "GEAR HOUSING", kGear));
  const std::string before = Snapshot(ps.database_path());
  struct Case {
    PutRequest req;
    Errc code;
    std::string needle;
  };
  std::vector<Case> cases = {
      {Req("HOST", "", kGear), Errc::kInvalidArgument, "empty file name"},
      {Req("HOST", std::string(33, 'A'), kGear), Errc::kInvalidArgument, "too long: 33 characters"},
      {Req("HOST", "BAD,NAME", kGear), Errc::kInvalidArgument, "comma"},
      {Req("HOST", "A/B", kGear), Errc::kInvalidArgument, "path separator"},
      {Req("HOST", "BIN", std::string("%\n(NAM,X)\n\0\0\0", 13)), Errc::kInvalidArgument, "not text"},
      {Req("HOST", "MIX", "%\n(NAM,MIX)\nN1 VSET V1=2\n"), Errc::kInvalidArgument, "cannot tell the dialect"},
      {Req("HOST", "PLAIN", "G0 X0\nG1 X5 F100\nM30\n"), Errc::kInvalidArgument, "cannot tell the dialect"},
      {Req("HOST", "GEAR HOUSING", kGear2), Errc::kAlreadyExists, "use --force"},
      {Req("OK01", "1BAD.MIN", "O1\nVSET V1=1\nM02\n"), Errc::kInvalidArgument, "must begin with a letter"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.needle);
    ExpectError([&] { ps.Put(c.req); }, c.code, c.needle);
    EXPECT_EQ(Snapshot(ps.database_path()), before);
  }
  StoreOptions small = Options(tmp.path());
  small.max_file_size = 10;
  ProgramStore limited(small);
  ExpectError([&] { limited.Put(Req("HOST", "BIG", kGear)); }, Errc::kInvalidArgument, "too large");
  EXPECT_EQ(Snapshot(ps.database_path()), before);
}

TEST(ProgramStore, IdempotentRetriesReturnTheFirstResult) {
  TempDir tmp;
  std::uint64_t first_seq = 0;
  {
    ProgramStore ps(Options(tmp.path()));
    PutResult a = ps.Put(Req("HOST", "GEAR HOUSING", kGear, false, "put-1"));
    PutResult b = ps.Put(Req("HOST", "GEAR HOUSING", kGear, false, "put-1"));  // would fail without the key
    EXPECT_FALSE(a.replayed);
    EXPECT_TRUE(b.replayed);
    EXPECT_EQ(b.file.revision, 1u);
    EXPECT_EQ(b.file.sha256, a.file.sha256);
    EXPECT_EQ(b.events.at(0).seq, a.events.at(0).seq);
    first_seq = a.events.at(0).seq;
    PutResult f1 = ps.Put(Req("HOST", "GEAR HOUSING", kGear2, true, "put-2"));
    PutResult f2 = ps.Put(Req("HOST", "GEAR HOUSING", kGear2, true, "put-2"));
    EXPECT_EQ(f1.file.revision, 2u);
    EXPECT_EQ(f2.file.revision, 2u);
    EXPECT_EQ(ps.Show("HOST", "GEAR HOUSING").revisions.size(), 2u);
    ExpectError([&] { ps.Put(Req("HOST", "GEAR HOUSING", kGear, true, "put-2")); }, Errc::kFailedPrecondition,
                "idempotency key 'put-2' was already used for a different request");
  }
  // Durable: a retry after a restart still replays.
  ProgramStore ps(Options(tmp.path()));
  PutResult again = ps.Put(Req("HOST", "GEAR HOUSING", kGear, false, "put-1"));
  EXPECT_TRUE(again.replayed);
  EXPECT_EQ(again.file.revision, 1u);
  EXPECT_EQ(again.events.at(0).seq, first_seq);
  EXPECT_EQ(ps.Show("HOST", "GEAR HOUSING").revisions.size(), 2u);

  // Other operations too.
  CopyRequest cp{.from_node = "HOST",
                 .from_name = "GEAR HOUSING",
                 .from_revision = 0,
                 .to_node = "KT01",
                 .to_name = "",
                 .force = false,
                 .idempotency_key = "cp-1"};
  EXPECT_FALSE(ps.Copy(cp).replayed);
  EXPECT_TRUE(ps.Copy(cp).replayed);
  EXPECT_FALSE(ps.SetProtected("KT01", "GEAR HOUSING", true, "pr-1").replayed);
  EXPECT_TRUE(ps.SetProtected("KT01", "GEAR HOUSING", true, "pr-1").replayed);
  ps.SetProtected("KT01", "GEAR HOUSING", false);
  OpResult d1 = ps.Delete("KT01", "GEAR HOUSING", "rm-1");
  OpResult d2 = ps.Delete("KT01", "GEAR HOUSING", "rm-1");  // would be kNotFound without the key
  EXPECT_FALSE(d1.replayed);
  EXPECT_TRUE(d2.replayed);
  EXPECT_EQ(d2.events.at(0).kind, ChangeEvent::Kind::kDeleted);
  RenameRequest mv{
      .node = "HOST", .name = "GEAR HOUSING", .to_node = "", .to_name = "GEAR 2", .idempotency_key = "mv-1"};
  EXPECT_FALSE(ps.Rename(mv).replayed);
  EXPECT_TRUE(ps.Rename(mv).replayed);
  EXPECT_EQ(ps.List("HOST").size(), 1u);
}

// `program ls --after NAME` (DESIGN §6): by name in byte order, the cursor exclusive (it need not exist),
// the visit stops where the page is full; after the last name and in an empty namespace there is nothing.
TEST(ProgramStore, ListPagesAfterACursorByName) {
  TempDir tmp;
  ProgramStore ps(Options(tmp.path()));
  for (const char* name : {"GEAR HOUSING", "GEAR BOX", "PALLET38;FXT", "A1", "B1", "a1"})
    ps.Put(Req("KT01", name, std::string(name).find(";FXT") != std::string::npos ? "(FXC,H1 X0)\n" : kGear));
  auto page = [&](std::string_view pattern, std::string_view after, std::size_t limit) {
    std::vector<std::string> out;
    ps.List("KT01", pattern, after, [&](const FileInfo& f) {
      if (out.size() == limit) return false;
      out.push_back(f.name);
      return true;
    });
    return out;
  };
  EXPECT_THAT(page("*", "", 2), ElementsAre("A1", "B1"));
  EXPECT_THAT(page("*", "B1", 2), ElementsAre("GEAR BOX", "GEAR HOUSING"));
  EXPECT_THAT(page("*", "GEAR HOUSING", 9), ElementsAre("PALLET38;FXT", "a1"));  // 'a' sorts after 'P'
  EXPECT_THAT(page("*", "C", 1), ElementsAre("GEAR BOX"));
  EXPECT_THAT(page("GEAR*", "GEAR BOX", 9), ElementsAre("GEAR HOUSING"));
  EXPECT_THAT(page("*", "a1", 9), IsEmpty());
  EXPECT_THAT(page("*", "", 0), IsEmpty());
  std::vector<std::string> none;
  ps.List("KT02", "*", "", [&](const FileInfo& f) {
    none.push_back(f.name);
    return true;
  });
  EXPECT_THAT(none, IsEmpty());
}

// What a change republishes (service.cpp PublishEntry): the one file and its namespace's count, without a
// listing of the namespace (issue 39 item 1). The name is a name, not a pattern.
TEST(ProgramStore, InfoAndCountReadOneFileAndTheNamespaceSize) {
  TempDir tmp;
  ProgramStore ps(Options(tmp.path()));
  EXPECT_EQ(ps.Count("KT01"), 0u);
  EXPECT_FALSE(ps.Info("KT01", "A1"));
  for (const char* name : {"A1", "B1", "C1"}) ps.Put(Req("KT01", name, kGear));
  ps.Put(Req("HOST", "A1", kGear));
  PutRequest again = Req("KT01", "A1", std::string(kGear) + "N99 M30\n");
  again.force = true;
  ps.Put(again);
  EXPECT_EQ(ps.Count("KT01"), 3u);
  EXPECT_EQ(ps.Count("HOST"), 1u);
  std::optional<FileInfo> a1 = ps.Info("KT01", "A1");
  ASSERT_TRUE(a1);
  EXPECT_EQ(a1->revision, 2u);  // the head
  EXPECT_EQ(a1->node, "KT01");
  EXPECT_FALSE(ps.Info("KT01", "A*"));
  ps.Delete("KT01", "B1");
  EXPECT_FALSE(ps.Info("KT01", "B1"));
  EXPECT_EQ(ps.Count("KT01"), 2u);
  ExpectError([&] { ps.Count("KT09"); }, Errc::kNotFound, "unknown namespace");
}

TEST(ProgramStore, ListWithWildcards) {
  TempDir tmp;
  ProgramStore ps(Options(tmp.path()));
  for (const char* name : {"GEAR HOUSING", "GEAR BOX", "PALLET38;FXT", "PALLET39;FXT", "A1", "B1"}) {
    std::string content = std::string(name).find(";FXT") != std::string::npos ? "(FXC,H1 X0)\n" : kGear;
    ps.Put(Req("KT01", name, content));
  }
  ps.Put(Req("HOST", "GEAR ON HOST", kGear));
  auto names = [&](std::string_view pattern) {
    std::vector<std::string> out;
    for (const FileInfo& f : ps.List("KT01", pattern)) out.push_back(f.name);
    return out;
  };
  EXPECT_THAT(names("GEAR*"), ElementsAre("GEAR BOX", "GEAR HOUSING"));
  EXPECT_THAT(names("PALLET3?;FXT"), ElementsAre("PALLET38;FXT", "PALLET39;FXT"));
  EXPECT_THAT(names("*;FXT"), ElementsAre("PALLET38;FXT", "PALLET39;FXT"));
  EXPECT_THAT(names("?1"), ElementsAre("A1", "B1"));
  EXPECT_THAT(names("*"),
              ElementsAre("A1", "B1", "GEAR BOX", "GEAR HOUSING", "PALLET38;FXT", "PALLET39;FXT"));
  EXPECT_EQ(names("").size(), 6u);
  EXPECT_THAT(names("GEAR"), IsEmpty());
  EXPECT_THAT(names("A1"), ElementsAre("A1"));
  EXPECT_THAT(names("*X*"), ElementsAre("GEAR BOX", "PALLET38;FXT", "PALLET39;FXT"));
  std::vector<FileInfo> host = ps.List("HOST");
  ASSERT_EQ(host.size(), 1u);
  EXPECT_EQ(host[0].node, "HOST");
  EXPECT_EQ(host[0].metadata.type, FileType::kPartProgram);
  EXPECT_TRUE(ps.List("KT02").empty());

  EXPECT_TRUE(WildcardMatch("*", ""));
  EXPECT_FALSE(WildcardMatch("?", ""));
  EXPECT_TRUE(WildcardMatch("a*b*c", "aXXbYYc"));
  EXPECT_FALSE(WildcardMatch("a*b*c", "aXXbYY"));
  EXPECT_TRUE(WildcardMatch("**a", "ba"));
}

int CountRows(const fs::path& db_path, const char* table) {
  store::Database db = store::Database::Open(db_path);
  return static_cast<int>(db.QueryInt64(fmt::format("SELECT count(*) FROM {}", table)));
}

TEST(ProgramStore, CopyBetweenNamespaces) {
  TempDir tmp;
  ProgramStore ps(Options(tmp.path()));
  ps.Put(Req("HOST", "GEAR HOUSING", kGear));
  ps.Put(Req("HOST", "GEAR HOUSING", kGear2, true));
  CopyRequest rcp;
  rcp.from_node = "HOST";
  rcp.from_name = "GEAR HOUSING";
  rcp.to_node = "KT01";
  PutResult c = ps.Copy(rcp);
  EXPECT_TRUE(c.created);
  EXPECT_EQ(c.file.node, "KT01");
  EXPECT_EQ(c.file.name, "GEAR HOUSING");
  EXPECT_EQ(c.file.revision, 1u);
  EXPECT_EQ(c.file.sha256, Sha256Hex(kGear2));
  EXPECT_THAT(c.file.metadata.utl, ElementsAre("12", "3", "44"));
  EXPECT_EQ(ps.Get("KT01", "GEAR HOUSING").content, kGear2);
  EXPECT_EQ(CountRows(ps.database_path(), "blobs"), 2);  // content is shared, not duplicated

  ExpectError([&] { ps.Copy(rcp); }, Errc::kAlreadyExists, "'GEAR HOUSING' in KT01 already exists");
  rcp.from_revision = 1;
  rcp.force = true;
  PutResult again = ps.Copy(rcp);
  EXPECT_EQ(again.file.revision, 2u);
  EXPECT_EQ(ps.Get("KT01", "GEAR HOUSING").content, kGear);

  CopyRequest back{.from_node = "KT01",
                   .from_name = "GEAR HOUSING",
                   .from_revision = 0,
                   .to_node = "HOST",
                   .to_name = "HOUSING783",
                   .force = false,
                   .idempotency_key = ""};
  EXPECT_EQ(ps.Copy(back).file.sha256, Sha256Hex(kGear));
  ExpectError(
      [&] {
        ps.Copy({.from_node = "HOST",
                 .from_name = "NONE",
                 .from_revision = 0,
                 .to_node = "KT01",
                 .to_name = "",
                 .force = false,
                 .idempotency_key = ""});
      },
      Errc::kNotFound, "no file 'NONE' in HOST");
  ExpectError(
      [&] {
        ps.Copy({.from_node = "HOST",
                 .from_name = "HOUSING783",
                 .from_revision = 0,
                 .to_node = "HOST",
                 .to_name = "",
                 .force = true,
                 .idempotency_key = ""});
      },
      Errc::kInvalidArgument, "onto itself");
  ExpectError(
      [&] {
        ps.Copy({.from_node = "HOST",
                 .from_name = "HOUSING783",
                 .from_revision = 0,
                 .to_node = "KT01",
                 .to_name = "BAD,NAME",
                 .force = false,
                 .idempotency_key = ""});
      },
      Errc::kInvalidArgument, "comma");
  ExpectError(
      [&] {
        ps.Copy({.from_node = "HOST",
                 .from_name = "HOUSING783",
                 .from_revision = 0,
                 .to_node = "KT07",
                 .to_name = "",
                 .force = false,
                 .idempotency_key = ""});
      },
      Errc::kNotFound, "unknown namespace 'KT07'");
}

TEST(ProgramStore, RenameKeepsHistory) {
  TempDir tmp;
  ProgramStore ps(Options(tmp.path()));
  ps.Put(Req("HOST", "GEAR HOUSING", kGear));
  ps.Put(Req("HOST", "GEAR HOUSING", kGear2, true));
  ps.Put(Req("HOST", "OTHER", kGear));
  OpResult r = ps.Rename(
      {.node = "HOST", .name = "GEAR HOUSING", .to_node = "", .to_name = "GEAR 2", .idempotency_key = ""});
  EXPECT_EQ(r.file.name, "GEAR 2");
  EXPECT_EQ(r.file.head_revision, 2u);
  ASSERT_EQ(r.events.size(), 2u);
  EXPECT_EQ(r.events[0].kind, ChangeEvent::Kind::kDeleted);
  EXPECT_EQ(r.events[0].name, "GEAR HOUSING");
  EXPECT_EQ(r.events[1].kind, ChangeEvent::Kind::kCreated);
  EXPECT_EQ(r.events[1].name, "GEAR 2");
  EXPECT_EQ(ps.Get("HOST", "GEAR 2", 1).content, kGear);
  ExpectError([&] { ps.Get("HOST", "GEAR HOUSING"); }, Errc::kNotFound, "no file");
  // Move to a station namespace under the same name.
  OpResult moved =
      ps.Rename({.node = "HOST", .name = "GEAR 2", .to_node = "KT02", .to_name = "", .idempotency_key = ""});
  EXPECT_EQ(moved.file.node, "KT02");
  EXPECT_EQ(ps.Show("KT02", "GEAR 2").revisions.size(), 2u);
  const std::string before = Snapshot(ps.database_path());
  ExpectError(
      [&] {
        ps.Rename(
            {.node = "HOST", .name = "OTHER", .to_node = "KT02", .to_name = "GEAR 2", .idempotency_key = ""});
      },
      Errc::kAlreadyExists, "rename never overwrites");
  ExpectError(
      [&] {
        ps.Rename({.node = "HOST", .name = "MISSING", .to_node = "", .to_name = "X", .idempotency_key = ""});
      },
      Errc::kNotFound, "no file 'MISSING'");
  ExpectError(
      [&] {
        ps.Rename({.node = "HOST",
                   .name = "OTHER",
                   .to_node = "",
                   .to_name = std::string(40, 'Z'),
                   .idempotency_key = ""});
      },
      Errc::kInvalidArgument, "too long");
  EXPECT_EQ(Snapshot(ps.database_path()), before);
}

TEST(ProgramStore, DeleteAndProtect) {
  TempDir tmp;
  ProgramStore ps(Options(tmp.path()));
  ps.Put(Req("HOST", "GEAR HOUSING", kGear));
  ps.Put(Req("HOST", "GEAR HOUSING", kGear2, true));
  ps.Copy({.from_node = "HOST",
           .from_name = "GEAR HOUSING",
           .from_revision = 1,
           .to_node = "KT01",
           .to_name = "",
           .force = false,
           .idempotency_key = ""});
  EXPECT_EQ(CountRows(ps.database_path(), "blobs"), 2);

  OpResult p = ps.SetProtected("HOST", "GEAR HOUSING", true);
  EXPECT_TRUE(p.file.is_protected);
  ASSERT_EQ(p.events.size(), 1u);
  EXPECT_EQ(p.events[0].kind, ChangeEvent::Kind::kUpdated);
  EXPECT_TRUE(ps.SetProtected("HOST", "GEAR HOUSING", true).events.empty());  // already protected: no change
  EXPECT_TRUE(ps.List("HOST")[0].is_protected);
  const std::string before = Snapshot(ps.database_path());
  ExpectError([&] { ps.Put(Req("HOST", "GEAR HOUSING", kGear, true)); }, Errc::kPermissionDenied,
              "protected");
  ExpectError([&] { ps.Delete("HOST", "GEAR HOUSING"); }, Errc::kPermissionDenied, "protected");
  ExpectError(
      [&] {
        ps.Rename(
            {.node = "HOST", .name = "GEAR HOUSING", .to_node = "", .to_name = "X", .idempotency_key = ""});
      },
      Errc::kPermissionDenied, "protected");
  ExpectError(
      [&] {
        ps.Copy({.from_node = "KT01",
                 .from_name = "GEAR HOUSING",
                 .from_revision = 0,
                 .to_node = "HOST",
                 .to_name = "",
                 .force = true,
                 .idempotency_key = ""});
      },
      Errc::kPermissionDenied, "protected");
  ExpectError([&] { ps.BeginPut("s1", Req("HOST", "GEAR HOUSING", "", true)); }, Errc::kPermissionDenied,
              "protected");
  EXPECT_EQ(Snapshot(ps.database_path()), before);
  // Copying *from* a protected file is fine.
  ps.Copy({.from_node = "HOST",
           .from_name = "GEAR HOUSING",
           .from_revision = 0,
           .to_node = "KT02",
           .to_name = "",
           .force = false,
           .idempotency_key = ""});

  ps.SetProtected("HOST", "GEAR HOUSING", false);
  OpResult d = ps.Delete("HOST", "GEAR HOUSING");
  EXPECT_EQ(d.events.at(0).kind, ChangeEvent::Kind::kDeleted);
  EXPECT_EQ(d.events.at(0).revision, 2u);
  ExpectError([&] { ps.Get("HOST", "GEAR HOUSING"); }, Errc::kNotFound, "no file");
  ExpectError([&] { ps.Delete("HOST", "GEAR HOUSING"); }, Errc::kNotFound, "no file");
  // Content still used by KT01 (rev 1) and KT02 (rev 2) stays; nothing else is left behind.
  EXPECT_EQ(CountRows(ps.database_path(), "blobs"), 2);
  EXPECT_EQ(ps.Get("KT01", "GEAR HOUSING").content, kGear);
  ps.Delete("KT01", "GEAR HOUSING");
  EXPECT_EQ(CountRows(ps.database_path(), "blobs"), 1);
  ps.Delete("KT02", "GEAR HOUSING");
  EXPECT_EQ(CountRows(ps.database_path(), "blobs"), 0);
  EXPECT_EQ(CountRows(ps.database_path(), "revisions"), 0);
  // A name can be created again after deletion, starting at revision 1.
  EXPECT_EQ(ps.Put(Req("HOST", "GEAR HOUSING", kGear)).file.revision, 1u);
}

TEST(ProgramStore, ChangeEventsAreReportedAndDurable) {
  TempDir tmp;
  std::vector<ChangeEvent> returned;
  std::vector<ChangeEvent> heard;
  {
    ProgramStore ps(Options(tmp.path()));
    ps.SetChangeListener([&](const ChangeEvent& e) { heard.push_back(e); });
    auto add = [&](const std::vector<ChangeEvent>& v) {
      returned.insert(returned.end(), v.begin(), v.end());
    };
    add(ps.Put(Req("HOST", "A1", kGear)).events);
    add(ps.Put(Req("HOST", "A1", kGear2, true)).events);
    add(ps.Copy({.from_node = "HOST",
                 .from_name = "A1",
                 .from_revision = 0,
                 .to_node = "KT01",
                 .to_name = "",
                 .force = false,
                 .idempotency_key = ""})
            .events);
    add(ps.Rename({.node = "KT01", .name = "A1", .to_node = "", .to_name = "A2", .idempotency_key = ""})
            .events);
    add(ps.SetProtected("KT01", "A2", true).events);
    add(ps.SetProtected("KT01", "A2", false).events);
    add(ps.Delete("KT01", "A2").events);
    ps.Put(Req("HOST", "A1", kGear, true, "k"));
    heard.pop_back();  // the replay below must not be heard again
    ps.Put(Req("HOST", "A1", kGear, true, "k"));
  }
  ASSERT_EQ(returned.size(), 8u);
  ASSERT_EQ(heard.size(), 8u);
  std::vector<std::string> summary;
  for (std::size_t i = 0; i < returned.size(); ++i) {
    EXPECT_EQ(heard[i].seq, returned[i].seq);
    if (i > 0) {
      EXPECT_GT(returned[i].seq, returned[i - 1].seq);
    }
    summary.push_back(fmt::format("{} {}/{} r{}", ChangeKindName(returned[i].kind), returned[i].node,
                                  returned[i].name, returned[i].revision));
  }
  EXPECT_THAT(summary, ElementsAre("created HOST/A1 r1", "updated HOST/A1 r2", "created KT01/A1 r1",
                                   "deleted KT01/A1 r1", "created KT01/A2 r1", "updated KT01/A2 r1",
                                   "updated KT01/A2 r1", "deleted KT01/A2 r1"));
  ProgramStore reopened(Options(tmp.path()));
  std::vector<ChangeEvent> log = reopened.EventsSince(0);
  ASSERT_EQ(log.size(), 9u);
  EXPECT_EQ(log[3].seq, returned[3].seq);
  EXPECT_EQ(log[8].revision, 3u);
  EXPECT_EQ(reopened.EventsSince(returned[6].seq).size(), 2u);
  EXPECT_EQ(reopened.EventsSince(0, 2).size(), 2u);
}

std::string BigProgram(std::size_t bytes, char variant) {
  std::string s = "%\n(NAM,BIG)\n(UTL,1)\n(UCY,60)\n";
  int n = 0;
  while (s.size() < bytes) {
    ++n;
    s += fmt::format("N{} G1 X{}.{} Y{} F100 ({})\n", n, n % 1000, variant, n % 77, variant);
  }
  s += "N99999999 M30\n";
  return s;
}

TEST(ProgramStore, ChunkedPutIsAtomic) {
  TempDir tmp;
  ProgramStore ps(Options(tmp.path()));
  const std::string old_content = BigProgram(1000, 'a');
  const std::string big = BigProgram(20u << 20, 'b');  // 20 MB
  ASSERT_GE(big.size(), 20u << 20);
  ps.Put(Req("KT01", "BIG", old_content));
  const std::string old_sha = Sha256Hex(old_content), new_sha = Sha256Hex(big);

  // A second connection reads all the while: it must see the old or the new revision, never a mix.
  std::atomic<bool> stop{false};
  std::atomic<int> reads_old{0}, reads_new{0}, bad{0};
  std::thread reader([&] {
    try {
      ProgramStore other(Options(tmp.path()));
      while (!stop) {
        GetResult g = other.Get("KT01", "BIG");
        std::string sha = Sha256Hex(g.content);
        if (sha == old_sha && g.file.sha256 == old_sha) {
          ++reads_old;
        } else if (sha == new_sha && g.file.sha256 == new_sha) {
          ++reads_new;
        } else {
          ++bad;
        }
      }
    } catch (const std::exception& e) {
      std::fprintf(stderr, "reader: %s\n", e.what());
      ++bad;
    }
  });
  while (reads_old == 0 && bad == 0) std::this_thread::yield();

  ps.BeginPut("s-big", Req("KT01", "BIG", "", /*force=*/true));
  const std::size_t chunk = 1u << 20;
  std::uint32_t index = 0;
  for (std::size_t off = 0; off < big.size(); off += chunk) {
    ps.PutChunk("s-big", index, std::string_view(big).substr(off, chunk));
    if (index == 3) {
      ps.PutChunk("s-big", index, std::string_view(big).substr(off, chunk));  // a retried chunk is a no-op
      EXPECT_EQ(ps.Get("KT01", "BIG").content, old_content);                  // half way: still the old one
    }
    ++index;
  }
  PutResult r = ps.CommitPut("s-big");
  while (reads_new == 0 && bad == 0) std::this_thread::yield();
  stop = true;
  reader.join();
  EXPECT_EQ(bad, 0);
  EXPECT_EQ(r.file.revision, 2u);
  EXPECT_EQ(r.file.sha256, new_sha);
  EXPECT_EQ(r.file.metadata.size, big.size());
  EXPECT_EQ(r.file.metadata.nam, "BIG");
  EXPECT_EQ(ps.Get("KT01", "BIG").content, big);
  EXPECT_EQ(ps.Get("KT01", "BIG", 1).content, old_content);
  EXPECT_EQ(ps.OpenStreams(), 0u);
  // A retried commit returns the first result.
  PutResult again = ps.CommitPut("s-big");
  EXPECT_TRUE(again.replayed);
  EXPECT_EQ(again.file.revision, 2u);
  EXPECT_EQ(StagedFiles(ps.database_path()), 0);
}

// Issue 39 item 4: a chunked put (over one chunk: cellctl's path above 30 KB) repeated under the same
// idempotency key, as a supervisor retries after a crash, replays the first result; it failed "already
// exists" at BeginPut. The same key with other content is refused; without a key, "already exists" stands.
TEST(ProgramStore, AChunkedPutRetriedUnderItsKeyReplays) {
  TempDir tmp;
  ProgramStore ps(Options(tmp.path()));
  auto chunked = [&](const std::string& stream, const std::string& key, const std::string& tail) {
    ps.BeginPut(stream, Req("HOST", "BIG", "", false, key));
    ps.PutChunk(stream, 0, "%\n(NAM,BIG)\n");
    ps.PutChunk(stream, 1, "N10 G71\n" + tail + "N20 M30\n%\n");
    return ps.CommitPut(stream);
  };
  const PutResult first = chunked("put-a", "big-1", "");
  EXPECT_TRUE(first.created);
  const PutResult again = chunked("put-b", "big-1", "");  // a new stream id: a new cellctl process
  EXPECT_TRUE(again.replayed);
  EXPECT_EQ(again.file.head_revision, first.file.head_revision);
  EXPECT_EQ(ps.Show("HOST", "BIG", 0).revisions.size(), 1u);
  ExpectError([&] { chunked("put-c", "big-1", "N15 G90\n"); }, Errc::kFailedPrecondition,
              "already used for a different request");
  ExpectError([&] { ps.BeginPut("put-d", Req("HOST", "BIG", "")); }, Errc::kAlreadyExists, "--force");
  EXPECT_EQ(ps.Show("HOST", "BIG", 0).revisions.size(), 1u);
}

TEST(ProgramStore, BrokenStreamsLeaveTheStoreAsItWas) {
  TempDir tmp;
  std::string before;
  {
    ProgramStore ps(Options(tmp.path()));
    ps.Put(Req("HOST", "GEAR HOUSING", kGear));
    before = Snapshot(ps.database_path());
    // Checked at begin: existing without force, bad declared name, unknown namespace, inline content.
    ExpectError([&] { ps.BeginPut("s0", Req("HOST", "GEAR HOUSING", "")); }, Errc::kAlreadyExists, "--force");
    PutRequest bad = Req("HOST", "BAD,NAME", "");
    bad.dialect = kKtapl;
    ExpectError([&] { ps.BeginPut("s0", bad); }, Errc::kInvalidArgument, "comma");
    ExpectError([&] { ps.BeginPut("s0", Req("XX", "A", "")); }, Errc::kNotFound, "unknown namespace");
    ExpectError([&] { ps.BeginPut("s0", Req("HOST", "A", "x")); }, Errc::kInvalidArgument, "in chunks");
    EXPECT_EQ(Snapshot(ps.database_path()), before);

    // Out of order: the stream is abandoned.
    ps.BeginPut("s1", Req("HOST", "NEW", ""));
    ps.BeginPut("s1", Req("HOST", "NEW", ""));  // a retried begin is a no-op
    ExpectError([&] { ps.BeginPut("s1", Req("HOST", "OTHER", "")); }, Errc::kAlreadyExists, "already open");
    ps.PutChunk("s1", 0, "%\n(NAM,NEW)\n");
    ExpectError([&] { ps.PutChunk("s1", 2, "N1 M30\n"); }, Errc::kFailedPrecondition,
                "chunk 2 out of order, expected 1");
    ExpectError([&] { ps.PutChunk("s1", 1, "N1 M30\n"); }, Errc::kNotFound, "no open stream 's1'");
    ExpectError([&] { ps.CommitPut("s1"); }, Errc::kNotFound, "no open stream 's1'");
    EXPECT_EQ(Snapshot(ps.database_path()), before);

    // A retried chunk with different bytes.
    ps.BeginPut("s2", Req("HOST", "NEW", ""));
    ps.PutChunk("s2", 0, "%\n");
    ExpectError([&] { ps.PutChunk("s2", 0, "%%\n"); }, Errc::kFailedPrecondition, "different bytes");
    EXPECT_EQ(Snapshot(ps.database_path()), before);

    // Content that fails validation at commit: nothing stored, stream gone.
    ps.BeginPut("s3", Req("HOST", "NEW", ""));
    ps.PutChunk("s3", 0, "%\n(NAM,NEW)\n");
    ps.PutChunk("s3", 1, std::string("\0\1\2", 3));
    ExpectError([&] { ps.CommitPut("s3"); }, Errc::kInvalidArgument, "not text");
    EXPECT_EQ(ps.OpenStreams(), 0u);
    EXPECT_EQ(StagedFiles(ps.database_path()), 0);
    EXPECT_EQ(Snapshot(ps.database_path()), before);

    // Too large in total.
    StoreOptions small = Options(tmp.path());
    small.max_file_size = 8;
    ProgramStore limited(small);
    limited.BeginPut("s4", Req("HOST", "NEW", ""));
    limited.PutChunk("s4", 0, "12345");
    ExpectError([&] { limited.PutChunk("s4", 1, "67890"); }, Errc::kInvalidArgument, "too large");
    EXPECT_EQ(Snapshot(ps.database_path()), before);

    // Aborted, expired, and abandoned by a restart.
    ps.BeginPut("s5", Req("HOST", "NEW", ""));
    ps.PutChunk("s5", 0, "%\n");
    EXPECT_EQ(StagedFiles(ps.database_path()), 1);
    ps.AbortPut("s5");
    EXPECT_EQ(StagedFiles(ps.database_path()), 0);
    EXPECT_EQ(Snapshot(ps.database_path()), before);
    ps.BeginPut("s6", Req("HOST", "NEW", ""));
    ps.PutChunk("s6", 0, "%\n");
    EXPECT_EQ(ps.ExpireStreams(std::chrono::hours(1)), 0u);
    EXPECT_EQ(ps.ExpireStreams(std::chrono::seconds(0)), 1u);
    EXPECT_EQ(Snapshot(ps.database_path()), before);
    ps.BeginPut("s7", Req("HOST", "NEW", ""));
    ps.PutChunk("s7", 0, "%\n(NAM,NEW)\n");
    EXPECT_EQ(ps.OpenStreams(), 1u);
    EXPECT_EQ(StagedFiles(ps.database_path()), 1);
  }
  ProgramStore reopened(Options(tmp.path()));
  EXPECT_EQ(reopened.OpenStreams(), 0u);
  EXPECT_EQ(StagedFiles(reopened.database_path()), 0);
  EXPECT_EQ(Snapshot(reopened.database_path()), before);
  ExpectError([&] { reopened.CommitPut("s7"); }, Errc::kNotFound, "no open stream");
}

TEST(ProgramStore, LiveStreamSurvivesASecondOpenerCleaningScratchFiles) {
  TempDir tmp;
  ProgramStore ps(Options(tmp.path()));
  ps.BeginPut("live", Req("HOST", "LIVE", ""));
  ps.PutChunk("live", 0, "%\n(NAM,LIVE)\n");
  ProgramStore second(Options(tmp.path()));  // empties the scratch folder
  EXPECT_EQ(StagedFiles(ps.database_path()), 0);
  ps.PutChunk("live", 1, "N1 G0 X0 F0\nN2 M30\n");
  PutResult r = ps.CommitPut("live");
  EXPECT_EQ(second.Get("HOST", "LIVE").content, "%\n(NAM,LIVE)\nN1 G0 X0 F0\nN2 M30\n");
  EXPECT_EQ(r.file.metadata.nam, "LIVE");
}

TEST(ProgramStore, OpensAVersion1DatabaseAndMigratesIt) {
  TempDir tmp;
  StoreOptions opts = Options(tmp.path());
  {
    // A database as the first release wrote it: schema v1 only, with one file in it.
    store::Database db = store::Database::Open(opts.data_dir / opts.database_file);
    std::vector<store::Migration> v1 = ProgramStore::Migrations();
    v1.resize(1);
    ASSERT_EQ(store::Migrate(db, v1), 1);
    std::string sha = Sha256Hex(kGear);
    store::Statement blob = db.Prepare("INSERT INTO blobs VALUES (?, ?, ?)");
    blob.BindText(1, sha)
        .BindInt64(2, static_cast<std::int64_t>(std::string(kGear).size()))
        .BindBlob(3, kGear)
        .Run();
    db.Exec(
        "INSERT INTO files(id, node, name, head, protected, created_at) VALUES (1, 'HOST', 'OLD', 1, 1, "
        "'x')");
    store::Statement rev = db.Prepare(
        "INSERT INTO revisions VALUES (1, 1, ?, ?, 6, 'part_program', 'ktapl', 1, 'OLD', '[\"12\"]', 840, "
        "'[]', "
        "'[]', '2026-01-01T00:00:00.000Z')");
    rev.BindText(1, sha).BindInt64(2, static_cast<std::int64_t>(std::string(kGear).size())).Run();
  }
  ProgramStore ps(opts);
  {
    store::Database db = store::Database::Open(ps.database_path());
    EXPECT_EQ(store::SchemaVersion(db), static_cast<int>(ProgramStore::Migrations().size()));
    EXPECT_EQ(db.QueryInt64("SELECT count(*) FROM sqlite_master WHERE name = 'revisions_by_sha256'"), 1);
  }
  GetResult g = ps.Get("HOST", "OLD");
  EXPECT_EQ(g.content, kGear);
  EXPECT_TRUE(g.file.is_protected);
  EXPECT_THAT(g.file.metadata.utl, ElementsAre("12"));
  EXPECT_EQ(ps.Put(Req("HOST", "NEW", kGear)).file.revision, 1u);
}

// --- crash safety ---------------------------------------------------------------------------------------

// A child process puts programs (some large, some new revisions) as fast as it can and reports each put on a
// pipe only after Put() returned. It is SIGKILLed at an arbitrary moment. After reopening, every reported put
// is present with its content intact, the database is sound, and nothing half-written is visible.
void RunCrashRound(const fs::path& dir, int round, std::chrono::milliseconds kill_after) {
  int fds[2];
  ASSERT_EQ(pipe(fds), 0);
  pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    close(fds[0]);
    try {
      ProgramStore ps(Options(dir));
      for (int i = 0;; ++i) {
        std::string name = fmt::format("R{}P{}", round, i % 40);
        std::string content =
            BigProgram(i % 7 == 0 ? 300000 : 2000 + static_cast<std::size_t>(i), 'a' + i % 26);
        if (i % 11 == 5) {
          // A chunked put now and then, killed half way some of the time.
          std::string stream = fmt::format("r{}s{}", round, i);
          ps.BeginPut(stream, Req("KT01", name, "", true));
          for (std::size_t off = 0, k = 0; off < content.size(); off += 4096, ++k) {
            ps.PutChunk(stream, static_cast<std::uint32_t>(k), std::string_view(content).substr(off, 4096));
          }
          PutResult r = ps.CommitPut(stream);
          std::string line = fmt::format("KT01\t{}\t{}\t{}\n", name, r.file.revision, r.file.sha256);
          if (write(fds[1], line.data(), line.size()) != static_cast<ssize_t>(line.size())) _exit(3);
          continue;
        }
        PutResult r = ps.Put(Req("HOST", name, content, /*force=*/true));
        std::string line = fmt::format("HOST\t{}\t{}\t{}\n", name, r.file.revision, r.file.sha256);
        if (write(fds[1], line.data(), line.size()) != static_cast<ssize_t>(line.size())) _exit(3);
      }
    } catch (const std::exception& e) {
      std::fprintf(stderr, "child: %s\n", e.what());
      _exit(2);
    }
  }
  close(fds[1]);
  // Let the child get going (first acknowledgement), then kill it after `kill_after`, whatever it is doing.
  std::string acks;
  char buf[4096];
  while (acks.find('\n') == std::string::npos) {
    ssize_t n = read(fds[0], buf, sizeof buf);
    if (n <= 0) break;
    acks.append(buf, static_cast<std::size_t>(n));
  }
  std::this_thread::sleep_for(kill_after);
  ASSERT_EQ(kill(pid, SIGKILL), 0);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFSIGNALED(status)) << "child exited early with " << WEXITSTATUS(status);
  for (ssize_t n; (n = read(fds[0], buf, sizeof buf)) > 0;) acks.append(buf, static_cast<std::size_t>(n));
  close(fds[0]);

  ProgramStore ps(Options(dir));
  EXPECT_EQ(ps.OpenStreams(), 0u);
  EXPECT_EQ(StagedFiles(ps.database_path()), 0);
  {
    store::Database db = store::Database::Open(ps.database_path());
    EXPECT_EQ(db.IntegrityCheck(), "ok");
    EXPECT_EQ(db.QueryInt64("PRAGMA foreign_key_check"), 0);
  }
  // Every acknowledged revision is there, intact.
  std::map<std::pair<std::string, std::string>, std::uint32_t> last_ack;
  int count = 0;
  std::size_t pos = 0;
  while (pos < acks.size()) {
    std::size_t end = acks.find('\n', pos);
    if (end == std::string::npos) break;  // a torn last line was never fully acknowledged
    std::string line = acks.substr(pos, end - pos);
    pos = end + 1;
    std::vector<std::string> f;
    for (std::size_t s = 0, t; (t = line.find('\t', s)) != std::string::npos || s <= line.size(); s = t + 1) {
      if (t == std::string::npos) t = line.size();
      f.push_back(line.substr(s, t - s));
      if (t == line.size()) break;
    }
    ASSERT_EQ(f.size(), 4u) << line;
    auto rev = static_cast<std::uint32_t>(std::stoul(f[2]));
    GetResult g = ps.Get(f[0], f[1], rev);
    EXPECT_EQ(g.file.sha256, f[3]);
    EXPECT_EQ(Sha256Hex(g.content), f[3]);
    last_ack[{f[0], f[1]}] = rev;
    ++count;
  }
  EXPECT_GT(count, 0) << "the child acknowledged nothing before it was killed";
  // At most one put beyond the acknowledged ones is visible (committed, killed before the ack), and every
  // visible revision of every file is intact.
  int unacked = 0;
  for (const char* node : {"HOST", "KT01"}) {
    for (const FileInfo& f : ps.List(node, fmt::format("R{}P*", round))) {
      auto it = last_ack.find({node, f.name});
      std::uint32_t acked = it == last_ack.end() ? 0 : it->second;
      EXPECT_GE(f.head_revision, acked);
      unacked += static_cast<int>(f.head_revision - acked);
      for (const RevisionInfo& r : ps.Show(node, f.name).revisions) {
        GetResult g = ps.Get(node, f.name, r.revision);
        EXPECT_EQ(Sha256Hex(g.content), r.sha256) << node << "/" << f.name << " r" << r.revision;
      }
    }
  }
  EXPECT_LE(unacked, 1);
  std::printf(
      "round %d: killed after %lld ms, %d acknowledged puts verified, %d committed but unacknowledged\n",
      round, static_cast<long long>(kill_after.count()), count, unacked);
}

TEST(CrashSafety, KilledClientLosesNoAcknowledgedPut) {
  TempDir tmp;
  int round = 0;
  for (int ms : {0, 7, 150, 400, 900}) {
    SCOPED_TRACE(fmt::format("killed after {} ms", ms));
    RunCrashRound(tmp.path(), round++, std::chrono::milliseconds(ms));
    if (HasFatalFailure()) return;
  }
}

}  // namespace
}  // namespace cell::program_store
