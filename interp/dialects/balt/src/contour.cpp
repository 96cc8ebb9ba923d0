// Balt-System contouring (see contour.h).
#include "contour.h"

#include "cell/interp/geometry/arc.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>

namespace cell::interp::balt {

using namespace geom;  // NOLINT: the contour is written in the offset geometry's terms

namespace {

[[noreturn]] void Undefined(const std::string& why) {
  throw ContourError{77, why};
}

Vec2 Unit(Vec2 v) {
  double n = Norm(v);
  return n < 1e-12 ? Vec2{1, 0} : Vec2{v.x / n, v.y / n};
}

// The point of a path nearest to q on its line or circle (a foot, not clipped to the path).
Vec2 Foot(const Path& p, Vec2 q) {
  if (!p.arc) {
    Vec2 t = Unit(p.end - p.start);
    return p.start + Dot(q - p.start, t) * t;
  }
  double rad = Norm(p.start - p.center);
  return p.center + rad * Unit(q - p.center);
}

// How far along a path a point of it lies: mm for a line, degrees for an arc.
double Along(const Path& p, Vec2 q) {
  if (!p.arc) return Dot(q - p.start, Unit(p.end - p.start));
  if (Norm(q - p.start) < kTiny) return 0;
  return Sweep(p.start, q, p.center, p.cw);
}

// The locus of centres at distance v on `side` of a path near its corner end (at_end) or start.
struct Locus {
  bool arc = false;
  Vec2 p, d;  // line
  Vec2 c;     // circle
  double rad = 0;
};
Locus OffsetLocus(const Path& p, double v, int side, bool at_end) {
  Locus l;
  if (!p.arc) {
    l.d = Unit(p.end - p.start);
    l.p = (at_end ? p.end : p.start) + v * SideNormal(l.d, side);
    return l;
  }
  l.arc = true;
  l.c = p.center;
  l.rad = Norm(p.start - p.center) + (InsideArc(p, side) ? -v : v);
  if (l.rad <= kTiny) Undefined("the radius is larger than the arc it joins");
  return l;
}

int IntersectLoci(const Locus& a, const Locus& b, Vec2 out[2]) {
  if (!a.arc && !b.arc) return IntersectLineLine(a.p, a.d, b.p, b.d, out);
  if (!a.arc) return IntersectLineCircle(a.p, a.d, b.c, b.rad, out);
  if (!b.arc) return IntersectLineCircle(b.p, b.d, a.c, a.rad, out);
  return IntersectCircleCircle(a.c, a.rad, b.c, b.rad, out);
}

// The path cut at its end at q (a point of it).
void CutEnd(Path& p, Vec2 q) {
  if (p.arc) p.sweep = Along(p, q);
  p.end = q;
}
void CutStart(Path& p, Vec2 q) {
  if (p.arc) p.sweep -= Along(p, q);
  p.start = q;
}

}  // namespace

void Contour::Sync(const AxisArray& pos) {
  used_ = 0;
  last_ = pos;
  actual_ = Plane(pos);
  prog_ = actual_;
}

void Contour::Start(int side, double r, int g) {
  if (on_) {
    next_side_ = side;  // a change of side: the held element ends at its own offset point
    next_r_ = r;
    g_ = g;
    if (side != side_) plan_ = kStartPlan;
    return;
  }
  next_side_ = side;
  next_r_ = r;
  g_ = g;
  plan_ = kStartPlan;
}

void Contour::Stop() {
  if (on_) plan_ = kStopPlan;
  if (!on_ && plan_ == kStartPlan) plan_ = kNoPlan;
}

void Contour::Corner(char kind, double v, int line) {
  if (!held_ || hold_.kind == kVirtual) Undefined("a profile may not start with a radius or a bevel");
  if (corner_) Undefined("two corner words in a row");
  corner_ = true;
  corner_kind_ = kind;
  corner_v_ = v;
  corner_line_ = line;
  after_corner_ = true;
}

void Contour::Out(Canon&& c) {
  if (Target* t = c.target()) {
    t->used |= used_;  // what was held behind a move carries the axes that move used
    if (std::fabs(t->pos[p1_] - actual_.x) >= kTiny) t->used |= 1u << p1_;
    if (std::fabs(t->pos[p2_] - actual_.y) >= kTiny) t->used |= 1u << p2_;
    used_ = t->used;
    last_ = t->pos;
    actual_ = Plane(last_);
  }
  ready_.push_back(std::move(c));
}

std::vector<Canon> Contour::TakeChecked() {
  if (!held_) Checked();  // nothing waits for a later element: everything is settled
  std::vector<Canon> out(std::make_move_iterator(ready_.begin()),
                         std::make_move_iterator(ready_.begin() + static_cast<std::ptrdiff_t>(checked_)));
  ready_.erase(ready_.begin(), ready_.begin() + static_cast<std::ptrdiff_t>(checked_));
  checked_ = 0;
  return out;
}

void Contour::ReleaseAfter() {
  while (!after_.empty()) {
    Canon c = std::move(after_.front());
    after_.pop_front();
    if (Target* t = c.target()) SetPlaneOf(t->pos, actual_);  // moves off the plane happen at the corner
    Out(std::move(c));
  }
}

void Contour::EmitHeld(Vec2 end, double trim_end) {
  Pending h = std::move(hold_);
  held_ = false;
  if (h.kind != kVirtual) {
    Target& t = *h.c.target();
    SetPlaneOf(t.pos, end);
    bool others_move = t.travel_mask != 0;
    for (int a = 0; a < kAxisCount; ++a) {
      if (a != p1_ && a != p2_ && std::fabs(t.pos[a] - last_[a]) > 1e-9) others_move = true;
    }
    bool null_move;
    if (ArcOp* arc = h.c.If<ArcOp>()) {
      double sweep = h.path.sweep - h.trim_start - trim_end;
      if (sweep < -1e-6) Undefined("the compensated arc runs backwards");
      arc->angle = std::max(0.0, sweep) + h.extra;  // a helix keeps its full turns
      null_move = arc->angle < 1e-9;
    } else {
      null_move = Norm(end - actual_) < kTiny;
    }
    if (null_move && !others_move) {
      actual_ = end;
    } else {
      Out(std::move(h.c));
    }
  }
  ReleaseAfter();
}

Canon Contour::StraightTo(int line, Target t, Vec2 to, const Feed* feed) const {
  return StraightMove(t, to, p1_, p2_, feed, line);
}

Canon Contour::Straight(const Canon& like, Vec2 to) const {
  Target tgt = *like.target();
  tgt.travel = {};
  tgt.travel_mask = 0;
  return StraightTo(like.line, tgt, to, like.feed());
}

Canon Contour::FillIn(const geom::Corner& k, Vec2 corner, int line, const Feed* feed,
                      std::uint32_t used) const {
  // About the programmed corner, at the position of every other axis after the element before it.
  Target to;
  to.pos = last_;
  to.used = used;
  return FillInMove(k, to, corner, p1_, p2_, feed, line);  // both moves rapid (no feed): a rapid move
}

// A corner word between the held move and `next` (ln 3160-3200, 5192-5215): the programmed elements are
// cut back to where a radius touches them (or a bevel starts) and the radius or bevel becomes the held move.
void Contour::ApplyCorner(Pending& next) {
  corner_ = false;
  Pending& a = hold_;
  if (corner_kind_ == 'r' && std::fabs(corner_v_) < 1e-9) {
    a.roll = true;  // r0: with compensation the cutter rolls round the corner point
    return;
  }
  Vec2 ta = EndTangent(a.path), tb = StartTangent(next.path);
  double turn = Cross(ta, tb);
  if (std::fabs(turn) < 1e-9) Undefined("the elements meet without a corner to round or bevel");
  int side = turn > 0 ? kLeft : kRight;
  Pending mid;
  mid.c.line = corner_line_;
  Vec2 t1, t2;
  double v = std::fabs(corner_v_);
  if (corner_kind_ == 'b') {
    if (a.path.arc || next.path.arc) Undefined("a bevel joins two straight lines");
    t1 = a.path.end + (-v) * ta;
    t2 = next.path.start + v * tb;
  } else {
    Locus la = OffsetLocus(a.path, v, side, true), lb = OffsetLocus(next.path, v, side, false);
    Vec2 cand[2];
    int n = IntersectLoci(la, lb, cand);
    if (n == 0) Undefined(fmt::format("no radius {} fits the corner", v));
    Vec2 c = cand[0];
    if (n == 2 && Norm(cand[1] - a.path.end) < Norm(cand[0] - a.path.end)) c = cand[1];
    t1 = Foot(a.path, c);
    t2 = Foot(next.path, c);
    Path arc;
    arc.arc = true;
    arc.start = t1;
    arc.end = t2;
    arc.center = c;
    arc.cw = side == kRight;
    arc.sweep = Sweep(t1, t2, c, arc.cw);
    mid.path = arc;
  }
  // The radius or bevel must lie within both elements.
  double along_a = Along(a.path, t1), along_b = Along(next.path, t2);
  if (along_a < -1e-6 || along_a > Extent(a.path) - a.trim_start + 1e-6 ||
      (next.path.arc ? along_b > next.path.sweep + 1e-6
                     : along_b > Norm(next.path.end - next.path.start) + 1e-6) ||
      along_b < -1e-6) {
    Undefined(fmt::format("the {} {} does not fit between the elements",
                          corner_kind_ == 'b' ? "bevel" : "radius", v));
  }
  CutEnd(a.path, t1);
  CutStart(next.path, t2);
  // The radius / bevel move: from the end of a, at a's feed (the next one's when a is a rapid).
  Target to = *a.c.target();
  to.travel = {};
  to.travel_mask = 0;
  SetPlaneOf(to.pos, t2);
  const Feed* feed = a.c.feed() ? a.c.feed() : next.c.feed();
  if (corner_kind_ == 'b') {
    Path line;
    line.start = t1;
    line.end = t2;
    mid.path = line;
    if (feed) {
      LinearOp& l = mid.c.Set<LinearOp>();
      l.to = to;
      l.feed = *feed;
    } else {
      mid.c.Set<RapidOp>().to = to;
    }
  } else {
    ArcOp& arc = mid.c.Set<ArcOp>();
    arc.to = to;
    arc.feed = feed ? *feed : Feed{};
    arc.cw = mid.path.cw;
    arc.angle = mid.path.sweep;
    arc.plane = {static_cast<std::int8_t>(p1_), static_cast<std::int8_t>(p2_)};
    arc.center = {to.pos[kX], to.pos[kY], to.pos[kZ]};
    arc.center[CenterSlot(p1_)] = mid.path.center.x;
    arc.center[CenterSlot(p2_)] = mid.path.center.y;
  }
  // a ends at t1 and joins the radius (tangent) or the bevel; the radius / bevel is held.
  Join(mid);
  hold_ = std::move(mid);
  held_ = true;
}

// The held move ends where it meets `next` (its compensated corner); next's compensated start is set.
void Contour::Join(Pending& next) {
  const double r = R();
  if (next.path.arc && on_ && InsideArc(next.path, side_) &&
      std::min(OffsetRadiusAtStart(next.path, r, side_), OffsetRadiusAtEnd(next.path, r, side_)) < 0.001) {
    Undefined("the cutter radius is larger than the arc");
  }
  Pending& a = hold_;
  if (a.kind == kRamp) {
    // The start move ends with the cutter at 90 degrees to the first element (ln 3088).
    Vec2 s = OffsetStart(next.path, r, side_);
    next.start = s;
    next.trim_start = 0;
    EmitHeld(s, 0);
    return;
  }
  geom::Corner k = ComputeCorner(a.path, next.path, r, side_, !a.roll);
  std::optional<Vec2> via;
  // Only where the offset elements meet ahead of both ends: where they do not, the tangents' offsets meet far
  // out at a corner that turns back and would pass inside a neighbour, so the fill-in arc stays (call 50).
  if (k.kind == geom::Corner::kAway && !k.fill_in && !a.roll && (a.path.arc || next.path.arc)) {
    k = TangentCorner(a.path, next.path, r, side_, &via);
  }
  if (k.kind == geom::Corner::kToward && !k.intersects) Undefined("the offset elements do not intersect");
  if (a.kind != kVirtual && RemainingLength(a.path, r, side_, a.trim_start, k.a_trim) < -kTiny) {
    Undefined("the element is shorter than the compensation needs");
  }
  if (RemainingLength(next.path, r, side_, k.b_trim, 0) < -kTiny) {
    Undefined("the element is shorter than the compensation needs");
  }
  Checked();  // the held element is long enough: the corner before it stands
  next.start = k.b_start;
  next.trim_start = k.b_trim;
  const Vec2 corner = a.path.end;
  const int line = a.kind == kVirtual ? next.c.line : a.c.line;
  std::optional<Feed> feed;
  if (a.kind != kVirtual && a.c.feed()) feed = *a.c.feed();
  if (!feed && next.c.feed()) feed = *next.c.feed();
  const Feed* corner_feed = feed ? &*feed : nullptr;  // the moves made at the corner (none: rapids)
  const std::uint32_t used = next.c.target() ? next.c.target()->used : 0;
  if (a.kind == kVirtual) {
    // A closed GTL profile starts at the corner of its last and first elements.
    held_ = false;
    if (ramp_) {
      ramp_ = false;
      hold_ = std::move(ramp_move_);
      held_ = true;
      EmitHeld(via ? *via : k.a_end, 0);  // the profile starts at the corner point
    }
  } else {
    EmitHeld(k.a_end, k.a_trim);
    if (via && Norm(*via - actual_) >= kTiny) Out(Segment(*via, line, corner_feed, used));
  }
  if (k.fill_in) Out(FillIn(k, corner, line, corner_feed, used));
  // On to the next arc's offset start, unless a profile ends here (a virtual element) or its start
  // was not cut from the corner point.
  if (via && next.kind != kVirtual && Norm(actual_ - *via) < kTiny && Norm(k.b_start - *via) >= kTiny) {
    Out(Segment(k.b_start, line, corner_feed, used));
  }
}

Canon Contour::Segment(Vec2 to, int line, const Feed* feed, std::uint32_t used) const {
  // A straight move at a corner, at the position of every other axis after the element before it.
  Target t;
  t.pos = last_;
  t.used = used;
  return StraightTo(line, t, to, feed);
}

void Contour::Take(Canon&& c, const Path* path, bool hold) {
  if (!path) {
    if (c.target() && after_corner_ && held_) {
      throw ContourError{25, "a move off the plane may not follow an automatic radius"};
    }
    if (held_) {
      after_.push_back(std::move(c));
    } else {
      if (Target* t = c.target()) SetPlaneOf(t->pos, actual_);
      Out(std::move(c));
    }
    return;
  }
  after_corner_ = false;
  Pending next;
  next.c = std::move(c);
  next.path = *path;
  next.start = path->start;
  if (const ArcOp* arc = next.c.If<ArcOp>()) next.extra = std::max(0.0, arc->angle - path->sweep);
  prog_ = path->end;

  if (plan_ == kStartPlan && (!on_ || next_side_ != side_)) {
    if (on_) {
      // G41 <-> G42: the held element ends at its own offset point, the new side starts from there.
      if (held_) EmitHeld(OffsetEnd(hold_.path, r_, side_), 0);
      side_ = next_side_;
      r_ = next_r_;
      plan_ = kNoPlan;
      next.start = actual_;
      hold_ = std::move(next);
      held_ = true;
      return;
    }
    // The start move (ln 3088): linear, from where the cutter is.
    if (path->arc) throw ContourError{25, fmt::format("the G{} start move must be linear (G00/G01)", g_)};
    if (held_) EmitHeld(hold_.path.end, 0);
    on_ = true;
    residual_ = false;
    side_ = next_side_;
    r_ = next_r_;
    plan_ = kNoPlan;
    next.kind = kRamp;
    next.start = actual_;
    hold_ = std::move(next);
    held_ = true;
    return;
  }

  if (!on_) {
    if (held_) {
      if (corner_) ApplyCorner(next);
      Join(next);
    } else if (residual_) {
      // The first move after G40 without a move: from the offset point to its programmed end.
      if (path->arc && Norm(actual_ - path->start) >= kTiny) Out(Straight(next.c, path->start));
      residual_ = false;
    }
    if (hold) {
      hold_ = std::move(next);
      held_ = true;
    } else {
      Out(std::move(next.c));
    }
    return;
  }

  // Compensation on.
  if (plan_ == kStopPlan && !path->arc) {
    // The exit move (ln 3130): the held element ends at 90 degrees at its end, then straight to the
    // programmed end point.
    if (corner_) Undefined("a radius or bevel before the G40 move");
    if (held_)
      EmitHeld(hold_.kind == kRamp ? hold_.path.end + r_ * SideNormal(EndTangent(hold_.path), side_)
                                   : OffsetEnd(hold_.path, r_, side_),
               0);
    plan_ = kNoPlan;
    on_ = false;
    Out(std::move(next.c));
    return;
  }
  if (!held_) {
    next.start = OffsetStart(next.path, r_, side_);
    if (Norm(next.start - actual_) >= kTiny) Out(Straight(next.c, next.start));
  } else {
    if (corner_) ApplyCorner(next);
    Join(next);
  }
  if (plan_ == kStopPlan) {
    plan_ = kNoPlan;
    on_ = false;
    // An arc in the G40 block (ln 3141-3155): cut compensated, then straight to its programmed end point.
    Vec2 e = OffsetEnd(next.path, r_, side_);
    hold_ = std::move(next);
    held_ = true;
    Canon exit = Straight(hold_.c, hold_.path.end);
    const bool away = Norm(e - hold_.path.end) >= kTiny;
    EmitHeld(e, 0);
    if (away) Out(std::move(exit));
    return;
  }
  hold_ = std::move(next);
  held_ = true;
}

void Contour::TakeVirtual(const Path& path) {
  Pending v;
  v.kind = kVirtual;
  v.path = path;
  v.start = path.start;
  if (held_ && hold_.kind == kRamp) {
    ramp_ = true;
    ramp_move_ = std::move(hold_);
    held_ = false;
  } else if (held_) {
    if (corner_) Undefined("a profile may not end with a radius or a bevel");
    Join(v);
  }
  hold_ = std::move(v);
  held_ = true;
}

void Contour::EndBlock() {
  if (plan_ == kStopPlan) Release();
}

void Contour::Release() {
  if (corner_) Undefined("a profile may not end with a radius or a bevel");
  after_corner_ = false;
  if (ramp_) {
    ramp_ = false;
    hold_ = std::move(ramp_move_);
    held_ = true;
  }
  if (held_) {
    if (hold_.kind == kVirtual) {
      held_ = false;
      ReleaseAfter();
    } else {
      EmitHeld(OffsetEnd(hold_.path, R(), side_), 0);
    }
  }
  ReleaseAfter();
  if (on_) residual_ = Norm(actual_ - prog_) >= kTiny;
  on_ = false;
  plan_ = kNoPlan;
}

void Contour::Reset() {
  ready_.clear();
  checked_ = 0;
  after_.clear();
  on_ = residual_ = held_ = ramp_ = corner_ = after_corner_ = false;
  plan_ = kNoPlan;
}

}  // namespace cell::interp::balt
