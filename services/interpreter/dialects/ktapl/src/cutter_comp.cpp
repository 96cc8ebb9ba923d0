// KT-APL cutter diameter compensation: geometry and the one-block look-ahead (see cutter_comp.h).
#include "cutter_comp.h"

#include <fmt/format.h>

#include <algorithm>
#include <utility>

namespace cell::interp::ktapl::cc {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = 180.0 / kPi;

Vec2 Unit(Vec2 v) {
  double n = Norm(v);
  if (n < 1e-12) return {1, 0};
  return {v.x / n, v.y / n};
}

// Angle of v in radians, and the difference of two angles wrapped to (-pi, pi].
double Angle(Vec2 v) {
  return std::atan2(v.y, v.x);
}
double Wrap(double a) {
  while (a <= -kPi) a += 2 * kPi;
  while (a > kPi) a -= 2 * kPi;
  return a;
}

double ArcSign(const Path& p) {
  return p.cw ? -1.0 : 1.0;
}

Vec2 ArcTangent(const Path& p, Vec2 at) {
  Vec2 v = Unit(at - p.center);
  return p.cw ? Vec2{v.y, -v.x} : Vec2{-v.y, v.x};
}

// Slot of an axis in Canon::center ([x, y, z]; U, V, W take the slot of their parallel axis).
int CenterSlot(int axis) {
  if (axis == kX || axis == kU) return 0;
  if (axis == kY || axis == kV) return 1;
  return 2;
}

// Intersections of the offset paths of `a` (near its end) and `b` (near its start).
int IntersectOffsets(const Path& a, const Path& b, double r, int side, Vec2 out[2]) {
  Vec2 ap = OffsetEnd(a, r, side), bp = OffsetStart(b, r, side);
  double ar = a.arc ? OffsetRadiusAtEnd(a, r, side) : 0;
  double br = b.arc ? OffsetRadiusAtStart(b, r, side) : 0;
  if ((a.arc && ar <= 0) || (b.arc && br <= 0)) return 0;
  if (!a.arc && !b.arc) return IntersectLineLine(ap, EndTangent(a), bp, StartTangent(b), out);
  if (!a.arc) return IntersectLineCircle(ap, EndTangent(a), b.center, br, out);
  if (!b.arc) return IntersectLineCircle(bp, StartTangent(b), a.center, ar, out);
  return IntersectCircleCircle(a.center, ar, b.center, br, out);
}

// How far `a` is cut back at its end, and `b` at its start, when they meet at x (mm / degrees).
double TrimEnd(const Path& a, double r, int side, Vec2 x) {
  Vec2 e = OffsetEnd(a, r, side);
  if (!a.arc) return Dot(e - x, EndTangent(a));
  return ArcSign(a) * Wrap(Angle(e - a.center) - Angle(x - a.center)) * kDeg;
}
double TrimStart(const Path& b, double r, int side, Vec2 x) {
  Vec2 s = OffsetStart(b, r, side);
  if (!b.arc) return Dot(x - s, StartTangent(b));
  return ArcSign(b) * Wrap(Angle(x - b.center) - Angle(s - b.center)) * kDeg;
}

}  // namespace

Vec2 StartTangent(const Path& p) {
  return p.arc ? ArcTangent(p, p.start) : Unit(p.end - p.start);
}

Vec2 EndTangent(const Path& p) {
  return p.arc ? ArcTangent(p, p.end) : Unit(p.end - p.start);
}

bool InsideArc(const Path& p, int side) {
  return p.cw ? side == kRight : side == kLeft;
}

double OffsetRadiusAtStart(const Path& p, double r, int side) {
  return Norm(p.start - p.center) + (InsideArc(p, side) ? -r : r);
}

double OffsetRadiusAtEnd(const Path& p, double r, int side) {
  return Norm(p.end - p.center) + (InsideArc(p, side) ? -r : r);
}

Vec2 OffsetStart(const Path& p, double r, int side) {
  return p.start + r * SideNormal(StartTangent(p), side);
}

Vec2 OffsetEnd(const Path& p, double r, int side) {
  return p.end + r * SideNormal(EndTangent(p), side);
}

