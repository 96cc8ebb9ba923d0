// KT-APL cutter diameter compensation: geometry and the one-block look-ahead (see cutter_comp.h).
#include "cutter_comp.h"

#include <fmt/format.h>

#include <algorithm>
#include <optional>
#include <utility>
#include <vector>

namespace cell::interp::ktapl::cc {

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

// A G33 thread is a straight move of the path like G01 (the G833/G834 cycles cut it under G41/G42, ln
// 7298-7301).
bool IsMove(Op op) {
  return op == Op::kRapid || op == Op::kLinear || op == Op::kArc || op == Op::kThread;
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
  if (const Target* t = c.target()) {
    last_ = t->pos;
    actual_ = PlaneOf(last_);
  }
  staged_.push_back(std::move(c));
}

void Compensator::Settle() {
  for (Canon& c : staged_) ready_.push_back(std::move(c));
  staged_.clear();
}

Vec2 Compensator::OwnEnd(const Pending& p) const {
  return OffsetEnd(p.path, r_, p.side);
}

void Compensator::ReleaseHeld() {
  while (!held_.empty()) {
    Canon h = std::move(held_.front());
    held_.pop_front();
    // Moves without travel in the plane (and G38 checks) happen where the cutter is.
    if (h.op() == Op::kRapid || h.op() == Op::kLinear || h.op() == Op::kThread || h.op() == Op::kProbe)
      SetPlane(h.target()->pos, actual_);
    Out(std::move(h));
  }
}

void Compensator::Release(Vec2 end, double trim_end, std::vector<Canon> corner) {
  // The held block passed its checks against the next one: the block before it, which ends at their
  // corner, stands (judgement call 88).
  Settle();
  Canon c = std::move(pend_.c);
  Target& t = *c.target();
  SetPlane(t.pos, end);
  bool others_move = t.travel_mask != 0;
  for (int a = 0; a < kAxisCount; ++a) {
    if (a != p1_ && a != p2_ && std::fabs(t.pos[a] - last_[a]) > 1e-9) others_move = true;
  }
  bool null_move;
  if (pend_.path.arc) {
    ArcOp& arc = c.As<ArcOp>();
    arc.angle = std::max(0.0, pend_.path.sweep - pend_.trim_start - trim_end);
    null_move = arc.angle < 1e-9;
  } else {
    null_move = Norm(end - actual_) < kTiny;
  }
  if (null_move && !others_move) {
    actual_ = end;
  } else {
    Out(std::move(c));
  }
  for (Canon& m : corner) Out(std::move(m));  // the moves made at the corner (a fill-in arc, G46's lines)
  ReleaseHeld();
}

Canon Compensator::FillIn(const Corner& k, const Canon& next) const {
  const Canon& a = pend_.c;
  Target to = *a.target();
  to.travel = {};
  to.travel_mask = 0;
  // Both blocks at F0: a rapid move, a positioning move rather than a contour.
  const Feed* feed = a.feed() ? a.feed() : next.feed();
  return FillInMove(k, to, pend_.path.end, p1_, p2_, feed, a.line);
}

// A straight move at a corner (G46 where an arc meets: to and from the tangents' intersection), made like a
// fill-in arc: the held block's line and feed, rapid if both blocks are F0.
Canon Compensator::CornerLine(Vec2 to, const Canon& next) const {
  const Canon& a = pend_.c;
  Target t = *a.target();
  t.travel = {};
  t.travel_mask = 0;
  return StraightMove(t, to, p1_, p2_, a.feed() ? a.feed() : next.feed(), a.line);
}

// Not a move: held behind the held block while compensation is on.
void Compensator::TakeOther(Canon&& c) {
  const ProbeOp* probe = c.If<ProbeOp>();
  if (c.op() == Op::kToolChange || c.op() == Op::kRegrid || (probe && probe->g != 38)) {
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
}

void Compensator::Take(Canon&& c) {
  TakeOne(std::move(c));
  if (state_ != kOn) Settle();
}

void Compensator::TakeOne(Canon&& c) {
  if (!IsMove(c.op())) {
    TakeOther(std::move(c));
    return;
  }
  Path p;
  p.start = prog_;
  p.end = PlaneOf(c.target()->pos);
  if (const ArcOp* arc = c.If<ArcOp>()) {
    p.arc = true;
    p.center = {arc->center[CenterSlot(p1_)], arc->center[CenterSlot(p2_)]};
    p.cw = arc->cw;
    p.sweep = arc->angle;
  }
  prog_ = p.end;
  bool in_plane = p.arc || Norm(p.end - p.start) >= kTiny;

  if (plan_ == kPlanRampOn && state_ != kOn) {
    TakeRampOn(std::move(c), p, in_plane);
    return;
  }
  if (state_ == kOff) {
    Out(std::move(c));
    return;
  }
  if (state_ == kResidual) {
    TakeResidual(std::move(c), p, in_plane);
    return;
  }
  TakeHeld(std::move(c), p, in_plane);
}

// Ramp-on (ln 1613-1641, 6466): no comp at its start, the full offset at its end.
void Compensator::TakeRampOn(Canon&& c, const Path& p, bool in_plane) {
  if (p.arc)
    throw Error("", fmt::format("G{} RAMP-ON BLOCK MUST BE A LINEAR MOVE (G00/G01)", g_), CompError::kAtCode);
  if (!in_plane || Norm(p.end - p.start) < min_move_ - 1e-9) {
    throw Error(
        "",
        fmt::format("G{} RAMP-ON BLOCK NEEDS A MOVE OF AT LEAST 0.0001 IN (0.001 MM) IN {}", g_, AxesText()),
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
}

// After G40 without motion (ln 6532) the cutter is still offset; the next move in the plane starts there
// and goes to its programmed point.
void Compensator::TakeResidual(Canon&& c, const Path& p, bool in_plane) {
  if (!in_plane) {
    SetPlane(c.target()->pos, actual_);
    Out(std::move(c));
    return;
  }
  if (p.arc && Norm(actual_ - p.start) >= kTiny) {
    // An arc cannot start off its circle: straight to its start first, at the arc's feed.
    Canon l;
    l.line = c.line;
    LinearOp& lin = l.Set<LinearOp>();
    lin.feed = c.As<ArcOp>().feed;
    lin.to.pos = last_;
    lin.to.used = c.target()->used;
    SetPlane(lin.to.pos, p.start);
    Out(std::move(l));
  }
  Out(std::move(c));
  state_ = kOff;
  Update();
}

// Compensation on: a block is held.
void Compensator::TakeHeld(Canon&& c, const Path& p, bool in_plane) {
  if (plan_ == kPlanCancel) {
    // Ramp-off (ln 1599-1611, 6533-6550): the held block ends at its own offset point, the G40 move goes
    // straight from there to its programmed end point.
    if (p.arc) throw Error("", "G40 RAMP-OFF BLOCK MUST BE A LINEAR MOVE (G00/G01)", CompError::kAtCode);
    Release(OwnEnd(pend_), 0);
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

  Join(next, p);
  pend_ = std::move(next);
}

// The held block and `next` (its programmed path `p`): where the held one ends and `next` starts.
void Compensator::Join(Pending& next, const Path& p) {
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
    Release(e, 0);
  } else if (a.kind != kNormal) {
    // A ramp-on or G43 block ends at 90 degrees to the next path (ln 6453, Fig 6.12).
    Vec2 s = OffsetStart(p, r_, next.side);
    if (a.kind == kRamp && Dot(s - a.start, StartTangent(a.path)) < -kTiny) {
      // The clearance before the part is smaller than the cutter radius (ln 6501, 6507).
      throw Error("0001", "Cutter Comp Error 0001 Intersection error in previous block");
    }
    next.start = s;
    next.trim_start = 0;
    Release(s, 0);
  } else {
    Corner k = ComputeCorner(a.path, p, r_, a.side, bypass_);
    // G46 where an arc meets: the tangents' intersection, as Balt-System's outside corner (ktapl.md judgement
    // call 39; the offset circle run on to the other offset came back into the part, docs/testing.md).
    std::optional<Vec2> via;
    if (bypass_ && k.kind == Corner::kAway && !k.fill_in && (a.path.arc || p.arc)) {
      k = TangentCorner(a.path, p, r_, a.side, &via);
    }
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
    std::vector<Canon> corner;
    if (k.fill_in) corner.push_back(FillIn(k, next.c));
    if (via && Norm(*via - k.a_end) >= kTiny) corner.push_back(CornerLine(*via, next.c));
    if (via && Norm(k.b_start - *via) >= kTiny) corner.push_back(CornerLine(k.b_start, next.c));
    Release(k.a_end, k.a_trim, std::move(corner));
  }
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
    Release(OwnEnd(pend_), 0);
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
  if (state_ != kOn) Settle();
  plan_ = kNoPlan;
  block_motion_ = false;
  block_clears_ = false;
  Update();
}

void Compensator::Finish() {
  if (state_ == kOn) Release(OwnEnd(pend_), 0);
  ReleaseHeld();
  Settle();
  state_ = kOff;
  plan_ = kNoPlan;
  block_motion_ = false;
  block_clears_ = false;
  no_motion_blocks_ = 0;
  Update();
}

}  // namespace cell::interp::ktapl::cc
