// The names of the cell's enumerations as every view prints them (DESIGN §3: the MTConnect / OPC 40501
// words for a station's state; §6: a job's state is a bare word).
#pragma once

#include <optional>
#include <string_view>

#include "cell/idl/run.h"
#include "cell/idl/scheduler.h"
#include "cell/idl/station.h"

namespace cell::records {

// What execution and condition read while a station is not announced (as MTConnect reports it).
inline constexpr std::string_view kUnavailable = "UNAVAILABLE";

std::string_view ExecutionName(cell::Execution e);  // "READY", "FEED_HOLD", ...
std::string_view ConditionName(cell::Condition c);  // "NORMAL", "WARNING", "FAULT"
std::string_view JobStateName(cell::JobState s);    // "QUEUED", "WAITING", ...
std::optional<cell::JobState> JobStateFromName(std::string_view name);
bool IsTerminalJobState(std::string_view name);   // COMPLETED, FAILED, CANCELLED
std::string_view RunStateName(cell::RunState s);  // "QUEUED", "ACTIVE", ...

}  // namespace cell::records
