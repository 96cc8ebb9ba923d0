#include "cell/program_store/service.h"

#include <spdlog/spdlog.h>

#include "cell/bus/topics.h"
#include "cell/program_store/client.h"

namespace cell::program_store {

nlohmann::json FileJson(const FileInfo& f) {
  const Metadata& m = f.metadata;
  nlohmann::json j = {{"name", f.name},
                      {"node", f.node},
                      {"type", std::string(FileTypeName(m.type))},
                      {"dialect", std::string(DialectName(m.dialect))},
                      {"revision", f.revision},
                      {"head_revision", f.head_revision},
                      {"size", m.size},
                      {"lines", m.lines},
                      {"protected", f.is_protected},
                      {"selected", f.is_selected},
                      {"hidden", f.is_hidden},
                      {"sha256", f.sha256},
                      {"created_at", f.created_at},
                      {"dialect_detected", m.dialect_detected},
                      {"warnings", m.warnings}};
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

constexpr size_t kListPageBytes = 60000;  // below the 65,536 bound of ProgramReply::info

void SetInfo(cell::ProgramReply& rep, const nlohmann::json& j) {
  std::string s = j.dump();
  if (s.size() > 65536)
    throw Error(Errc::kFailedPrecondition,
                "reply too large (" + std::to_string(s.size()) + " bytes); narrow the pattern");
  rep.info(s);
}

}  // namespace

Service::Service(bus::Participant& p, ProgramStore& store, std::chrono::seconds stream_idle)
    : store_(store),
      stream_idle_(stream_idle),
      changes_(p, bus::topics::kProgramChange, bus::QosKind::kEvent),
      server_(p, bus::topics::kProgramStore, [this](const cell::ProgramRequest& r) { return Handle(r); }) {
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
  });
}

void Service::Housekeeping() {
  std::lock_guard lk(mu_);
  size_t n = store_.ExpireStreams(stream_idle_);
  if (n) spdlog::warn("dropped {} abandoned upload stream(s)", n);
}

cell::ProgramReply Service::Handle(const cell::ProgramRequest& r) {
  std::lock_guard lk(mu_);
  cell::ProgramReply rep;
  const std::string node = r.node().to_string(), name = r.name().to_string();
  const std::string key = r.hdr().idempotency_key().to_string();
  switch (r.op()) {
    case cell::PROGRAM_PUT: {
      PutRequest p = PutFrom(r);
      p.content.assign(r.data().begin(), r.data().end());
      PutResult res = store_.Put(p);
      rep.revision(res.file.revision);
      SetInfo(rep, FileJson(res.file));
      break;
    }
    case cell::PROGRAM_PUT_CHUNK: {
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
      break;
    }
    case cell::PROGRAM_GET: {
      // Chunk i of a large file: the content is read once per revision, not once per chunk.
      if (r.chunk_index() == 0 || cache_.node != node || cache_.name != name ||
          cache_.revision != r.revision()) {
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
      break;
    }
    case cell::PROGRAM_SHOW: {
      ShowResult s = store_.Show(node, name, r.revision());
      nlohmann::json j = FileJson(s.file);
      j["revisions"] = nlohmann::json::array();
      for (auto& rv : s.revisions)
        j["revisions"].push_back({{"revision", rv.revision},
                                  {"sha256", rv.sha256},
                                  {"size", rv.size},
                                  {"created_at", rv.created_at}});
      rep.revision(s.file.revision);
      SetInfo(rep, j);
      break;
    }
    case cell::PROGRAM_LIST: {
      // A listing is paged: page chunk_index of chunk_count, each at most kListPageBytes of JSON, so a
      // namespace of any size can be listed (one reply's info is bounded to 64 KiB).
      std::vector<std::string> rows;
      for (auto& f : store_.List(node, name.empty() ? "*" : name)) {
        nlohmann::json j = FileJson(f);
        rows.push_back(nlohmann::json{
            {"name", j["name"]},
            {"node", j["node"]},
            {"type", j["type"]},
            {"dialect", j["dialect"]},
            {"revision", j["revision"]},
            {"size", j["size"]},
            {"protected", j["protected"]},
            {"selected", j["selected"]},
            {"hidden",
             j["hidden"]}}.dump());
      }
      std::vector<size_t> page_start = {0};
      size_t bytes = 2;
      for (size_t i = 0; i < rows.size(); ++i) {
        if (bytes + rows[i].size() + 1 > kListPageBytes && i > page_start.back()) {
          page_start.push_back(i);
          bytes = 2;
        }
        bytes += rows[i].size() + 1;
      }
      if (r.chunk_index() >= page_start.size())
        throw Error(Errc::kInvalidArgument,
                    "listing page " + std::to_string(r.chunk_index()) + " past the end");
      size_t begin = page_start[r.chunk_index()];
      size_t end = r.chunk_index() + 1 < page_start.size() ? page_start[r.chunk_index() + 1] : rows.size();
      std::string page = "[";
      for (size_t i = begin; i < end; ++i) page += (i > begin ? "," : "") + rows[i];
      page += "]";
      rep.info(page);
      rep.chunk_index(r.chunk_index());
      rep.chunk_count(static_cast<uint32_t>(page_start.size()));
      break;
    }
    case cell::PROGRAM_COPY: {
      CopyRequest c;
      c.from_node = node;
      c.from_name = name;
      c.from_revision = r.revision();
      c.to_node = r.to_node().to_string();
      c.to_name = r.to_name().to_string();
      c.force = r.force();
      c.idempotency_key = key;
      PutResult res = store_.Copy(c);
      rep.revision(res.file.revision);
      SetInfo(rep, FileJson(res.file));
      break;
    }
    case cell::PROGRAM_RENAME: {
      RenameRequest m;
      m.node = node;
      m.name = name;
      m.to_node = r.to_node().to_string();
      m.to_name = r.to_name().to_string();
      m.idempotency_key = key;
      OpResult res = store_.Rename(m);
      SetInfo(rep, FileJson(res.file));
      break;
    }
    case cell::PROGRAM_DELETE: {
      OpResult res = store_.Delete(node, name, key);
      SetInfo(rep, FileJson(res.file));
      break;
    }
    case cell::PROGRAM_PROTECT:
    case cell::PROGRAM_UNPROTECT: {
      // PROTECT/UNPROTECT set and clear one flag: to_name names it ("" or "protected", "selected" for a
      // Balt-System SPG/REL, "hidden" for ATT HIDDEN), so the memory commands need no new op on the wire.
      const std::string flag = r.to_name().to_string();
      FileFlag f = FileFlag::kProtected;
      if (flag == "selected") {
        f = FileFlag::kSelected;
      } else if (flag == "hidden") {
        f = FileFlag::kHidden;
      } else if (!flag.empty() && flag != "protected") {
        throw Error(Errc::kInvalidArgument, "unknown file flag '" + flag + "' (protected, selected, hidden)");
      }
      OpResult res = store_.SetFlag(node, name, f, r.op() == cell::PROGRAM_PROTECT, key);
      SetInfo(rep, FileJson(res.file));
      break;
    }
  }
  return rep;
}

}  // namespace cell::program_store
