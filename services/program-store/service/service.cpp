#include "cell/program_store/service.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "cell/bus/topics.h"
#include "cell/program_store/client.h"
#include "cell/records/entries.h"
#include "cell/records/page.h"

namespace cell::program_store {

namespace {
records::ProgramEntry Entry(const FileInfo& f) {
  return {f.name,
          f.node,
          std::string(FileTypeName(f.metadata.type)),
          std::string(DialectName(f.metadata.dialect)),
          f.revision,
          f.metadata.size,
          f.is_protected,
          f.is_selected,
          f.is_hidden};
}
}  // namespace

// `program show`: the `program ls` row and the rest of what the store knows.
nlohmann::json FileJson(const FileInfo& f) {
  const Metadata& m = f.metadata;
  nlohmann::json j = records::ProgramRow(Entry(f));
  j["head_revision"] = f.head_revision;
  j["lines"] = m.lines;
  j["sha256"] = f.sha256;
  j["created_at"] = f.created_at;
  j["dialect_detected"] = m.dialect_detected;
  j["warnings"] = m.warnings;
  if (!m.nam.empty()) j["nam"] = m.nam;
  if (!m.utl.empty()) j["utl"] = m.utl;
  if (m.ucy_s) j["ucy_s"] = *m.ucy_s;
  if (!m.program_names.empty()) j["program_names"] = m.program_names;
  return j;
}

namespace {

PutRequest PutFrom(const cell::ProgramRequest& r) {
  PutRequest p;
  p.node = r.node().to_string();
  p.name = r.name().to_string();
  if (!r.dialect().to_string().empty()) p.dialect = ParseDialect(r.dialect().to_string());
  if (!r.file_type().to_string().empty()) p.type = ParseFileType(r.file_type().to_string());
  p.force = r.force();
  p.idempotency_key = r.hdr().idempotency_key().to_string();
  return p;
}

void SetInfo(cell::ProgramReply& rep, const nlohmann::json& j) {
  std::string s = j.dump();
  if (s.size() > 65536)
    throw Error(Errc::kFailedPrecondition,
                "reply too large (" + std::to_string(s.size()) + " bytes); narrow the pattern");
  rep.info(s);
}

// The namespaces a request changes; none for a query.
std::vector<std::string> Changes(const cell::ProgramRequest& r) {
  const std::string node = r.node().to_string(), to = r.to_node().to_string();
  switch (r.op()) {
    case cell::PROGRAM_PUT:
    case cell::PROGRAM_PUT_CHUNK:
    case cell::PROGRAM_DELETE:
    case cell::PROGRAM_PROTECT:
    case cell::PROGRAM_UNPROTECT:
      return {node};
    case cell::PROGRAM_COPY:
      return {to.empty() ? node : to};
    case cell::PROGRAM_RENAME:
      return {node, to.empty() ? node : to};
    default:
      return {};
  }
}

const char* OpName(cell::ProgramOp op) {
  switch (op) {
    case cell::PROGRAM_PUT:
    case cell::PROGRAM_PUT_CHUNK:
      return "put";
    case cell::PROGRAM_COPY:
      return "copy";
    case cell::PROGRAM_RENAME:
      return "rename";
    case cell::PROGRAM_DELETE:
      return "delete";
    case cell::PROGRAM_PROTECT:
      return "protect";
    case cell::PROGRAM_UNPROTECT:
      return "unprotect";
    default:
      return "query";
  }
}

// The audit trail names what changed (a chunked put once, at its last chunk).
std::string Describe(const cell::ProgramRequest& r) {
  if (Changes(r).empty() || (r.op() == cell::PROGRAM_PUT_CHUNK && !r.last_chunk())) return {};
  std::string what =
      fmt::format("program {} {}:{}", OpName(r.op()), r.node().to_string(), r.name().to_string());
  if (r.op() == cell::PROGRAM_COPY || r.op() == cell::PROGRAM_RENAME)
    what += fmt::format(" -> {}:{}", r.to_node().size() == 0 ? r.node().to_string() : r.to_node().to_string(),
                        r.to_name().to_string());
  return what;
}

// A station's interpreter stores its own files (USF, probe results) in its namespace and its memories
// (Balt-System BS01/MP3), and reads any namespace. Elsewhere it may only send HOST a data or inspection file
// (KT-APL RCP TO HOST, ln 8316-8356): it changes no other station's namespace and no program in HOST
// (docs/security.md: the store checks the sender's identity).
void CheckRequester(const cell::ProgramRequest& r) {
  const std::string& who = bus::RequesterIdentity();
  const std::string own = bus::StationOfIdentity(who);
  if (own.empty()) return;
  const std::string type = r.file_type().to_string();
  const bool sends_host_a_file = (r.op() == cell::PROGRAM_PUT || r.op() == cell::PROGRAM_PUT_CHUNK) &&
                                 (type == "data" || type == "inspection");
  for (const auto& node : Changes(r)) {
    if (bus::StationOwns(own, node) || (node == "HOST" && sends_host_a_file)) continue;
    throw Error(Errc::kPermissionDenied,
                fmt::format("identity '{}' may change namespace {} only (and send HOST data or inspection "
                            "files), not {} in {}",
                            who, own, OpName(r.op()), node));
  }
}

cell::ProgramEntry PresentEntry(const FileInfo& f) {
  cell::ProgramEntry e;
  e.node(f.node);
  e.name(f.name);
  e.present(true);
  e.info(FileJson(f).dump());
  return e;
}

}  // namespace

Service::Service(bus::Participant& p, ProgramStore& store, std::chrono::seconds stream_idle)
    : store_(store),
      stream_idle_(stream_idle),
      changes_(p, bus::topics::kProgramChange, bus::QosKind::kEvent),
      list_(p, bus::topics::kProgramList, bus::QosKind::kState),
      server_(
          p, bus::topics::kProgramStore, [this](const cell::ProgramRequest& r) { return Handle(r); },
          Describe) {
  store_.SetChangeListener([this](const ChangeEvent& e) {
    cell::ProgramChange c;
    c.seq(e.seq);
    c.kind(e.kind == ChangeEvent::Kind::kCreated   ? cell::CHANGE_CREATED
           : e.kind == ChangeEvent::Kind::kUpdated ? cell::CHANGE_UPDATED
                                                   : cell::CHANGE_DELETED);
    c.node(e.node);
    c.name(e.name);
    c.revision(e.revision);
    // A cached GET stream of a file that just changed must not serve stale chunks (a name deleted and
    // put again restarts at revision 1 with other bytes). The listener runs inside Handle, under mu_.
    if (e.node == cache_.node && e.name == cache_.name) cache_ = {};
    changes_.Write(c);
    spdlog::info("{} {}:{} revision {}", ChangeKindName(e.kind), e.node, e.name, e.revision);
    pending_.emplace_back(e.node, e.name);  // the listener may not call back into the store: Handle lists
  });
  std::lock_guard lk(mu_);
  std::vector<std::string> nodes{std::string(kHostNamespace)};
  for (const auto& n : store_.namespaces())
    if (n != kHostNamespace) nodes.push_back(n);
  for (const auto& node : nodes) {
    const std::vector<FileInfo> files = store_.List(node);
    for (const auto& f : files) WriteEntry(PresentEntry(f));
    WriteSummary(node, files.size());
  }
}

// cell/program/list (ProgramEntry): what a viewer sees of the store. One file changed or gone: its entry and
// its namespace's count, read as such (listing the whole namespace on every change cost a copy of every
// file's metadata per put, issue 39). A list that cannot be published (a namespace past the topic's 4096
// instances) is a warning, never a failed request.
void Service::PublishEntry(const std::string& node, const std::string& name) {
  if (std::optional<FileInfo> f = store_.Info(node, name)) {
    WriteEntry(PresentEntry(*f));
  } else {
    cell::ProgramEntry e;  // deleted (or moved away)
    e.node(node);
    e.name(name);
    e.present(false);
    WriteEntry(e);
  }
  WriteSummary(node, store_.Count(node));
}

void Service::WriteSummary(const std::string& node, size_t files) {
  cell::ProgramEntry e;
  e.node(node);
  e.present(true);
  e.info(nlohmann::json{{"files", files}}.dump());
  WriteEntry(e);
}

void Service::WriteEntry(const cell::ProgramEntry& e) {
  try {
    list_.Write(e);
  } catch (const Error& err) {
    spdlog::warn("{}: {}:{} not published: {}", bus::topics::kProgramList, e.node().to_string(),
                 e.name().to_string(), err.what());
  }
}

void Service::Housekeeping() {
  std::lock_guard lk(mu_);
  size_t n = store_.ExpireStreams(stream_idle_);
  if (n) spdlog::warn("dropped {} abandoned upload stream(s)", n);
}

cell::ProgramReply Service::Handle(const cell::ProgramRequest& r) {
  CheckRequester(r);
  std::lock_guard lk(mu_);
  cell::ProgramReply rep;
  switch (r.op()) {
    case cell::PROGRAM_PUT:
      rep = Put(r);
      break;
    case cell::PROGRAM_PUT_CHUNK:
      rep = PutChunk(r);
      break;
    case cell::PROGRAM_GET:
      rep = Get(r);
      break;
    case cell::PROGRAM_SHOW:
      rep = Show(r);
      break;
    case cell::PROGRAM_LIST:
      rep = List(r);
      break;
    case cell::PROGRAM_COPY:
      rep = Copy(r);
      break;
    case cell::PROGRAM_RENAME:
      rep = Rename(r);
      break;
    case cell::PROGRAM_DELETE:
      rep = Delete(r);
      break;
    case cell::PROGRAM_PROTECT:
    case cell::PROGRAM_UNPROTECT:
      rep = SetFlag(r);
      break;
  }
  for (const auto& [n, m] : std::exchange(pending_, {})) PublishEntry(n, m);
  return rep;
}

cell::ProgramReply Service::Put(const cell::ProgramRequest& r) {
  cell::ProgramReply rep;
  PutRequest p = PutFrom(r);
  p.content.assign(r.data().begin(), r.data().end());
  PutResult res = store_.Put(p);
  rep.revision(res.file.revision);
  SetInfo(rep, FileJson(res.file));
  return rep;
}

cell::ProgramReply Service::PutChunk(const cell::ProgramRequest& r) {
  cell::ProgramReply rep;
  const std::string sid = r.stream_id().to_string();
  if (r.chunk_index() == 0) store_.BeginPut(sid, PutFrom(r));
  store_.PutChunk(sid, r.chunk_index(),
                  std::string_view(reinterpret_cast<const char*>(r.data().data()), r.data().size()));
  if (r.last_chunk()) {
    PutResult res = store_.CommitPut(sid);
    rep.revision(res.file.revision);
    SetInfo(rep, FileJson(res.file));
  }
  rep.chunk_index(r.chunk_index());
  return rep;
}

cell::ProgramReply Service::Get(const cell::ProgramRequest& r) {
  cell::ProgramReply rep;
  const std::string node = r.node().to_string(), name = r.name().to_string();
  // Chunk i of a large file: the content is read once per revision, not once per chunk.
  if (r.chunk_index() == 0 || cache_.node != node || cache_.name != name || cache_.revision != r.revision()) {
    GetResult g = store_.Get(node, name, r.revision());
    cache_ = {node, name, g.file.revision, std::move(g.content), FileJson(g.file)};
  }
  size_t n = std::max<size_t>(1, (cache_.content.size() + kChunkBytes - 1) / kChunkBytes);
  if (r.chunk_index() >= n) throw Error(Errc::kInvalidArgument, "chunk index past the end of " + name);
  size_t off = r.chunk_index() * kChunkBytes, len = std::min(kChunkBytes, cache_.content.size() - off);
  rep.data().assign(cache_.content.begin() + static_cast<long>(off),
                    cache_.content.begin() + static_cast<long>(off + len));
  rep.revision(cache_.revision);
  rep.chunk_index(r.chunk_index());
  rep.chunk_count(static_cast<uint32_t>(n));
  if (r.chunk_index() == 0) SetInfo(rep, cache_.info);  // what the file is: its dialect, type, heading
  if (r.chunk_index() + 1 == n) cache_ = {};            // do not hold up to 256 MiB between gets
  return rep;
}

cell::ProgramReply Service::Show(const cell::ProgramRequest& r) {
  cell::ProgramReply rep;
  ShowResult s = store_.Show(r.node().to_string(), r.name().to_string(), r.revision());
  nlohmann::json j = FileJson(s.file);
  j["revisions"] = nlohmann::json::array();
  for (auto& rv : s.revisions)
    j["revisions"].push_back(
        {{"revision", rv.revision}, {"sha256", rv.sha256}, {"size", rv.size}, {"created_at", rv.created_at}});
  rep.revision(s.file.revision);
  SetInfo(rep, j);
  return rep;
}

// `program ls`: one page of the namespace by name after the request's cursor, within the reply's bound
// (records::PageBuilder), so a namespace of any size can be listed.
cell::ProgramReply Service::List(const cell::ProgramRequest& r) {
  cell::ProgramReply rep;
  records::PageBuilder page(r.page().limit());
  store_.List(r.node().to_string(), r.name().to_string(), r.page().after().to_string(),
              [&](const FileInfo& f) { return page.Add(records::ProgramRow(Entry(f))); });
  rep.info(page.Text());
  rep.more(page.more());
  return rep;
}

cell::ProgramReply Service::Copy(const cell::ProgramRequest& r) {
  cell::ProgramReply rep;
  CopyRequest c;
  c.from_node = r.node().to_string();
  c.from_name = r.name().to_string();
  c.from_revision = r.revision();
  c.to_node = r.to_node().to_string();
  c.to_name = r.to_name().to_string();
  c.force = r.force();
  c.idempotency_key = r.hdr().idempotency_key().to_string();
  PutResult res = store_.Copy(c);
  rep.revision(res.file.revision);
  SetInfo(rep, FileJson(res.file));
  return rep;
}

cell::ProgramReply Service::Rename(const cell::ProgramRequest& r) {
  cell::ProgramReply rep;
  RenameRequest m;
  m.node = r.node().to_string();
  m.name = r.name().to_string();
  m.to_node = r.to_node().to_string();
  m.to_name = r.to_name().to_string();
  m.idempotency_key = r.hdr().idempotency_key().to_string();
  OpResult res = store_.Rename(m);
  SetInfo(rep, FileJson(res.file));
  return rep;
}

cell::ProgramReply Service::Delete(const cell::ProgramRequest& r) {
  cell::ProgramReply rep;
  OpResult res =
      store_.Delete(r.node().to_string(), r.name().to_string(), r.hdr().idempotency_key().to_string());
  SetInfo(rep, FileJson(res.file));
  return rep;
}

// PROTECT/UNPROTECT set and clear one flag: to_name names it ("" or "protected", "selected" for a Balt-System
// SPG/REL, "hidden" for ATT HIDDEN), so the memory commands need no new op on the wire.
cell::ProgramReply Service::SetFlag(const cell::ProgramRequest& r) {
  cell::ProgramReply rep;
  const std::string node = r.node().to_string(), name = r.name().to_string();
  const std::string flag = r.to_name().to_string();
  FileFlag f = FileFlag::kProtected;
  if (flag == "selected") {
    f = FileFlag::kSelected;
  } else if (flag == "hidden") {
    f = FileFlag::kHidden;
  } else if (!flag.empty() && flag != "protected") {
    throw Error(Errc::kInvalidArgument, "unknown file flag '" + flag + "' (protected, selected, hidden)");
  }
  OpResult res =
      store_.SetFlag(node, name, f, r.op() == cell::PROGRAM_PROTECT, r.hdr().idempotency_key().to_string());
  SetInfo(rep, FileJson(res.file));
  pending_.emplace_back(node, name);  // a flag is no change event, but the list shows it
  return rep;
}

}  // namespace cell::program_store
