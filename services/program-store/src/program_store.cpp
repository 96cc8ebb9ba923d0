#include "cell/program_store/program_store.h"

#include <fmt/format.h>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <nlohmann/json.hpp>

#include "cell/error/error.h"
#include "cell/program_store/sha256.h"

namespace cell::program_store {

namespace fs = std::filesystem;
using nlohmann::json;
using store::Database;
using store::Statement;
using store::Transaction;

namespace {

constexpr const char* kNow = "strftime('%Y-%m-%dT%H:%M:%fZ','now')";

// ---------------------------------------------------------------------------------------------------------
// Schema history. Each step moves version n-1 -> n; never edit a released step, add one.

constexpr const char* kSchemaV1 = R"sql(
CREATE TABLE blobs(
  sha256 TEXT PRIMARY KEY,
  size INTEGER NOT NULL,
  data BLOB NOT NULL);
CREATE TABLE files(
  id INTEGER PRIMARY KEY,
  node TEXT NOT NULL,
  name TEXT NOT NULL,
  head INTEGER NOT NULL,
  protected INTEGER NOT NULL DEFAULT 0,
  created_at TEXT NOT NULL,
  UNIQUE(node, name));
CREATE TABLE revisions(
  file_id INTEGER NOT NULL REFERENCES files(id) ON DELETE CASCADE,
  rev INTEGER NOT NULL,
  sha256 TEXT NOT NULL REFERENCES blobs(sha256),
  size INTEGER NOT NULL,
  lines INTEGER NOT NULL,
  type TEXT NOT NULL,
  dialect TEXT NOT NULL,
  dialect_detected INTEGER NOT NULL,
  nam TEXT NOT NULL,
  utl TEXT NOT NULL,
  ucy REAL,
  program_names TEXT NOT NULL,
  warnings TEXT NOT NULL,
  created_at TEXT NOT NULL,
  PRIMARY KEY(file_id, rev));
CREATE TABLE events(
  seq INTEGER PRIMARY KEY AUTOINCREMENT,
  kind TEXT NOT NULL,
  node TEXT NOT NULL,
  name TEXT NOT NULL,
  rev INTEGER NOT NULL,
  at TEXT NOT NULL);
CREATE TABLE idempotency(
  key TEXT PRIMARY KEY,
  fingerprint TEXT NOT NULL,
  result TEXT NOT NULL,
  created_unix INTEGER NOT NULL);
)sql";

constexpr const char* kSchemaV2 = R"sql(
CREATE INDEX revisions_by_sha256 ON revisions(sha256);
CREATE INDEX idempotency_by_age ON idempotency(created_unix);
)sql";

[[noreturn]] void Fail(Errc code, const std::string& what) {
  throw cell::Error(code, what);
}

std::string Quote(std::string_view node, std::string_view name) {
  return fmt::format("'{}' in {}", name, node);
}

json ToJson(const Metadata& md) {
  json j = {{"type", FileTypeName(md.type)},
            {"dialect", DialectName(md.dialect)},
            {"dialect_detected", md.dialect_detected},
            {"nam", md.nam},
            {"utl", md.utl},
            {"program_names", md.program_names},
            {"size", md.size},
            {"lines", md.lines},
            {"warnings", md.warnings}};
  j["ucy"] = md.ucy_s ? json(*md.ucy_s) : json(nullptr);
  return j;
}

Metadata MetadataFromJson(const json& j) {
  Metadata md;
  md.type = ParseFileType(j.at("type").get<std::string>());
  md.dialect = ParseDialect(j.at("dialect").get<std::string>());
  md.dialect_detected = j.at("dialect_detected").get<bool>();
  md.nam = j.at("nam").get<std::string>();
  md.utl = j.at("utl").get<std::vector<std::string>>();
  md.program_names = j.at("program_names").get<std::vector<std::string>>();
  md.size = j.at("size").get<std::uint64_t>();
  md.lines = j.at("lines").get<std::uint64_t>();
  md.warnings = j.at("warnings").get<std::vector<std::string>>();
  if (!j.at("ucy").is_null()) md.ucy_s = j.at("ucy").get<double>();
  return md;
}

json ToJson(const FileInfo& f) {
  return {{"node", f.node},
          {"name", f.name},
          {"revision", f.revision},
          {"head_revision", f.head_revision},
          {"sha256", f.sha256},
          {"protected", f.is_protected},
          {"selected", f.is_selected},
          {"hidden", f.is_hidden},
          {"created_at", f.created_at},
          {"metadata", ToJson(f.metadata)}};
}

FileInfo FileInfoFromJson(const json& j) {
  FileInfo f;
  f.node = j.at("node").get<std::string>();
  f.name = j.at("name").get<std::string>();
  f.revision = j.at("revision").get<std::uint32_t>();
  f.head_revision = j.at("head_revision").get<std::uint32_t>();
  f.sha256 = j.at("sha256").get<std::string>();
  f.is_protected = j.at("protected").get<bool>();
  f.is_selected = j.value("selected", false);  // results stored before the flags existed lack them
  f.is_hidden = j.value("hidden", false);
  f.created_at = j.at("created_at").get<std::string>();
  f.metadata = MetadataFromJson(j.at("metadata"));
  return f;
}

ChangeEvent::Kind ParseKind(std::string_view s) {
  if (s == "created") return ChangeEvent::Kind::kCreated;
  if (s == "updated") return ChangeEvent::Kind::kUpdated;
  return ChangeEvent::Kind::kDeleted;
}