double Extent(const Path& p) {
  return p.arc ? p.sweep : Norm(p.end - p.start);
}

double RemainingLength(const Path& p, double r, int side, double trim_start, double trim_end) {
  double left = Extent(p) - trim_start - trim_end;
  if (!p.arc) return left;
  double radius = (OffsetRadiusAtStart(p, r, side) + OffsetRadiusAtEnd(p, r, side)) / 2;
  return left / kDeg * std::fabs(radius);
}

int IntersectLineLine(Vec2 p, Vec2 d, Vec2 q, Vec2 e, Vec2* out) {
  double den = Cross(d, e);
  if (std::fabs(den) < 1e-12) return 0;
  double t = Cross(q - p, e) / den;
  out[0] = p + t * d;
  return 1;
}

int IntersectLineCircle(Vec2 p, Vec2 d, Vec2 c, double r, Vec2 out[2]) {
  Vec2 w = p - c;
  double b = Dot(w, d);
  double disc = b * b - (Dot(w, w) - r * r);
  if (disc < -1e-9 * (1 + r * r)) return 0;
  double s = std::sqrt(std::max(0.0, disc));
  out[0] = p + (-b - s) * d;
  if (s < 1e-12) return 1;
  out[1] = p + (-b + s) * d;
  return 2;
}

int IntersectCircleCircle(Vec2 c1, double r1, Vec2 c2, double r2, Vec2 out[2]) {
  Vec2 dc = c2 - c1;
  double d = Norm(dc);
  if (d < 1e-12) return 0;
  double tol = 1e-9 * (1 + r1 + r2);
  if (d > r1 + r2 + tol || d < std::fabs(r1 - r2) - tol) return 0;
  double a = (r1 * r1 - r2 * r2 + d * d) / (2 * d);
  double h = std::sqrt(std::max(0.0, r1 * r1 - a * a));
  Vec2 u{dc.x / d, dc.y / d};
  Vec2 base = c1 + a * u;
  Vec2 perp{-u.y, u.x};
  out[0] = base + h * perp;
  if (h < 1e-12) return 1;
  out[1] = base + (-h) * perp;
  return 2;
}

Corner ComputeCorner(const Path& a, const Path& b, double r, int side, bool bypass_fill_in) {
  Corner k;
  k.a_end = OffsetEnd(a, r, side);
  k.b_start = OffsetStart(b, r, side);
  if (Norm(k.a_end - k.b_start) < kTiny) return k;  // tangent paths (or no offset): they meet
  Vec2 ta = EndTangent(a), tb = StartTangent(b);
  double turn = Cross(ta, tb);
  bool reversal = std::fabs(turn) < 1e-9 && Dot(ta, tb) < 0;
  bool toward = !reversal && side * turn > 0;
  Vec2 corner = a.end;
  if (toward || bypass_fill_in) {
    Vec2 pts[2];
    int n = IntersectOffsets(a, b, r, side, pts);
    if (n > 0) {
      Vec2 x = pts[0];
      if (n == 2 && Norm(pts[1] - corner) < Norm(pts[0] - corner)) x = pts[1];
      double at = TrimEnd(a, r, side, x), bt = TrimStart(b, r, side, x);
      if (toward || (at <= kTiny && bt <= kTiny)) {
        k.kind = toward ? Corner::kToward : Corner::kAway;
        k.a_end = k.b_start = x;
        k.a_trim = at;
        k.b_trim = bt;
        return k;
      }
    } else if (toward) {
      k.kind = Corner::kToward;
      k.intersects = false;
      return k;
    }
  }
  k.kind = Corner::kAway;
  k.fill_in = true;
  k.fill_cw = side == kLeft;  // the cutter goes round the corner on the outside of the turn
  double from = Angle(k.a_end - corner), to = Angle(k.b_start - corner);
  double sweep = (k.fill_cw ? from - to : to - from) * kDeg;
  while (sweep <= 0) sweep += 360.0;
  while (sweep > 360.0) sweep -= 360.0;
  k.fill_sweep = sweep;
  return k;
}

// ---------------------------------------------------------------------------------------------------------
// Compensator

