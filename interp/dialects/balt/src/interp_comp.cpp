// The executor's side of Balt-System compensation: G40/G41/G42 with the block rules of ln 3203-3216 (what
// is refused while compensation is on), the radius (K/2 of the active offset plus the stock allowance UOV,
// ln 501-508, 4071-4089), the routing of commands through the contour (contour.h), and the paraxial factors
// u v w (§5.11, ln 3800-3907).
#include <fmt/format.h>

#include "interp_internal.h"

namespace cell::interp::balt {

double BaltRun::CompRadius() const {
  return tool_dia_ / 2 + uov_;
}

void BaltRun::CompCodes(const BlockG& g, const ParsedBlock& pb) {
  const bool on = contour_.on() || mode_.comp != 40;
  const int col = g.first_col;
  // GTL pairs G21 G41/G42 and G20 G40 are the profile's own (ln 3203-3215, 5049-5150).
  if (on && g.comp != 40) {
    if (g.cycle) Fail(col, 25, "fixed cycles with cutter compensation on");
    if (g.g79) Fail(col, 25, "G79 with cutter compensation on");
    if (g.probe) Fail(col, 25, "probing with cutter compensation on");
    if (g.any_motion && g.motion == Motion::kThread) Fail(col, 25, "G33 with cutter compensation on");
    if (g.gtl == 21 && !(g.comp == 41 || g.comp == 42) && !gtl_profile_) {
      Fail(col, 25, "G21 with compensation on: program G21 G41/G42");
    }
  }
  if (g.gtl == 20 && (g.comp == 41 || g.comp == 42)) Fail(col, 25, "G20 goes with G40, not G41/G42");
  for (const Word& w : pb.words) {
    if ((w.letter == 'u' || w.letter == 'v' || w.letter == 'w') && (on || g.comp == 41 || g.comp == 42)) {
      Fail(w.col, 25, "paraxial factors are not combined with G41/G42");
    }
  }
  if (g.comp == 41 || g.comp == 42) {
    int side = g.comp == 41 ? geom::kLeft : geom::kRight;
    // Mirroring one axis of the plane swaps the sides on the machine.
    if (MirrorFlipsPlane()) side = -side;
    double r = CompRadius();
    if (r < 0) {
      r = -r;
      side = -side;
    }
    if (!contour_.engaged()) contour_.Sync(pos_);
    contour_.Start(side, r, g.comp);
    mode_.comp = g.comp;
  } else if (g.comp == 40) {
    // A GTL profile's G20 G40 ends compensation at the profile's end point (GtlBlock releases it).
    if (!(gtl_profile_ && g.gtl == 20)) contour_.Stop();
    mode_.comp = 40;
  }
}

// u v w (ln 3800-3907): the end point moves by factor x the tool radius along axis 1, 2, 3 (X, Y, Z); only
// in its block, only with the coordinate it belongs to, never with G41/G42 or GTL.
void BaltRun::Paraxial(const ParsedBlock& pb, Targets& t) {
  if (!(pb.letters & (LetterBit('u') | LetterBit('v') | LetterBit('w')))) return;
  for (const Word& w : pb.words) {
    int axis = w.letter == 'u' ? kX : w.letter == 'v' ? kY : w.letter == 'w' ? kZ : -1;
    if (axis < 0) continue;
    if (contour_.on() || mode_.comp != 40 || gtl_profile_)
      Fail(w.col, 25, "paraxial factors with G41/G42 or GTL");
    if (!(t.mask & (1u << axis))) {
      Fail(w.col, 24, fmt::format("{} goes with the {} coordinate", w.letter, LetterOfAxis(axis)));
    }
    t.prog[axis] += ValueOf(w.v, w.col) * tool_dia_ / 2;
  }
}

void BaltRun::CommitStage() {
  if (!staged_) return;
  staged_ = false;
  if (GtlDefers()) {
    profile_.deferred.push_back(std::move(stage_));
    return;
  }
  if (!contour_.engaged()) contour_.Sync(pos_);
  try {
    contour_.Take(std::move(stage_), nullptr, false);
  } catch (const ContourError& e) {
    ContourFail(e);
  }
  ContourDrain();
}

void BaltRun::ContourDrain() {
  if (!contour_.HasReady()) return;  // every block calls it: no empty vector made and dropped
  for (auto& c : contour_.TakeChecked()) out_.push_back(std::move(c));
}

void BaltRun::ContourFail(const ContourError& e) {
  Fail(1, e.code, e.text);
}

}  // namespace cell::interp::balt
