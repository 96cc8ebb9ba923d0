// The program store's storage side (Issue 5): programs and other cell files, per namespace (HOST and one
// per configured station), with revisions, SHA-256 content hashes, metadata, protection, idempotent
// operations, atomic chunked puts and change events. No DDS here: the `cell-program-store` service binds
// this library to the bus.
//
// Durability: one SQLite database (via cell_store, WAL + synchronous=FULL) under the data directory; every
// operation is one transaction, so when a call returns its effect is on disk, and a crash at any moment
// leaves either all of it or none of it. All calls are thread-safe (one internal mutex).
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cell/program_store/metadata.h"
#include "cell/store/sqlite.h"

namespace cell::program_store {

inline constexpr std::string_view kHostNamespace = "HOST";
// The characters one Balt-System memory MP0-MP6 holds: the control's user memory (ln 223, "64,000
// characters"). A put, copy or move that would overfill a memory is refused with the control's FILMS3 15.
inline constexpr std::uint64_t kMemoryCapacity = 64000;
inline constexpr const char* kNoFreeSectors = "[FILMS3 15] NO FREE SECTORS";

struct StoreOptions {
  std::filesystem::path data_dir;  // the database is data_dir / database_file
  std::string database_file = "program-store.db";
  std::vector<std::string> namespaces;  // configured station ids; HOST is always there
  // Optional: each station's dialect (from its config), the fallback when a file's dialect is not declared
  // and cannot be detected (see ExtractOptions::namespace_dialect). Keys must be in `namespaces`.
  std::map<std::string, Dialect> namespace_dialects;
  std::uint64_t max_file_size = 256ull << 20;
  std::uint64_t max_chunk_size = 16ull << 20;
  std::size_t max_open_streams = 64;
  // Idempotency keys older than this are forgotten (at open).
  std::chrono::seconds idempotency_retention = std::chrono::hours(24 * 7);
};

struct ChangeEvent {
  enum class Kind { kCreated, kUpdated, kDeleted };
  std::uint64_t seq = 0;  // store-wide, increasing, durable
  Kind kind = Kind::kCreated;
  std::string node;
  std::string name;
  std::uint32_t revision = 0;  // the new head; for kDeleted the last revision the file had
};
std::string_view ChangeKindName(ChangeEvent::Kind kind);  // "created", "updated", "deleted"

// One file as `program ls` / `program show` report it, at one revision.
struct FileInfo {
  std::string node;
  std::string name;
  std::uint32_t revision = 0;       // the revision described here
  std::uint32_t head_revision = 0;  // the file's latest revision
  std::string sha256;               // of this revision's content
  bool is_protected = false;
  bool is_selected = false;  // selected for execution (Balt-System SPG): cannot be changed or deleted
  bool is_hidden = false;    // Balt-System ATT HIDDEN: a DIR of the memory does not show it
  std::string created_at;    // this revision's time, ISO-8601 UTC
  Metadata metadata;         // type, dialect, NAM/UTL/UCY, program names, size, lines, warnings
};

// A file's flags (kept as bits of the files.protected column). Protected and selected files refuse put,
// delete, rename and being a copy destination; hidden ones are only marked (the memory commands' DIR leaves
// them out).
enum class FileFlag { kProtected = 1, kSelected = 2, kHidden = 4 };
std::string_view FileFlagName(FileFlag flag);  // "protected", "selected", "hidden"

struct RevisionInfo {
  std::uint32_t revision = 0;
  std::string sha256;
  std::uint64_t size = 0;
  std::string created_at;
};

struct PutRequest {
  std::string node = std::string(kHostNamespace);
  std::string name;
  std::string content;             // for BeginPut: empty (the content comes in chunks)
  std::optional<Dialect> dialect;  // declared; detected when absent
  std::optional<FileType> type;    // declared; from name/content when absent
  bool force = false;              // allow a new revision of an existing name
  std::string idempotency_key;     // optional: a retry with the same key returns the first result
};

struct PutResult {
  FileInfo file;
  bool created = false;   // a new name (otherwise a new revision of an existing one)
  bool replayed = false;  // this is the stored result of an earlier call with the same idempotency key
  std::vector<ChangeEvent> events;
  const std::vector<std::string>& warnings() const { return file.metadata.warnings; }
};

struct GetResult {
  FileInfo file;
  std::string content;
};

struct ShowResult {
  FileInfo file;
  std::vector<RevisionInfo> revisions;  // oldest first
};

struct CopyRequest {
  std::string from_node = std::string(kHostNamespace);
  std::string from_name;
  std::uint32_t from_revision = 0;  // 0: latest
  std::string to_node = std::string(kHostNamespace);
  std::string to_name;  // empty: same name
  bool force = false;
  std::string idempotency_key;
};

struct RenameRequest {
  std::string node = std::string(kHostNamespace);
  std::string name;
  std::string to_node;  // empty: same namespace
  std::string to_name;  // empty: same name (a move between namespaces)
  std::string idempotency_key;
};

struct OpResult {
  FileInfo file;  // the file after the operation (for delete: as it was)
  bool replayed = false;
  std::vector<ChangeEvent> events;
};

class ProgramStore {
 public:
  // Opens (creating) the database, migrates its schema, drops staged chunk streams left by a previous
  // process (they can never complete) and expired idempotency keys.
  // Chunk streams are staged in data_dir/program-store-streams/ (unsynced scratch files: a stream is not
  // durable until CommitPut, which is one SQLite transaction).
  explicit ProgramStore(StoreOptions options);
  ~ProgramStore();
  ProgramStore(const ProgramStore&) = delete;
  ProgramStore& operator=(const ProgramStore&) = delete;