namespace {

CompError Error(const char* alarm, const std::string& text, CompError::At at = CompError::kAtMotion) {
  CompError e;
  e.alarm = alarm;
  e.text = text;
  e.at = at;
  return e;
}

bool IsMove(Op op) {
  return op == Op::kRapid || op == Op::kLinear || op == Op::kArc;
}

}  // namespace

std::string Compensator::AxesText() const {
  std::string s = AxisName(p1_);
  s += '/';
  s += AxisName(p2_);
  for (auto& ch : s) ch = static_cast<char>(ch >= 'a' && ch <= 'z' ? ch - 'a' + 'A' : ch);
  return s;
}

void Compensator::RampOn(const Setup& s) {
  if (state_ == kOn) return;
  if (state_ == kOff) last_ = s.pos;  // after G40 without motion the slides still carry the old offset
  p1_ = s.p1;
  p2_ = s.p2;
  r_ = s.radius;
  side_ = s.side;
  g_ = s.g;
  min_move_ = s.min_move;
  prog_ = {s.pos[p1_], s.pos[p2_]};
  actual_ = PlaneOf(last_);
  plan_ = kPlanRampOn;
  Update();
}

void Compensator::SetSide(int side, int g) {
  side_ = side;
  g_ = g;
}

void Compensator::Cancel() {
  if (state_ != kOn) return;
  plan_ = kPlanCancel;
  Update();
}

void Compensator::Perpendicular() {
  if (state_ != kOn || plan_ != kNoPlan) return;
  plan_ = kPlanPerpendicular;
  Update();
}

void Compensator::Out(Canon&& c) {
  if (IsMove(c.op) || c.op == Op::kProbe || c.op == Op::kRegrid) {
    last_ = c.pos;
    actual_ = PlaneOf(last_);
  }
  ready_.push_back(std::move(c));
}

Vec2 Compensator::OwnEnd(const Pending& p) const {
  return OffsetEnd(p.path, r_, p.side);
}

void Compensator::ReleaseHeld() {
  while (!held_.empty()) {
    Canon h = std::move(held_.front());
    held_.pop_front();
    // Moves without travel in the plane (and G38 checks) happen where the cutter is.
    if (h.op == Op::kRapid || h.op == Op::kLinear || h.op == Op::kProbe) SetPlane(h.pos, actual_);
    Out(std::move(h));
  }
}

void Compensator::Release(Vec2 end, double trim_end, const Canon* fill) {
  Canon c = std::move(pend_.c);
  SetPlane(c.pos, end);
  bool others_move = c.travel_mask != 0;
  for (int a = 0; a < kAxisCount; ++a) {
    if (a != p1_ && a != p2_ && std::fabs(c.pos[a] - last_[a]) > 1e-9) others_move = true;
  }
  bool null_move;
  if (pend_.path.arc) {
    c.turns = std::max(0.0, pend_.path.sweep - pend_.trim_start - trim_end);
    null_move = c.turns < 1e-9;
  } else {
    null_move = Norm(end - actual_) < kTiny;
  }
  if (null_move && !others_move) {
    actual_ = end;
  } else {
    Out(std::move(c));
  }
  if (fill) Out(Canon(*fill));
  ReleaseHeld();
}

Canon Compensator::FillIn(const Corner& k, const Canon& next) const {
  const Canon& a = pend_.c;
  Canon f = a;
  f.travel = {};
  f.travel_mask = 0;
  SetPlane(f.pos, k.b_start);
  const Canon* feed = a.op != Op::kRapid ? &a : (next.op != Op::kRapid ? &next : nullptr);
  if (!feed) {
    f.op = Op::kRapid;  // both blocks at F0: a positioning move, not a contour
    return f;
  }
  f.op = Op::kArc;
  f.feed = feed->feed;
  f.f_mode = feed->f_mode;
  f.exact_stop = feed->exact_stop;
  f.cw = k.fill_cw;
  f.turns = k.fill_sweep;
  f.plane = {AxisName(p1_)[0], AxisName(p2_)[0]};
  f.center = {f.pos[kX], f.pos[kY], f.pos[kZ]};
  f.center[CenterSlot(p1_)] = pend_.path.end.x;
  f.center[CenterSlot(p2_)] = pend_.path.end.y;
  return f;
}

