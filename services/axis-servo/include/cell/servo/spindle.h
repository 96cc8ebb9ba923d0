// The spindle of a station: its speed under the acceleration limit, constant surface speed on lathes, and
// the angle from the index mark (the one-per-revolution pulse) that threads synchronise with.
#pragma once

#include <cmath>

namespace cell::servo {

class Spindle {
 public:
  void Configure(double max_rpm, double accel_rpm_s);

  // Commands. Speeds are signed: + clockwise (M03), - counter-clockwise (M04).
  void SetRpm(double signed_rpm);  // constant speed (constant surface speed off)
  // Constant surface speed `v_m_min` at the X diameter given to Step(); `limit_rpm` is the programmed
  // spindle limit (0: the machine's max_rpm); `dir` +1 or -1.
  void SetSurfaceSpeed(double v_m_min, double limit_rpm, int dir);

  // The speed the spindle heads for at X diameter `x_diameter` (mm):
  // min(limit, max_rpm, 1000 v / (pi D)) with constant surface speed (the limit at D = 0), else the rpm.
  double TargetAt(double x_diameter) const;
  // One servo period: the target follows the diameter unless `hold_target` (a thread is being cut), the
  // speed moves towards it by at most acceleration x ts, and the angle integrates the speed.
  void Step(double ts, double x_diameter, bool hold_target) {
    if (!hold_target) target_ = css_v_ > 0 ? TargetAt(x_diameter) : cmd_rpm_;
    prev_pos_ = pos_;
    prev_turned_ = turned_;
    if (rpm_ != 0 || target_ != 0) Turn(ts);  // inline: a machining centre's spindle mostly stands still
  }
  // End of a commanded ramp: exactly at the target.
  void Snap(double x_diameter) { rpm_ = target_ = TargetAt(x_diameter); }
  // Oriented (M19, stopped): at the index mark, angle() 0, as at power-up.
  void Orient() { pos_ = prev_pos_ = std::round(pos_); }
  bool AtSpeed() const { return rpm_ == target_; }
  // Turning, or commanded to: Step() has something to do.
  bool Active() const { return rpm_ != 0 || cmd_rpm_ != 0 || css_v_ > 0; }

  double rpm() const { return rpm_; }        // signed
  double position() const { return pos_; }   // signed revolutions since start-up
  double turned() const { return turned_; }  // revolutions turned either way: never decreases
  double angle() const;                      // degrees from the index mark, [0, 360), clockwise
  // The value of turned() at which the spindle passed `deg` during the last Step() (in its direction of
  // turn), or -1 when it did not.
  double Crossing(double deg) const;

 private:
  void Turn(double ts);

  double max_rpm_ = 0, accel_ = 0;
  double cmd_rpm_ = 0;                   // constant-speed command
  double css_v_ = 0, css_limit_ = 0;     // m/min (0: off), rpm
  int css_dir_ = 0;                      // +1 / -1
  double rpm_ = 0, target_ = 0;          // actual and target speed
  double pos_ = 0, prev_pos_ = 0;        // revolutions, signed
  double turned_ = 0, prev_turned_ = 0;  // revolutions, unsigned sum
};

}  // namespace cell::servo
