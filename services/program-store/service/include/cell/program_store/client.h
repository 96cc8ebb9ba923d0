// The program store's public client: what the scheduler, the stations and cellctl call.
// Every call is a bus request/reply; errors come back as cell::Error with the store's reason.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "cell/bus/bus.h"
#include "cell/idl/program_store.h"

namespace cell::program_store {

inline constexpr size_t kChunkBytes = 61440;  // sequence<octet, 61440> in ProgramRequest/Reply

class Client {
 public:
  explicit Client(bus::Participant& p, bus::Millis timeout = bus::Millis(30000));

  struct PutOptions {
    std::string node = "HOST";
    bool force = false;
    std::string dialect;    // empty: detected
    std::string file_type;  // empty: from name and content
    std::string idempotency_key;
  };
  // Stores a new file or (force) a new revision; returns the stored file's JSON (with warnings).
  nlohmann::json Put(const std::string& name, const std::string& content, const PutOptions& o);
  // A stored file: its content and what the store knows of it (FileJson: name, node, type, dialect, ...).
  struct File {
    std::string content;
    nlohmann::json info;
    std::string dialect() const {
      return info.is_object() ? info.value("dialect", std::string()) : std::string();
    }
  };
  // The file, or nullopt when there is no such file in that namespace.
  std::optional<File> Fetch(const std::string& node, const std::string& name, uint32_t revision = 0);
  // The content alone.
  std::optional<std::string> Get(const std::string& node, const std::string& name, uint32_t revision = 0);
  // Looks in `node` first, then HOST (DESIGN §6 schedule lookup, KT-APL library search).
  std::optional<std::string> GetWithFallback(const std::string& node, const std::string& name);
  std::optional<File> FetchWithFallback(const std::string& node, const std::string& name);
  nlohmann::json Show(const std::string& node, const std::string& name);
  // Files by name after `after` (exclusive; "" from the first), at most `limit` (0: all), page by page
  // (records::CollectPages: one reply is bounded to 64 KiB).
  nlohmann::json List(const std::string& node, const std::string& pattern, std::uint32_t limit = 0,
                      const std::string& after = "");
  nlohmann::json Copy(const std::string& from_node, const std::string& from, const std::string& to_node,
                      const std::string& to, bool force, const std::string& key = "");
  nlohmann::json Rename(const std::string& from_node, const std::string& from, const std::string& to_node,
                        const std::string& to, const std::string& key = "");
  nlohmann::json Delete(const std::string& node, const std::string& name, const std::string& key = "");
  nlohmann::json Protect(const std::string& node, const std::string& name, bool on);
  // Sets or clears a file flag: "protected", "selected" (Balt-System SPG/REL) or "hidden" (ATT HIDDEN).
  nlohmann::json Flag(const std::string& node, const std::string& name, const std::string& flag, bool on,
                      const std::string& key = "");
  bool WaitForServer(bus::Millis timeout) const { return client_.WaitForServer(timeout); }

 private:
  cell::ProgramReply Call(cell::ProgramRequest req);
  bus::Client<cell::ProgramRequest, cell::ProgramReply> client_;
  bus::Millis timeout_;
};

// The list as the store publishes it on cell/program/list: how a read-only viewer, which may not use the
// store's request topic, lists a namespace (the same JSON objects as List, by name). Waits, up to
// `timeout`, until the namespace's summary and as many present files as it counts have arrived; throws
// cell::Error(kUnavailable) when they have not.
nlohmann::json ListPublished(bus::Participant& p, const std::string& node, const std::string& pattern,
                             bus::Millis timeout);

}  // namespace cell::program_store
