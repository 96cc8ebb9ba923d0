#include "cell/servo/planner.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace cell::servo {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Fraction of an axis's acceleration left for tangential acceleration on elements that may end in a
// kink; the rest is the budget for the one-tick direction change at the kink.
constexpr double kKinkShare = 0.2;
constexpr double kAccelMargin = 0.98;  // discretisation margin (chords, ticks straddling two elements)
// Split of the path tolerance: fillet deviation from the corner, jerk-filter rounding; the rest is left
// for the servo's contour error.
constexpr double kFilletShare = 0.4;
constexpr double kFilterShare = 0.4;

bool LinearOnly(const AxisVector& v) {
  return v.segment<3>(kA).squaredNorm() == 0.0;
}

// The linear axes X Y Z U V W of `v`: a corner's angle and a fillet's plane are measured in them.
Eigen::Matrix<double, 6, 1> LinearPart(const AxisVector& v) {
  Eigen::Matrix<double, 6, 1> l;
  l.head<3>() = v.head<3>();
  l.tail<3>() = v.tail<3>();
  return l;
}

}  // namespace

AxisVector PathElement::Position(double s) const {
  AxisVector p = p0;
  PositionInto<kNumAxes>(s, p);
  return p;
}

// Every period: the first N axes of the position at s into `p` (N = 6 on a machine without U V W, whose
// co-axes stand still; nine-wide arithmetic would cost such a machine 2 % more instructions per period).
template <int N>
void PathElement::PositionInto(double s, AxisVector& p) const {
  if (!arc) {
    p.head<N>() = p0.head<N>() + u.head<N>() * s;
    return;
  }
  const double phi = k * s;
  // In two steps, the same arithmetic: each is small enough for Eigen and the compiler to inline.
  p.head<N>() = std::cos(phi) * e1.head<N>() + std::sin(phi) * e2.head<N>();
  p.head<N>() = c.head<N>() + (r0 + dr * phi) * p.head<N>() + w.head<N>() * phi;
}

AxisVector PathElement::Tangent(double s) const {
  if (!arc) return u;
  const double phi = k * s;
  const double cs = std::cos(phi), sn = std::sin(phi);
  return k * (dr * (cs * e1 + sn * e2) + (r0 + dr * phi) * (-sn * e1 + cs * e2) + w);
}

Planner::Planner(const PlannerLimits& limits, std::size_t capacity)
    : lim_(limits),
      co_axes_(limits.present[kU] || limits.present[kV] || limits.present[kW]),
      elems_(std::max<std::size_t>(capacity, 8)),
      tracks_(elems_.size()) {
  for (int i = 0; i < kNumAxes; ++i)
    if (lim_.present[i]) axes_[num_axes_++] = i;
  marks_.reserve(elems_.size() + 4);
}

void Planner::SetOverrides(double feed, double rapid) {
  feed_ovr_ = std::clamp(feed, 0.0, 2.0);
  rapid_ovr_ = std::clamp(rapid, 0.0, 1.0);
  BackwardPass(0);
}

PathElement Planner::LineElement(const AxisVector& end, bool rapid, bool stop_end) const {
  PathElement e;
  e.p0 = tail_;
  AxisVector d = end - tail_;
  for (int i = 0; i < kNumAxes; ++i)
    if (!lim_.present[i]) d[i] = 0;
  e.p1 = tail_ + d;
  const double len = PathLength(d);
  e.len = e.orig_len = e.seg_total = len;
  e.rapid = rapid;
  e.stop_end = e.wait_in_position = stop_end;
  if (len < 1e-9) return e;
  e.u = d / len;
  e.vgeom = kInf;
  e.at = kInf;
  const AxisVector& vlim = rapid ? lim_.rapid : lim_.max_velocity;
  for (int n = 0; n < num_axes_; ++n) {  // an absent axis has u 0
    const int i = axes_[n];
    const double ui = std::abs(e.u[i]);
    if (ui < 1e-12) continue;
    e.vgeom = std::min(e.vgeom, vlim[i] / ui);
    e.at = std::min(e.at, lim_.max_acceleration[i] / ui);
  }
  e.at *= kAccelMargin * (stop_end ? 1.0 : 1.0 - kKinkShare);
  return e;
}

