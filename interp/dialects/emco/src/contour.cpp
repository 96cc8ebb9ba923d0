// The EMCO look-ahead stages on the core's offset-path geometry: chamfer/radius insertion between two G01
// lines (DC 5.10, manual ln 55-116) and tool-nose radius compensation G41/G42 (ln 2357-3118): the approach
// (neutral and below 180 degrees: the nose centre straight to the normal of the next path at its start;
// above 180: to the normal of the approach path, then round the point on an arc of the nose radius), the
// corners (inside: the intersection of the equidistant paths; outside: an arc round the programmed point),
// the departure (the theoretical tip to its programmed point; above 180 degrees the held block first arcs
// round its end point onto the normal of the departure path) and ALARM 570.
#include <fmt/format.h>

#include <cmath>

#include "interp_internal.h"

namespace cell::interp::emco {

namespace {

constexpr double kDeg = 180.0 / kPi;

Vec2 Unit(Vec2 v) {
  double n = geom::Norm(v);
  return n < 1e-12 ? Vec2{1, 0} : Vec2{v.x / n, v.y / n};
}

}  // namespace

// ---------------------------------------------------------------------------------------------------------
// Chamfer / radius insertion

void CornerInsert::Hold(Move&& m, Vec2 start, double size, bool chamfer) {
  double trim = 0;
  if (held_) {
    // A chain of corners: this line closes the held corner and holds its own. It is not written here: it
    // starts where the first insertion ends and ends where the second one starts (each laid symmetrically
    // into its corner, ln 77-84).
    Item it;
    it.m = m;
    trim = Close(it);
  }
  held_ = true;
  line_ = std::move(m);
  start_ = start;
  trim_start_ = trim;
  size_ = size;
  chamfer_ = chamfer;
}

void CornerInsert::Take(Item&& it) {
  if (!it.is_move) {
    after_.push_back(std::move(it));
    return;
  }
  Close(it);
  out_(std::move(it));
}

double CornerInsert::Close(const Item& it) {
  held_ = false;
  Vec2 c = line_.end, e = it.m.end;
  double len_a = geom::Norm(c - start_), len_b = geom::Norm(e - c);
  if (len_a < 1e-9 || len_b < 1e-9) Alarm(384, it.m.col, "a line of the corner has no length");
  Vec2 da = Unit(c - start_), db = Unit(e - c);
  double cross = geom::Cross(da, db), dot = geom::Dot(da, db);
  if (std::fabs(cross) < 1e-9) Alarm(384, it.m.col, "the two lines do not form a corner");
  double turn = std::atan2(std::fabs(cross), dot);  // radians, (0, pi)
  double t = chamfer_ ? size_ : size_ * std::tan(turn / 2);
  if (t > std::min(len_a, len_b) + 1e-9) {
    Alarm(
        389, it.m.col,
        fmt::format("{:.3f} mm back from the corner, the shorter line is {:.3f}", t, std::min(len_a, len_b)));
  }
  // In a chain the held line has lost `trim_start_` to the insertion before it; the two must not overlap.
  if (trim_start_ + t > len_a + 1e-9) {
    Alarm(389, it.m.col,
          fmt::format("{:.3f} + {:.3f} mm back from the two corners of a {:.3f} mm line", trim_start_, t,
                      len_a));
  }
  Vec2 p1 = c + (-t) * da, p2 = c + t * db;
  Item first;
  first.m = line_;
  first.m.end = p1;
  out_(std::move(first));
  Item ins;
  ins.m = line_;
  ins.m.end = p2;
  if (!chamfer_) {
    Vec2 n = cross > 0 ? Vec2{-da.y, da.x} : Vec2{da.y, -da.x};  // toward the inside of the turn
    ins.m.kind = Move::kArc;
    ins.m.center = p1 + size_ * n;
    ins.m.cw = cross < 0;
    ins.m.sweep = turn * kDeg;
  }
  out_(std::move(ins));
  while (!after_.empty()) {
    out_(std::move(after_.front()));
    after_.pop_front();
  }
  return t;
}

// ---------------------------------------------------------------------------------------------------------
// Tool-nose radius compensation

void NoseComp::Select(int side, double radius, Vec2 tip_offset, Vec2 from, bool suppress_570) {
  state_ = kSelectPending;
  side_ = side;
  r_ = radius;
  tip_ = tip_offset;
  prog_ = from;
  suppress_570_ = suppress_570;
  has_held_ = false;
}

geom::Path NoseComp::PathOf(const Move& m, Vec2 start) const {
  geom::Path p;
  p.start = start;
  p.end = m.end;
  if (m.kind == Move::kArc) {
    p.arc = true;
    p.center = m.center;
    p.cw = m.cw;
    p.sweep = m.sweep;
  }
  return p;
}

void NoseComp::Check570(bool ok) {
  if (!ok && !suppress_570_) Alarm(570, col_);
}

void NoseComp::Emit(const Move& m, Vec2 end, const Vec2* center, double sweep) {
  Item it;
  it.m = m;
  it.m.end = end + tip_;
  if (center) it.m.center = *center + tip_;
  it.m.sweep = sweep;
  Put(std::move(it));
}

void NoseComp::FillArc(const geom::Corner& k, const Move& like) {
  Item it;
  it.m = like;
  it.m.end = k.b_start + tip_;
  if (like.kind == Move::kRapid) {
    Put(std::move(it));  // between rapid moves the nose goes round the corner at rapid, on the chord
    return;
  }
  it.m.kind = Move::kArc;
  it.m.center = held_.path.end + tip_;
  it.m.cw = k.fill_cw;
  it.m.sweep = k.fill_sweep;
  Put(std::move(it));
}

// A written move is final once the move after it has passed its own checks (the control knows "the previous
// and the next set", ln 2996): an ALARM 570 found at the next corner stops the run before the corner leading
// into the failing move (emco.md judgement call 34; KT-APL's call 88, Balt-System's call 49).
void NoseComp::Settle() {
  while (!staged_.empty()) {
    out_(std::move(staged_.front()));
    staged_.pop_front();
  }
}

// What was held behind the released move follows it.
void NoseComp::PutAfter() {
  while (!after_.empty()) {
    Put(std::move(after_.front()));
    after_.pop_front();
  }
}

// The held move ends at `end` (nose centre), an arc cut back by `trim_end` degrees; then what was held
// behind it.
void NoseComp::Release(Vec2 end, double trim_end) {
  const geom::Path& a = held_.path;
  if (a.arc) {
    Check570(geom::OffsetRadiusAtEnd(a, r_, side_) > 1e-9);
    double sweep = a.sweep - held_.trim_start - trim_end;
    Check570(sweep > -1e-6 || a.sweep >= 360);
    Settle();
    Emit(held_.m, end, &a.center, std::max(0.0, sweep));
  } else {
    if (!held_.approach) Check570(geom::RemainingLength(a, r_, side_, held_.trim_start, trim_end) > -1e-6);
    Settle();
    Emit(held_.m, end, nullptr, 0);
  }
  has_held_ = false;
}

void NoseComp::Take(Item&& it) {
  if (!it.is_move || state_ == kOff) {
    if (has_held_) {
      after_.push_back(std::move(it));
    } else {
      Put(std::move(it));
      if (state_ == kOff) Settle();
    }
    return;
  }
  Move& m = it.m;
  col_ = m.col;
  geom::Path b = PathOf(m, prog_);
  if (!b.arc && geom::Norm(b.end - b.start) < geom::kTiny) return;      // no travel in the plane
  if (b.arc) Check570(geom::OffsetRadiusAtStart(b, r_, side_) > 1e-9);  // an arc smaller than the nose
  if (state_ == kSelectPending) {
    held_ = Held{b, m, true, 0};
    has_held_ = true;
    state_ = kOn;
    prog_ = m.end;
    return;
  }
  const geom::Path& a = held_.path;
  geom::Corner k = geom::ComputeCorner(a, b, r_, side_, false);
  bool outside = k.kind == geom::Corner::kAway && k.fill_in;
  // Going back the way it came is the "angle below 180 degrees" case of the approach and the departure (the
  // threshold examples ln 2928-2968: no motion); between two compensated moves the nose goes round the end.
  Vec2 ta = geom::EndTangent(a), tb = geom::StartTangent(b);
  bool reversal = std::fabs(geom::Cross(ta, tb)) < 1e-9 && geom::Dot(ta, tb) < 0;
  if (state_ == kCancelPending) {
    // Departure: the held block ends on its own normal (and above 180 degrees arcs onto the departure
    // path's normal); then the theoretical tip goes to the programmed point.
    Move held = held_.m;
    Release(geom::OffsetEnd(a, r_, side_), 0);
    if (outside && !reversal) FillArc(k, held.kind == Move::kRapid ? m : held);
    PutAfter();
    state_ = kOff;
    Put(std::move(it));
    Settle();  // compensation is off: nothing after can undo these
    prog_ = m.end;
    return;
  }
  double b_trim = 0;
  Move held = held_.m;
  const Move& fill_like = held.kind == Move::kRapid ? m : held;
  if (held_.approach) {
    if (outside && !reversal) {
      Release(geom::OffsetEnd(a, r_, side_), 0);
      FillArc(k, fill_like);
    } else {
      Release(geom::OffsetStart(b, r_, side_), 0);
    }
  } else if (k.kind == geom::Corner::kToward) {
    Check570(k.intersects);
    if (k.intersects) {
      Check570(geom::RemainingLength(b, r_, side_, k.b_trim, 0) > -1e-6 || b.arc);
      Release(k.a_end, k.a_trim);
      b_trim = k.b_trim;
    } else {
      Release(geom::OffsetEnd(a, r_, side_), 0);
    }
  } else {
    Release(k.a_end, 0);
    if (outside) FillArc(k, fill_like);
  }
  PutAfter();
  held_ = Held{b, m, false, b_trim};
  has_held_ = true;
  prog_ = m.end;
}

void NoseComp::Finish() {
  if (has_held_) {
    Release(geom::OffsetEnd(held_.path, r_, side_), 0);
    PutAfter();
  }
  Settle();
  state_ = kOff;
}

}  // namespace cell::interp::emco