  // Stores a new file or (with force) a new revision. Errors (cell::Error): kNotFound unknown namespace;
  // kInvalidArgument bad name / non-text / undetectable dialect / too large; kAlreadyExists exists without
  // force; kPermissionDenied protected; kFailedPrecondition idempotency key reused for another request.
  PutResult Put(const PutRequest& request);

  // revision 0: latest. kNotFound when the file or revision does not exist.
  GetResult Get(std::string_view node, std::string_view name, std::uint32_t revision = 0);
  ShowResult Show(std::string_view node, std::string_view name, std::uint32_t revision = 0);
  // Files whose name matches `pattern` (`*` any run, `?` one character; "" matches all), by name.
  std::vector<FileInfo> List(std::string_view node, std::string_view pattern = "*");
  // The same files after `after` (exclusive, in the byte order of names; "" from the first), one at a time
  // until visit returns false: a page of a large namespace (`program ls --after`) reads only what it shows.
  // visit runs under the store's lock and must not call back into the store.
  void List(std::string_view node, std::string_view pattern, std::string_view after,
            const std::function<bool(const FileInfo&)>& visit);

  // One file at its head revision, or nullopt; and how many files a namespace holds. What a change
  // republishes (one entry and its namespace's count) without listing the namespace.
  std::optional<FileInfo> Info(std::string_view node, std::string_view name);
  std::size_t Count(std::string_view node);

  PutResult Copy(const CopyRequest& request);
  OpResult Rename(const RenameRequest& request);
  OpResult Delete(std::string_view node, std::string_view name, std::string_view idempotency_key = {});
  OpResult SetProtected(std::string_view node, std::string_view name, bool is_protected,
                        std::string_view idempotency_key = {});
  OpResult SetFlag(std::string_view node, std::string_view name, FileFlag flag, bool on,
                   std::string_view idempotency_key = {});

  // Chunked put for large files. BeginPut checks what it can early (namespace, name, protection, force)
  // and stages nothing visible; PutChunk appends chunk `index` (0, 1, 2, ... in order; re-sending the last
  // accepted index with the same bytes is a no-op, for retries); CommitPut stores the whole content
  // atomically exactly like Put and forgets the stream (a retried CommitPut returns the same result);
  // AbortPut forgets it. A failed CommitPut also forgets the stream. Streams do not survive a restart.
  void BeginPut(const std::string& stream_id, const PutRequest& header);
  void PutChunk(const std::string& stream_id, std::uint32_t index, std::string_view data);
  PutResult CommitPut(const std::string& stream_id);
  void AbortPut(const std::string& stream_id);
  // Drops streams with no activity for `max_idle` (steady clock); returns how many.
  std::size_t ExpireStreams(std::chrono::seconds max_idle);
  std::size_t OpenStreams();

  // Durable change log, for (re)publishing after a restart.
  std::vector<ChangeEvent> EventsSince(std::uint64_t after_seq, std::size_t limit = 1000);
  // Called after each committed change (outside the store's lock is NOT guaranteed: keep it short and do not
  // call back into the store).
  void SetChangeListener(std::function<void(const ChangeEvent&)> listener);

  bool HasNamespace(std::string_view node) const;
  Dialect NamespaceDialect(std::string_view node) const;  // nullptr for HOST or when not configured
  // A Balt-System memory (held to kMemoryCapacity): "ID/MPn", or a station namespace of that dialect (MP1).
  bool IsMemory(std::string_view node) const;
  const std::vector<std::string>& namespaces() const { return namespaces_; }
  const std::filesystem::path& database_path() const { return db_path_; }

  // The schema history (v1 ...), for tests and docs.
  static std::vector<store::Migration> Migrations();

 private:
  struct Impl;
  struct Stream;
  void Publish(const std::vector<ChangeEvent>& events);

  StoreOptions options_;
  std::vector<std::string> namespaces_;
  std::filesystem::path db_path_;
  std::mutex mutex_;
  std::unique_ptr<store::Database> db_;
  std::function<void(const ChangeEvent&)> listener_;
  std::filesystem::path streams_dir_;
  std::map<std::string, std::unique_ptr<Stream>> streams_;
};

// True when `name` matches `pattern` with `*` (any run, also empty) and `?` (exactly one character).
bool WildcardMatch(std::string_view pattern, std::string_view name);

}  // namespace cell::program_store
