// Tool-nose radius compensation G40/G41/G42 (manual ln 2177-3096) on the core's offset geometry (see
// staged.h). The nose-R centre at the end of an element is the intersection of its offset with the next
// element's offset (lines and the offset circles of arcs); parallel offsets (a straight continuation, or a
// return along the same line) end where the nose touches the programmed point.
#include <fmt/format.h>

#include <cmath>

#include "staged.h"

namespace cell::interp::okuma {
namespace {

constexpr double kTiny = geom::kTiny;

geom::Path PathOf(const Canon& c, Vec2 start) {
  geom::Path p;
  p.start = start;
  p.end = PlaneOf(c.target()->pos);
  if (const ArcOp* a = c.If<ArcOp>()) {
    p.arc = true;
    p.center = {a->center[2], a->center[0] / 2};
    p.cw = a->cw;
    p.sweep = a->angle;
  }
  return p;
}

}  // namespace

void NoseComp::Out(Staged&& s) {
  if (s.kind == Staged::kOp) {
    if (const Target* t = s.c.target()) {
      last_ = t->pos;
      have_last_ = true;
    }
  }
  ready_.push_back(std::move(s));
}

void NoseComp::Take(Staged&& s) {
  switch (s.kind) {
    case Staged::kCompOn:
      r_ = s.radius;
      tip_ = s.tip;
      side_ = s.side;
      if (state_ != kOn) {
        plan_ = kPlanStart;
        plan_ik_ = s.has_ik;
        plan_ikv_ = s.ik;
        if (state_ == kOff) {
          prog_ = PlaneOf(s.from);
          centre_ = prog_ - tip_;
        }
      }
      return;
    case Staged::kCompOff:
      if (state_ == kOn) {
        plan_ = kPlanCancel;
        plan_ik_ = s.has_ik;
        plan_ikv_ = s.ik;
      } else if (plan_ == kPlanStart) {
        plan_ = kNoPlan;
      }
      return;
    case Staged::kBlockEnd:
      BlockEnd(s.xz);
      return;
    case Staged::kOp:
      Op(std::move(s));
      return;
  }
}

Vec2 NoseComp::Corner(const Elem& a, const Elem& b) const {
  const Vec2 ea = geom::OffsetEnd(a.path, r_, a.side);
  const Vec2 sb = geom::OffsetStart(b.path, r_, b.side);
  if (geom::Norm(ea - sb) < 1e-7) return ea;  // tangent, or no radius
  if (!a.path.arc && !b.path.arc) {
    const Vec2 da = geom::EndTangent(a.path), db = geom::StartTangent(b.path);
    if (std::fabs(geom::Cross(da, db)) < 1e-9) return ea;  // straight on, or back along the same line
    Vec2 p;
    geom::IntersectLineLine(ea, da, sb, db, &p);
    return p;
  }
  // With an arc: the offset circle(s) and line(s); of two points the one nearer the programmed corner.
  Vec2 pts[2];
  int n = 0;
  auto radius_end = [&](const Elem& e) { return geom::OffsetRadiusAtEnd(e.path, r_, e.side); };
  auto radius_start = [&](const Elem& e) { return geom::OffsetRadiusAtStart(e.path, r_, e.side); };
  if (a.path.arc && b.path.arc) {
    const double ra = radius_end(a), rb = radius_start(b);
    if (ra < 0 || rb < 0) Fail(1, "nose radius compensation: the nose radius is larger than an arc's radius");
    n = geom::IntersectCircleCircle(a.path.center, ra, b.path.center, rb, pts);
  } else if (a.path.arc) {
    const double ra = radius_end(a);
    if (ra < 0) Fail(1, "nose radius compensation: the nose radius is larger than an arc's radius");
    n = geom::IntersectLineCircle(sb, geom::StartTangent(b.path), a.path.center, ra, pts);
  } else {
    const double rb = radius_start(b);
    if (rb < 0) Fail(1, "nose radius compensation: the nose radius is larger than an arc's radius");
    n = geom::IntersectLineCircle(ea, geom::EndTangent(a.path), b.path.center, rb, pts);
  }
  if (n == 0) {
    Fail(1,
         "nose radius compensation: the offset path is discontinuous (the offsets of two elements do not "
         "meet)");
  }
  const Vec2 mid = 0.5 * (ea + sb);
  if (n == 2 && geom::Norm(pts[1] - mid) < geom::Norm(pts[0] - mid)) return pts[1];
  return pts[0];
}

void NoseComp::CheckInsideArc(const Elem& e) const {
  if (!e.path.arc || r_ <= 0) return;
  const double radius = geom::Norm(e.path.start - e.path.center);
  // ln 2688-2723: inside an arc the arc radius must be at least twice the nose radius.
  if (geom::InsideArc(e.path, e.side) && radius < 2 * r_ - 1e-9) {
    Fail(1,
         fmt::format("nose radius compensation: inside arc radius {:.3f} is less than twice the nose radius "
                     "{:.3f}",
                     radius, r_));
  }
}

void NoseComp::Release(Vec2 end_centre) {
  Staged s = std::move(pend_->s);
  Target& t = *s.c.target();
  SetPlane(t.pos, end_centre + tip_);
  if (ArcOp* a = s.c.If<ArcOp>()) {
    const Vec2 c = pend_->e.path.center;
    a->center[0] = 2 * (c.y + tip_.y);
    a->center[2] = c.x + tip_.x;
    double sweep = geom::Sweep(centre_, end_centre, c, a->cw);
    // An arc whose compensated end falls just behind its start (a complete or nearly complete circle) keeps
    // its programmed sweep.
    if (sweep > 359.999 && pend_->e.path.sweep < 359.999) sweep = 0;
    // An arc whose compensated end falls behind its start (the nose larger than what is left of the arc
    // between the corners at its ends) would go nearly round its centre, through the part: the path in
    // contact "with each arc or its extension" (ln 2745) cannot be had going forward, an alarm as where such
    // a point "cannot be obtained" (ln 2716, 2748; okuma.md judgement call 68).
    else if (sweep > pend_->e.path.sweep + 180)
      Fail(1, fmt::format("nose radius compensation: the nose radius {:.3f} is too large for the arc (its "
                          "compensated path would run back {:.3f} degrees)",
                          r_, 360 - sweep));
    a->angle = sweep;
  }
  centre_ = end_centre;
  pend_.reset();
  Out(std::move(s));
  while (!held_.empty()) {
    Staged h = std::move(held_.front());
    held_.pop_front();
    if (h.kind == Staged::kOp && IsMove(h.c.op())) SetPlane(h.c.target()->pos, centre_ + tip_);
    Out(std::move(h));
  }
}

void NoseComp::Op(Staged&& s) {
  if (!IsMove(s.c.op())) {
    if (pend_) {
      held_.push_back(std::move(s));
    } else {
      Out(std::move(s));
    }
    return;
  }
  geom::Path p = PathOf(s.c, prog_);
  prog_ = p.end;
  const bool in_plane = p.arc || geom::Norm(p.end - p.start) >= kTiny;
  if (in_plane) block_motion_ = true;

  if (state_ == kOff) {
    if (plan_ == kPlanStart && in_plane) {
      // The start-up move (ln 2335-2447): held until the next element is known.
      if (p.arc) Fail(1, "G41/G42 must be given in G00 or G01 mode");
      pend_ = Pending{std::move(s), Elem{p, side_}, true, plan_ik_, plan_ikv_};
      state_ = kOn;
      plan_ = kNoPlan;
      since_startup_ = true;
      quiet_blocks_ = 0;
      return;
    }
    Out(std::move(s));
    return;
  }
  if (state_ == kResidual) {
    // After a G40 without motion the tool still stands offset; this move goes to its programmed point.
    Out(std::move(s));
    if (in_plane) state_ = kOff;
    return;
  }
  // Compensating.
  if (!in_plane) {
    if (pend_ && pend_->startup)
      Fail(1, "the block after the start-up of nose radius compensation repeats its point");
    if (!pend_ && since_startup_) Fail(1, "the first point after G41/G42 is the start-up point");
    // The same point again (ln 2601-2648): the tool goes to touch the contour at the programmed point.
    if (pend_) Release(OwnEnd(pend_->e));
    SetPlane(s.c.target()->pos, centre_ + tip_);
    Out(std::move(s));
    return;
  }
  Elem e{p, side_};
  CheckInsideArc(e);
  if (plan_ == kPlanCancel) {
    // The G40 move (ln 2825-2943): the last element ends where the nose touches its end point (or, with I/K,
    // the imaginary line of the exit vector), then the tool goes to the uncompensated point.
    if (p.arc) Fail(1, "G40 must be given in G00 or G01 mode");
    ReleaseAtCancel();
    Out(std::move(s));
    state_ = kOff;
    plan_ = kNoPlan;
    return;
  }
  if (!pend_) {
    // The first element after a start-up without motion, or after the tool touched a repeated point: it
    // starts where the tool is.
    pend_ = Pending{std::move(s), e, false, false, {}};
    since_startup_ = false;
    return;
  }
  Vec2 end;
  if (pend_->startup) {
    if (pend_->has_ik && geom::Norm(pend_->ik) > kTiny) {
      // I/K in the G41/G42 block (ln 2426-2447): the nose touches the next element and the imaginary line
      // from the point given by I, K to the start-up point.
      const Vec2 ps = pend_->e.path.end;
      geom::Path imag;
      imag.start = ps + pend_->ik;
      imag.end = ps;
      end = Corner(Elem{imag, pend_->e.side}, e);
    } else {
      end = geom::OffsetStart(p, r_, e.side);
    }
  } else {
    end = Corner(pend_->e, e);
  }
  Release(end);
  pend_ = Pending{std::move(s), e, false, false, {}};
  since_startup_ = false;
  quiet_blocks_ = 0;
}

// At G40 (with or without motion): the last element ends where the nose touches its end point or, with I/K,
// the imaginary line of the exit vector (ln 2825-2943).
void NoseComp::ReleaseAtCancel() {
  if (!pend_) return;
  Vec2 end = OwnEnd(pend_->e);
  if (plan_ik_ && geom::Norm(plan_ikv_) > kTiny) {
    const Vec2 pe = pend_->e.path.end;
    geom::Path imag;
    imag.start = pe;
    imag.end = pe + plan_ikv_;
    end = Corner(pend_->e, Elem{imag, pend_->e.side});
  }
  Release(end);
}

void NoseComp::BlockEnd(bool xz) {
  if (state_ == kOn) {
    if (plan_ == kPlanCancel) {
      // G40 alone (ln 2920-2943): the nose goes to touch the last programmed point and stays there.
      ReleaseAtCancel();
      state_ = geom::Norm(centre_ + tip_ - prog_) > kTiny ? kResidual : kOff;
      plan_ = kNoPlan;
    } else if (!block_motion_ && !xz) {
      ++quiet_blocks_;
      if (since_startup_ && quiet_blocks_ >= 2) {
        Fail(1, "two blocks without X or Z after the start-up of nose radius compensation");
      }
      if (quiet_blocks_ == 2 && pend_ && !pend_->startup) {
        // Two blocks without axis commands (ln 2617-2648): the nose goes to touch the programmed point.
        Release(OwnEnd(pend_->e));
      }
    } else if (block_motion_) {
      quiet_blocks_ = 0;
    }
  } else if (plan_ == kPlanStart) {
    // G41/G42 without X/Z (ln 2380-2393): compensation starts with the next move.
    state_ = kOn;
    since_startup_ = true;
    quiet_blocks_ = 0;
    plan_ = kNoPlan;
  }
  block_motion_ = false;
}

void NoseComp::Finish() {
  if (pend_) Release(OwnEnd(pend_->e));
  while (!held_.empty()) {
    Out(std::move(held_.front()));
    held_.pop_front();
  }
  state_ = kOff;
  plan_ = kNoPlan;
}

}  // namespace cell::interp::okuma