void Planner::AddLine(const AxisVector& end, Feed feed, bool rapid, bool exact_stop, std::uint64_t seg,
                      bool probe) {
  PathElement e = LineElement(end, rapid, exact_stop || rapid || probe);
  e.vfeed = rapid ? kInf : feed.rate;
  e.per_rev = !rapid && feed.per_rev;
  e.probe = probe;
  e.seg = seg;
  if (e.len < 1e-9) {
    // A zero-length block (duplicate point): a transparent marker that completes when passed, unless it
    // demands a stop.
    e.len = 0;
    e.vgeom = kInf;
    e.vfeed = kInf;
    e.per_rev = false;
    e.rapid = false;
    e.at = 1e9;
    e.v_junction = kInf;
  }
  Append(e);
}

void Planner::AddThread(const AxisVector& end, double lead, double lead_change, double major,
                        double start_angle, bool exact_stop, std::uint64_t seg) {
  // Full tangential acceleration: a thread starts and ends at rest, or passes into the next thread at
  // the spindle's pace whatever the corner (the lead wins, as on a real lathe).
  PathElement e = LineElement(end, false, true);
  // Link() decides: stop, or go on into a chained thread; exact_stop always stops (the next thread waits for
  // its own start angle).
  e.stop_end = e.wait_in_position = exact_stop;
  e.seg = seg;
  e.sync = true;
  e.vfeed = kInf;
  const double lead_k = major > 0 ? e.len / major : 0;
  Append(e);  // no fillet before or after a thread: it is the last element placed
  tracks_[(head_ + count_ - 1) % tracks_.size()] = {lead, lead_change, lead_k, start_angle};
}

bool Planner::MakeArc(const AxisVector& start, const AxisVector& end, const std::array<double, 3>& center,
                      ArcPlane plane, ArcDirection dir, std::uint32_t turns, PathElement& e,
                      std::string& why) const {
  // An arc turns in a plane of two of the linear axes, in the program's order. The centre is x y z, a
  // co-axis's (U V W) in the slot of its parallel axis (a (Z, U) arc's U centre is center[kX]).
  const int i = plane.first, j = plane.second;
  const auto linear = [](int a) { return a <= kZ || (a >= kU && a < kNumAxes); };
  if (!linear(i) || !linear(j) || i == j) {
    const auto name = [](int a) { return a < kNumAxes ? std::string(1, "XYZABCUVW"[a]) : std::string("?"); };
    why =
        fmt::format("arc plane {}{} is not two of the machine's linear axes (X Y Z U V W)", name(i), name(j));
    return false;
  }
  // A co-axis the machine lacks stands at 0 (the DDS receiver refuses moving it): an arc must not swing it.
  for (int a : {i, j}) {
    if (a >= kU && !lim_.present[a]) {
      why = fmt::format("arc plane {}{}: the station has no {} axis", "XYZABCUVW"[i], "XYZABCUVW"[j],
                        "XYZABCUVW"[a]);
      return false;
    }
  }
  const auto slot = [](int a) { return a >= kU ? a - kU : a; };
  const double ci = center[slot(i)], cj = center[slot(j)];
  const double x0 = start[i] - ci, y0 = start[j] - cj, x1 = end[i] - ci, y1 = end[j] - cj;
  const double r0 = std::hypot(x0, y0), r1 = std::hypot(x1, y1);
  if (r0 < 1e-6 || r1 < 1e-6) {
    why = "arc radius is zero";
    return false;
  }
  if (std::abs(r1 - r0) > 0.01 + 1e-4 * r0) {
    why = fmt::format("arc start radius {:.4f} and end radius {:.4f} differ", r0, r1);
    return false;
  }
  const double a0 = std::atan2(y0, x0), a1 = std::atan2(y1, x1);
  const bool ccw = dir == ArcDirection::kCCW;
  double sweep = ccw ? a1 - a0 : a0 - a1;
  while (sweep <= 1e-9) sweep += 2 * M_PI;
  while (sweep > 2 * M_PI + 1e-9) sweep -= 2 * M_PI;
  sweep += 2 * M_PI * turns;
  e = PathElement{};
  e.arc = true;
  e.p0 = start;
  e.p1 = end;
  e.e1.setZero();
  e.e2.setZero();
  e.e1[i] = x0 / r0;
  e.e1[j] = y0 / r0;
  e.e2[i] = ccw ? -e.e1[j] : e.e1[j];
  e.e2[j] = ccw ? e.e1[i] : -e.e1[i];
  e.c = start;
  e.c[i] = ci;
  e.c[j] = cj;
  e.w = end - start;
  e.w[i] = 0;
  e.w[j] = 0;
  for (int a = 0; a < kNumAxes; ++a)
    if (!lim_.present[a]) e.w[a] = 0;
  e.w /= sweep;
  e.r0 = r0;
  e.dr = (r1 - r0) / sweep;
  e.sweep = sweep;
  const double rm = 0.5 * (r0 + r1);
  e.len = e.orig_len = sweep * std::sqrt(rm * rm + e.dr * e.dr + e.w.squaredNorm());
  e.k = sweep / e.len;
  return true;
}

