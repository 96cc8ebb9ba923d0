// Shared plumbing of cellctl verbs: the bus (joined only when a verb needs it), clients, output.
#pragma once

#include <cstdint>
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
#include "cell/idl/inspection.h"
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
  // The verb calls the host services only (scheduler, program store, inspection writer): the bus announces
  // itself to them alone, not to every station (bus::ParticipantOptions::host_services_only). Set by
  // ServicesOnly before the verb runs.
  bool host_services_only = false;
  bus::Participant& Bus();
  cell::program_store::Client& Programs();
  // One client per service for the whole command: the service replays a reply to the same client and
  // request id, and a second client on the same participant would count its requests from 1 again.
  cell::SchedulerReply Scheduler(cell::SchedulerRequest req, bus::Millis timeout = bus::Millis(30000));
  // True when the scheduler answers requests within `timeout` (a verb that only adds its data asks first).
  bool SchedulerUp(bus::Millis timeout);
  cell::InspectionReply Inspection(cell::InspectionRequest req, bus::Millis timeout = bus::Millis(10000));
  std::optional<cell::ToolTable> Tools(const std::string& station, bus::Millis timeout);
  std::optional<cell::StationVariables> Variables(const std::string& station, bus::Millis timeout);
  cell::StationReply StationCommand(const std::string& station, cell::StationRequest req);
  // The key on the wire for `verb` ("route-operate", "program-put", ...): CELLCTL_IDEMPOTENCY_KEY with the
  // verb, so a retried command is recognised and a different command under the same key refused by the
  // service, which compares the request's arguments; without the variable, a key unique to this invocation.
  // A key that breaks the rule (docs/operations.md "Names") is an error, never cut.
  std::string IdempotencyKey(const std::string& verb) const;
  // The one-line reason for a failed command: e's message, and for a service that is absent after the
  // discovery bound, what was on the domain instead.
  std::string Explain(const cell::Error& e);

 private:
  std::optional<std::string> local_service_;  // a local cell service on our domain (LocalServiceOn)
  std::unique_ptr<bus::Participant> bus_;
  std::unique_ptr<cell::program_store::Client> programs_;
  std::unique_ptr<bus::Client<cell::SchedulerRequest, cell::SchedulerReply>> scheduler_;
  std::unique_ptr<bus::Client<cell::InspectionRequest, cell::InspectionReply>> inspection_;
};

// The whole content of a local file. Exit{1, reason} when it cannot be read (a directory, a read error such
// as /proc/self/mem's), when it is empty, or when it is larger than max_bytes (checked from the file's size
// before anything is read, and again while reading a file whose size the system does not know).
std::string ReadLocalFile(const std::string& path, std::uint64_t max_bytes, const std::string& what);

// CLI11 checks for numbers on the command line: decimal digits only (CLI11 itself reads "0x10" as 16 and
// "010" as 8); Decimal drops leading zeros, so it must be given as a transform (a check's edits are
// discarded). Real allows one decimal point, no exponent, no hexadecimal float.
CLI::Validator Decimal();
CLI::Validator Real();

// A listing's `--limit N` (default 1000, at least 1) and `--after CURSOR` (the last id or name of the
// previous page; a job id is decimal) (DESIGN §6). The verb fetches page after page with
// records::CollectPages until it has `limit` rows or the listing ends; the table and --json print the same
// rows.
struct Paging {
  std::uint32_t limit = 1000;
  std::string after;
};
void AddPaging(CLI::App* verb, Paging& paging, bool numeric_cursor);

void Print(const Context& ctx, const nlohmann::json& j, const std::vector<std::string>& columns);
// The store's warnings of a put reply ("warnings": [...]), one "warning: " line each on stderr.
void PrintWarnings(const nlohmann::json& reply);

// Marks `noun` (and every verb under it) as calling the host services only (Context::host_services_only):
// on a large Fast DDS cell a `cellctl` that announces itself to every station costs the whole cell seconds
// of CPU (docs/operations.md §9.4). A verb that reads what stations publish must not be marked.
void ServicesOnly(CLI::App* noun, Context& ctx);

// Verb registration, one file per noun.
void AddProgramVerbs(CLI::App& app, Context& ctx);
void AddStationVerbs(CLI::App& app, Context& ctx);
void AddFmsVerbs(CLI::App& app, Context& ctx);  // pallet, route, schedule, tools
void AddJobVerbs(CLI::App& app, Context& ctx);
void AddInspectVerbs(CLI::App& app, Context& ctx);
void AddCellVerbs(CLI::App& app, Context& ctx);  // up, down, watch
void AddPkiVerbs(CLI::App& app, Context& ctx);   // pki init
void AddDncVerbs(CLI::App& app, Context& ctx);   // dnc send|receive|drip|status

}  // namespace cellctl