json ToJson(const std::vector<ChangeEvent>& events) {
  json a = json::array();
  for (const ChangeEvent& e : events) {
    a.push_back({{"seq", e.seq},
                 {"kind", ChangeKindName(e.kind)},
                 {"node", e.node},
                 {"name", e.name},
                 {"revision", e.revision}});
  }
  return a;
}

std::vector<ChangeEvent> EventsFromJson(const json& a) {
  std::vector<ChangeEvent> events;
  for (const json& j : a) {
    events.push_back({j.at("seq").get<std::uint64_t>(), ParseKind(j.at("kind").get<std::string>()),
                      j.at("node").get<std::string>(), j.at("name").get<std::string>(),
                      j.at("revision").get<std::uint32_t>()});
  }
  return events;
}

json HeaderToJson(const PutRequest& r) {
  json j = {{"node", r.node}, {"name", r.name}, {"force", r.force}, {"idempotency_key", r.idempotency_key}};
  j["dialect"] = r.dialect ? json(DialectName(*r.dialect)) : json(nullptr);
  j["type"] = r.type ? json(FileTypeName(*r.type)) : json(nullptr);
  return j;
}

std::int64_t UnixNow() {
  return std::chrono::duration_cast<std::chrono::seconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

constexpr const char* kFileColumns =
    "f.node, f.name, r.rev, f.head, r.sha256, f.protected, r.created_at, r.size, r.lines, r.type, r.dialect, "
    "r.dialect_detected, r.nam, r.utl, r.ucy, r.program_names, r.warnings, f.id";

FileInfo ReadFileInfo(const Statement& st) {
  FileInfo f;
  f.node = st.ColumnText(0);
  f.name = st.ColumnText(1);
  f.revision = static_cast<std::uint32_t>(st.ColumnInt64(2));
  f.head_revision = static_cast<std::uint32_t>(st.ColumnInt64(3));
  f.sha256 = st.ColumnText(4);
  const std::int64_t flags = st.ColumnInt64(5);  // the `protected` column holds the FileFlag bits
  f.is_protected = (flags & static_cast<int>(FileFlag::kProtected)) != 0;
  f.is_selected = (flags & static_cast<int>(FileFlag::kSelected)) != 0;
  f.is_hidden = (flags & static_cast<int>(FileFlag::kHidden)) != 0;
  f.created_at = st.ColumnText(6);
  Metadata& md = f.metadata;
  md.size = static_cast<std::uint64_t>(st.ColumnInt64(7));
  md.lines = static_cast<std::uint64_t>(st.ColumnInt64(8));
  md.type = ParseFileType(st.ColumnText(9));
  md.dialect = ParseDialect(st.ColumnText(10));
  md.dialect_detected = st.ColumnInt64(11) != 0;
  md.nam = st.ColumnText(12);
  md.utl = json::parse(st.ColumnText(13)).get<std::vector<std::string>>();
  if (!st.IsNull(14)) md.ucy_s = st.ColumnDouble(14);
  md.program_names = json::parse(st.ColumnText(15)).get<std::vector<std::string>>();
  md.warnings = json::parse(st.ColumnText(16)).get<std::vector<std::string>>();
  return f;
}

struct Located {
  FileInfo info;
  std::int64_t file_id = 0;
};

// The file (node, name) at `revision` (0 = head), or nullopt.
std::optional<Located> Find(Database& db, std::string_view node, std::string_view name,
                            std::uint32_t revision) {
  Statement st = db.Prepare(fmt::format(
      "SELECT {} FROM files f JOIN revisions r ON r.file_id = f.id AND r.rev = CASE WHEN ?3 = 0 THEN f.head "
      "ELSE ?3 END WHERE f.node = ?1 AND f.name = ?2",
      kFileColumns));
  st.BindText(1, node).BindText(2, name).BindInt64(3, revision);
  if (!st.Step()) return std::nullopt;
  return Located{ReadFileInfo(st), st.ColumnInt64(17)};
}

Located MustFind(Database& db, std::string_view node, std::string_view name, std::uint32_t revision) {
  std::optional<Located> found = Find(db, node, name, revision);
  if (found) return *found;
  if (revision != 0 && Find(db, node, name, 0)) {
    Fail(Errc::kNotFound, fmt::format("{} has no revision {}", Quote(node, name), revision));
  }
  Fail(Errc::kNotFound, fmt::format("no file {}", Quote(node, name)));
}

ChangeEvent RecordEvent(Database& db, ChangeEvent::Kind kind, std::string_view node, std::string_view name,
                        std::uint32_t revision) {
  Statement st =
      db.Prepare(fmt::format("INSERT INTO events(kind, node, name, rev, at) VALUES (?, ?, ?, ?, {})", kNow));
  st.BindText(1, ChangeKindName(kind)).BindText(2, node).BindText(3, name).BindInt64(4, revision).Run();
  return ChangeEvent{static_cast<std::uint64_t>(db.LastInsertRowId()), kind, std::string(node),
                     std::string(name), revision};
}

// Looks up an idempotency key: nullopt when new; the stored result when the fingerprint matches; throws when
// the key was used for a different request.
std::optional<json> Replay(Database& db, std::string_view key, std::string_view fingerprint) {
  if (key.empty()) return std::nullopt;
  Statement st = db.Prepare("SELECT fingerprint, result FROM idempotency WHERE key = ?");
  st.BindText(1, key);
  if (!st.Step()) return std::nullopt;
  if (st.ColumnText(0) != fingerprint) {
    Fail(Errc::kFailedPrecondition,
         fmt::format("idempotency key '{}' was already used for a different request", key));
  }
  return json::parse(st.ColumnText(1));
}

bool KeyUsed(Database& db, std::string_view key) {
  if (key.empty()) return false;
  Statement st = db.Prepare("SELECT 1 FROM idempotency WHERE key = ?");
  st.BindText(1, key);
  return st.Step();
}

void Remember(Database& db, std::string_view key, std::string_view fingerprint, const json& result) {
  if (key.empty()) return;
  Statement st =
      db.Prepare("INSERT INTO idempotency(key, fingerprint, result, created_unix) VALUES (?, ?, ?, ?)");
  st.BindText(1, key).BindText(2, fingerprint).BindText(3, result.dump()).BindInt64(4, UnixNow()).Run();
}

json ToJson(const PutResult& r) {
  return {{"file", ToJson(r.file)}, {"created", r.created}, {"events", ToJson(r.events)}};
}

PutResult PutResultFromJson(const json& j) {
  PutResult r;
  r.file = FileInfoFromJson(j.at("file"));
  r.created = j.at("created").get<bool>();
  r.events = EventsFromJson(j.at("events"));
  r.replayed = true;
  return r;
}

json ToJson(const OpResult& r) {
  return {{"file", ToJson(r.file)}, {"events", ToJson(r.events)}};
}

OpResult OpResultFromJson(const json& j) {
  OpResult r;
  r.file = FileInfoFromJson(j.at("file"));
  r.events = EventsFromJson(j.at("events"));
  r.replayed = true;
  return r;
}

std::string Fingerprint(std::initializer_list<std::string_view> parts) {
  Sha256 h;
  for (std::string_view p : parts) {
    h.Update(p);
    h.Update(std::string_view("\x1f", 1));
  }
  return h.HexDigest();
}

// Inserts a new revision (and the file row when new) of content `sha256` with metadata `md`.
// Returns the new revision number.
std::uint32_t InsertRevision(Database& db, std::optional<Located>& existing, std::string_view node,
                             std::string_view name, std::string_view sha256, const Metadata& md) {
  std::int64_t file_id = 0;
  std::uint32_t rev = 1;
  if (existing) {
    file_id = existing->file_id;
    rev = existing->info.head_revision + 1;
    Statement up = db.Prepare("UPDATE files SET head = ? WHERE id = ?");
    up.BindInt64(1, rev).BindInt64(2, file_id).Run();
  } else {
    Statement ins =
        db.Prepare(fmt::format("INSERT INTO files(node, name, head, created_at) VALUES (?, ?, 1, {})", kNow));
    ins.BindText(1, node).BindText(2, name).Run();
    file_id = db.LastInsertRowId();
  }
  Statement st = db.Prepare(
      fmt::format("INSERT INTO revisions(file_id, rev, sha256, size, lines, type, dialect, dialect_detected, "
                  "nam, utl, ucy, "
                  "program_names, warnings, created_at) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, {})",
                  kNow));
  st.BindInt64(1, file_id)
      .BindInt64(2, rev)
      .BindText(3, sha256)
      .BindInt64(4, static_cast<std::int64_t>(md.size))
      .BindInt64(5, static_cast<std::int64_t>(md.lines))
      .BindText(6, FileTypeName(md.type))
      .BindText(7, DialectName(md.dialect))
      .BindInt64(8, md.dialect_detected ? 1 : 0)
      .BindText(9, md.nam)
      .BindText(10, json(md.utl).dump())
      .BindText(12, json(md.program_names).dump())
      .BindText(13, json(md.warnings).dump());
  if (md.ucy_s) {
    st.BindDouble(11, *md.ucy_s);
  } else {
    st.BindNull(11);
  }
  st.Run();
  return rev;
}

// Deletes blobs no revision refers to any more.
void CollectBlobs(Database& db, const std::vector<std::string>& candidates) {
  Statement st = db.Prepare(
      "DELETE FROM blobs WHERE sha256 = ?1 AND NOT EXISTS (SELECT 1 FROM revisions WHERE sha256 = ?1)");
  for (const std::string& sha : candidates) {
    st.BindText(1, sha).Run();
    st.Reset();
  }
}

}  // namespace