void Planner::AddArc(PathElement e, Feed feed, bool exact_stop, std::uint64_t seg) {
  e.p0 = tail_;
  e.vfeed = feed.rate;
  e.per_rev = feed.per_rev;
  e.stop_end = exact_stop;
  e.wait_in_position = exact_stop;
  e.seg = seg;
  e.seg_total = e.len;
  // Geometric limits: per-axis speed, centripetal acceleration, jerk-filter contour error.
  const double r = e.r0 + 0.5 * e.dr * e.sweep;
  const double rk = std::max(e.r0, e.r0 + e.dr * e.sweep) * e.k;  // |dp_plane/ds| upper bound
  double v = kInf, aplane = kInf;
  for (int n = 0; n < num_axes_; ++n) {
    const int a = axes_[n];
    const bool in_plane = e.e1[a] != 0.0 || e.e2[a] != 0.0;
    const double rate = in_plane ? rk : std::abs(e.w[a]) * e.k;
    if (rate > 1e-12) v = std::min(v, lim_.max_velocity[a] / rate);
    if (in_plane) aplane = std::min(aplane, lim_.max_acceleration[a]);
  }
  // Centripetal acceleration (v r k)^2 / r = v^2 r k^2 <= 0.8 aplane.
  v = std::min(v, std::sqrt(0.8 * aplane / (r * e.k * e.k)));
  // A moving average of length L over a circle pulls it in by v_p^2 L^2 / (24 r); allow half the tolerance.
  const double L = lim_.filter_time;
  if (L > 0) v = std::min(v, std::sqrt(24.0 * r * kFilterShare * lim_.path_tolerance) / L / (r * e.k));
  e.vgeom = v;
  const double acent = v * v * r * e.k * e.k;
  double at = kInf;
  for (int n = 0; n < num_axes_; ++n) {
    const int a = axes_[n];
    const bool in_plane = e.e1[a] != 0.0 || e.e2[a] != 0.0;
    if (in_plane)
      at = std::min(at, (lim_.max_acceleration[a] - acent) / rk);
    else if (std::abs(e.w[a]) * e.k > 1e-12)
      at = std::min(at, lim_.max_acceleration[a] / (std::abs(e.w[a]) * e.k));
  }
  e.at = at * kAccelMargin * (e.stop_end ? 1.0 : 1.0 - kKinkShare);
  Append(e);
}

