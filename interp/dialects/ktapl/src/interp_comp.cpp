// The executor's side of KT-APL cutter diameter compensation G40-G46 (manual ln 1599-1676, 6437-6696): the
// block's codes are checked and handed to the one-block look-ahead (cutter_comp.h) on the core's offset
// geometry.
#include <fmt/format.h>

#include <algorithm>

#include "interp_internal.h"

namespace cell::interp::ktapl {

void KtRun::CompPrepare(const Words& words, int motion_col, bool running_cycle, bool probe, bool g92) {
  const CompCodes k = comp_codes_;
  comp_codes_ = CompCodes();
  comp_col_ = motion_col;
  comp_g_col_ = k.g ? k.g_col : 1;
  bool set = k.g == 41 || k.g == 42;
  // G46 goes in the G41/G42 block and lasts until the next G41/G42 unless repeated there (ln 1658-1676).
  if (k.g46 && !set) Fail(k.g46_col, "G46 MUST BE ENTERED IN THE SAME BLOCK AS G41 OR G42");
  if (set) {
    mode_.fill_in_bypass = k.g46;
    comp_.SetBypass(mode_.fill_in_bypass);
  }
  // The plane's axes as in Arc (App. H: G18 is Z, X; G20/G21 substitute the co-axes).
  const geom::PlaneAxesN axes = PlaneAxes();
  const int p1 = axes.first, p2 = axes.second;
  if (set || (comp_.on() && k.g != 40)) {
    // Compensation is in effect through this block.
    if (comp_.on() && (p1 != comp_.p1() || p2 != comp_.p2())) {
      Fail(1, "THE PLANE CANNOT CHANGE WITH G41/G42 IN EFFECT");
    }
    if (mode_.cycle != 0 && !running_cycle) Fail(1, "FIXED CYCLES ARE NOT ALLOWED WITH G41/G42 IN EFFECT");
    if (probe) Fail(1, "PROBE MOVES ARE NOT ALLOWED WITH G41/G42 IN EFFECT");
    if (g92) Fail(1, "G92 IS NOT ALLOWED WITH G41/G42 IN EFFECT");
    const bool z_word =
        std::any_of(words.begin(), words.end(), [](const Word& a) { return a.letter == 'Z'; });
    for (const auto& w : words) {
      // ln 6523: G40 must precede the next tool change.
      if (w.letter == 'M' && w.v == 6)
        Fail(w.col, "An automatic tool change cannot be programmed with G41 or G42 in effect");
      // P0 would shift a compensated axis's offset path by the tool length (call 78).
      if (w.letter == 'P' && w.v == 0 && (p1 == kZ || p2 == kZ) && z_word)
        Fail(w.col, "P0 MAY NOT MOVE THE COMPENSATION PLANE WITH G41/G42 IN EFFECT");
      if (w.letter != 'M' || w.v != 25) continue;
      for (const auto& a : words) {
        int ax = AxisOfLetter(a.letter);
        if (ax == p1 || ax == p2)
          Fail(w.col, "M25 MAY NOT MOVE THE COMPENSATION PLANE WITH G41/G42 IN EFFECT");
      }
    }
  }
  if (set) {
    int side = k.g == 41 ? cc::kLeft : cc::kRight;
    // Inverting exactly one axis of the plane swaps G41 and G42 (ln 5354-5355).
    if (((p1 == kX || p2 == kX) && mir_x_) != ((p1 == kY || p2 == kY) && mir_y_)) side = -side;
    double r = tool_dia_ / 2;
    if (r < 0) {  // preset tooling, a smaller cutter than programmed (ln 6447): the other side
      r = -r;
      side = -side;
    }
    if (comp_.on()) {
      comp_.SetSide(side, k.g);
    } else {
      cc::Compensator::Setup s;
      s.p1 = p1;
      s.p2 = p2;
      s.radius = r;
      s.side = side;
      s.pos = pos_;
      s.min_move = metric_ ? 0.001 : 0.0001 * kInch;  // ln 1617, 6466
      s.g = k.g;
      used_ |= (1u << p1) | (1u << p2);  // the offset moves both axes of the plane
      comp_.RampOn(s);
    }
    mode_.cutter_comp = k.g == 41 ? CutterComp::kLeft : CutterComp::kRight;
  } else if (k.g == 40) {
    comp_.Cancel();
    mode_.cutter_comp = CutterComp::kOff;
  }
  if (k.g43) comp_.Perpendicular();
}

void KtRun::CompCommit() {
  comp_staged_ = false;
  try {
    comp_.Take(std::move(comp_stage_));
  } catch (const cc::CompError& e) {
    CompFail(e);
  }
  CompDrain();
}

void KtRun::CompEndBlock(bool counts) {
  if (comp_staged_) CompCommit();
  try {
    comp_.EndBlock(counts);
  } catch (const cc::CompError& e) {
    CompFail(e);
  }
  CompDrain();
  comp_col_ = comp_g_col_ = 1;
}

void KtRun::CompFinish() {
  if (comp_staged_) CompCommit();
  comp_.Finish();
  CompDrain();
}

void KtRun::CompDrain() {
  auto& ready = comp_.Ready();
  for (auto& c : ready) out_.push_back(std::move(c));
  ready.clear();
}

void KtRun::CompFail(const cc::CompError& e) {
  int col = e.at == cc::CompError::kAtCode ? comp_g_col_ : (e.at == cc::CompError::kAtMotion ? comp_col_ : 1);
  Fail(col, e.text, e.alarm);
}

}  // namespace cell::interp::ktapl