std::string_view ChangeKindName(ChangeEvent::Kind kind) {
  switch (kind) {
    case ChangeEvent::Kind::kCreated:
      return "created";
    case ChangeEvent::Kind::kUpdated:
      return "updated";
    case ChangeEvent::Kind::kDeleted:
      return "deleted";
  }
  return "updated";
}

bool WildcardMatch(std::string_view pattern, std::string_view name) {
  // Iterative glob with single-star backtracking: O(|pattern| * |name|) worst case.
  std::size_t p = 0, n = 0, star = std::string_view::npos, mark = 0;
  while (n < name.size()) {
    if (p < pattern.size() && (pattern[p] == '?' || pattern[p] == name[n])) {
      ++p;
      ++n;
    } else if (p < pattern.size() && pattern[p] == '*') {
      star = p++;
      mark = n;
    } else if (star != std::string_view::npos) {
      p = star + 1;
      n = ++mark;
    } else {
      return false;
    }
  }
  while (p < pattern.size() && pattern[p] == '*') ++p;
  return p == pattern.size();
}

std::vector<store::Migration> ProgramStore::Migrations() {
  return {store::Migration::Sql(1, "files, revisions, blobs, events, idempotency keys", kSchemaV1),
          store::Migration::Sql(2, "indexes for blob collection and key expiry", kSchemaV2)};
}

// ---------------------------------------------------------------------------------------------------------

