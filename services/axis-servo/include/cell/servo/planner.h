// Trajectory planner: look-ahead over queued path elements, producing the interpolated ("pre-filter")
// position every servo tick. Jerk limiting is done after interpolation by cell::servo::JerkFilter.
//
// Design (docs/axis-servo.md has the full argument):
//  * Every programmed line, arc or helix becomes a path element with a geometric speed cap (per-axis
//    velocity, centripetal acceleration, and the contour error the jerk filter adds on curves), a feed cap
//    (programmed feed x override) and a tangential acceleration limit chosen so that no axis exceeds its
//    acceleration limit.
//  * Continuous blocks (no exact stop) are blended: a corner between two lines gets a circular fillet whose
//    deviation from the corner is half the path tolerance; corners that cannot be filleted pass at a speed
//    whose one-tick velocity change fits the axis acceleration budget.
//  * A backward pass over the queue gives every element its exit speed; the queue always ends at rest, so
//    a starved queue decelerates safely. Each tick picks v = min(brake curve, v ± a·Ts, cap): discrete
//    velocity changes never exceed a·Ts.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "cell/servo/segment.h"

namespace cell::servo {

struct PlannerLimits {
  std::array<bool, kNumAxes> present{};
  AxisVector max_velocity = AxisVector::Zero();      // units/s (programmed feed clamp)
  AxisVector rapid = AxisVector::Zero();             // units/s
  AxisVector max_acceleration = AxisVector::Zero();  // units/s²
  double period = 0.001;                             // s
  double path_tolerance = 0.02;                      // mm
  double filter_time = 0.05;                         // s, length of the jerk filter (contour error on curves)
};

struct PathElement {
  bool arc = false;
  AxisVector p0 = AxisVector::Zero(), p1 = AxisVector::Zero();
  AxisVector u = AxisVector::Zero();  // line: dp/ds
  // arc: p(phi) = c + (r0 + dr*phi)(cos(phi) e1 + sin(phi) e2) + w*phi, phi = k*s
  AxisVector c = AxisVector::Zero(), e1 = AxisVector::Zero(), e2 = AxisVector::Zero(), w = AxisVector::Zero();
  double r0 = 0, dr = 0, sweep = 0, k = 0;
  double len = 0, orig_len = 0;
  double vgeom = 0;  // geometric speed cap, units/s
  double vfeed = 0;  // programmed speed, units/s, before override
  bool rapid = false;
  double at = 0;                  // tangential acceleration limit
  double v_junction = 0;          // geometric limit at the end (into the next element)
  double v_exit = 0;              // planned exit speed (backward pass)
  double v_entry = -1;            // planned entry limit (backward pass); -1 before the first pass
  bool stop_end = false;          // exact stop at the end
  bool wait_in_position = false;  // the next element waits until the machine is in position
  double settle = 0;              // in-position window for that wait (0: the machine's in_position)
  bool last_of_segment = true;
  bool probe = false;
  std::uint64_t seg = 0;
  double seg_offset = 0, seg_total = 0;  // for progress fractions

  AxisVector Position(double s) const;
  AxisVector Tangent(double s) const;  // dp/ds
};

class Planner {
 public:
  Planner(const PlannerLimits& limits, std::size_t capacity);

  // Adds a straight move from the current end of the path. feed: units/s (ignored for rapids).
  void AddLine(const AxisVector& end, double feed, bool rapid, bool exact_stop, std::uint64_t seg,
               bool probe = false);
  // Adds an arc/helix already converted to machine units (see Machine); `e` holds centre and basis.
  void AddArc(PathElement e, double feed, bool exact_stop, std::uint64_t seg);
  // Builds an arc element from programme data; returns false (and leaves `why`) when radii disagree.
  bool MakeArc(const AxisVector& start, const AxisVector& end, const std::array<double, 3>& center,
               ArcPlane plane, ArcDirection dir, std::uint32_t turns, PathElement& out,
               std::string& why) const;

  bool Full() const { return count_ + 2 >= elems_.size(); }
  bool Idle() const { return count_ == 0 && !waiting_; }
  bool Waiting() const { return waiting_; }  // stopped at an exact-stop end, waiting for in-position
  void Release() { waiting_ = false; }
  double WaitTolerance() const { return wait_tol_; }  // 0: the machine's in-position window
  const AxisVector& EndOfPath() const { return tail_; }
  const AxisVector& Position() const { return pos_; }
  double Speed() const { return v_; }

  // One servo tick: advances along the path and returns the new interpolated position.
  const AxisVector& Tick();

  void SetHold(bool hold) { hold_ = hold; }
  bool Holding() const { return hold_; }
  void SetOverrides(double feed, double rapid);
  // Stops as fast as the limits allow on the current element (probe trip). Later elements are kept.
  void StopOnCurrent();
  // Forgets all elements and restarts from `pos` at rest.
  void Flush(const AxisVector& pos);

  // Segment ids whose first element started / last element finished during the last Tick().
  struct Mark {
    std::uint64_t seg;
    bool finished;
    bool wait_in_position;
  };
  const std::vector<Mark>& Marks() const { return marks_; }
  // Segment currently interpolated and its fraction, if any.
  bool Current(std::uint64_t& seg, double& fraction) const;
  const PlannerLimits& limits() const { return lim_; }

 private:
  PathElement& At(std::size_t i) { return elems_[(head_ + i) % elems_.size()]; }
  const PathElement& At(std::size_t i) const { return elems_[(head_ + i) % elems_.size()]; }
  double Cap(const PathElement& e) const;
  void Append(PathElement e);
  void Link(PathElement& a, PathElement& b, bool a_is_current);
  void BackwardPass(std::size_t changed_from);  // elements from this index on may have changed (0: all)
  void FinishCurrent();

  PlannerLimits lim_;
  std::vector<PathElement> elems_;
  std::size_t head_ = 0, count_ = 0;  // element 0 is the current one
  double s_ = 0, v_ = 0;
  bool started_ = false;  // current element has begun
  bool waiting_ = false, hold_ = false;
  double wait_tol_ = 0;
  double feed_ovr_ = 1.0, rapid_ovr_ = 1.0;
  AxisVector pos_ = AxisVector::Zero(), tail_ = AxisVector::Zero();
  std::vector<Mark> marks_;
  PathElement pending_fillet_;
  bool has_pending_fillet_ = false;
};

}  // namespace cell::servo