bool Planner::Link(PathElement& a, PathElement& b, bool a_is_current) {
  if (a.sync || b.sync) {
    // A thread after a thread that has not begun to stop continues its synchronisation at the spindle's
    // pace; any other thread starts from rest (it waits for the index pulse), and ends at rest.
    if (a.sync && b.sync && !a.stop_end) {
      a.v_junction = kInf;
    } else {
      a.stop_end = a.wait_in_position = true;
      a.v_junction = 0;
    }
    return false;
  }
  if (a.stop_end || a.len == 0 || b.len == 0) {
    a.v_junction = 0;
    return false;
  }
  const AxisVector ta = a.Tangent(a.len), tb = b.Tangent(0);
  // The jerk filter averages the path over L seconds. Near a corner of deflection theta passed at speed v
  // with tangential acceleration a around it, the average leaves the path by about
  //   sin(theta/2) * (v L / 4 + a L^2 / 24).
  // When the acceleration term alone uses up half the filter's share of the tolerance, blending cannot
  // stay within it: the corner becomes a stop that waits until the filter has flushed (as controls with
  // post-interpolation filters do). Otherwise v_corner bounds the speed through the corner.
  const double L = lim_.filter_time, eps = kFilterShare * lim_.path_tolerance;
  double v_corner = kInf, s2 = 0;
  const Eigen::Matrix<double, 6, 1> la = LinearPart(ta), lb = LinearPart(tb);
  if (L > 0 && la.norm() > 1e-9 && lb.norm() > 1e-9) {
    const double c = std::clamp(la.normalized().dot(lb.normalized()), -1.0, 1.0);
    s2 = std::sin(0.5 * std::acos(c));
    if (s2 > 1e-9) {
      const double acc_err = std::max(a.at, b.at) * L * L / 24;
      if (acc_err * s2 > 0.5 * eps) {
        a.stop_end = true;
        a.wait_in_position = true;
        a.settle = eps;
        a.v_junction = 0;
        return false;
      }
      v_corner = (eps / s2 - acc_err) * 4 / L;
    }
  }
  // Blend two linear-axis lines with a circular fillet within half the path tolerance.
  if (!a.arc && !b.arc && LinearOnly(a.u) && LinearOnly(b.u) && !a.probe && !b.probe) {
    const double cos_t = std::clamp(a.u.dot(b.u), -1.0, 1.0);
    const double theta = std::acos(cos_t);
    if (theta > 1e-4 && theta < M_PI * 0.97) {
      const double half = 0.5 * theta;
      const double d = kFilletShare * lim_.path_tolerance;
      const double cos_half = std::cos(half);
      double R = d * cos_half / (1 - cos_half);
      double T = R * std::tan(half);
      double tmax = 0.5 * std::min(a.orig_len, b.orig_len);
      if (a_is_current) {
        // The interpolator must not have passed the fillet's start yet (plus its braking distance).
        const double room = a.len - s_ - v_ * v_ / (2 * a.at) - 2 * v_ * lim_.period;
        tmax = std::min(tmax, room);
      }
      if (T > tmax) {
        T = tmax;
        R = T / std::tan(half);
      }
      if (T > 1e-6 && R > 1e-6) {
        const AxisVector corner = a.p1;
        // Built in its slot, the one after the queue's last element (Append places `b` after it).
        PathElement& f = elems_[(head_ + count_) % elems_.size()];
        f = PathElement{};
        f.arc = true;
        AxisVector n = b.u - cos_t * a.u;
        n.normalize();
        f.p0 = corner - a.u * T;
        f.p1 = corner + b.u * T;
        f.c = f.p0 + n * R;
        f.e1 = -n;
        f.e2 = a.u;
        f.w.setZero();
        f.r0 = R;
        f.dr = 0;
        f.sweep = theta;
        f.len = f.orig_len = R * theta;
        f.k = 1.0 / R;
        f.rapid = a.rapid;
        f.per_rev = a.per_rev && b.per_rev;
        // Per-revolution and per-minute feeds meet: the fillet takes the lower at today's spindle speed.
        f.vfeed = a.per_rev == b.per_rev
                      ? std::min(a.vfeed, b.vfeed)
                      : std::min(a.per_rev ? a.vfeed * rps_ : a.vfeed, b.per_rev ? b.vfeed * rps_ : b.vfeed);
        f.seg = a.seg;
        f.probe = false;
        f.stop_end = false;
        double v = kInf, am = kInf;
        for (int k = 0; k < num_axes_; ++k) {
          const int i = axes_[k];
          if (std::abs(f.e1[i]) + std::abs(f.e2[i]) < 1e-12) continue;  // the lines are linear only
          v = std::min(v, lim_.max_velocity[i]);
          am = std::min(am, lim_.max_acceleration[i]);
        }
        v = std::min(v, std::sqrt(0.8 * am * R));
        // Jerk-filter rounding: the circle estimate v^2 L^2 / (24 R) while the filter window lies on the
        // fillet, the corner estimate once it spans the corner; both must hold.
        if (L > 0) v = std::min({v, std::sqrt(24.0 * R * eps) / L, v_corner});
        f.vgeom = v;
        f.at = (am - v * v / R) * kAccelMargin * (1.0 - kKinkShare);
        // Trim the lines.
        a.len -= T;
        a.p1 = f.p0;
        a.last_of_segment = false;
        f.seg_offset = a.seg_offset + a.len;
        a.seg_total = f.seg_total = a.seg_offset + a.len + f.len;
        b.p0 = f.p1;
        b.len -= T;
        b.seg_total = b.len;
        a.v_junction = std::min({a.vgeom, f.vgeom});
        f.v_junction = std::min({f.vgeom, b.vgeom});
        return true;
      }
    }
  }
  // A kink: the direction changes within one tick. Keep v*|dt_i| within the axis's kink budget and the
  // jerk filter's corner rounding (about v L sin(theta/2) / 4) within half the tolerance.
  const AxisVector dt = tb - ta;
  double v = std::min(a.vgeom, b.vgeom);
  for (int n = 0; n < num_axes_; ++n)
    if (const int i = axes_[n]; std::abs(dt[i]) > 1e-12)
      v = std::min(v, kKinkShare * lim_.max_acceleration[i] * lim_.period / std::abs(dt[i]));
  a.v_junction = std::min(v, v_corner);
  return false;
}