ProgramStore::ProgramStore(StoreOptions options) : options_(std::move(options)) {
  if (options_.data_dir.empty()) Fail(Errc::kInvalidArgument, "program store: no data directory given");
  namespaces_.emplace_back(kHostNamespace);
  for (const std::string& ns : options_.namespaces) {
    // A station id, or a station's further memory "ID/MPn" (Balt-System MP0, MP2..MP6).
    const std::string_view id = std::string_view(ns).substr(0, ns.find('/'));
    const std::string_view memory =
        ns.find('/') == std::string::npos ? "" : std::string_view(ns).substr(id.size() + 1);
    const bool good_memory = memory.empty() || (memory.size() == 3 && memory.substr(0, 2) == "MP" &&
                                                memory[2] >= '0' && memory[2] <= '6' && memory[2] != '1');
    if (id.empty() || ns.size() > 16 || !good_memory || !std::all_of(id.begin(), id.end(), [](char c) {
          return std::isalnum(static_cast<unsigned char>(c));
        })) {
      Fail(Errc::kInvalidArgument,
           fmt::format("program store: bad namespace '{}' (1-16 letters and digits, or ID/MP0, ID/MP2..MP6)",
                       ns));
    }
    if (std::find(namespaces_.begin(), namespaces_.end(), ns) == namespaces_.end()) namespaces_.push_back(ns);
  }
  for (const auto& [ns, dialect] : options_.namespace_dialects) {
    if (ns == kHostNamespace || !HasNamespace(ns)) {
      Fail(Errc::kInvalidArgument,
           fmt::format("program store: dialect given for '{}', which is not a configured "
                       "station namespace",
                       ns));
    }
  }
  db_path_ = options_.data_dir / options_.database_file;
  db_ = std::make_unique<Database>(Database::Open(db_path_));
  store::Migrate(*db_, Migrations());
  // Streams belong to the process that received them; they cannot complete after a restart.
  streams_dir_ = options_.data_dir / "program-store-streams";
  std::error_code ec;
  fs::remove_all(streams_dir_, ec);
  fs::create_directories(streams_dir_, ec);
  if (ec) Fail(Errc::kIo, fmt::format("cannot create {}: {}", streams_dir_.string(), ec.message()));
  Transaction tx(*db_);
  Statement old = db_->Prepare("DELETE FROM idempotency WHERE created_unix < ?");
  old.BindInt64(1, UnixNow() - options_.idempotency_retention.count()).Run();
  db_->Exec("DELETE FROM events WHERE seq <= (SELECT max(seq) FROM events) - 100000");
  tx.Commit();
}

ProgramStore::~ProgramStore() = default;

Dialect ProgramStore::NamespaceDialect(std::string_view node) const {
  auto it = options_.namespace_dialects.find(std::string(node));
  return it == options_.namespace_dialects.end() ? nullptr : it->second;
}

bool ProgramStore::HasNamespace(std::string_view node) const {
  return std::find(namespaces_.begin(), namespaces_.end(), node) != namespaces_.end();
}

bool ProgramStore::IsMemory(std::string_view node) const {
  if (node.find('/') != std::string_view::npos) return true;  // "ID/MPn": only Balt-System stations have them
  const Dialect d = NamespaceDialect(node);
  return d && d->name() == "balt";
}

namespace {

// A Balt-System memory holds kMemoryCapacity characters (ln 223): storing `size` characters as `name` in
// `node` (replacing its head, if any) must leave it within that, else FILMS3 15 "the specified destination
// device is full" (ln 9758-9759) and nothing is stored. HOST and other stations' namespaces are not bounded.
void CheckMemoryRoom(const ProgramStore& store, Database& db, const std::string& node,
                     const std::string& name, std::uint64_t size) {
  if (!store.IsMemory(node)) return;
  Statement st = db.Prepare(
      "SELECT coalesce(sum(r.size), 0) FROM files f JOIN revisions r ON r.file_id = f.id AND r.rev = f.head "
      "WHERE f.node = ? AND f.name <> ?");
  st.BindText(1, node).BindText(2, name);
  const std::uint64_t others = st.Step() ? static_cast<std::uint64_t>(st.ColumnInt64(0)) : 0;
  if (others + size > kMemoryCapacity) {
    Fail(Errc::kFailedPrecondition, fmt::format("{}: {} would hold {} characters, {} at most (ln 223)",
                                                kNoFreeSectors, node, others + size, kMemoryCapacity));
  }
}

void RequireNamespace(const ProgramStore& store, std::string_view node) {
  if (node.empty()) Fail(Errc::kInvalidArgument, "no namespace given");
  if (!store.HasNamespace(node)) {
    std::string known;
    for (const std::string& ns : store.namespaces()) known += (known.empty() ? "" : ", ") + ns;
    Fail(Errc::kNotFound, fmt::format("unknown namespace '{}' (configured: {})", node, known));
  }
}

// What may not change: a protected file (ATT, `program protect`) and a program selected for execution (SPG).
void RefuseLocked(const FileInfo& f) {
  if (f.is_protected)
    Fail(Errc::kPermissionDenied, fmt::format("{} is protected; unprotect it first", Quote(f.node, f.name)));
  if (f.is_selected) {
    Fail(Errc::kPermissionDenied,
         fmt::format("{} is selected for execution (SPG); release it (REL) first", Quote(f.node, f.name)));
  }
}

}  // namespace

std::string_view FileFlagName(FileFlag flag) {
  switch (flag) {
    case FileFlag::kProtected:
      return "protected";
    case FileFlag::kSelected:
      return "selected";
    case FileFlag::kHidden:
      return "hidden";
  }
  return "?";
}

