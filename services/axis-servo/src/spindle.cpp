#include "cell/servo/spindle.h"

#include <algorithm>
#include <cmath>

namespace cell::servo {

void Spindle::Configure(double max_rpm, double accel_rpm_s) {
  max_rpm_ = max_rpm;
  accel_ = accel_rpm_s;
}

void Spindle::SetRpm(double signed_rpm) {
  cmd_rpm_ = signed_rpm;
  css_v_ = 0;
}

void Spindle::SetSurfaceSpeed(double v_m_min, double limit_rpm, int dir) {
  css_v_ = v_m_min;
  css_limit_ = limit_rpm > 0 ? std::min(limit_rpm, max_rpm_) : max_rpm_;
  css_dir_ = dir < 0 ? -1 : 1;
}

double Spindle::TargetAt(double x_diameter) const {
  if (css_v_ <= 0) return cmd_rpm_;
  const double d = std::abs(x_diameter);
  const double rpm = d > 0 ? std::min(css_limit_, 1000.0 * css_v_ / (M_PI * d)) : css_limit_;
  return css_dir_ * rpm;
}

void Spindle::Turn(double ts) {
  const double before = rpm_;
  const double step = accel_ * ts;
  rpm_ = std::abs(target_ - rpm_) <= step ? target_ : rpm_ + std::copysign(step, target_ - rpm_);
  pos_ += (before + rpm_) * (ts / 120.0);  // trapezoid: mean rpm over the period, in revolutions
  turned_ += std::abs(pos_ - prev_pos_);
}

double Spindle::angle() const {
  double f = std::fmod(pos_, 1.0);
  if (f < 0) f += 1.0;
  return f * 360.0;
}

double Spindle::Crossing(double deg) const {
  const double a = deg / 360.0;
  if (pos_ > prev_pos_) {  // the mark positions are k + a; the first one in (prev, pos]
    const double k = std::floor(prev_pos_ - a) + 1 + a;
    if (k <= pos_) return prev_turned_ + (k - prev_pos_);
  } else if (pos_ < prev_pos_) {  // turning backwards: the first one in [pos, prev)
    const double k = std::ceil(prev_pos_ - a) - 1 + a;
    if (k >= pos_) return prev_turned_ + (prev_pos_ - k);
  }
  return -1;
}

}  // namespace cell::servo
