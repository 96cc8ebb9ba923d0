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
//  * Feed per revolution follows the spindle's actual speed; threads follow the spindle's angle
//    (docs/axis-servo.md, "Lathes").
#pragma once

#include <algorithm>
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

// A programmed feed: units/s, or units per spindle revolution (feed per revolution).
struct Feed {
  Feed(double r = 0, bool rev = false) : rate(r), per_rev(rev) {}  // NOLINT: a plain number is units/s
  double rate;
  bool per_rev;
};

// A thread element's synchronisation: after rho revolutions from its start the element has covered
// s = lead_k (lead rho + lead_change rho² / 2) (lead along the major axis, lead_k = path length per mm
// of it). The first thread of a chain waits for the spindle to pass start_angle (degrees). Kept beside
// the path elements, not in them: the interpolator's hot data stays small.
struct ThreadTrack {
  double lead = 0, lead_change = 0, lead_k = 0, start_angle = 0;
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
  double vfeed = 0;  // programmed speed, units/s (per_rev: units per spindle revolution), before override
  bool rapid = false;
  bool per_rev = false;           // (beside `rapid`: the fields Tick() reads share cache lines)
  bool sync = false;              // a thread: its synchronisation is a ThreadTrack in the slot beside it
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
  template <int N>
  void PositionInto(double s, AxisVector& p) const;
  AxisVector Tangent(double s) const;  // dp/ds
};

class Planner {
 public:
  Planner(const PlannerLimits& limits, std::size_t capacity);

  // Adds a straight move from the current end of the path (the feed is ignored for rapids).
  void AddLine(const AxisVector& end, Feed feed, bool rapid, bool exact_stop, std::uint64_t seg,
               bool probe = false);
  // Adds an arc/helix already converted to machine units (see Machine); `e` holds centre and basis.
  void AddArc(PathElement e, Feed feed, bool exact_stop, std::uint64_t seg);
  // Adds a thread: a straight move whose progress follows the spindle, `lead` (units per revolution,
  // changing by `lead_change` per revolution) along an axis whose travel is `major` units. A thread
  // directly after a thread continues its synchronisation; otherwise the path stops before it, waits for
  // the index pulse at `start_angle` (IndexPulse), accelerates and then tracks the spindle exactly. It ends
  // at rest (unless a thread follows and `exact_stop` is false), decelerating over the last v²/2a: the
  // incomplete thread.
  void AddThread(const AxisVector& end, double lead, double lead_change, double major, double start_angle,
                 bool exact_stop, std::uint64_t seg);
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

  void SetHold(bool hold) { hold_ = hold; }  // a thread being cut finishes first
  bool Holding() const { return hold_; }
  // Abort: a thread being cut leaves the spindle and decelerates like any move.
  void BreakSync();

  // The spindle for the next Tick(): revolutions turned (never decreasing) and speed (rev/s).
  void SetSpindle(double turned, double rev_per_s) {
    turned_ = turned;
    rps_ = rev_per_s;
    if (rps_ != planned_rps_) SpindleChanged();
  }
  // A thread waits for its index pulse at `*start_angle` degrees (not while held).
  bool AwaitingIndex(double* start_angle) const {
    if (sync_ != Sync::kAwaitIndex || hold_ || count_ == 0) return false;
    *start_angle = TrackAt(0).start_angle;
    return true;
  }
  // The spindle passed the start angle when it had turned `turned` revolutions (within this tick).
  void IndexPulse(double turned);
  // A thread is waiting for its index pulse or being cut: the spindle speed must not change.
  bool InThread() const { return sync_ != Sync::kNone; }
  // The current element is a feed move (not a rapid) and the path is not held at rest.
  bool OnFeedMove() const { return count_ > 0 && !At(0).rapid && !(hold_ && v_ == 0); }
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
  const ThreadTrack& TrackAt(std::size_t i) const { return tracks_[(head_ + i) % tracks_.size()]; }
  double Cap(const PathElement& e) const {
    if (!(e.rapid | e.sync | e.per_rev)) return std::min(e.vgeom, e.vfeed * feed_ovr_);
    if (e.rapid) return e.vgeom * rapid_ovr_;
    if (e.sync) return e.vgeom;  // the spindle sets a thread's speed; the feed override does not act
    return std::min(e.vgeom, e.vfeed * rps_ * feed_ovr_);  // feed per revolution
  }
  void SpindleChanged();
  void Append(PathElement& e);  // by reference: an element is some 600 bytes, copied once into its slot
  // Links `b` after `a`; true when it built a fillet between them in the slot after the last element.
  bool Link(PathElement& a, PathElement& b, bool a_is_current);
  void BackwardPass(std::size_t changed_from);  // elements from this index on may have changed (0: all)
  void FinishCurrent();
  PathElement LineElement(const AxisVector& end, bool rapid, bool exact_stop) const;
  bool TickThread();  // false: the thread left synchronisation, the ordinary interpolator takes over

  // pos_ = the position at s on e, over the axes the machine can move (PathElement::PositionInto).
  void PositionAt(const PathElement& e, double s);

  PlannerLimits lim_;
  bool co_axes_ = true;  // the machine has U, V or W
  // The present axes' indices in axis order, for the per-block loops over axes.
  std::array<int, kNumAxes> axes_{};
  int num_axes_ = 0;
  std::vector<PathElement> elems_;
  std::vector<ThreadTrack> tracks_;   // the same slots as elems_, used by thread elements
  std::size_t head_ = 0, count_ = 0;  // element 0 is the current one
  double s_ = 0, v_ = 0;
  bool started_ = false;  // current element has begun
  bool waiting_ = false, hold_ = false;
  double wait_tol_ = 0;
  double feed_ovr_ = 1.0, rapid_ovr_ = 1.0;
  AxisVector pos_ = AxisVector::Zero(), tail_ = AxisVector::Zero();
  std::vector<Mark> marks_;
  // Spindle and thread synchronisation.
  enum class Sync { kNone, kAwaitIndex, kTracking, kBraking };
  Sync sync_ = Sync::kNone;
  bool break_sync_ = false;
  double turned_ = 0, rps_ = 0, planned_rps_ = 0;
  double pulse_ = 0;  // turned revolutions at the index pulse
  double ramp_ = 0;   // revolutions of the acceleration ramp after the pulse
  double rho0_ = 0;   // synchronised revolutions at the start of the current element
};

}  // namespace cell::servo
