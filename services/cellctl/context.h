// Shared plumbing of cellctl verbs: the bus (joined only when a verb needs it), clients, output.
#pragma once

#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "cell/bus/bus.h"
#include "cell/error/error.h"
#include "cell/health/health.h"
#include "cell/idl/scheduler.h"
#include "cell/idl/station.h"
#include "cell/program_store/client.h"

namespace cellctl {

namespace bus = cell::bus;

// A verb's failure: one line on stderr, this exit code.
struct Exit {
  int code;
  std::string message;
};

class Context {
 public:
  bool json = false;
  bus::Participant& Bus();
  cell::program_store::Client& Programs();
  cell::SchedulerReply Scheduler(cell::SchedulerRequest req, bus::Millis timeout = bus::Millis(30000));
  std::optional<cell::ToolTable> Tools(const std::string& station, bus::Millis timeout);
  std::optional<cell::StationVariables> Variables(const std::string& station, bus::Millis timeout);
  cell::StationReply StationCommand(const std::string& station, cell::StationRequest req);
  // A key that makes a retried command idempotent: the same invocation, the same key.
  std::string IdempotencyKey(const std::string& what) const;

 private:
  std::unique_ptr<bus::Participant> bus_;
  std::unique_ptr<cell::program_store::Client> programs_;
  std::unique_ptr<bus::Client<cell::SchedulerRequest, cell::SchedulerReply>> scheduler_;
};

// The whole content of a local file; Exit{1, "cannot read PATH"} when it cannot be read.
std::string ReadLocalFile(const std::string& path);

void Print(const Context& ctx, const nlohmann::json& j, const std::vector<std::string>& columns);
// The store's warnings of a put reply ("warnings": [...]), one "warning: " line each on stderr.
void PrintWarnings(const nlohmann::json& reply);

// Verb registration, one file per noun.
void AddProgramVerbs(CLI::App& app, Context& ctx);
void AddStationVerbs(CLI::App& app, Context& ctx);
void AddFmsVerbs(CLI::App& app, Context& ctx);  // pallet, route, schedule, tools
void AddJobVerbs(CLI::App& app, Context& ctx);
void AddInspectVerbs(CLI::App& app, Context& ctx);
void AddCellVerbs(CLI::App& app, Context& ctx);  // up, down, watch

}  // namespace cellctl