struct ProgramStore::Impl {
  // The put path shared by Put and CommitPut; runs inside the caller's transaction.
  static PutResult DoPut(ProgramStore& self, const PutRequest& req, std::string_view content,
                         const std::vector<std::string>& keys) {
    Database& db = *self.db_;
    RequireNamespace(self, req.node);
    if (req.name.empty()) Fail(Errc::kInvalidArgument, "empty file name");
    if (content.size() > self.options_.max_file_size) {
      Fail(Errc::kInvalidArgument, fmt::format("file is too large: {} bytes, at most {}", content.size(),
                                               self.options_.max_file_size));
    }
    std::string sha = Sha256Hex(content);
    std::string fp = Fingerprint({"put", req.node, req.name, sha, req.force ? "force" : "",
                                  req.dialect ? DialectName(*req.dialect) : "?",
                                  req.type ? FileTypeName(*req.type) : "?"});
    for (const std::string& key : keys) {
      if (std::optional<json> previous = Replay(db, key, fp)) return PutResultFromJson(*previous);
    }
    ExtractOptions extract;
    extract.dialect = req.dialect;
    extract.type = req.type;
    extract.name = req.name;
    extract.namespace_dialect = self.NamespaceDialect(req.node);
    Metadata md = ExtractMetadata(content, extract);
    ValidateName(req.name, md.type, md.dialect);
    std::optional<Located> existing = Find(db, req.node, req.name, 0);
    if (existing) {
      RefuseLocked(existing->info);
      if (!req.force) {
        Fail(Errc::kAlreadyExists,
             fmt::format("{} already exists (revision {}); use --force to store a new revision",
                         Quote(req.node, req.name), existing->info.head_revision));
      }
    }
    CheckMemoryRoom(self, db, req.node, req.name, content.size());
    Statement blob = db.Prepare("INSERT OR IGNORE INTO blobs(sha256, size, data) VALUES (?, ?, ?)");
    blob.BindText(1, sha).BindInt64(2, static_cast<std::int64_t>(content.size())).BindBlob(3, content).Run();
    std::uint32_t rev = InsertRevision(db, existing, req.node, req.name, sha, md);
    PutResult result;
    result.created = !existing;
    result.file = MustFind(db, req.node, req.name, rev).info;
    result.events.push_back(RecordEvent(
        db, existing ? ChangeEvent::Kind::kUpdated : ChangeEvent::Kind::kCreated, req.node, req.name, rev));
    json stored = ToJson(result);
    for (const std::string& key : keys) Remember(db, key, fp, stored);
    return result;
  }
};

void ProgramStore::Publish(const std::vector<ChangeEvent>& events) {
  std::function<void(const ChangeEvent&)> listener;
  {
    std::lock_guard lock(mutex_);
    listener = listener_;
  }
  if (!listener) return;
  for (const ChangeEvent& e : events) listener(e);
}

void ProgramStore::SetChangeListener(std::function<void(const ChangeEvent&)> listener) {
  std::lock_guard lock(mutex_);
  listener_ = std::move(listener);
}

PutResult ProgramStore::Put(const PutRequest& request) {
  PutResult result;
  {
    std::lock_guard lock(mutex_);
    Transaction tx(*db_);
    std::vector<std::string> keys;
    if (!request.idempotency_key.empty()) keys.push_back(request.idempotency_key);
    result = Impl::DoPut(*this, request, request.content, keys);
    tx.Commit();
  }
  if (!result.replayed) Publish(result.events);
  return result;
}

GetResult ProgramStore::Get(std::string_view node, std::string_view name, std::uint32_t revision) {
  std::lock_guard lock(mutex_);
  RequireNamespace(*this, node);
  Transaction tx(*db_, Transaction::Mode::kDeferred);  // one consistent snapshot
  GetResult result;
  result.file = MustFind(*db_, node, name, revision).info;
  Statement st = db_->Prepare("SELECT data FROM blobs WHERE sha256 = ?");
  st.BindText(1, result.file.sha256);
  if (!st.Step()) Fail(Errc::kInternal, fmt::format("content {} of {} is missing", result.file.sha256, name));
  result.content = st.ColumnBlob(0);
  tx.Commit();
  return result;
}

ShowResult ProgramStore::Show(std::string_view node, std::string_view name, std::uint32_t revision) {
  std::lock_guard lock(mutex_);
  RequireNamespace(*this, node);
  Transaction tx(*db_, Transaction::Mode::kDeferred);
  ShowResult result;
  Located found = MustFind(*db_, node, name, revision);
  result.file = found.info;
  Statement st =
      db_->Prepare("SELECT rev, sha256, size, created_at FROM revisions WHERE file_id = ? ORDER BY rev");
  st.BindInt64(1, found.file_id);
  while (st.Step()) {
    result.revisions.push_back({static_cast<std::uint32_t>(st.ColumnInt64(0)), st.ColumnText(1),
                                static_cast<std::uint64_t>(st.ColumnInt64(2)), st.ColumnText(3)});
  }
  tx.Commit();
  return result;
}

std::vector<FileInfo> ProgramStore::List(std::string_view node, std::string_view pattern) {
  std::vector<FileInfo> out;
  List(node, pattern, "", [&](const FileInfo& f) {
    out.push_back(f);
    return true;
  });
  return out;
}

void ProgramStore::List(std::string_view node, std::string_view pattern, std::string_view after,
                        const std::function<bool(const FileInfo&)>& visit) {
  std::lock_guard lock(mutex_);
  RequireNamespace(*this, node);
  if (pattern.empty()) pattern = "*";
  // SQLite's default BINARY collation orders names by their bytes, as std::string compares them.
  Statement st = db_->Prepare(fmt::format(
      "SELECT {} FROM files f JOIN revisions r ON r.file_id = f.id AND r.rev = f.head WHERE f.node = ? "
      "AND f.name > ? ORDER BY f.name",
      kFileColumns));
  st.BindText(1, node);
  st.BindText(2, after);
  while (st.Step()) {
    if (WildcardMatch(pattern, st.ColumnText(1)) && !visit(ReadFileInfo(st))) return;
  }
}