void Planner::Append(PathElement& e) {
  e.p0 = tail_;
  // Link with the last element that has a length, across transparent zero-length markers.
  std::size_t prev_i = count_;
  for (std::size_t n = count_; n-- > 0;) {
    const PathElement& q = At(n);
    if (q.len > 0) {
      prev_i = n;
      break;
    }
    if (q.stop_end) break;  // a marker that stops: start from rest
  }
  const std::size_t changed_from = count_ > 0 ? count_ - 1 : 0;
  std::size_t changed = changed_from;
  if (prev_i < count_ && e.len > 0) {
    PathElement& prev = At(prev_i);
    changed = prev_i;
    if (Link(prev, e, prev_i == 0 && started_)) ++count_;  // Link() built a fillet in the next slot
  }
  elems_[(head_ + count_) % elems_.size()] = e;
  ++count_;
  tail_ = e.p1;
  BackwardPass(std::min(changed, changed_from));
}

void Planner::BackwardPass(std::size_t changed_from) {
  double v_next_entry = 0;  // entry speed allowed by the element after n
  for (std::size_t n = count_; n-- > 0;) {
    PathElement& e = At(n);
    const bool last = n + 1 == count_;
    const double cap = Cap(e);
    const double exit = (last || e.stop_end) ? 0.0 : std::min({e.v_junction, v_next_entry, cap});
    double entry = std::min(std::max(cap, 0.0), std::sqrt(exit * exit + 2 * e.at * e.len));
    if (e.rapid && rapid_ovr_ == 0) entry = 0;
    // Elements before `changed_from` only depend on their successor's entry speed: once an element's
    // plan is unchanged, everything before it is too.
    const bool same = exit == e.v_exit && entry == e.v_entry;
    e.v_exit = exit;
    e.v_entry = entry;
    if (same && n < changed_from) break;
    v_next_entry = entry;
  }
}

