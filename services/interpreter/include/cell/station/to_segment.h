// Canonical commands to motion segments for the axis servo.
#pragma once

#include <optional>

#include "cell/idl/motion.h"
#include "cell/interp/canon.h"

namespace cell::station {

// Maps one canonical command to a servo segment; nullopt for commands the CNC handles itself (messages,
// outputs, tool pre-selection, unit changes, ...). Station, run id and seq are left to the SegmentStream.
std::optional<cell::MotionSegment> ToSegment(const interp::Canon& c);

// The rotary contouring axes A and C as the servo runs them. A dialect gives their positions normalised to
// [0, 360) with the block's signed turn (interp::Target::travel: Okuma's C after M110, M15/M16 and its
// contour pieces; KT-APL's rotary words); the servo's A and C do not wrap (docs/axis-servo.md), so a move
// from C350 to C10 would turn back 340 degrees. The station sends the position the turn reaches from the last
// one sent instead (370), and keeps that offset for later moves of the axis that give no turn. A dialect that
// never gives a turn is sent as it is. B is not touched: an index table turns its own way.
class RotaryUnwrap {
 public:
  void Apply(const interp::Canon& c, cell::MotionSegment& s);

 private:
  double last_[2] = {0, 0};    // A, C as last sent to the servo
  double offset_[2] = {0, 0};  // sent minus the dialect's position
};

}  // namespace cell::station
