// The Machine's spindle commands (constant speed, constant surface speed, limit) and spindle-synchronised
// threads: what a lathe adds to the machine (docs/axis-servo.md, "Lathes").
#include <fmt/format.h>

#include <cmath>

#include "cell/servo/machine.h"

namespace cell::servo {

using machine::AxisType;

namespace {

// +1 clockwise (M03, Okuma M13), -1 counter-clockwise, 0 stopped (or oriented).
int Sign(SpindleDirection d) {
  return d == SpindleDirection::kCW ? 1 : d == SpindleDirection::kCCW ? -1 : 0;
}

}  // namespace

bool Machine::StartSpindle(const Segment& s) {
  if (s.spindle_dir == SpindleDirection::kAxis) {  // a machine whose C is not its spindle
    RaiseAlarm(AlarmCode::kInvalidSegment,
               fmt::format("segment {}: this machine's spindle cannot be joined as a C axis (a lathe with "
                           "axes.c)",
                           s.id),
               s.id);
    return false;
  }
  const int dir = Sign(s.spindle_dir);
  if (dir != 0 && s.css_surface_speed > 0) {
    if (!cfg_.axes[kX].diameter) {
      RaiseAlarm(
          AlarmCode::kInvalidSegment,
          fmt::format("segment {}: constant surface speed needs a lathe (X programmed as a diameter)", s.id),
          s.id);
      return false;
    }
    spindle_.SetSurfaceSpeed(s.css_surface_speed, s.spindle_max_rpm, dir);
    return true;
  }
  // A programmed limit clamps a constant speed too (Okuma G50 S: "the maximum spindle speed").
  double rpm = std::abs(s.spindle_rpm);
  if (s.spindle_max_rpm > 0) rpm = std::min(rpm, s.spindle_max_rpm);
  if (dir != 0 && rpm > cfg_.spindle_max_rpm) {
    RaiseAlarm(
        AlarmCode::kInvalidSegment,
        fmt::format("segment {}: spindle {:.0f} rpm above max_rpm {:.0f}", s.id, rpm, cfg_.spindle_max_rpm),
        s.id);
    return false;
  }
  spindle_.SetRpm(dir * rpm);
  return true;
}

// A lathe's live-tool (M-tool) spindle: a constant speed, stop, cw or ccw (Okuma M13/M14/M12 at SB=).
bool Machine::StartLiveTool(const Segment& s) {
  if (cfg_.live_tool_max_rpm <= 0) {
    RaiseAlarm(
        AlarmCode::kInvalidSegment,
        fmt::format("segment {}: this machine has no live-tool spindle (spindle.live_tool_max_rpm)", s.id),
        s.id);
    return false;
  }
  const int dir = Sign(s.spindle_dir);
  const double rpm = std::abs(s.spindle_rpm);
  if (dir != 0 && rpm > cfg_.live_tool_max_rpm) {
    RaiseAlarm(AlarmCode::kInvalidSegment,
               fmt::format("segment {}: live tool {:.0f} rpm above live_tool_max_rpm {:.0f}", s.id, rpm,
                           cfg_.live_tool_max_rpm),
               s.id);
    return false;
  }
  live_tool_.SetRpm(dir * rpm);
  return true;
}

// The C-axis joint of a lathe (Okuma M110/M109, ln 1983-1984, 2057-2069). Joining stops the spindle (its
// ramp down) and then engages in `c_joint_time`; a stop while joined releases in `c_joint_time`, the spindle
// left stopped in speed control. Turning or orienting while joined is refused: the spindle is an axis.
bool Machine::StartJoint(const Segment& s, double& t) {
  if (s.spindle_dir == SpindleDirection::kAxis) {
    t = std::abs(spindle_.rpm()) / cfg_.spindle_accel_rpm_s + (c_joined_ ? 0.0 : cfg_.c_joint_time);
    spindle_.SetRpm(0);
    spindle_oriented_ = false;
    return true;
  }
  if (s.spindle_dir != SpindleDirection::kStop) {
    RaiseAlarm(AlarmCode::kInvalidSegment,
               fmt::format("segment {}: the spindle is joined as the C axis (M110) and cannot {}; M109 "
                           "releases it",
                           s.id, s.spindle_dir == SpindleDirection::kOrient ? "orient" : "turn"),
               s.id);
    return false;
  }
  t = cfg_.c_joint_time;
  return true;
}

bool Machine::PlanThread(const Segment& s, const AxisVector& start, const AxisVector& end, std::string& why) {
  const AxisVector d = end - start;
  if (present_[kB] && cfg_.axes[kB].type == AxisType::kIndex && std::abs(d[kB]) > 1e-9) {
    why = "a thread cannot turn the B index table";
    return false;
  }
  // The lead is measured along the axis with the larger travel (Z on a tie; lathe X as a radius; a
  // U-head's taper thread, Z with U, along Z unless U travels further).
  int major = kZ;
  for (int i : {kX, kY, kU, kV, kW})
    if (present_[i] && std::abs(d[i]) > std::abs(d[major])) major = i;
  const double travel = std::abs(d[major]);
  if (travel < 1e-9) {
    why = "thread of zero length";
    return false;
  }
  // The speed at the thread's start (constant surface speed holds it there for the whole thread).
  const double rpm = std::abs(spindle_.TargetAt(2.0 * std::abs(start[kX])));
  if (rpm == 0) {
    why = "thread with the spindle stopped (no M03/M04 before it)";
    return false;
  }
  const double l0 = s.thread_lead, dl = s.thread_lead_change;
  if (!(l0 > 0)) {
    why = "thread lead is zero";
    return false;
  }
  // The lead after r revolutions is l0 + dl r; it must stay positive to the end (travel = l0 r + dl r²/2).
  const double disc = l0 * l0 + 2 * dl * travel;
  if (disc <= 0) {
    why =
        fmt::format("variable lead {:g} mm changing by {:g} mm/rev reaches zero before the end of {:.4f} mm",
                    l0, dl, travel);
    return false;
  }
  const double lead_max = std::max(l0, std::sqrt(disc));
  for (int i = 0; i < kNumAxes; ++i) {
    if (!present_[i] || std::abs(d[i]) < 1e-12) continue;
    const double need = lead_max * std::abs(d[i]) / travel * rpm;  // units/min
    if (need > cfg_.axes[i].max_velocity * (1 + 1e-9)) {
      why = fmt::format("thread lead {:g} mm at {:.0f} rpm needs {} {:.0f} mm/min, above max_velocity {:.0f}",
                        lead_max, rpm, static_cast<char>(std::toupper(kAxisNames[i])), need,
                        cfg_.axes[i].max_velocity);
      return false;
    }
  }
  const double angle = std::fmod(std::fmod(s.thread_start_angle, 360.0) + 360.0, 360.0);
  planner_.AddThread(end, l0, dl, travel, angle, s.exact_stop, s.id);
  return true;
}

}  // namespace cell::servo
