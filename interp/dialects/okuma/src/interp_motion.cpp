// Okuma motion (manual SECTIONS 2-4, seed ln 941-1202, 1473-1496, 1642-1722, 8988-9018): program and machine
// coordinates (zero offset, G50 zero shift, tool offset; turret B mirrors X), G00 / G01 with the direct taper
// angle A and angle-only lines, G75/G76 corners, the C axis (M15/M16 direction, QA= revolutions, the feed
// rule 360 deg = 500 mm), variable soft limits, G04 dwell and G50.
#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>

#include "interp_internal.h"

namespace cell::interp::okuma {
namespace {

constexpr uint32_t kXBit = 1u << kX;
constexpr uint32_t kZBit = 1u << kZ;
constexpr uint32_t kCBit = 1u << kC;

}  // namespace

double OkRun::Offset(int axis) const {
  double o = zero_offset_[static_cast<size_t>(axis)] + zero_shift_[static_cast<size_t>(axis)];
  if (offset_no_ <= 0) return o;  // no tool offset selected: no table lookup (this runs per axis and move)
  if (axis == kX) o += tools_.OffsetX(offset_no_);
  if (axis == kZ) o += tools_.OffsetZ(offset_no_);
  return o;
}

double OkRun::ToMachine(int axis, double prog) const {
  const double s = (axis == kX && modal_.turret_b) ? -prog : prog;
  return s + Offset(axis);
}

double OkRun::ToProgram(int axis, double machine) const {
  const double v = machine - Offset(axis);
  return (axis == kX && modal_.turret_b) ? -v : v;
}

void OkRun::Motion(const BlockWords& w, const Block& b, int motion_col) {
  if (w.Has('Y')) Fail(w.Col('Y'), "Y is a word of the coordinate conversion mode G137 (ln 6824, 6850)");
  const int mode = modal_.motion;
  const bool axes = w.Has('X') || w.Has('Z') || w.Has('C') || w.Has('A');
  if (open_line_ && axes && mode != 0 && mode != 1 && mode != 34 && mode != 35 && mode >= 0) {
    Fail(motion_col, "after a line given by an angle only, the next block must be a line with X, Z and A");
  }
  switch (mode) {
    case 0:
    case 1:
      if (axes)
        LineMotion(w, b, mode == 0, motion_col);
      else if (w.HasG(75) || w.HasG(76))
        Fail(motion_col, "G75/G76 need X or Z (or A)");
      return;
    case 2:
    case 3:
      if (w.Has('X') || w.Has('Z'))
        Arc(w, b, mode == 2, motion_col);
      else if (w.Has('I') || w.Has('K') || w.Has('L'))
        Fail(motion_col, "G02/G03 need the end point X and/or Z");
      return;
    case 31:
    case 32:
    case 33:
      // In a LAP contour a thread block is one element of the thread path (AP mode III, ln 5600-5628).
      if ((lap_.active || lap_.finish) && axes) {
        ThreadBlock(w, 34, motion_col);
      } else if (w.Has('X') || w.Has('Z')) {
        ThreadCycle(w, mode, motion_col);
      }
      return;
    case 34:
    case 35:
      if (axes) ThreadBlock(w, mode, motion_col);
      return;
    case 101:
    case 102:
    case 103:
      if (w.Has('X') || w.Has('Z') || w.Has('C')) ContourMove(w, mode, motion_col);
      return;
    case 132:
    case 133:
      if (w.Has('X') || w.Has('Z') || w.Has('C')) SideContour(w, mode, motion_col);
      return;
    case -1:  // after G137 (ln 6830-6831)
      if (axes)
        Fail(motion_col, "G137 cancelled the motion mode: designate G00, G01 or a cycle in this block");
      return;
    default:
      return;
  }
}

// The direction of a taper angle A: from +Z, counterclockwise positive in the Z-X plane (ln 9000-9012); in
// the machine plane (turret B mirrors X).
static geom::Vec2 AngleDir(double deg, bool mirror) {
  const double r = deg * kPi / 180.0;
  return {std::cos(r), mirror ? -std::sin(r) : std::sin(r)};
}

// The end of a line: X and/or Z (absolute or incremental), or one of them with the taper angle A, or A alone
// (the end comes with the next block). Returns false when there is nothing to move.
bool OkRun::TargetOf(const BlockWords& w, AxisArray& target, uint32_t* moved, int motion_col) {
  const bool has_x = w.Has('X'), has_z = w.Has('Z'), has_a = w.Has('A');
  auto prog_target = [&](int axis, char a) {
    const double cur = ToProgram(axis, pos_[static_cast<size_t>(axis)]);
    return ToMachine(axis, modal_.incremental && !w.absolute ? cur + w.Get(a) : w.Get(a));
  };
  const geom::Vec2 start = PlaneOf(pos_);
  if (open_line_) {
    if (!(has_x && has_z && has_a) || modal_.incremental) {
      Fail(motion_col, "after a line given by an angle only, give the end point with X, Z and A (absolute)");
    }
    target[kX] = prog_target(kX, 'X');
    target[kZ] = prog_target(kZ, 'Z');
    *moved |= kXBit | kZBit;
    return true;
  }
  if (has_a) {
    if (has_x && has_z) Fail(w.Col('A'), "A with both X and Z: give one of them with the angle");
    if (!has_x && !has_z) {
      *moved |= kXBit | kZBit;
      return true;  // an angle-only line
    }
    const geom::Vec2 d = AngleDir(w.Get('A'), modal_.turret_b);
    double t;
    if (has_x) {
      const double xr = prog_target(kX, 'X') / 2;
      if (std::fabs(d.y) < 1e-12) Fail(w.Col('A'), "no intersection of the taper angle A with X");
      t = (xr - start.y) / d.y;
    } else {
      const double z = prog_target(kZ, 'Z');
      if (std::fabs(d.x) < 1e-12) Fail(w.Col('A'), "no intersection of the taper angle A with Z");
      t = (z - start.x) / d.x;
    }
    if (t < -1e-9) Fail(w.Col('A'), "no intersection: the taper angle A points away from the end point");
    SetPlane(target, start + t * d);
    *moved |= kXBit | kZBit;
    return true;
  }
  if (has_x) {
    target[kX] = prog_target(kX, 'X');
    *moved |= kXBit;
  }
  if (has_z) {
    target[kZ] = prog_target(kZ, 'Z');
    *moved |= kZBit;
  }
  return has_x || has_z;
}

void OkRun::CTarget(const BlockWords& w, AxisArray& target, AxisArray& travel, uint32_t* travel_mask) {
  const int col = w.Col('C');
  if (!modal_.c_joined) Fail(col, "C-axis command while the spindle is not joined as the C axis (M110)");
  if (modal_.c_clamped) Fail(col, "C-axis command while the C axis is clamped (M147)");
  const double c = w.Get('C');
  const double cur = pos_[kC];
  double t, tr;
  if (modal_.incremental && !w.absolute) {
    tr = c;
    t = std::fmod(cur + tr, 360.0);
  } else {
    if (!w.absolute && std::fabs(c) > 359.999 + 1e-9) Fail(col, "C is 0 to +-359.999 degrees");
    t = std::fmod(c + Offset(kC), 360.0);
    if (t < 0) t += 360.0;
    tr = CTravelTo(t);
  }
  if (t < 0) t += 360.0;
  if (w.HasExt(2)) {  // QA= full revolutions, 1-1999
    const double qa = w.ext[2];
    if (qa < 1 || qa > 1999 || qa != std::floor(qa)) Fail(w.ext_col[2], "QA is 1-1999 revolutions");
    tr += (modal_.c_negative ? -360.0 : 360.0) * qa;
  }
  target[kC] = t;
  used_ |= kCBit;
  if (std::fabs(tr) > 1e-9) {
    travel[kC] = tr;
    *travel_mask |= kCBit;
  }
}

// The travel of a C positioning to t (0-360) from where C is: M15 the positive direction, M16 the negative
// one (ln 1947-1948, 2073-2077).
double OkRun::CTravelTo(double t) const {
  const double cur = pos_[kC];
  return modal_.c_negative ? -std::fmod(cur - t + 720.0, 360.0) : std::fmod(t - cur + 720.0, 360.0);
}

void OkRun::LineMotion(const BlockWords& w, const Block& b, bool rapid, int motion_col) {
  (void)b;
  AxisArray target = pos_;
  AxisArray travel{};
  uint32_t moved = 0, tmask = 0;
  CornerSpec spec;
  const bool was_open = open_line_;
  TargetOf(w, target, &moved, motion_col);
  if (was_open) {
    spec.end_angle = true;
    spec.end_dir = AngleDir(w.Get('A'), modal_.turret_b);
    open_line_ = false;
  } else if (w.Has('A') && !w.Has('X') && !w.Has('Z')) {
    spec.open_end = true;
    spec.dir = AngleDir(w.Get('A'), modal_.turret_b);
    open_line_ = true;
  }
  if (w.Has('C')) {
    CTarget(w, target, travel, &tmask);
    moved |= kCBit;
  }
  const auto* g75 = w.FindG(75);
  const auto* g76 = w.FindG(76);
  if (g75 || g76) {
    const int col = (g75 ? g75 : g76)->col;
    if (!w.Has('L'))
      Fail(col, fmt::format("G{} needs L (the {} size)", g75 ? 75 : 76, g75 ? "chamfer" : "rounding"));
    if (w.Has('X') && w.Has('Z') && !was_open) {
      Fail(col, "the automatic chamfering block takes only one of X or Z");
    }
    if (std::fabs(w.Get('L')) < 1e-9) Fail(w.Col('L'), "L must not be 0");
    spec.kind = g75 ? CornerSpec::kChamfer : CornerSpec::kRound;
    spec.size = std::fabs(w.Get('L'));
    spec.col = w.Col('L');
  }
  double feed = 0;
  FeedMode fm = FeedModeNow();
  if (!rapid) {
    if (f_ <= 0) Fail(motion_col, "no feedrate: F is 0 (F is cleared at reset)");
    feed = f_;
    if (tmask & kCBit) {
      // The C-axis feed rule (ln 745-939): 360 deg count as 500 mm and X as the programmed diameter
      // difference; C alone is deg/min, with X or Z the move's time goes out as inverse time. In G95 F stays
      // per revolution.
      const double dx = std::fabs(target[kX] - pos_[kX]), dz = std::fabs(target[kZ] - pos_[kZ]);
      if (!modal_.per_rev) {
        const double dc = std::fabs(travel[kC]) * 500.0 / 360.0;
        if (dx < 1e-9 && dz < 1e-9) {
          fm = FeedMode::kDegPerMinute;
          feed = f_ * 360.0 / 500.0;
        } else {
          fm = FeedMode::kInverseTime;
          feed = f_ / std::sqrt(dx * dx + dz * dz + dc * dc);
        }
      }
    }
  }
  CheckLimits(target, w.Has('X') ? w.Col('X') : (w.Has('Z') ? w.Col('Z') : motion_col));
  EmitMove(target, moved, rapid, feed, fm, travel, tmask, spec.any() ? &spec : nullptr);
}

void OkRun::CheckLimits(AxisArray& target, int col) {
  // Variable soft limits (ln 739-743): beyond the positive limit the target is the limit; beyond the negative
  // limit there is no motion and an alarm.
  if ((neg_limit_set_ | pos_limit_set_) == 0) return;  // no limit set (most programs)
  for (int a : {kX, kZ}) {
    const uint32_t bit = 1u << a;
    double& t = target[static_cast<size_t>(a)];
    if ((neg_limit_set_ & bit) && t < neg_limit_[static_cast<size_t>(a)] - 1e-9) {
      Fail(col, fmt::format("{} target {:.3f} beyond the negative variable limit {:.3f}", a == kX ? 'X' : 'Z',
                            t, neg_limit_[static_cast<size_t>(a)]));
    }
    if ((pos_limit_set_ & bit) && t > pos_limit_[static_cast<size_t>(a)])
      t = pos_limit_[static_cast<size_t>(a)];
  }
}

void OkRun::EmitMove(const AxisArray& target, uint32_t moved, bool rapid, double feed, FeedMode fm,
                     const AxisArray& travel, uint32_t travel_mask, const CornerSpec* spec) {
  used_ |= moved;
  bool change = travel_mask != 0 || spec != nullptr;
  const uint32_t axes = moved & ((1u << kAxisCount) - 1);
  // Only the moved axes are visited (two of nine in a turning block), here and below.
  for (uint32_t m = axes; m != 0 && !change; m &= m - 1) {
    const auto a = static_cast<size_t>(std::countr_zero(m));
    if (std::fabs(target[a] - pos_[a]) > 1e-9) change = true;
  }
  // A block that commands the current position does not move; under nose radius compensation it still counts
  // (a repeated point has a meaning there, ln 2601-2648).
  if (!change && !comp_.on()) return;
  const AxisArray from = pos_;
  for (uint32_t m = axes; m != 0; m &= m - 1) {
    const auto a = static_cast<size_t>(std::countr_zero(m));
    pos_[a] = target[a];
  }
  if (travel_mask & kCBit) c_net_ += travel[kC];
  if (spec) force_stage_ = true;
  Target* to;
  if (rapid) {
    to = &Out<RapidOp>().to;
  } else {
    LinearOp& l = Out<LinearOp>();
    l.feed = {feed, fm, modal_.droop};  // G65: each feed move ends in position (ln 1742-1746)
    to = &l.to;
  }
  force_stage_ = false;
  to->pos = pos_;
  to->used = used_;
  to->travel = travel;
  to->travel_mask = travel_mask;
  if (staged_) {
    stage_.from = from;
    if (spec) stage_.corner = *spec;
  }
}

void OkRun::Dwell(const BlockWords& w, int col) {
  if (w.Has('X') || w.Has('Z') || w.Has('C')) Fail(col, "no axis words in a G04 block");
  if (!w.Has('F')) Fail(col, "G04 needs F (the dwell time)");
  const double s = Scale('T', w.Get('F'), false);
  if (s < 0 || s > 9999.99) Fail(w.Col('F'), "the dwell time is 0-9999.99 seconds");
  Out<DwellOp>().seconds = s;
}

void OkRun::ZeroShift(const BlockWords& w, int col) {
  // G50 X Z C (ln 1657-1707): the current position gets the given program coordinates; G50 S is the spindle
  // limit (taken with the S word).
  if (w.Has('T')) Fail(w.Col('T'), "no tool offset number in a G50 block");
  if (!(w.Has('X') || w.Has('Z') || w.Has('C') || w.Has('S'))) Fail(col, "G50 needs X, Z, C or S");
  if ((w.Has('X') || w.Has('Z') || w.Has('C')) && modal_.comp != 40) {
    Fail(col, "G50 zero shift is not allowed in nose radius compensation mode");
  }
  for (auto [a, axis] : {std::pair{'X', kX}, std::pair{'Z', kZ}, std::pair{'C', kC}}) {
    if (!w.Has(a)) continue;
    const double old = ToProgram(axis, pos_[static_cast<size_t>(axis)]);
    const double sgn = (axis == kX && modal_.turret_b) ? -1.0 : 1.0;
    zero_shift_[static_cast<size_t>(axis)] += sgn * (old - w.Get(a));
    used_ |= 1u << axis;
  }
}

}  // namespace cell::interp::okuma