void Planner::StopOnCurrent() {
  if (count_ == 0) return;
  PathElement& e = At(0);
  const double brake = v_ * v_ / (2 * e.at) + v_ * lim_.period;
  e.len = std::min(e.len, s_ + brake);
  e.p1 = e.Position(e.len);
  e.stop_end = true;
  e.wait_in_position = true;
  e.last_of_segment = true;
  count_ = 1;
  tail_ = e.p1;
  BackwardPass(0);
}

void Planner::Flush(const AxisVector& pos) {
  count_ = 0;
  head_ = 0;
  s_ = v_ = 0;
  started_ = false;
  waiting_ = false;
  sync_ = Sync::kNone;
  break_sync_ = false;
  pos_ = tail_ = pos;
}

void Planner::FinishCurrent() {
  const PathElement& e = At(0);
  if (e.sync) sync_ = Sync::kNone;
  if (e.last_of_segment) marks_.push_back({e.seg, true, e.wait_in_position});
  if (e.wait_in_position) {
    waiting_ = true;
    wait_tol_ = e.settle;
  }
  head_ = (head_ + 1) % elems_.size();
  --count_;
  started_ = false;
}

bool Planner::Current(std::uint64_t& seg, double& fraction) const {
  if (count_ == 0) return false;
  const PathElement& e = At(0);
  seg = e.seg;
  fraction = e.seg_total > 0 ? std::clamp((e.seg_offset + s_) / e.seg_total, 0.0, 1.0) : 1.0;
  return true;
}

void Planner::PositionAt(const PathElement& e, double s) {
  if (co_axes_)
    e.PositionInto<kNumAxes>(s, pos_);
  else
    e.PositionInto<kU>(s, pos_);
}

const AxisVector& Planner::Tick() {
  marks_.clear();
  if (waiting_ || count_ == 0) return pos_;
  const double ts = lim_.period;
  PathElement* e = &At(0);
  if (!started_) {
    started_ = true;
    if (e->seg_offset == 0) marks_.push_back({e->seg, false, false});
  }
  const bool sync = e->sync;  // (a chained thread that TickThread() moves on to is a thread too)
  if (sync) [[unlikely]] {
    if (sync_ != Sync::kBraking && TickThread()) return pos_;
    e = &At(0);
  }
  // Speed for this tick from the current element's brake curve, acceleration limit and cap.
  const double a = e->at;
  const double d = std::max(e->len - s_, 0.0);
  const double vb = -a * ts + std::sqrt(a * a * ts * ts + e->v_exit * e->v_exit + 2 * a * d);
  // A thread is cut to its end whatever the feed hold (abort apart).
  const double cap = hold_ && (!sync || break_sync_) ? 0.0 : Cap(*e);
  double vn = std::min(vb, std::max(v_ - a * ts, std::min(v_ + a * ts, cap)));
  vn = std::max(vn, 0.0);
  double dist = vn * ts;
  // Distribute the tick's distance over the elements it reaches.
  while (true) {
    if (s_ + dist < e->len - 1e-9) {
      s_ += dist;
      PositionAt(*e, s_);
      break;
    }
    dist -= std::max(e->len - s_, 0.0);
    const bool stop_here = e->stop_end || count_ == 1;
    pos_ = e->p1;
    s_ = 0;
    FinishCurrent();
    if (stop_here || waiting_) {
      vn = 0;
      break;
    }
    e = &At(0);
    started_ = true;
    if (e->seg_offset == 0) marks_.push_back({e->seg, false, false});
    if (e->sync) {  // a thread starts from rest at its start point (behind a zero-length marker)
      vn = 0;
      break;
    }
  }
  v_ = vn;
  return pos_;
}