void Compensator::Take(Canon&& c) {
  if (!IsMove(c.op)) {
    if (c.op == Op::kToolChange || c.op == Op::kRegrid || (c.op == Op::kProbe && c.code != 38)) {
      block_clears_ = true;  // the slides went elsewhere: no residual offset is left
      if (state_ == kResidual) {
        state_ = kOff;
        Update();
      }
    }
    if (state_ == kOn) {
      held_.push_back(std::move(c));
    } else {
      Out(std::move(c));
    }
    return;
  }
  Path p;
  p.start = prog_;
  p.end = PlaneOf(c.pos);
  if (c.op == Op::kArc) {
    p.arc = true;
    p.center = {c.center[CenterSlot(p1_)], c.center[CenterSlot(p2_)]};
    p.cw = c.cw;
    p.sweep = c.turns;
  }
  prog_ = p.end;
  bool in_plane = p.arc || Norm(p.end - p.start) >= kTiny;

  if (plan_ == kPlanRampOn && state_ != kOn) {
    // Ramp-on (ln 1613-1641, 6466): no comp at its start, the full offset at its end.
    if (p.arc)
      throw Error("", fmt::format("G{} RAMP-ON BLOCK MUST BE A LINEAR MOVE (G00/G01)", g_),
                  CompError::kAtCode);
    if (!in_plane || Norm(p.end - p.start) < min_move_ - 1e-9) {
      throw Error("",
                  fmt::format("G{} RAMP-ON BLOCK NEEDS A MOVE OF AT LEAST 0.0001 IN (0.001 MM) IN {}", g_,
                              AxesText()),
                  CompError::kAtCode);
    }
    pend_.c = std::move(c);
    pend_.path = p;
    pend_.kind = kRamp;
    pend_.side = side_;
    pend_.g = g_;
    pend_.start = actual_;
    pend_.trim_start = 0;
    state_ = kOn;
    block_motion_ = true;
    no_motion_blocks_ = 0;
    Update();
    return;
  }
  if (state_ == kOff) {
    Out(std::move(c));
    return;
  }
  if (state_ == kResidual) {
    // After G40 without motion (ln 6532) the cutter is still offset; the next move in the plane starts
    // there and goes to its programmed point.
    if (!in_plane) {
      SetPlane(c.pos, actual_);
      Out(std::move(c));
      return;
    }
    if (p.arc && Norm(actual_ - p.start) >= kTiny) {
      Canon l = c;  // an arc cannot start off its circle: straight to its start first
      l.op = Op::kLinear;
      l.pos = last_;
      SetPlane(l.pos, p.start);
      l.travel = {};
      l.travel_mask = 0;
      Out(std::move(l));
    }
    Out(std::move(c));
    state_ = kOff;
    Update();
    return;
  }

  // Compensation on: a block is held.
  if (plan_ == kPlanCancel) {
    // Ramp-off (ln 1599-1611, 6533-6550): the held block ends at its own offset point, the G40 move goes
    // straight from there to its programmed end point.
    if (p.arc) throw Error("", "G40 RAMP-OFF BLOCK MUST BE A LINEAR MOVE (G00/G01)", CompError::kAtCode);
    Release(OwnEnd(pend_), 0, nullptr);
    Out(std::move(c));
    state_ = kOff;
    Update();
    return;
  }
  if (!in_plane) {
    held_.push_back(std::move(c));  // placed at the corner when the held block is resolved
    return;
  }
  if (p.arc && InsideArc(p, side_) &&
      std::min(OffsetRadiusAtStart(p, r_, side_), OffsetRadiusAtEnd(p, r_, side_)) < 0.001) {
    throw Error("0004",
                "Cutter Comp Error 0004 Comp too large for inside circle diameter (INPUT SOURCE ERROR)");
  }
  Pending next;
  next.c = std::move(c);
  next.path = p;
  next.kind = plan_ == kPlanPerpendicular ? kPerpendicular : kNormal;
  next.side = side_;
  next.g = g_;
  if (next.kind == kPerpendicular && p.arc) throw Error("", "G43 BLOCK MUST BE A LINEAR MOVE (G00/G01)");
  block_motion_ = true;
  no_motion_blocks_ = 0;

  const Pending& a = pend_;
  if (next.side != a.side || next.kind == kPerpendicular) {
    // G41<->G42 (retrace, ln 6692-6696) or a G43 excursion (ln 1643-1652): the held block ends at its own
    // offset point and the new block starts from there.
    Vec2 e = OwnEnd(a);
    Vec2 s = OffsetStart(p, r_, next.side);
    if (p.arc && Norm(s - e) > 0.001) {
      throw Error("", fmt::format("G{} ON AN ARC MAY ONLY RETRACE THE COMPENSATED PATH", next.g),
                  CompError::kAtCode);
    }
    next.start = p.arc ? s : e;
    next.trim_start = p.arc ? 0 : Dot(e - s, StartTangent(p));
    Release(e, 0, nullptr);
  } else if (a.kind != kNormal) {
    // A ramp-on or G43 block ends at 90 degrees to the next path (ln 6453, Fig 6.12).
    Vec2 s = OffsetStart(p, r_, next.side);
    if (a.kind == kRamp && Dot(s - a.start, StartTangent(a.path)) < -kTiny) {
      // The clearance before the part is smaller than the cutter radius (ln 6501, 6507).
      throw Error("0001", "Cutter Comp Error 0001 Intersection error in previous block");
    }
    next.start = s;
    next.trim_start = 0;
    Release(s, 0, nullptr);
  } else {
    Corner k = ComputeCorner(a.path, p, r_, a.side, bypass_);
    if (k.kind == Corner::kToward && !k.intersects) {
      throw Error("0002", "Cutter Comp Error 0002 Intersection error in current block");
    }
    if (RemainingLength(a.path, r_, a.side, a.trim_start, k.a_trim) < -kTiny) {
      throw Error("0001", "Cutter Comp Error 0001 Intersection error in previous block");
    }
    if (RemainingLength(p, r_, next.side, k.b_trim, 0) < -kTiny) {
      throw Error("0002", "Cutter Comp Error 0002 Intersection error in current block");
    }
    next.start = k.b_start;
    next.trim_start = k.b_trim;
    if (k.fill_in) {
      Canon f = FillIn(k, next.c);
      Release(k.a_end, k.a_trim, &f);
    } else {
      Release(k.a_end, k.a_trim, nullptr);
    }
  }
  pend_ = std::move(next);
}

