#include "cell/interp/station_rules.h"

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

}  // namespace cell::interp
