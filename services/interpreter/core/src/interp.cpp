#include "cell/interp/interp.h"

#include <ctime>

#include "cell/error/error.h"
#include "cell/interp/ktapl.h"

namespace cell::interp {

std::string Diagnostic::Format() const {
  std::string out = program + ":" + std::to_string(line) + ":" + std::to_string(col) + ": error: ";
  if (!alarm.empty()) out += "[" + alarm + "] ";
  out += text;
  return out;
}

ProbeResult Environment::Probe(bool contact, const std::array<double, kAxisCount>& from,
                               const std::array<double, kAxisCount>& to) {
  (void)contact;
  (void)from;
  ProbeResult r;
  r.at = to;
  return r;
}

std::array<int, 6> Environment::Now() {
  std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  return {tm.tm_year + 1900, tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec};
}

const std::vector<DialectInfo>& Dialects() {
  static const std::vector<DialectInfo> kDialects = {
      {"ktapl", true}, {"okuma", false}, {"emco", false}, {"balt", false}};
  return kDialects;
}

const DialectInfo* FindDialect(const std::string& name) {
  for (const auto& d : Dialects()) {
    if (d.name == name) return &d;
  }
  return nullptr;
}

std::unique_ptr<Run> StartRun(const RunOptions& options) {
  const DialectInfo* d = FindDialect(options.dialect);
  if (!d) throw Error(Errc::kInvalidArgument, "unknown dialect '" + options.dialect + "'");
  if (!d->implemented) {
    throw Error(Errc::kUnimplemented, "dialect '" + options.dialect + "' is not implemented yet");
  }
  return StartKtaplRun(options);
}

}  // namespace cell::interp