std::optional<FileInfo> ProgramStore::Info(std::string_view node, std::string_view name) {
  std::lock_guard lock(mutex_);
  RequireNamespace(*this, node);
  std::optional<Located> found = Find(*db_, node, name, 0);
  if (!found) return std::nullopt;
  return std::move(found->info);
}

std::size_t ProgramStore::Count(std::string_view node) {
  std::lock_guard lock(mutex_);
  RequireNamespace(*this, node);
  Statement st = db_->Prepare("SELECT count(*) FROM files WHERE node = ?");
  st.BindText(1, node);
  return st.Step() ? static_cast<std::size_t>(st.ColumnInt64(0)) : 0;
}

PutResult ProgramStore::Copy(const CopyRequest& request) {
  PutResult result;
  {
    std::lock_guard lock(mutex_);
    Database& db = *db_;
    RequireNamespace(*this, request.from_node);
    RequireNamespace(*this, request.to_node);
    const std::string to_name = request.to_name.empty() ? request.from_name : request.to_name;
    Transaction tx(db);
    std::string fp =
        Fingerprint({"copy", request.from_node, request.from_name, std::to_string(request.from_revision),
                     request.to_node, to_name, request.force ? "force" : ""});
    if (std::optional<json> previous = Replay(db, request.idempotency_key, fp))
      return PutResultFromJson(*previous);
    if (request.from_node == request.to_node && request.from_name == to_name) {
      Fail(Errc::kInvalidArgument, fmt::format("copy of {} onto itself", Quote(request.from_node, to_name)));
    }
    Located source = MustFind(db, request.from_node, request.from_name, request.from_revision);
    Metadata md = source.info.metadata;
    ValidateName(to_name, md.type, md.dialect);
    std::optional<Located> existing = Find(db, request.to_node, to_name, 0);
    if (existing) {
      RefuseLocked(existing->info);
      if (!request.force) {
        Fail(Errc::kAlreadyExists,
             fmt::format("{} already exists (revision {}); use --force to store a new revision",
                         Quote(request.to_node, to_name), existing->info.head_revision));
      }
    }
    CheckMemoryRoom(*this, db, request.to_node, to_name, source.info.metadata.size);
    std::uint32_t rev = InsertRevision(db, existing, request.to_node, to_name, source.info.sha256, md);
    result.created = !existing;
    result.file = MustFind(db, request.to_node, to_name, rev).info;
    result.events.push_back(RecordEvent(db,
                                        existing ? ChangeEvent::Kind::kUpdated : ChangeEvent::Kind::kCreated,
                                        request.to_node, to_name, rev));
    Remember(db, request.idempotency_key, fp, ToJson(result));
    tx.Commit();
  }
  Publish(result.events);
  return result;
}

OpResult ProgramStore::Rename(const RenameRequest& request) {
  OpResult result;
  {
    std::lock_guard lock(mutex_);
    Database& db = *db_;
    const std::string to_node = request.to_node.empty() ? request.node : request.to_node;
    const std::string to_name = request.to_name.empty() ? request.name : request.to_name;
    RequireNamespace(*this, request.node);
    RequireNamespace(*this, to_node);
    Transaction tx(db);
    std::string fp = Fingerprint({"rename", request.node, request.name, to_node, to_name});
    if (std::optional<json> previous = Replay(db, request.idempotency_key, fp))
      return OpResultFromJson(*previous);
    if (request.node == to_node && request.name == to_name) {
      Fail(Errc::kInvalidArgument, fmt::format("rename of {} onto itself", Quote(to_node, to_name)));
    }
    Located source = MustFind(db, request.node, request.name, 0);
    RefuseLocked(source.info);
    ValidateName(to_name, source.info.metadata.type, source.info.metadata.dialect);
    if (Find(db, to_node, to_name, 0)) {
      Fail(Errc::kAlreadyExists, fmt::format("{} already exists; remove it first (rename never overwrites)",
                                             Quote(to_node, to_name)));
    }
    if (to_node != request.node) CheckMemoryRoom(*this, db, to_node, to_name, source.info.metadata.size);
    Statement up = db.Prepare("UPDATE files SET node = ?, name = ? WHERE id = ?");
    up.BindText(1, to_node).BindText(2, to_name).BindInt64(3, source.file_id).Run();
    std::uint32_t head = source.info.head_revision;
    result.events.push_back(RecordEvent(db, ChangeEvent::Kind::kDeleted, request.node, request.name, head));
    result.events.push_back(RecordEvent(db, ChangeEvent::Kind::kCreated, to_node, to_name, head));
    result.file = MustFind(db, to_node, to_name, 0).info;
    Remember(db, request.idempotency_key, fp, ToJson(result));
    tx.Commit();
  }
  Publish(result.events);
  return result;
}

