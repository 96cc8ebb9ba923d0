#include "cell/interp/station_rules.h"

#include <cstdlib>

#include <fmt/format.h>

#include <algorithm>
#include <cctype>

#include "cell/error/error.h"
#include "cell/interp/interp.h"

namespace cell::interp {

const config::DialectRules& StationRules() {
  static const config::DialectRules kRules = [] {
    config::DialectRules r;
    for (const Dialect* d : Dialects()) {
      if (!r.names.empty()) r.names += ", ";
      r.names += d->name();
    }
    r.canonical = [](std::string_view name) {
      const Dialect* d = FindDialect(name);
      return d == nullptr ? std::string() : std::string(d->name());
    };
    r.check_tool = [](std::string_view dialect, const tooltable::ToolEntry& tool) {
      const Dialect* d = FindDialect(dialect);
      return d == nullptr ? std::string() : d->CheckToolEntry(tool);
    };
    return r;
  }();
  return kRules;
}

config::StationConfig LoadStation(std::string_view id) {
  return config::LoadStation(id, &StationRules());
}

namespace {

// Where the text writes W<pallet> in a TLD statement: "LINE:COL: " (1-based), or "" when not found.
std::string WhereWritten(std::string_view text, int pallet) {
  int line_no = 0;
  std::size_t start = 0;
  const std::string wanted = std::to_string(pallet);
  while (start < text.size()) {
    std::size_t nl = text.find('\n', start);
    std::string line(text.substr(start, nl == std::string_view::npos ? text.size() - start : nl - start));
    start = nl == std::string_view::npos ? text.size() : nl + 1;
    ++line_no;
    for (char& c : line) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    if (line.find("TLD") == std::string::npos) continue;
    for (std::size_t i = 0; i + 1 < line.size(); ++i) {
      if (line[i] != 'W') continue;
      std::size_t e = i + 1;
      while (e < line.size() && std::isdigit(static_cast<unsigned char>(line[e]))) ++e;
      if (e > i + 1 && std::stoi(line.substr(i + 1, e - i - 1)) == pallet)
        return fmt::format("{}:{}: ", line_no, i + 1);  // "LINE:COL: "
    }
  }
  return "";
}

}  // namespace

tooltable::ToolTable ParseStationTools(const config::StationConfig& cfg, std::string_view text,
                                       std::string_view source, const tooltable::ToolTable& base) {
  tooltable::ToolTable table = DialectOrThrow(cfg.dialect).ParseToolTable(text, source, base);
  const int max = MaxPallet(cfg);
  for (const tooltable::ProcessComp& p : table.process_comps()) {
    if (p.pallet <= max) continue;
    if (std::any_of(base.process_comps().begin(), base.process_comps().end(),
                    [&](const tooltable::ProcessComp& b) { return b == p; }))
      continue;  // already there (an older load): not this text's
    const std::string where = WhereWritten(text, p.pallet);
    throw Error(
        Errc::kInvalidArgument,
        fmt::format("{}:{} error: TLD W VALUE {} OUTSIDE 1-{}: {} has coded pallets (KT-APL ln 4081-4083)",
                    source, where.empty() ? "" : where.substr(0, where.size() - 1), p.pallet, max, cfg.id));
  }
  return table;
}

std::optional<double> ParamNumber(const config::StationConfig& cfg, const std::string& name) {
  auto it = cfg.params.find(name);
  if (it == cfg.params.end()) return std::nullopt;
  char* end = nullptr;
  const double v = std::strtod(it->second.c_str(), &end);
  if (end == it->second.c_str()) return std::nullopt;
  return v;
}

}  // namespace cell::interp