void Compensator::EndBlock(bool counts) {
  if (plan_ == kPlanRampOn && state_ != kOn) {
    throw Error(
        "",
        fmt::format("G{} RAMP-ON BLOCK NEEDS A MOVE OF AT LEAST 0.0001 IN (0.001 MM) IN {}", g_, AxesText()),
        CompError::kAtCode);
  }
  if (plan_ == kPlanCancel && state_ == kOn) {
    // G40 without motion (ln 1603, 6532): the cutter stays where it is; the registers show the programmed
    // position, and the next move in the plane starts from the offset point.
    Release(OwnEnd(pend_), 0, nullptr);
    state_ = Norm(actual_ - prog_) >= kTiny ? kResidual : kOff;
  } else if (state_ == kOn && counts && !block_motion_) {
    if (++no_motion_blocks_ > 4) {
      throw Error("0003",
                  fmt::format("Cutter Comp Error 0003 Not enough blocks on ready list (more than 4 blocks "
                              "without {} motion)",
                              AxesText()),
                  CompError::kAtBlock);
    }
  }
  if (block_clears_ && state_ == kResidual) state_ = kOff;
  plan_ = kNoPlan;
  block_motion_ = false;
  block_clears_ = false;
  Update();
}

void Compensator::Finish() {
  if (state_ == kOn) Release(OwnEnd(pend_), 0, nullptr);
  ReleaseHeld();
  state_ = kOff;
  plan_ = kNoPlan;
  block_motion_ = false;
  block_clears_ = false;
  no_motion_blocks_ = 0;
  Update();
}

}  // namespace cell::interp::ktapl::cc