OpResult ProgramStore::Delete(std::string_view node, std::string_view name,
                              std::string_view idempotency_key) {
  OpResult result;
  {
    std::lock_guard lock(mutex_);
    Database& db = *db_;
    RequireNamespace(*this, node);
    Transaction tx(db);
    std::string fp = Fingerprint({"delete", node, name});
    if (std::optional<json> previous = Replay(db, idempotency_key, fp)) return OpResultFromJson(*previous);
    Located found = MustFind(db, node, name, 0);
    RefuseLocked(found.info);
    std::vector<std::string> hashes;
    Statement h = db.Prepare("SELECT DISTINCT sha256 FROM revisions WHERE file_id = ?");
    h.BindInt64(1, found.file_id);
    while (h.Step()) hashes.push_back(h.ColumnText(0));
    Statement revs = db.Prepare("DELETE FROM revisions WHERE file_id = ?");
    revs.BindInt64(1, found.file_id).Run();
    Statement file = db.Prepare("DELETE FROM files WHERE id = ?");
    file.BindInt64(1, found.file_id).Run();
    CollectBlobs(db, hashes);
    result.file = found.info;
    result.events.push_back(
        RecordEvent(db, ChangeEvent::Kind::kDeleted, node, name, found.info.head_revision));
    Remember(db, idempotency_key, fp, ToJson(result));
    tx.Commit();
  }
  Publish(result.events);
  return result;
}

OpResult ProgramStore::SetProtected(std::string_view node, std::string_view name, bool is_protected,
                                    std::string_view idempotency_key) {
  return SetFlag(node, name, FileFlag::kProtected, is_protected, idempotency_key);
}

OpResult ProgramStore::SetFlag(std::string_view node, std::string_view name, FileFlag flag, bool on,
                               std::string_view idempotency_key) {
  OpResult result;
  {
    std::lock_guard lock(mutex_);
    Database& db = *db_;
    RequireNamespace(*this, node);
    Transaction tx(db);
    // The protect fingerprint is the one older stored keys carry.
    std::string fp = flag == FileFlag::kProtected
                         ? Fingerprint({on ? "protect" : "unprotect", node, name})
                         : Fingerprint({on ? "flag" : "unflag", FileFlagName(flag), node, name});
    if (std::optional<json> previous = Replay(db, idempotency_key, fp)) return OpResultFromJson(*previous);
    Located found = MustFind(db, node, name, 0);
    const std::int64_t bits = (found.info.is_protected ? static_cast<int>(FileFlag::kProtected) : 0) |
                              (found.info.is_selected ? static_cast<int>(FileFlag::kSelected) : 0) |
                              (found.info.is_hidden ? static_cast<int>(FileFlag::kHidden) : 0);
    const std::int64_t want = on ? bits | static_cast<int>(flag) : bits & ~static_cast<std::int64_t>(flag);
    if (want != bits) {
      Statement up = db.Prepare("UPDATE files SET protected = ? WHERE id = ?");
      up.BindInt64(1, want).BindInt64(2, found.file_id).Run();
      result.events.push_back(
          RecordEvent(db, ChangeEvent::Kind::kUpdated, node, name, found.info.head_revision));
    }
    result.file = MustFind(db, node, name, 0).info;
    Remember(db, idempotency_key, fp, ToJson(result));
    tx.Commit();
  }
  Publish(result.events);
  return result;
}

// ---------------------------------------------------------------------------------------------------------
// Chunked puts

struct ProgramStore::Stream {
  PutRequest header;
  std::string header_json;
  std::uint32_t next_index = 0;
  std::uint64_t bytes = 0;
  std::string last_chunk_sha256;
  std::chrono::steady_clock::time_point last_activity;
  fs::path file;
  int fd = -1;

  ~Stream() {
    if (fd >= 0) ::close(fd);
    std::error_code ec;
    fs::remove(file, ec);
  }
};

