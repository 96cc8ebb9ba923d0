// Balt-System fixed cycles G81-G89 / G80 (manual §5.8.7, ln 3283-3590, Table 5.6): the declaration block
// stores R1 [R2], the depth on the spindle axis it names, I J K, and moves nothing; every following block
// with plane coordinates (or a stored point) drills there. Per hole: rapid to the point, rapid to R1, the
// cycle's approach, its bottom action, the return to R1 or R2. The update rules of ln 3531-3590: "X Y R Z"
// moves, updates R and Z, then drills; "X Y R1 R2" drills, then updates R1 R2 and returns to the new R2.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "interp_internal.h"

namespace cell::interp::balt {

void BaltRun::DeclareCycle(const ParsedBlock& pb, const BlockG& g) {
  int col = g.first_col;
  if (mode_.cycle != 80)
    Fail(col, 25, fmt::format("G{} is active: close it with G80 first (ln 3331)", mode_.cycle));
  if (contour_.engaged() || gtl_profile_)
    Fail(col, 25, "fixed cycles are not allowed with compensation or in GTL");
  if ((g.cycle == 86 || g.cycle == 89) && mode_.feed == FeedCode::kG95) {
    Fail(col, 98, fmt::format("G{} in G95", g.cycle));
  }
  if (pb.elem.kind) Fail(pb.elem.col, 24, "the declaration block moves nothing");
  Cycle c;
  c.g = g.cycle;
  int axis = -1, axis_col = col;
  double depth = 0;
  InlineVec<double, 2> rs;
  const AxisArray& prog = Prog();
  for (const Word& w : pb.words) {
    int a = AxisOfLetter(w.letter);
    double v = (w.letter == 'G' || w.letter == 'M' || w.letter == 'S' || w.letter == 'T' || w.letter == 'H' ||
                w.letter == 'F' || w.letter == 't')
                   ? 0
                   : ValueOf(w.v, w.col);
    if (a >= 0) {
      if (axis >= 0) Fail(w.col, 24, "the declaration names one axis, the spindle axis (ln 3319)");
      if (!(spindle_axes_ & (1u << a))) Fail(w.col, 88, fmt::format("{} is not a spindle axis", w.letter));
      axis = a;
      axis_col = w.col;
      depth = v * UnitFactor();
    } else if (w.letter == 'R') {
      if (!rs.push_back(v * UnitFactor())) Fail(w.col, 24, "at most two R (R1, R2)");
    } else if (w.letter == 'I') {
      c.has_i = true;
      c.i = v * UnitFactor();
    } else if (w.letter == 'J') {
      c.has_j = true;
      c.j = v * UnitFactor();
    } else if (w.letter == 'K') {
      c.has_k = true;
      c.k = w.v.kind == Val::kNone ? 0 : v;
    } else if (w.letter == 'u' || w.letter == 'v' || w.letter == 'w' || w.letter == 'r' || w.letter == 'b') {
      Fail(w.col, 24, fmt::format("'{}' in a fixed cycle", w.letter));
    }
  }
  if (axis < 0) Fail(col, 12, "the depth on the spindle axis is missing");
  if (rs.empty() && g.cycle != 84) Fail(col, 12, "R1 is missing");
  if ((c.has_i || c.has_j || c.has_k) && g.cycle != 83 && !(g.cycle == 84 && !c.has_i && !c.has_j)) {
    Fail(col, 24, "I, J, K belong to G83 (K also to G84)");
  }
  if (g.cycle == 83 && !c.has_i) Fail(col, 12, "G83 needs the increment I");
  if (g.cycle == 83 && c.i <= 0) Fail(col, 13, "the G83 increment I is positive");
  if (g.cycle == 84 && c.has_k && !transducer_) Fail(col, 22, "K in G84 without a spindle transducer");
  c.axis = axis;
  // Values in program coordinates of the spindle axis; G91: R1 from the current position, the depth and R2
  // from R1 (a judgement call).
  double here = prog[axis];
  double r1 = rs.empty() ? (mode_.incremental ? 0 : here) : rs[0];
  c.r1 = mode_.incremental ? here + r1 : r1;
  c.has_r2 = rs.size() > 1;
  if (c.has_r2) c.r2 = mode_.incremental ? c.r1 + rs[1] : rs[1];
  c.depth = mode_.incremental ? c.r1 + depth : depth;
  (void)axis_col;
  cycle_ = c;
  mode_.cycle = g.cycle;
}

// A move of the spindle axis alone, to a program coordinate.
void BaltRun::SpindleAxisMove(double prog_value, bool rapid, double feed) {
  AxisArray p = Prog();
  p[cycle_.axis] = prog_value;
  AxisArray mach = ToMachine(p);
  geom::Path none;
  none.start = none.end = {pos_[mode_.p1], pos_[mode_.p2]};
  Feed f;
  f.rate = feed;
  // In G95 F is per revolution (ln 2494-2496, judgement call 18), in a cycle too; G84's transducer feed
  // K x rpm (ln 3484-3496) is already per minute.
  bool transducer = cycle_.g == 84 && cycle_.has_k;
  f.mode = mode_.feed == FeedCode::kG95 && !transducer ? FeedMode::kPerRev : FeedMode::kPerMinute;
  f.exact_stop = true;
  CheckLimits(pos_, mach, nullptr, 1);
  EmitMotion(rapid ? Op::kRapid : Op::kLinear, mach, 1u << cycle_.axis, f, none, {}, 0, 0);
  prog_[cycle_.axis] = prog_value;
}

void BaltRun::DrillHole(int col) {
  const Cycle& c = cycle_;
  if (!feed_ && !(c.g == 84 && c.has_k)) Fail(col, 86, "no F programmed for the cycle");
  double feed = feed_ ? *feed_ : 0;
  if (c.g == 84 && c.has_k) {
    // ln 3484-3496: with a transducer F = K x rpm.
    feed = c.k * UnitFactor() * speed_;
  }
  if ((c.g == 84 || c.g == 86) &&
      (!speed_set_ || spindle_ == SpindleDir::kStop || spindle_ == SpindleDir::kOrient)) {
    Fail(col, 10, fmt::format("G{}: the spindle is not turning", c.g));
  }
  const double ret = c.has_r2 ? c.r2 : c.r1;
  const double dir = c.depth < c.r1 ? -1.0 : 1.0;  // toward the bottom
  SpindleAxisMove(c.r1, true, 0);
  switch (c.g) {
    case 83: {
      if (c.has_k || c.has_j) {
        // Chip discharge (ln 3380-3402): b. rapid to R1, c. feed to R1 + I, d. rapid back to the initial R1
        // (step b "always carried out at the initial R1": the discharge leaves the hole), e. R1 = R1 + I - 1,
        // f. I = I*K, at least J. The next peck rapids down to the new R1, 1 mm (`PECK_CLEARANCE`) short of
        // the last bottom, and feeds I from there: it cuts I - 1 of new depth, not I. The pecks are worked
        // out before any move so that a hole that would never reach Z is refused undrilled.
        std::vector<double> bottoms;
        double inc = c.i, r1 = c.r1;
        const double k = c.has_k ? c.k : 1.0, j = c.has_j ? c.j : 0.0;
        for (;;) {
          double next = r1 + dir * inc;
          if (dir < 0 ? next <= c.depth : next >= c.depth) {
            bottoms.push_back(c.depth);
            break;
          }
          bottoms.push_back(next);
          r1 = next - dir * peck_clearance_;
          inc = std::max(inc * k, j);
          // A peck no longer than the re-approach gets no deeper (K < 1 without J, or J <= 1 mm).
          if (inc <= peck_clearance_ + 1e-6 || bottoms.size() >= 10000) {
            Fail(col, 13,
                 fmt::format("G83: the increment falls to {:g} mm, not more than the {:g} mm re-approach of "
                             "R1 = R1 + I - 1: Z is never reached (ln 3395-3402)",
                             inc, peck_clearance_));
          }
        }
        for (std::size_t n = 0; n < bottoms.size(); ++n) {
          if (n > 0) {
            SpindleAxisMove(c.r1, true, 0);                                    // d. chip discharge
            SpindleAxisMove(bottoms[n - 1] - dir * peck_clearance_, true, 0);  // b. to the new R1
          }
          SpindleAxisMove(bottoms[n], false, feed);  // c. to R1 + I
        }
      } else {
        // Woodpecking without discharge (ln 3404-3414): feed by I, dwell TMR, feed by I, ...
        double bottom = c.r1;
        for (int n = 0; n < 100000; ++n) {
          double next = bottom + dir * c.i;
          bool last = dir < 0 ? next <= c.depth : next >= c.depth;
          if (last) next = c.depth;
          SpindleAxisMove(next, false, feed);
          bottom = next;
          if (last) break;
          EmitDwell(tmr_);
        }
      }
      SpindleAxisMove(ret, true, 0);
      break;
    }
    case 84: {
      // Feed in with the spindle turning, reverse it at the bottom, feed out to R1 (RMS percent of F), the
      // spindle back, rapid to R2 if given.
      SpindleDir d = spindle_;
      SpindleAxisMove(c.depth, false, feed);
      EmitSpindle(d == SpindleDir::kCw ? SpindleDir::kCcw : SpindleDir::kCw);
      SpindleAxisMove(c.r1, false, feed * rms_ / 100.0);
      EmitSpindle(d);
      if (c.has_r2) SpindleAxisMove(c.r2, true, 0);
      break;
    }
    case 85:
    case 89:
      SpindleAxisMove(c.depth, false, feed);
      if (c.g == 89) EmitDwell(tmr_);
      SpindleAxisMove(c.r1, false, feed);
      if (c.has_r2) SpindleAxisMove(c.r2, true, 0);
      break;
    case 86: {
      SpindleDir d = spindle_;
      SpindleAxisMove(c.depth, false, feed);
      EmitSpindle(SpindleDir::kStop);
      SpindleAxisMove(ret, true, 0);
      EmitSpindle(d);  // turning again for the next hole
      break;
    }
    default:  // 81, 82
      SpindleAxisMove(c.depth, false, feed);
      if (c.g == 82) EmitDwell(tmr_);
      SpindleAxisMove(ret, true, 0);
      break;
  }
}

void BaltRun::CycleBlock(const ParsedBlock& pb, const BlockG& g, const Targets& t) {
  if (contour_.engaged() || gtl_profile_)
    Fail(g.first_col, 25, "fixed cycles are not allowed with compensation or in GTL");
  if (g.any_motion &&
      (mode_.motion == Motion::kCw || mode_.motion == Motion::kCcw || mode_.motion == Motion::kThread)) {
    Fail(g.first_col, 25, "G02/G03/G33 in a fixed cycle");
  }
  int col = g.first_col;
  InlineVec<double, 2> rs;
  bool depth_given = false;
  double depth = 0;
  for (const Word& w : pb.words) {
    if (w.letter == 'R') {
      if (!rs.push_back(ValueOf(w.v, w.col) * UnitFactor())) Fail(w.col, 24, "at most two R (R1, R2)");
      col = w.col;
    }
    if (AxisOfLetter(w.letter) == cycle_.axis) {
      depth_given = true;
      depth = ValueOf(w.v, w.col) * UnitFactor();
    }
    if (AxisOfLetter(w.letter) >= 0 && col == g.first_col) col = w.col;
  }
  // The hole position: every axis of the block but the spindle axis.
  Targets pos = t;
  pos.mask &= ~(1u << cycle_.axis);
  pos.prog[cycle_.axis] = Prog()[cycle_.axis];
  const bool hole = pos.mask != 0;
  if (hole) {
    BlockG rapid = g;
    rapid.g79 = false;
    Motion keep = mode_.motion;
    mode_.motion = Motion::kRapid;
    LinearMove(pb, rapid, pos, true);
    mode_.motion = keep;
  }
  auto update_depth = [&]() {
    if (depth_given) cycle_.depth = mode_.incremental ? cycle_.r1 + depth : depth;
  };
  if (rs.size() == 2) {
    // "X Y R1 R2": drill with the current values, then take the new ones and go to the new R2.
    if (hole) DrillHole(col);
    cycle_.r1 = rs[0];
    cycle_.r2 = rs[1];
    cycle_.has_r2 = true;
    update_depth();
    if (hole) SpindleAxisMove(cycle_.r2, true, 0);
    return;
  }
  if (rs.size() == 1) {
    cycle_.r1 = mode_.incremental ? Prog()[cycle_.axis] + rs[0] : rs[0];
  }
  update_depth();
  if (hole) DrillHole(col);
}

}  // namespace cell::interp::balt