// ---- Threads: progress as a function of the spindle's revolutions.

void Planner::SpindleChanged() {
  // Feeds per revolution follow the spindle (Cap() reads it every tick); the exit speeds planned with
  // it are re-planned when it has changed by 1 %.
  if (std::abs(rps_ - planned_rps_) > 0.01 * planned_rps_ || (rps_ > 0) != (planned_rps_ > 0)) {
    planned_rps_ = rps_;
    if (count_ > 0) BackwardPass(0);
  }
}

void Planner::IndexPulse(double turned) {
  if (sync_ != Sync::kAwaitIndex || count_ == 0) return;
  const PathElement& e = At(0);
  const ThreadTrack& th = TrackAt(0);
  sync_ = Sync::kTracking;
  pulse_ = turned;
  rho0_ = 0;
  // The axes cannot jump to the spindle's pace: they accelerate at the element's limit over ramp_
  // revolutions, progress rho = R²/(2 ramp) after R revolutions, then rho = R - ramp/2, exactly in step.
  // The lag (ramp/2 revolutions) is the same on every pass at the same speed: same groove.
  const double v = th.lead_k * th.lead * rps_;
  ramp_ = e.at > 0 ? rps_ * v / e.at : 0;
}

void Planner::BreakSync() {
  break_sync_ = true;
  if (sync_ == Sync::kTracking && count_ > 0) {
    At(0).stop_end = At(0).wait_in_position = true;
    sync_ = Sync::kBraking;
    BackwardPass(0);
  }
}

bool Planner::TickThread() {
  const double ts = lim_.period;
  if (sync_ == Sync::kNone) sync_ = Sync::kAwaitIndex;  // the first thread of a chain: wait for the pulse
  if (sync_ == Sync::kAwaitIndex) {
    v_ = 0;
    return true;
  }
  const double r = std::max(turned_ - pulse_, 0.0);
  const double rho = r < ramp_ ? r * r / (2 * ramp_) : r - 0.5 * ramp_;
  const double drho = r < ramp_ ? r / ramp_ : 1.0;  // d rho / d r
  PathElement* e = &At(0);
  while (true) {
    const ThreadTrack& th = TrackAt(0);
    const double local = rho - rho0_;
    const double st = th.lead_k * (th.lead * local + 0.5 * th.lead_change * local * local);
    const bool chained = count_ > 1 && At(1).sync && !e->stop_end;
    if (!chained) {
      // Leave the spindle where the remaining travel is the braking distance (the incomplete thread).
      const double a = e->at, d = std::max(e->len - s_, 0.0);
      const double vb = -a * ts + std::sqrt(a * a * ts * ts + 2 * a * d);
      if (st - s_ > vb * ts || st >= e->len) {
        e->stop_end = e->wait_in_position = true;
        sync_ = Sync::kBraking;
        BackwardPass(0);
        return false;
      }
    }
    if (st < e->len || !chained) {
      s_ = st;
      PositionAt(*e, s_);
      v_ = th.lead_k * (th.lead + th.lead_change * local) * rps_ * drho;
      return true;
    }
    // Into the next thread of the chain: it starts where this one has covered its length.
    const double d = e->len / th.lead_k, l0 = th.lead, dl = th.lead_change;
    rho0_ += std::abs(dl) > 1e-12 ? (std::sqrt(l0 * l0 + 2 * dl * d) - l0) / dl : d / l0;
    FinishCurrent();
    sync_ = Sync::kTracking;
    s_ = 0;
    e = &At(0);
    started_ = true;
    if (e->seg_offset == 0) marks_.push_back({e->seg, false, false});
  }
}

}  // namespace cell::servo
