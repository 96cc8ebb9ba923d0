// Binds the program store library to the bus: the request/reply service and change events.
#pragma once

#include <chrono>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "cell/bus/bus.h"
#include "cell/idl/program_store.h"
#include "cell/program_store/program_store.h"

namespace cell::program_store {

// The JSON shape of one file (DESIGN §6 `program ls`: name, node, type, dialect, revision, size,
// protected; plus the metadata `program show` prints).
nlohmann::json FileJson(const FileInfo& f);

class Service {
 public:
  // Chunked uploads silent for longer than stream_idle are dropped by Housekeeping.
  Service(bus::Participant& p, ProgramStore& store,
          std::chrono::seconds stream_idle = std::chrono::seconds(120));
  // Called from the main loop: forgets chunk streams abandoned by a dead client.
  void Housekeeping();

 private:
  // Runs one request under mu_, then publishes what it changed on cell/program/list.
  cell::ProgramReply Handle(const cell::ProgramRequest& r);
  // One per request kind.
  cell::ProgramReply Put(const cell::ProgramRequest& r);
  cell::ProgramReply PutChunk(const cell::ProgramRequest& r);
  cell::ProgramReply Get(const cell::ProgramRequest& r);
  cell::ProgramReply Show(const cell::ProgramRequest& r);
  cell::ProgramReply List(const cell::ProgramRequest& r);
  cell::ProgramReply Copy(const cell::ProgramRequest& r);
  cell::ProgramReply Rename(const cell::ProgramRequest& r);
  cell::ProgramReply Delete(const cell::ProgramRequest& r);
  cell::ProgramReply SetFlag(const cell::ProgramRequest& r);
  // cell/program/list: a changed file's entry (absent: deleted) and its namespace's count; the count alone;
  // one entry.
  void PublishEntry(const std::string& node, const std::string& name);
  void WriteSummary(const std::string& node, size_t files);
  void WriteEntry(const cell::ProgramEntry& e);
  ProgramStore& store_;
  std::chrono::seconds stream_idle_;
  bus::Writer<cell::ProgramChange> changes_;
  bus::Writer<cell::ProgramEntry> list_;
  std::vector<std::pair<std::string, std::string>> pending_;  // (node, name) changed, to publish; under mu_
  std::mutex mu_;  // Handle runs on the dispatch thread, Housekeeping on main
  struct CachedGet {
    std::string node, name;
    uint32_t revision = 0;
    std::string content;
    nlohmann::json info;  // the file's metadata, sent with chunk 0
  } cache_;
  bus::Server<cell::ProgramRequest, cell::ProgramReply> server_;
};

}  // namespace cell::program_store
