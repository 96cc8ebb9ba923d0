// The run API's and the dialect interface's out-of-line parts.
#include "cell/interp/run.h"

#include <cmath>
#include <ctime>
#include <string>

#include "cell/error/error.h"
#include "cell/interp/dialect.h"
#include "cell/interp/run_base.h"

namespace cell::interp {

std::string Diagnostic::Format() const {
  std::string out = program + ":" + std::to_string(line) + ":" + std::to_string(col) + ": error: ";
  if (!alarm.empty()) out += "[" + alarm + "] ";
  out += text;
  return out;
}

RunBase::RunBase(const RunOptions& o) : env_(o.env ? o.env : &default_env_) {
  opt_.dialect = o.dialect;
  opt_.program_name = o.program_name;
  opt_.library = o.library;
  opt_.save = o.save;
  opt_.params = o.params;
  opt_.env = o.env;
}

ProbeResult Environment::Probe(const ProbeMove& move) {
  ProbeResult r;
  r.at = move.to;
  return r;
}

std::array<int, 6> Environment::Now() {
  std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  return {tm.tm_year + 1900, tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec};
}

std::string HeadingNotice::Format() const {
  if (line <= 0) return text;
  return "line " + std::to_string(line) + ": " + text;
}

bool ProgramNameCollector::Add(const std::string& name, int line, std::string_view key) {
  auto [it, inserted] = first_line_.emplace(name, line);
  if (!inserted) {
    h_.notices.push_back({HeadingNotice::Kind::kValue, std::string(key), line, 1,
                          "program name " + name + " appears again (first on line " +
                              std::to_string(it->second) + "); selection by name is ambiguous"});
    return false;
  }
  h_.program_names.push_back(name);
  return true;
}

std::string Dialect::CheckToolEntry(const tooltable::ToolEntry& e) const {
  for (double v : {e.length, e.diameter, e.life_left_min, e.max_hp, e.x_offset, e.z_offset, e.nose_radius}) {
    if (!std::isfinite(v)) return "tool " + e.tool + ": a value is not a finite number";
  }
  return "";
}

std::string Dialect::ImportListing(std::string_view text) const {
  (void)text;
  throw Error(Errc::kInvalidArgument, "--listing is not defined for dialect '" + std::string(name()) + "'");
}

std::string Dialect::CheckVariable(std::string_view name, double value) const {
  (void)value;
  return "'" + std::string(name) + "' is not a variable a " + std::string(title()) +
         " station keeps (it keeps none)";
}

void Dialect::PalletArrives(std::map<std::string, double>& variables) const {
  (void)variables;
}

std::unique_ptr<Run> UnimplementedRuns::StartRun(const RunOptions& options) const {
  (void)options;
  throw Error(Errc::kUnimplemented, "dialect '" + std::string(name()) + "' is not implemented yet");
}

tooltable::ToolTable UnimplementedRuns::ParseToolTable(std::string_view text, std::string_view source,
                                                       const tooltable::ToolTable& base) const {
  (void)text;
  (void)source;
  (void)base;
  throw Error(Errc::kUnimplemented,
              "tool tables of dialect '" + std::string(name()) + "' are not implemented yet");
}

std::string_view FileKindName(FileKind kind) {
  switch (kind) {
    case FileKind::kPartProgram:
      return "part_program";
    case FileKind::kLibrary:
      return "library";
    case FileKind::kSchedule:
      return "schedule";
    case FileKind::kToolTable:
      return "tool_table";
    case FileKind::kFixtureOffsets:
      return "fixture_offsets";
    case FileKind::kInspection:
      return "inspection";
    case FileKind::kData:
      return "data";
    case FileKind::kPartModel:
      return "part_model";
  }
  return "data";
}

std::string_view MachineKindName(MachineKind kind) {
  return kind == MachineKind::kLathe ? "lathe" : "hmc";
}

}  // namespace cell::interp
