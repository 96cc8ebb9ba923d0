// Canonical commands to motion segments for the axis servo.
#pragma once

#include <optional>

#include "cell/idl/motion.h"
#include "cell/interp/canon.h"

namespace cell::station {

// Maps one canonical command to a servo segment; nullopt for commands the CNC handles itself (messages,
// outputs, tool pre-selection, unit changes, ...). Station, run id and seq are left to the SegmentStream.
std::optional<cell::MotionSegment> ToSegment(const interp::Canon& c);

}  // namespace cell::station