void ProgramStore::BeginPut(const std::string& stream_id, const PutRequest& header) {
  std::lock_guard lock(mutex_);
  Database& db = *db_;
  if (stream_id.empty() || stream_id.size() > 64) {
    Fail(Errc::kInvalidArgument, "stream id must be 1-64 characters");
  }
  if (!header.content.empty())
    Fail(Errc::kInvalidArgument, "BeginPut takes the content in chunks, not inline");
  std::string header_json = HeaderToJson(header).dump();
  if (auto it = streams_.find(stream_id); it != streams_.end()) {
    if (it->second->header_json == header_json) return;  // a retried BeginPut
    Fail(Errc::kAlreadyExists, fmt::format("stream '{}' is already open for another put", stream_id));
  }
  RequireNamespace(*this, header.node);
  if (header.name.empty()) Fail(Errc::kInvalidArgument, "empty file name");
  // Check the name now when its rules are already known (declared or implied by the extension).
  std::optional<FileType> type = header.type ? header.type : TypeFromName(header.name);
  if (header.dialect || (type && OwnerOf(*type) != nullptr)) {
    ValidateName(header.name, type.value_or(FileType::kPartProgram), header.dialect.value_or(nullptr));
  }
  {
    Transaction tx(db, Transaction::Mode::kDeferred);
    std::optional<Located> existing = Find(db, header.node, header.name, 0);
    if (existing) RefuseLocked(existing->info);
    // A put retried under its idempotency key finds its own file: the commit replays the first result (or
    // refuses a different request under the key), so "already exists" must not stop it here (issue 39 item 4:
    // puts over one chunk failed the second time).
    if (existing && !header.force && !KeyUsed(db, header.idempotency_key)) {
      Fail(Errc::kAlreadyExists,
           fmt::format("{} already exists (revision {}); use --force to store a new revision",
                       Quote(header.node, header.name), existing->info.head_revision));
    }
    tx.Commit();
  }
  if (streams_.size() >= options_.max_open_streams) {
    Fail(Errc::kUnavailable, fmt::format("too many open chunk streams ({})", streams_.size()));
  }
  auto stream = std::make_unique<Stream>();
  stream->header = header;
  stream->header_json = std::move(header_json);
  stream->last_activity = std::chrono::steady_clock::now();
  stream->file = streams_dir_ / (Sha256Hex(stream_id) + ".part");
  stream->fd = ::open(stream->file.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (stream->fd < 0) {
    Fail(Errc::kIo, fmt::format("cannot create {}: {}", stream->file.string(), std::strerror(errno)));
  }
  streams_.emplace(stream_id, std::move(stream));
}

void ProgramStore::PutChunk(const std::string& stream_id, std::uint32_t index, std::string_view data) {
  std::lock_guard lock(mutex_);
  auto it = streams_.find(stream_id);
  if (it == streams_.end()) {
    Fail(Errc::kNotFound,
         fmt::format("no open stream '{}' (never begun, finished, abandoned or expired)", stream_id));
  }
  Stream& s = *it->second;
  auto abandon = [&](Errc code, const std::string& why) {
    streams_.erase(it);
    Fail(code, fmt::format("stream '{}' abandoned: {}", stream_id, why));
  };
  if (s.next_index > 0 && index == s.next_index - 1) {
    if (Sha256Hex(data) == s.last_chunk_sha256) return;  // a retried chunk
    abandon(Errc::kFailedPrecondition, fmt::format("chunk {} sent again with different bytes", index));
  }
  if (index != s.next_index) {
    abandon(Errc::kFailedPrecondition,
            fmt::format("chunk {} out of order, expected {}", index, s.next_index));
  }
  if (data.size() > options_.max_chunk_size) {
    abandon(Errc::kInvalidArgument,
            fmt::format("chunk {} is {} bytes, at most {}", index, data.size(), options_.max_chunk_size));
  }
  if (s.bytes + data.size() > options_.max_file_size) {
    abandon(Errc::kInvalidArgument,
            fmt::format("file is too large: more than {} bytes", options_.max_file_size));
  }
  for (std::size_t done = 0; done < data.size();) {
    ssize_t n = ::write(s.fd, data.data() + done, data.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) abandon(Errc::kIo, fmt::format("cannot write {}: {}", s.file.string(), std::strerror(errno)));
    done += static_cast<std::size_t>(n);
  }
  s.bytes += data.size();
  s.last_chunk_sha256 = Sha256Hex(data);
  s.next_index = index + 1;
  s.last_activity = std::chrono::steady_clock::now();
}

PutResult ProgramStore::CommitPut(const std::string& stream_id) {
  PutResult result;
  {
    std::lock_guard lock(mutex_);
    Database& db = *db_;
    const std::string stream_key = "stream:" + stream_id;
    auto it = streams_.find(stream_id);
    if (it == streams_.end()) {
      // A retried commit of a stream that already committed returns the first result.
      Statement done = db.Prepare("SELECT result FROM idempotency WHERE key = ?");
      done.BindText(1, stream_key);
      if (done.Step()) return PutResultFromJson(json::parse(done.ColumnText(0)));
      Fail(Errc::kNotFound,
           fmt::format("no open stream '{}' (never begun, abandoned or expired)", stream_id));
    }
    // Whatever happens now, the stream is finished: on failure nothing of it is stored.
    std::unique_ptr<Stream> stream = std::move(it->second);
    streams_.erase(it);
    // Read back through the descriptor kept open since BeginPut (not by path), so the content is exactly what
    // this process wrote even if the scratch folder was meddled with.
    std::string content(stream->bytes, '\0');
    std::size_t got = 0;
    while (got < content.size()) {
      ssize_t n = ::pread(stream->fd, content.data() + got, content.size() - got, static_cast<off_t>(got));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;
      got += static_cast<std::size_t>(n);
    }
    if (got != content.size()) {
      Fail(Errc::kIo,
           fmt::format("stream '{}' staging file is short: {} of {} bytes", stream_id, got, content.size()));
    }
    std::vector<std::string> keys = {stream_key};
    if (!stream->header.idempotency_key.empty()) keys.push_back(stream->header.idempotency_key);
    Transaction tx(db);
    result = Impl::DoPut(*this, stream->header, content, keys);
    tx.Commit();
  }
  if (!result.replayed) Publish(result.events);
  return result;
}

void ProgramStore::AbortPut(const std::string& stream_id) {
  std::lock_guard lock(mutex_);
  streams_.erase(stream_id);
}

std::size_t ProgramStore::ExpireStreams(std::chrono::seconds max_idle) {
  std::lock_guard lock(mutex_);
  auto deadline = std::chrono::steady_clock::now() - max_idle;
  std::size_t dropped = 0;
  for (auto it = streams_.begin(); it != streams_.end();) {
    if (it->second->last_activity <= deadline) {
      it = streams_.erase(it);
      ++dropped;
    } else {
      ++it;
    }
  }
  return dropped;
}

std::size_t ProgramStore::OpenStreams() {
  std::lock_guard lock(mutex_);
  return streams_.size();
}

std::vector<ChangeEvent> ProgramStore::EventsSince(std::uint64_t after_seq, std::size_t limit) {
  std::lock_guard lock(mutex_);
  Statement st =
      db_->Prepare("SELECT seq, kind, node, name, rev FROM events WHERE seq > ? ORDER BY seq LIMIT ?");
  st.BindInt64(1, static_cast<std::int64_t>(after_seq)).BindInt64(2, static_cast<std::int64_t>(limit));
  std::vector<ChangeEvent> out;
  while (st.Step()) {
    out.push_back({static_cast<std::uint64_t>(st.ColumnInt64(0)), ParseKind(st.ColumnText(1)),
                   st.ColumnText(2), st.ColumnText(3), static_cast<std::uint32_t>(st.ColumnInt64(4))});
  }
  return out;
}

}  // namespace cell::program_store
