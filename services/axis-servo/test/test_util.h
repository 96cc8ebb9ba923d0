// Test helpers: run a Machine tick by tick and check the commanded motion against the axis limits.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

#include "cell/servo/machine.h"

namespace cell::servo::testing {

inline Segment Line(std::uint64_t id, double x, double y, double z, double feed, bool exact = false) {
  Segment s;
  s.id = id;
  s.kind = SegmentKind::kLinear;
  s.end = {x, y, z, 0, 0, 0};
  s.axes = 0x07;
  s.feed = feed;
  s.exact_stop = exact;
  return s;
}

inline Segment Rapid(std::uint64_t id, double x, double y, double z) {
  Segment s = Line(id, x, y, z, 0, true);
  s.kind = SegmentKind::kRapid;
  return s;
}

// The spindle on, clockwise, at `rpm`.
inline Segment SpindleOn(std::uint64_t id, double rpm) {
  Segment s;
  s.id = id;
  s.kind = SegmentKind::kSpindle;
  s.spindle_rpm = rpm;
  s.spindle_dir = SpindleDirection::kCW;
  return s;
}

inline Segment Arc(std::uint64_t id, double x, double y, double z, double cx, double cy, bool ccw,
                   double feed, std::uint32_t turns = 0) {
  Segment s = Line(id, x, y, z, feed);
  s.kind = SegmentKind::kArc;
  s.center = {cx, cy, 0};
  s.plane = {kX, kY};
  s.direction = ccw ? ArcDirection::kCCW : ArcDirection::kCW;
  s.turns = turns;
  return s;
}

// Every tick: finite differences of the commanded (post-filter) positions against max velocity (rapid),
// acceleration and jerk of each axis; records worst ratios and following errors.
class LimitChecker {
 public:
  explicit LimitChecker(const Machine& m) : m_(m) {
    for (int i = 0; i < kNumAxes; ++i) {
      const machine::AxisConfig& a = m.config().axes[i];
      if (!a.present) continue;
      vmax_[i] = std::max(a.rapid, a.max_velocity) / 60.0;
      amax_[i] = a.max_acceleration;
      jmax_[i] = a.max_jerk;
    }
  }
  void Sample() {
    const double ts = m_.period();
    const AxisVector p = m_.commanded();
    if (n_ >= 1) {
      const AxisVector v = (p - p1_) / ts;
      if (n_ >= 2) {
        const AxisVector a = (v - v1_) / ts;
        if (n_ >= 3) {
          const AxisVector j = (a - a1_) / ts;
          for (int i = 0; i < kNumAxes; ++i)
            if (jmax_[i] > 0) worst_j = std::max(worst_j, std::abs(j[i]) / jmax_[i]);
        }
        for (int i = 0; i < kNumAxes; ++i)
          if (amax_[i] > 0) worst_a = std::max(worst_a, std::abs(a[i]) / amax_[i]);
        a1_ = a;
      }
      for (int i = 0; i < kNumAxes; ++i)
        if (vmax_[i] > 0) worst_v = std::max(worst_v, std::abs(v[i]) / vmax_[i]);
      v1_ = v;
    }
    p1_ = p;
    ++n_;
    const AxisVector fe = m_.following_error();
    for (int i = 0; i < kNumAxes; ++i) max_fe = std::max(max_fe, std::abs(fe[i]));
  }
  void ExpectWithinLimits(double slack = 1e-6) const {
    EXPECT_LE(worst_v, 1 + slack) << "velocity limit exceeded";
    EXPECT_LE(worst_a, 1 + slack) << "acceleration limit exceeded";
    EXPECT_LE(worst_j, 1 + slack) << "jerk limit exceeded";
  }
  double worst_v = 0, worst_a = 0, worst_j = 0, max_fe = 0;

 private:
  const Machine& m_;
  AxisVector vmax_ = AxisVector::Zero(), amax_ = AxisVector::Zero(), jmax_ = AxisVector::Zero();
  AxisVector p1_ = AxisVector::Zero(), v1_ = AxisVector::Zero(), a1_ = AxisVector::Zero();
  long n_ = 0;
};

// Runs until idle (or max_s machine seconds), checking limits every tick and calling `each` after it.
inline std::vector<Event> RunChecked(Machine& m, LimitChecker& check, double max_s = 600,
                                     const std::function<void()>& each = {}) {
  std::vector<Event> all;
  const std::uint64_t limit = m.ticks() + static_cast<std::uint64_t>(max_s / m.period());
  while (m.ticks() < limit && m.Step()) {
    check.Sample();
    if (each) each();
    for (auto& e : m.TakeEvents()) all.push_back(e);
  }
  for (auto& e : m.TakeEvents()) all.push_back(e);
  return all;
}

inline const Event* Find(const std::vector<Event>& ev, EventKind kind, std::uint64_t seg) {
  for (const auto& e : ev)
    if (e.kind == kind && e.segment_id == seg) return &e;
  return nullptr;
}

// Distance from p to segment [a, b] in XYZ.
inline double DistToSegment(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d d = b - a;
  const double l2 = d.squaredNorm();
  const double t = l2 > 0 ? std::clamp((p - a).dot(d) / l2, 0.0, 1.0) : 0.0;
  return (a + t * d - p).norm();
}

}  // namespace cell::servo::testing
