// The registry's rules for station files: common/config names a station's dialect as a string and links no
// dialect; the processes that run programs load station files through these rules, so that an unknown dialect
// or a tool outside the dialect's ranges is refused with the file and line.
//
//   auto cfg = cell::config::LoadStation(id, &cell::interp::StationRules());
#pragma once

#include <optional>
#include <string>
#include <string_view>

#include "cell/config/config.h"
#include "cell/tooltable/tooltable.h"

namespace cell::interp {

// Names from Dialects() (aliases accepted, any case), tools checked by Dialect::CheckToolEntry.
const config::DialectRules& StationRules();

// config::LoadStation(id) with StationRules().
config::StationConfig LoadStation(std::string_view id);

// A tool load onto station `cfg` (`cellctl tools load`, the station's own check): the dialect's tool-table
// form (Dialect::ParseToolTable onto `base`), then what the station file adds: on a coded-pallet station
// (KT-APL FMS modules, `coded_pallets = true`) a process compensation's pallet W is 1-127 (KT-APL manual ln
// 4081-4083), "SOURCE:LINE:COL: error: TLD W VALUE 200 OUTSIDE 1-127 ...". Throws cell::Error.
tooltable::ToolTable ParseStationTools(const config::StationConfig& cfg, std::string_view text,
                                       std::string_view source, const tooltable::ToolTable& base);

// A station file's [params] entry read as a number: what the machine reports by the dialect's own names
// (KT-APL L3060, the control's serial number), for the station and the predictor alike; nullopt when the
// file has no such entry or it is not a number.
std::optional<double> ParamNumber(const config::StationConfig& cfg, const std::string& name);

// The coded-pallet limit (1-127) or the table's (1-255).
inline int MaxPallet(const config::StationConfig& cfg) {
  return cfg.coded_pallets ? 127 : 255;
}

}  // namespace cell::interp
