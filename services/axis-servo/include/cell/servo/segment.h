// Motion segments and machine events: the plain C++ seam between the axis-servo library and its callers.
// The DDS service maps its IDL types onto these structs; nothing here knows about DDS.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>

#include "cell/machine/machine_config.h"

namespace cell::servo {

// The axes are the station file's (cell::machine); the servo indexes by them everywhere.
using machine::IsRotary;
using machine::kAxisNames;
using machine::kNumAxes;
using enum machine::Axis;

// Positions of the nine axes: mm for X Y Z and U V W, degrees for A B C.
using AxisVector = Eigen::Matrix<double, kNumAxes, 1>;

// The length of a move `d`: along the linear axes (X Y Z U V W) when it moves one, else along the rotary
// axes (degrees), which is what a feed of a move of rotary axes alone is measured along.
inline double PathLength(const AxisVector& d) {
  const double lin = d.head<3>().squaredNorm() + d.tail<3>().squaredNorm();
  return lin >= 1e-18 ? std::sqrt(lin) : d.segment<3>(kA).norm();
}

enum class SegmentKind : std::uint8_t {
  kRapid,       // straight line at the machine's rapid rates, exact stop at its end
  kLinear,      // straight line at `feed`; `exact_stop` demands deceleration (KT-APL G00 with a feed)
  kArc,         // circle or helix around `center` in `plane`, `turns` extra full revolutions
  kDwell,       // wait `dwell_s` machine seconds
  kToolChange,  // put `tool` in the spindle (must be in the magazine)
  kSpindle,  // `spindle_dir` (stop, cw, ccw, orient, C joint) at `spindle_rpm`, or at constant surface speed
  kCoolant,  // `coolant` on/off
  kPalletChange,  // shuttle `pallet` onto the table (0: swap table and shuttle)
  kProbe,         // straight move towards `end` at `feed`, stops where the probe makes contact with the part
                  // model (G22) or, with `probe_break`, loses it (G23); with `tool_check` a G38 check
                  // of the spindle tool at the detection post, where the axes stand
  kEnd,           // program end: completes once all motion is in position
  kThread,        // spindle-synchronised straight move to `end`: `thread_lead` mm per spindle revolution
};

// The plane of an arc: its first and second axis as the program selected them (indices of the station's
// x y z a b c u v w; the servo moves two linear axes, X Y Z or U V W, in a plane). Any pair and either order:
// Balt-System (DPI,X,Z) is {kX, kZ}, G18 is {kZ, kX}.
struct ArcPlane {
  std::uint8_t first = kX, second = kY;
};
// Seen with the first axis pointing right and the second up (from the positive end of first x second).
enum class ArcDirection : std::uint8_t { kCW, kCCW };
enum class FeedMode : std::uint8_t { kPerMinute, kPerRevolution, kInverseTime };
// kAxis: a lathe's work spindle joined as the rotary axis C (position control, Okuma M110); a later kStop
// releases the joint (M109). C moves only while joined; the spindle cannot turn while it is.
enum class SpindleDirection : std::uint8_t { kStop, kCW, kCCW, kOrient, kAxis };
enum class CoolantMode : std::uint8_t { kOff, kFlood, kMist, kThroughSpindle };

// The small fields side by side, so that a segment in the machine's queue (Machine::Entry) fits two to a
// 512-byte deque node: with nine axes and the fields in their old order it took one allocation per segment.
struct Segment {
  std::uint64_t id = 0;
  SegmentKind kind = SegmentKind::kLinear;
  // Axes given in `end` (bit i: axis i of x y z a b c u v w).
  std::uint16_t axes = 0x1ff;
  FeedMode feed_mode = FeedMode::kPerMinute;  // of `feed`
  bool exact_stop = false;
  SpindleDirection spindle_dir = SpindleDirection::kStop;  // kSpindle
  bool live_tool = false;  // kSpindle: a lathe's live-tool (M-tool) spindle (stop, cw, ccw at spindle_rpm)
  // Absolute end position, after all offsets (mm / degrees). Lathes (x_diameter) give X as a DIAMETER;
  // the servo halves it. Axes whose bit is clear in `axes` keep their current position; axes the machine
  // does not have are ignored (the DDS receiver refuses a segment that moves one).
  std::array<double, kNumAxes> end{};
  // kLinear / kArc / kProbe: mm/min (per_rev: mm/rev of the spindle; inverse_time: 1/min).
  // kRapid ignores it and uses the machine's rapid rates.
  double feed = 0.0;
  // kArc: centre (x y z; lathe x as a diameter; a co-axis U V W in the slot of its parallel X Y Z, as on the
  // wire), plane, direction, extra full turns for helices.
  std::array<double, 3> center{};
  ArcPlane plane;
  ArcDirection direction = ArcDirection::kCCW;
  std::uint32_t turns = 0;
  double dwell_s = 0.0;  // kDwell
  std::string tool;      // kToolChange, e.g. "1001" or "33412.5"; "" or "0": the spindle emptied (with a
                         // tool_socket, the magazine then brings that socket to the change position)
  int tool_socket =
      0;  // kToolChange: the socket the control chose (an alternate tool); 0: the first holding it
  // kSpindle. Every spindle segment states the whole spindle command; nothing carries over from the last.
  double spindle_rpm = 0.0;  // rpm when css_surface_speed is 0
  // Constant surface speed in m/min (0: off): rpm = min(limit, max_rpm, 1000 v / (pi D)), D = X diameter.
  double css_surface_speed = 0.0;
  // The programmed spindle limit in rpm (Okuma G50 S, EMCO G92 S); 0: the machine's max_rpm.
  double spindle_max_rpm = 0.0;
  // kThread: lead along the major axis (the one with the larger travel; lathe X counted as a radius),
  // in mm per spindle revolution; it changes by `thread_lead_change` mm/rev every revolution (variable
  // lead, Okuma G34/G35). The cut begins when the spindle passes `thread_start_angle` degrees from its
  // index mark (each pass of a multi-pass thread lands in the same groove; multi-start threads use
  // different angles). A thread directly after a thread continues its synchronisation (no index wait).
  double thread_lead = 0.0;
  double thread_lead_change = 0.0;
  double thread_start_angle = 0.0;
  double probe_length = 0.0;  // kProbe: the probe's length compensation in Z (mm), to the ball's tip
  int pallet = 0;             // kPalletChange
  CoolantMode coolant = CoolantMode::kOff;  // kCoolant
  bool probe_break = false;                 // kProbe: trip when contact is lost (G23), not made (G22)
  bool tool_check = false;  // kProbe: a G38 broken-tool check of the spindle tool, no motion; the result's
                            // contact = every edge seen (the tool is whole)
};

// A probe move's result: the latched axis positions at the trip, or the end of travel without a trip.
struct ProbeResult {
  bool contact = false;  // the probe tripped: contact made (G22) or, for a probe_break move, lost (G23)
  bool already = false;  // the probe was in that state at the start: no motion, nothing latched
  AxisVector position = AxisVector::Zero();  // segment convention (lathe X as a diameter)
};

enum class AlarmCode : std::uint16_t {
  kNone = 0,
  kSoftLimit = 500,       // a segment would leave the travel limits: no motion
  kFollowingError = 410,  // "DIFF over": following error above the axis limit
  kToolNotInMagazine = 600,
  kInvalidSegment = 601,   // arc radii disagree, index position off the increment, bad feed, ...
  kProbeOvertravel = 602,  // the stylus was driven past its overtravel after a trip
};

struct Alarm {
  AlarmCode code = AlarmCode::kNone;
  std::string text;
};

enum class EventKind : std::uint8_t {
  kStarted,    // the machine began executing the segment
  kCompleted,  // the machine finished the segment (probe segments carry `probe`)
  kFlushed,    // dropped by abort, reset or an alarm without being executed to its end
  kAlarm,      // `alarm` raised (segment_id: the segment that caused it, 0 if none)
};

struct Event {
  EventKind kind = EventKind::kStarted;
  std::uint64_t segment_id = 0;
  double machine_time = 0.0;  // seconds of machine time
  ProbeResult probe;          // kCompleted of a kProbe segment
  Alarm alarm;                // kAlarm
};

}  // namespace cell::servo
