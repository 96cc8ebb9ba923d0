// Okuma circular interpolation G02/G03 (manual ln 1204-1300) on the core's arc geometry: the end point X Z
// (absolute or incremental), the centre by I and K (radius values, incremental from the start in G90 and G91
// alike; an omitted one is 0) or the radius L (both X and Z needed, the arc under 180 degrees unless CALRG),
// the allowable radius error (OTHER FUNCTION 1 No. 6, the run's ARC_TOLERANCE).
#include <fmt/format.h>

#include <cmath>

#include "interp_internal.h"

namespace cell::interp::okuma {

void OkRun::Arc(const BlockWords& w, const Block& b, bool cw, int col) {
  if (w.Has('A')) Fail(w.Col('A'), "the taper angle A is not allowed in G02/G03");
  if (w.Has('C')) Fail(w.Col('C'), "C is not allowed in G02/G03");
  const bool has_l = w.Has('L'), has_ik = w.Has('I') || w.Has('K');
  if (has_l && has_ik) Fail(w.Col('L'), "L together with I or K in one block");
  if (!has_l && !has_ik) Fail(col, "G02/G03 need the centre (I, K) or the radius L");
  if (f_ <= 0) Fail(col, "no feedrate: F is 0 (F is cleared at reset)");
  // Turret B mirrors X: the arc turns the other way on the machine (ln 7224-7231).
  if (modal_.turret_b) cw = !cw;
  AxisArray target = pos_;
  uint32_t moved = 0;
  auto prog_target = [&](int axis, char a) {
    const double cur = ToProgram(axis, pos_[static_cast<size_t>(axis)]);
    return ToMachine(axis, modal_.incremental ? cur + w.Get(a) : w.Get(a));
  };
  if (w.Has('X')) {
    target[kX] = prog_target(kX, 'X');
    moved |= 1u << kX;
  }
  if (w.Has('Z')) {
    target[kZ] = prog_target(kZ, 'Z');
    moved |= 1u << kZ;
  }
  const geom::Vec2 start = PlaneOf(pos_), end = PlaneOf(target);
  constexpr double kMinRadius = 0.001;
  geom::ArcSolution sol;
  if (has_l) {
    if (!(w.Has('X') && w.Has('Z'))) Fail(col, "an arc given by its radius L needs both X and Z");
    const double l = w.Get('L');
    if (l <= 0) Fail(w.Col('L'), "the arc radius L must be positive");
    sol = geom::ArcFromRadius(start, end, l, cw, b.calrg, kMinRadius);
    switch (sol.error) {
      case geom::ArcError::kFullCircleWithRadius:
        Fail(w.Col('L'), "an arc given by its radius L cannot be a full circle");
      case geom::ArcError::kRadiusTooSmall:
        Fail(w.Col('L'), "the end point is more than twice the radius L away");
      case geom::ArcError::kBelowMinimum:
        Fail(w.Col('L'), "the arc radius L is too small");
      default:
        break;
    }
  } else {
    if (b.calrg) Fail(b.calrg_col, "CALRG is taken only with the radius L");
    const double i = w.Has('I') ? w.Get('I') : 0, k = w.Has('K') ? w.Get('K') : 0;
    const geom::Vec2 centre{start.x + k, start.y + (modal_.turret_b ? -i : i)};
    sol = geom::ArcFromCenter(start, end, centre, cw, kMinRadius, arc_tolerance_);
    if (sol.error == geom::ArcError::kBelowMinimum) Fail(col, "the arc radius is too small");
    if (sol.error == geom::ArcError::kRadiiDiffer) {
      Fail(col,
           fmt::format("the arc's radius differs between its start ({:.4f}) and end ({:.4f}) by more than "
                       "the allowable error {:.4f}",
                       sol.radius_start, sol.radius_end, arc_tolerance_));
    }
  }
  used_ |= moved;
  const AxisArray from = pos_;
  pos_ = target;
  ArcOp& a = Out<ArcOp>();
  a.to.pos = pos_;
  a.to.used = used_;
  a.feed = {f_, FeedModeNow(), modal_.droop};
  a.center = {2 * sol.center.y, pos_[kY], sol.center.x};
  a.cw = cw;
  a.plane = {static_cast<std::int8_t>(kZ), static_cast<std::int8_t>(kX)};
  a.angle = sol.sweep;
  if (staged_) stage_.from = from;
}

}  // namespace cell::interp::okuma
