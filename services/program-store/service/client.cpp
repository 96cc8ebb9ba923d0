#include "cell/program_store/client.h"

#include <algorithm>
#include <chrono>
#include <map>
#include <optional>
#include <random>

#include <fmt/format.h>

#include "cell/bus/topics.h"
#include "cell/names/names.h"
#include "cell/program_store/program_store.h"
#include "cell/records/page.h"

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
// Namespace and name of a request, through the one guarded assignment (a longer value is an error, never
// cut).
void Address(cell::ProgramRequest& req, const std::string& node, const std::string& name) {
  names::Assign(req.node(), node, "namespace");
  names::Assign(req.name(), name, "program name");
}
void Target(cell::ProgramRequest& req, const std::string& node, const std::string& name) {
  names::Assign(req.to_node(), node, "namespace");
  names::Assign(req.to_name(), name, "program name");
}

}  // namespace

Client::Client(bus::Participant& p, bus::Millis timeout)
    : client_(p, bus::topics::kProgramStore), timeout_(timeout) {}

cell::ProgramReply Client::Call(cell::ProgramRequest req) {
  cell::ProgramReply r = client_.Call(std::move(req), timeout_);
  bus::ThrowIfError(r);
  return r;
}

nlohmann::json Client::Put(const std::string& name, const std::string& content, const PutOptions& o) {
  cell::ProgramRequest req;
  Address(req, o.node, name);
  req.force(o.force);
  names::Assign(req.dialect(), o.dialect, "dialect");
  names::Assign(req.file_type(), o.file_type, "file type");
  names::Assign(req.hdr().idempotency_key(), o.idempotency_key, "idempotency key");
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
  cell::ProgramRequest req;
  req.op(cell::PROGRAM_GET);
  Address(req, node, name);
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
  cell::ProgramRequest req;
  req.op(cell::PROGRAM_SHOW);
  Address(req, node, name);
  return Info(Call(req));
}

nlohmann::json Client::List(const std::string& node, const std::string& pattern, std::uint32_t limit,
                            const std::string& after) {
  cell::ProgramRequest req;
  req.op(cell::PROGRAM_LIST);
  Address(req, node, pattern);
  return records::CollectPages(limit, after, "name", [&](const std::string& from, std::uint32_t want) {
    names::Assign(req.page().after(), from, "--after");
    req.page().limit(want);
    cell::ProgramReply r = Call(req);
    return records::Page{Info(r), r.more()};
  });
}

nlohmann::json Client::Copy(const std::string& from_node, const std::string& from, const std::string& to_node,
                            const std::string& to, bool force, const std::string& key) {
  cell::ProgramRequest req;
  req.op(cell::PROGRAM_COPY);
  Address(req, from_node, from);
  Target(req, to_node, to);
  req.force(force);
  names::Assign(req.hdr().idempotency_key(), key, "idempotency key");
  return Info(Call(req));
}

nlohmann::json Client::Rename(const std::string& from_node, const std::string& from,
                              const std::string& to_node, const std::string& to, const std::string& key) {
  cell::ProgramRequest req;
  req.op(cell::PROGRAM_RENAME);
  Address(req, from_node, from);
  Target(req, to_node, to);
  names::Assign(req.hdr().idempotency_key(), key, "idempotency key");
  return Info(Call(req));
}

nlohmann::json Client::Delete(const std::string& node, const std::string& name, const std::string& key) {
  cell::ProgramRequest req;
  req.op(cell::PROGRAM_DELETE);
  Address(req, node, name);
  names::Assign(req.hdr().idempotency_key(), key, "idempotency key");
  return Info(Call(req));
}

nlohmann::json Client::Protect(const std::string& node, const std::string& name, bool on) {
  return Flag(node, name, "protected", on);
}

nlohmann::json Client::Flag(const std::string& node, const std::string& name, const std::string& flag,
                            bool on, const std::string& key) {
  cell::ProgramRequest req;
  req.op(on ? cell::PROGRAM_PROTECT : cell::PROGRAM_UNPROTECT);
  Address(req, node, name);
  names::Assign(req.to_name(), flag, "flag");
  names::Assign(req.hdr().idempotency_key(), key, "idempotency key");
  return Info(Call(req));
}

nlohmann::json ListPublished(bus::Participant& p, const std::string& node, const std::string& pattern,
                             bus::Millis timeout) {
  bus::Reader<cell::ProgramEntry> r(p, bus::topics::kProgramList, bus::QosKind::kState);
  std::map<std::string, nlohmann::json> files;
  std::optional<size_t> count;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!count || files.size() != *count) {
    const auto left = std::chrono::duration_cast<bus::Millis>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) break;
    auto e = r.Take(std::min(left, bus::Millis(100)));
    if (!e || e->node() != node) continue;
    const std::string name = e->name().to_string();
    const auto info = nlohmann::json::parse(e->info().to_string(), nullptr, false);
    if (name.empty()) {
      if (info.is_object() && info.contains("files")) count = info["files"].get<size_t>();
    } else if (e->present() && info.is_object()) {
      files[name] = info;
    } else {
      files.erase(name);
    }
  }
  if (!count)
    throw Error(Errc::kUnavailable,
                fmt::format("the program store's list of {} was not heard on {} within {} ms", node,
                            bus::topics::kProgramList, timeout.count()));
  if (files.size() != *count)
    throw Error(Errc::kUnavailable, fmt::format("the program store's list of {} arrived incomplete ({} of {} "
                                                "files within {} ms)",
                                                node, files.size(), *count, timeout.count()));
  nlohmann::json out = nlohmann::json::array();
  for (const auto& [name, info] : files)
    if (pattern.empty() || WildcardMatch(pattern, name)) out.push_back(info);  // "": all, as List
  return out;
}

}  // namespace cell::program_store
