// The EMCO tool data file: the EDIT TOOL DATA screen (manual ln 1400-1456, 2502-2553) as text, one
// correction per line:
//
//   T0303 Z-30.250 R0.400 L3     correction 03, belonging to turret position 3
//   07 X0 Z-41.5 R0.8 L2                  correction 07 (no turret position given)
//
// The first word is the correction number 01-99, or a T word TTCC naming the turret position TT (the
// tool-table entry's socket) and the correction CC. X and Z are the offsets measured from the tool holder
// reference point N (X as a radius, like the zero shift registers), R the nose radius, L the tip position
// code 0-9. Lengths without a decimal point are um, as on tape. Comments in round brackets, blank lines and
// "%" lines are skipped. In the cell's tool model (common/tooltable) the entry's tool is the correction
// number ("3"), x_offset is on the diameter (twice X), z_offset, nose_radius and tip as written.
#pragma once

#include <string>
#include <string_view>

#include "cell/tooltable/tooltable.h"

namespace cell::interp::emco {

// Applies the file to `base` (the corrections it names change; socket, life and flags are kept when not
// given). Throws cell::Error(kInvalidArgument) "SOURCE:LINE:COL: error: text" at the first bad entry, or
// when the text holds no tool data.
tooltable::ToolTable ParseToolData(std::string_view text, std::string_view source,
                                   const tooltable::ToolTable& base);

// The file form of a table's corrections (entries whose tool is 1-99), in correction order.
std::string FormatToolData(const tooltable::ToolTable& table);

}  // namespace cell::interp::emco
