// Per-axis servo (PID with velocity and acceleration feed-forward) on an Eigen plant model, and the
// moving-average jerk filter between interpolator and servo.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "cell/machine/machine_config.h"
#include "cell/servo/segment.h"

namespace cell::servo {

// Motor + load on a shaft: (Jm + Jl) * dw/dt = torque - b * w, discretised exactly for a zero-order-hold
// torque over one servo period: x' = Phi x + Gamma u with x = [angle rad, speed rad/s].
class AxisServo {
 public:
  AxisServo() = default;
  void Configure(const machine::AxisConfig& axis, double period);
  void Reset(double position);                              // axis units; at rest, integrator cleared
  void Shift(double units) { state_[0] += units * gain_; }  // renumber the position (modular axes)

  // One period: command position, velocity and acceleration in axis units (mm or deg, /s, /s²).
  void Step(double x_cmd, double v_cmd, double a_cmd);

  double position() const { return state_[0] / gain_; }      // axis units
  double velocity() const { return state_[1] / gain_; }      // units/s
  double following_error() const { return error_ / gain_; }  // command - actual, units
  double torque() const { return torque_; }                  // N·m
  bool saturated() const { return saturated_; }

  double kp() const { return kp_; }
  double kd() const { return kd_; }
  double ki() const { return ki_; }

 private:
  Eigen::Matrix2d phi_ = Eigen::Matrix2d::Identity();
  Eigen::Vector2d gamma_ = Eigen::Vector2d::Zero();
  Eigen::Vector2d state_ = Eigen::Vector2d::Zero();
  double gain_ = 1.0;  // rad per axis unit
  double inertia_ = 0, friction_ = 0, max_torque_ = 0;
  double kp_ = 0, ki_ = 0, kd_ = 0, kvff_ = 0, kaff_ = 0, period_ = 0.001;
  double integral_ = 0, error_ = 0, torque_ = 0;
  bool saturated_ = false;
};

// Moving average of the interpolated positions over N periods. With |a| <= A before the filter, the
// output keeps |v| and |a| and has |jerk| <= 2A/(N*Ts); N = ceil(2A/(J*Ts)) over all axes.
class JerkFilter {
 public:
  // `co_axes`: the machine has a U, V or W. Without one the filter averages X Y Z A B C alone (U V W stand
  // still there): a six-axis machine's period costs what it did before the vector carried nine axes.
  void Configure(int n, bool co_axes);
  void Reset(const AxisVector& p);
  const AxisVector& Push(const AxisVector& p);
  const AxisVector& Output() const { return out_; }
  int length() const { return n_; }
  bool Settled() const { return steady_ >= n_; }

 private:
  // The window of M axes: X..C (M = 6) and U V W (M = 3) apart, each a vector Eigen keeps aligned and
  // unrolls.
  template <int M>
  struct Window {
    using V = Eigen::Matrix<double, M, 1>;
    std::vector<V> ring;
    V sum = V::Zero(), last = V::Zero();
    void Reset(const V& p, int n) {
      ring.assign(static_cast<std::size_t>(n), p);
      sum = p * n;
      last = p;
    }
    void Push(const V& p, int idx) {
      last = p;
      sum += p - ring[static_cast<std::size_t>(idx)];
      ring[static_cast<std::size_t>(idx)] = p;
    }
    void Resum() {  // bound the rounding drift of the running sum
      sum.setZero();
      for (const auto& r : ring) sum += r;
    }
  };

  Window<kU> head_;  // X Y Z A B C
  Window<3> co_;     // U V W, when co_axes_
  bool co_axes_ = true;
  AxisVector out_ = AxisVector::Zero();
  int n_ = 1, idx_ = 0, steady_ = 0;
  long since_resum_ = 0;
};

}  // namespace cell::servo
