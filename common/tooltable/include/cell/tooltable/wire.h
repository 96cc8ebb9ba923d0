// The tool table on the bus: common/tooltable's model <-> the IDL ToolTable (idl/station.idl). The one
// mapping every process uses (the station publishes it, the scheduler, servo, dashboard and cellctl read it).
#pragma once

#include <string_view>

#include "cell/idl/station.h"
#include "cell/tooltable/tooltable.h"

namespace cell::tooltable {

// Throws cell::Error(kInvalidArgument) when a tool number or the table exceeds the wire bounds (a tool
// number is at most 16 characters, a table at most 512 entries and 512 process compensations).
cell::ToolTable ToWire(const ToolTable& t, std::string_view station, unsigned revision);
ToolTable FromWire(const cell::ToolTable& t);
ToolEntry FromWire(const cell::ToolEntry& w);

}  // namespace cell::tooltable
