#include "cell/program_store/client.h"

#include <algorithm>
#include <random>

#include <fmt/format.h>

#include "cell/bus/topics.h"

namespace cell::program_store {

namespace {
std::string NewStreamId() {
  std::random_device rd;
  return fmt::format("{:08x}{:08x}{:08x}", rd(), rd(), rd());
}
nlohmann::json Info(const cell::ProgramReply& r) {
  std::string s = r.info().to_string();
  return s.empty() ? nlohmann::json::object() : nlohmann::json::parse(s, nullptr, false);
}
}  // namespace

void CheckWireName(const std::string& node, const std::string& name) {
  if (node.size() > 16)
    throw Error(Errc::kInvalidArgument, "namespace '" + node + "' is longer than 16 characters");
  if (name.size() > 128) throw Error(Errc::kInvalidArgument, "name is longer than 128 characters: " + name);
}

Client::Client(bus::Participant& p, bus::Millis timeout)
    : client_(p, bus::topics::kProgramStore), timeout_(timeout) {}

cell::ProgramReply Client::Call(cell::ProgramRequest req) {
  cell::ProgramReply r = client_.Call(std::move(req), timeout_);
  bus::ThrowIfError(r);
  return r;
}

nlohmann::json Client::Put(const std::string& name, const std::string& content, const PutOptions& o) {
  CheckWireName(o.node, name);
  cell::ProgramRequest req;
  req.node(o.node);
  req.name(name);
  req.force(o.force);
  req.dialect(o.dialect);
  req.file_type(o.file_type);
  req.hdr().idempotency_key(o.idempotency_key);
  if (content.size() <= kChunkBytes) {
    req.op(cell::PROGRAM_PUT);
    req.data().assign(content.begin(), content.end());
    return Info(Call(req));
  }
  // Large files stream in chunks; the store commits atomically on the last one.
  req.op(cell::PROGRAM_PUT_CHUNK);
  req.stream_id(NewStreamId());
  size_t n = (content.size() + kChunkBytes - 1) / kChunkBytes;
  cell::ProgramReply last;
  for (size_t i = 0; i < n; ++i) {
    size_t off = i * kChunkBytes, len = std::min(kChunkBytes, content.size() - off);
    req.chunk_index(static_cast<uint32_t>(i));
    req.last_chunk(i + 1 == n);
    req.data().assign(content.begin() + static_cast<long>(off),
                      content.begin() + static_cast<long>(off + len));
    last = Call(req);
  }
  return Info(last);
}

std::optional<std::string> Client::Get(const std::string& node, const std::string& name, uint32_t revision) {
  auto f = Fetch(node, name, revision);
  if (!f) return std::nullopt;
  return std::move(f->content);
}

std::optional<Client::File> Client::Fetch(const std::string& node, const std::string& name,
                                          uint32_t revision) {
  CheckWireName(node, name);
  cell::ProgramRequest req;
  req.op(cell::PROGRAM_GET);
  req.node(node);
  req.name(name);
  req.revision(revision);
  File out;
  uint32_t count = 1;
  for (uint32_t i = 0; i < count; ++i) {
    req.chunk_index(i);
    cell::ProgramReply r;
    try {
      r = Call(req);
    } catch (const Error& e) {
      if (e.code() == Errc::kNotFound) return std::nullopt;
      throw;
    }
    count = r.chunk_count();
    req.revision(r.revision());  // every chunk from the same revision
    out.content.append(r.data().begin(), r.data().end());
    if (i == 0) out.info = Info(r);
  }
  return out;
}

std::optional<std::string> Client::GetWithFallback(const std::string& node, const std::string& name) {
  auto f = FetchWithFallback(node, name);
  if (!f) return std::nullopt;
  return std::move(f->content);
}

std::optional<Client::File> Client::FetchWithFallback(const std::string& node, const std::string& name) {
  if (node != "HOST") {
    try {
      if (auto f = Fetch(node, name)) return f;
    } catch (const Error& e) {
      if (e.code() != Errc::kNotFound && e.code() != Errc::kInvalidArgument) throw;
    }
  }
  return Fetch("HOST", name);
}

nlohmann::json Client::Show(const std::string& node, const std::string& name) {
  CheckWireName(node, name);
  cell::ProgramRequest req;
  req.op(cell::PROGRAM_SHOW);
  req.node(node);
  req.name(name);
  return Info(Call(req));
}

nlohmann::json Client::List(const std::string& node, const std::string& pattern) {
  CheckWireName(node, pattern);
  cell::ProgramRequest req;
  req.op(cell::PROGRAM_LIST);
  req.node(node);
  req.name(pattern);
  // Paged: the service answers page chunk_index of chunk_count (a reply is bounded to 64 KiB).
  nlohmann::json all = nlohmann::json::array();
  uint32_t pages = 1;
  for (uint32_t i = 0; i < pages; ++i) {
    req.chunk_index(i);
    cell::ProgramReply r = Call(req);
    pages = std::max<uint32_t>(1, r.chunk_count());
    nlohmann::json page = Info(r);
    if (!page.is_array()) throw Error(Errc::kInternal, "program store sent a malformed listing");
    for (auto& e : page) all.push_back(std::move(e));
  }
  return all;
}

nlohmann::json Client::Copy(const std::string& from_node, const std::string& from, const std::string& to_node,
                            const std::string& to, bool force, const std::string& key) {
  CheckWireName(from_node, from);
  CheckWireName(to_node, to);
  cell::ProgramRequest req;
  req.op(cell::PROGRAM_COPY);
  req.node(from_node);
  req.name(from);
  req.to_node(to_node);
  req.to_name(to);
  req.force(force);
  req.hdr().idempotency_key(key);
  return Info(Call(req));
}

nlohmann::json Client::Rename(const std::string& from_node, const std::string& from,
                              const std::string& to_node, const std::string& to, const std::string& key) {
  CheckWireName(from_node, from);
  CheckWireName(to_node, to);
  cell::ProgramRequest req;
  req.op(cell::PROGRAM_RENAME);
  req.node(from_node);
  req.name(from);
  req.to_node(to_node);
  req.to_name(to);
  req.hdr().idempotency_key(key);
  return Info(Call(req));
}

nlohmann::json Client::Delete(const std::string& node, const std::string& name, const std::string& key) {
  CheckWireName(node, name);
  cell::ProgramRequest req;
  req.op(cell::PROGRAM_DELETE);
  req.node(node);
  req.name(name);
  req.hdr().idempotency_key(key);
  return Info(Call(req));
}

nlohmann::json Client::Protect(const std::string& node, const std::string& name, bool on) {
  CheckWireName(node, name);
  cell::ProgramRequest req;
  req.op(on ? cell::PROGRAM_PROTECT : cell::PROGRAM_UNPROTECT);
  req.node(node);
  req.name(name);
  return Info(Call(req));
}

}  // namespace cell::program_store
