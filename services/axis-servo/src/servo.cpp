#include "cell/servo/servo.h"

#include <algorithm>
#include <cmath>

namespace cell::servo {

using machine::AxisConfig;
using machine::DriveConfig;

void AxisServo::Configure(const AxisConfig& axis, double period) {
  const DriveConfig& d = axis.drive;
  period_ = period;
  gain_ = 2 * M_PI / d.units_per_rev;
  inertia_ = d.motor_inertia + d.load_inertia;
  friction_ = d.viscous_friction;
  max_torque_ = d.max_torque;
  const double wn = 2 * M_PI * d.bandwidth_hz;
  kp_ = d.kp > 0 ? d.kp : inertia_ * wn * wn;
  kd_ = d.kd > 0 ? d.kd : std::max(0.0, 2 * d.damping * inertia_ * wn - friction_);
  ki_ = d.ki > 0 ? d.ki : kp_ * wn / 10;
  kvff_ = d.kvff;
  kaff_ = d.kaff;
  // Exact discretisation of [theta' = w, w' = (u - b w)/J] for a piecewise-constant torque.
  const double T = period;
  if (friction_ > 0) {
    const double al = friction_ / inertia_;
    const double e = std::exp(-al * T);
    phi_ << 1, (1 - e) / al, 0, e;
    gamma_ << (T - (1 - e) / al) / friction_, (1 - e) / friction_;
  } else {
    phi_ << 1, T, 0, 1;
    gamma_ << T * T / (2 * inertia_), T / inertia_;
  }
}

void AxisServo::Reset(double position) {
  state_ << position * gain_, 0;
  integral_ = error_ = torque_ = 0;
  saturated_ = false;
}

void AxisServo::Step(double x_cmd, double v_cmd, double a_cmd) {
  const double th = x_cmd * gain_, w = v_cmd * gain_, al = a_cmd * gain_;
  const double e = th - state_[0];
  const double u_unsat = kp_ * e + ki_ * (integral_ + e * period_) + kd_ * (w - state_[1]) +
                         kvff_ * friction_ * w + kaff_ * inertia_ * al;
  const double u = std::clamp(u_unsat, -max_torque_, max_torque_);
  saturated_ = u != u_unsat;
  if (!saturated_) integral_ += e * period_;  // conditional integration (anti-windup)
  error_ = e;
  torque_ = u;
  state_ = phi_ * state_ + gamma_ * u;
}

void JerkFilter::Configure(int n, bool co_axes) {
  n_ = std::max(1, n);
  co_axes_ = co_axes;
  Reset(AxisVector::Zero());
}

void JerkFilter::Reset(const AxisVector& p) {
  head_.Reset(p.head<kU>(), n_);
  co_.Reset(co_axes_ ? Window<3>::V(p.tail<3>()) : Window<3>::V::Zero(), co_axes_ ? n_ : 0);
  out_ = p;
  idx_ = 0;
  steady_ = n_;
  since_resum_ = 0;
}

const AxisVector& JerkFilter::Push(const AxisVector& p) {
  const Window<kU>::V in = p.head<kU>();
  const Window<3>::V in_co = p.tail<3>();
  const bool same = in == head_.last && (!co_axes_ || in_co == co_.last);
  steady_ = same ? std::min(steady_ + 1, n_) : 0;
  head_.Push(in, idx_);
  if (co_axes_) co_.Push(in_co, idx_);
  if (++idx_ == n_) idx_ = 0;
  if (++since_resum_ >= 64L * n_) {
    since_resum_ = 0;
    head_.Resum();
    if (co_axes_) co_.Resum();
  }
  if (steady_ >= n_) {
    out_ = p;
  } else {
    out_.head<kU>() = head_.sum / n_;
    if (co_axes_) out_.tail<3>() = co_.sum / n_;
  }
  return out_;
}

}  // namespace cell::servo
