// The registry's rules for station files: common/config names a station's dialect as a string and links no
// dialect; the processes that run programs load station files through these rules, so that an unknown dialect
// or a tool outside the dialect's ranges is refused with the file and line.
//
//   auto cfg = cell::config::LoadStation(id, &cell::interp::StationRules());
#pragma once

#include <string_view>

#include "cell/config/config.h"

namespace cell::interp {

// Names from Dialects() (aliases accepted, any case), tools checked by Dialect::CheckToolEntry.
const config::DialectRules& StationRules();

// config::LoadStation(id) with StationRules().
config::StationConfig LoadStation(std::string_view id);

}  // namespace cell::interp
