// Okuma grooving / drilling compound cycles G73 (longitudinal: infeed along X, shift along Z) and G74
// (transverse: infeed along Z, shift along X) (manual ln 3907-4004), and the tapping cycles G77 (right-hand)
// and G78 (left-hand) (ln 4006-4071).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "interp_internal.h"

namespace cell::interp::okuma {
namespace {

double Sign(double v) {
  return v < 0 ? -1.0 : (v > 0 ? 1.0 : 0.0);
}

}  // namespace

void OkRun::Grooving(const BlockWords& w, int g, int col) {
  // G73 / G74 X Z I K D L DA= E F T.
  const bool g73 = g == 73;
  if (g == 74 && !w.Has('Z')) Fail(col, "G74 needs Z");
  if (!w.Has('D') || w.Get('D') <= 0) Fail(col, fmt::format("G{} needs the depth of cut D > 0", g));
  if (f_ <= 0) Fail(col, fmt::format("G{} needs a feedrate F", g));
  const int in_axis = g73 ? kX : kZ;  // infeed
  const int sh_axis = g73 ? kZ : kX;  // shift
  const char in_letter = g73 ? 'X' : 'Z';
  const char sh_letter = g73 ? 'Z' : 'X';
  const AxisArray s = pos_;
  auto prog = [&](int axis, char a) {
    const double cur = ToProgram(axis, s[static_cast<size_t>(axis)]);
    return ToMachine(axis, modal_.incremental ? cur + w.Get(a) : w.Get(a));
  };
  const double in_target = w.Has(in_letter) ? prog(in_axis, in_letter) : s[static_cast<size_t>(in_axis)];
  const double sh_target = w.Has(sh_letter) ? prog(sh_axis, sh_letter) : s[static_cast<size_t>(sh_axis)];
  const double in_dir = Sign(in_target - s[static_cast<size_t>(in_axis)]);
  const double sh_dir = Sign(sh_target - s[static_cast<size_t>(sh_axis)]);
  // I and K: G73 approaches by I along X and shifts by K along Z; G74 approaches by K along Z and shifts by I
  // along X (ln 3997-4004).
  const double approach = std::fabs(g73 ? (w.Has('I') ? w.Get('I') : 0) : (w.Has('K') ? w.Get('K') : 0));
  const double shift = std::fabs(g73 ? (w.Has('K') ? w.Get('K') : 0) : (w.Has('I') ? w.Get('I') : 0));
  const double depth = w.Get('D');
  const double total = w.Has('L') ? w.Get('L') : 0;
  const double retract = w.HasExt(3) ? w.ext[3] : peck_retract_;  // DA=
  if (retract < 0) Fail(w.ext_col[3], "DA (retraction) must not be negative");
  const double dwell = w.Has('E') ? Scale('T', w.Get('E'), false) : 0;
  // T: the offset number of the last groove (the other side of a grooving tool, ln 3933-3952).
  double last_in_off = 0, last_sh_off = 0;
  if (w.Has('T')) {
    const int t = static_cast<int>(w.Get('T')) % 100;
    const double dx = tools_.OffsetX(t) - tools_.OffsetX(offset_no_);
    const double dz = tools_.OffsetZ(t) - tools_.OffsetZ(offset_no_);
    last_in_off = g73 ? dx : dz;
    last_sh_off = g73 ? dz : dx;
  }
  const double start_level = s[static_cast<size_t>(in_axis)];
  const double v0 = start_level + in_dir * approach;
  const FeedMode fm = FeedModeNow();
  auto move = [&](int axis, double v, bool rapid) {
    AxisArray t = pos_;
    t[static_cast<size_t>(axis)] = v;
    EmitMove(t, 1u << axis, rapid, rapid ? 0 : f_, fm, {}, 0, nullptr);
  };
  long moves_left = 200000;
  auto groove = [&](double u, double in_off) {
    move(sh_axis, u, true);
    const double bottom = in_target + in_off;
    const double top = v0 + in_off;
    move(in_axis, top, true);
    double cur = top, since_return = 0;
    moves_left -= static_cast<long>(std::fabs(bottom - top) / depth) + 1;
    if (moves_left < 0) Fail(col, "more than 200000 pecks in the cycle: D is too small");
    const double dir = Sign(bottom - top) != 0 ? Sign(bottom - top) : in_dir;
    while ((bottom - cur) * dir > 1e-9) {
      const double next = (bottom - (cur + dir * depth)) * dir > 0 ? cur + dir * depth : bottom;
      move(in_axis, next, false);
      since_return += std::fabs(next - cur);
      cur = next;
      if ((bottom - cur) * dir <= 1e-9) break;
      if (total > 0 && since_return >= total - 1e-9) {
        // L: back to the cycle start level, then down again to just above the depth reached.
        move(in_axis, start_level + in_off, true);
        move(in_axis, cur - dir * retract, true);
        since_return = 0;
      } else if (retract > 0) {
        move(in_axis, cur - dir * retract, true);
      }
    }
    if (dwell > 0) Out<DwellOp>().seconds = dwell;
    move(in_axis, start_level + (in_off != 0 ? in_off : 0), true);
  };
  const double final_u = sh_target + last_sh_off;
  double u = s[static_cast<size_t>(sh_axis)];
  if (sh_dir == 0 || shift <= 0) {
    groove(final_u == u ? u : final_u, last_in_off);
  } else {
    int n = 0;
    while ((final_u - u) * sh_dir > 1e-9) {
      groove(u, 0);
      u += sh_dir * shift;
      if (++n > 10000) Fail(col, "more than 10000 grooves: the shift is too small");
    }
    groove(final_u, last_in_off);
  }
  // Back to the cycle start point.
  move(in_axis, start_level, true);
  move(sh_axis, s[static_cast<size_t>(sh_axis)], true);
}

void OkRun::Tapping(const BlockWords& w, int g, int col) {
  // G77 / G78 X Z K F: Q1 X rapid, Q2 spindle forward (G77) / reverse (G78) at the speed in force, Q3 Z rapid
  // by K toward the hole, Q4 tap to Z at F, Q5 spindle stop and reverse, Q6 back to the Q3 point at F, Q7 Z
  // rapid back to the start; the spindle stays stopped (ln 4006-4071). K is the rapid approach distance. The
  // feed override is 100 % over the whole cycle (judgement 62).
  if (!w.Has('Z')) Fail(col, fmt::format("G{} needs Z (the tapping end point)", g));
  if (f_ <= 0) Fail(col, fmt::format("G{} needs a feedrate F (the pitch in G95)", g));
  if (modal_.css) Fail(col, "tapping needs a constant spindle speed (G97)");
  if (s_ <= 0) Fail(col, "tapping needs a spindle speed S before the cycle");
  const AxisArray s = pos_;
  auto prog = [&](int axis, char a) {
    const double cur = ToProgram(axis, s[static_cast<size_t>(axis)]);
    return ToMachine(axis, modal_.incremental ? cur + w.Get(a) : w.Get(a));
  };
  const FeedMode fm = FeedModeNow();
  auto move = [&](int axis, double v, bool rapid) {
    AxisArray t = pos_;
    t[static_cast<size_t>(axis)] = v;
    EmitMove(t, 1u << axis, rapid, rapid ? 0 : f_, fm, {}, 0, nullptr);
  };
  auto spindle = [&](SpindleDir d) {
    modal_.spindle = d;
    SpindleOp& sp = Out<SpindleOp>();
    sp.dir = d;
    sp.rpm = s_;
    sp.max_rpm = max_rpm_;
  };
  CycleFeedFixed(true);  // "the feedrate override is fixed at 100 %" while the cycle runs (ln 4069)
  if (w.Has('X')) move(kX, prog(kX, 'X'), true);
  bool forward = g == 77;
  if (modal_.turret_b) forward = !forward;  // ln 7362
  spindle(forward ? SpindleDir::kCw : SpindleDir::kCcw);
  const double z_end = prog(kZ, 'Z');
  const double k = w.Has('K') ? std::fabs(w.Get('K')) : 0;
  const double zc = s[kZ] + Sign(z_end - s[kZ]) * k;
  move(kZ, zc, true);
  move(kZ, z_end, false);
  spindle(SpindleDir::kStop);
  spindle(forward ? SpindleDir::kCcw : SpindleDir::kCw);
  move(kZ, zc, false);
  move(kZ, s[kZ], true);
  spindle(SpindleDir::kStop);
  CycleFeedFixed(false);
}

}  // namespace cell::interp::okuma
