// Balt-System circular and helical interpolation G02/G03 (manual ln 2732-2836) on the core's arc
// geometry: I and J are the centre's abscissa and ordinate in any plane, absolute in G90 and relative to the
// start in G91 (ln 2762-2781); R gives the radius (+ up to 180 degrees, - from 180); no end point is a full
// circle (I/J only); the plane's third axis with K (the pitch) makes a helix of as many turns as the depth
// holds pitches.
#include <fmt/format.h>

#include <cmath>

#include "interp_internal.h"

namespace cell::interp::balt {
namespace {

// The axis perpendicular to a plane of linear axes (X Y Z, or their co-axes U V W), or -1.
int NormalOf(int p1, int p2) {
  auto base = [](int a) { return a >= kU ? a - kU : a; };
  if (IsRotaryAxis(p1) || IsRotaryAxis(p2)) return -1;
  int b1 = base(p1), b2 = base(p2);
  for (int a : {kX, kY, kZ}) {
    if (a != b1 && a != b2) return a;
  }
  return -1;
}

}  // namespace

void BaltRun::ArcMove(const ParsedBlock& pb, const BlockG& g, const Targets& t_in) {
  Targets t = t_in;
  const int p1 = mode_.p1, p2 = mode_.p2;
  const int pn = NormalOf(p1, p2);
  int col = 1;
  const Word* wi = nullptr;
  const Word* wj = nullptr;
  const Word* wr = nullptr;
  const Word* wk = nullptr;
  for (const Word& w : pb.words) {
    if (w.letter == 'G' && col == 1) col = w.col;
    if (w.letter == 'I') wi = &w;
    if (w.letter == 'J') wj = &w;
    if (w.letter == 'R') wr = &w;
    if (w.letter == 'K') wk = &w;
    int a = AxisOfLetter(w.letter);
    if (a >= 0 && a != p1 && a != p2 && a != pn) {
      Fail(w.col, 24,
           fmt::format("{} is not an axis of the {}{} plane", w.letter, LetterOfAxis(p1), LetterOfAxis(p2)));
    }
  }
  if (g.g79) Fail(col, 25, "G79 with a circle");
  if (IsRotaryAxis(p1) || IsRotaryAxis(p2)) Fail(col, 24, "circles need a plane of two linear axes");
  const bool full = (t.mask & ((1u << p1) | (1u << p2))) == 0;
  const bool centre_form = wi || wj;
  if (centre_form && wr) Fail(wr->col, 24, "I/J and R in one circle");
  if (!centre_form && !wr) Fail(col, 12, "a circle needs I and J (or R)");
  if (centre_form && !(wi && wj)) Fail((wi ? wi : wj)->col, 12, "a circle needs both I and J");
  if (full && wr) Fail(wr->col, 24, "a full circle is programmed with I and J");
  Paraxial(pb, t);
  const AxisArray start_prog = Prog();
  AxisArray mach = ToMachine(t.prog);
  geom::Vec2 start{pos_[p1], pos_[p2]};
  geom::Vec2 end{mach[p1], mach[p2]};
  if (full) end = start;
  // Mirroring one axis of the plane reverses the direction on the machine.
  bool cw = mode_.motion == Motion::kCw;
  if (MirrorFlipsPlane()) cw = !cw;
  const double unit = UnitFactor();
  geom::ArcSolution sol;
  if (wr) {
    double r = ValueOf(wr->v, wr->col) * unit * PlaneScale();
    sol = geom::ArcFromRadius(start, end, std::fabs(r), cw, r < 0, 0.0001);
    switch (sol.error) {
      case geom::ArcError::kFullCircleWithRadius:
        Fail(wr->col, 24, "a full circle is programmed with I and J");
      case geom::ArcError::kBelowMinimum:
      case geom::ArcError::kRadiusTooSmall:
        Fail(wr->col, 77, "the radius is too small for the end point");
      default:
        break;
    }
  } else {
    AxisArray c = start_prog;
    double ci = ValueOf(wi->v, wi->col) * unit, cj = ValueOf(wj->v, wj->col) * unit;
    if (mode_.incremental) {
      c[p1] = start_prog[p1] + ci;
      c[p2] = start_prog[p2] + cj;
    } else {
      c[p1] = ci;
      c[p2] = cj;
    }
    AxisArray cm = ToMachine(c);
    // Start and end within 0.01 mm of one radius (the radius is at most 99.9999 m, ln 186).
    sol = geom::ArcFromCenter(start, end, {cm[p1], cm[p2]}, cw, 0.0001, 0.01);
    if (sol.error == geom::ArcError::kBelowMinimum) Fail(wi->col, 77, "the centre is the start point");
    if (sol.error == geom::ArcError::kRadiiDiffer) {
      Fail(col, 77,
           fmt::format("start and end are not on one circle (radius {:.4f} / {:.4f})",
                       sol.radius_start / unit, sol.radius_end / unit));
    }
  }
  // Helix (ln 2790-2836): the plane's third axis moves along; K is the pitch (omitted below one turn).
  double turns = 0;
  if (wk) {
    if (pn < 0 || !(t.mask & (1u << pn)))
      Fail(wk->col, 96, "a helix needs the axis perpendicular to the plane");
    // K is a length on the perpendicular axis: SCF scales it with that axis (judgement call 48).
    double pitch = ValueOf(wk->v, wk->col) * unit * scale_[static_cast<std::size_t>(pn)];
    if (pitch <= 0) Fail(wk->col, 13, "the helix pitch K is positive");
    double depth = std::fabs(mach[pn] - pos_[pn]);
    turns = std::round(depth / pitch - sol.sweep / 360.0);
    if (turns < 0) turns = 0;
  }
  geom::Path path;
  path.arc = true;
  path.start = start;
  path.end = end;
  path.center = sol.center;
  path.cw = cw;
  path.sweep = sol.sweep;
  const double rad = sol.radius_start;
  Feed feed;
  feed.rate = BlockFeed(pb, (sol.sweep + 360 * turns) * kDeg * rad, false, &feed.mode, col);
  // G28 blends (no corner deceleration, ln 2969); G29 stops; G27 decelerates to 0 at each block end with
  // the default ERF=0 (ln 4317) and, as the canon carries no form error, with any ERF (balt.md).
  feed.exact_stop = mode_.dynamic != Dynamic::kG28 || g.decel;
  if (lim_mask_) CheckLimits(pos_, mach, &path, col);
  if (AreasActive()) CheckAreas(pos_, mach, &path, col);
  std::uint32_t moved = t.mask | (1u << p1) | (1u << p2);
  mach[p1] = end.x;
  mach[p2] = end.y;
  EmitMotion(Op::kArc, mach, moved, feed, path, {}, 0, turns);
  prog_ = t.prog;  // paraxial factors included: axes left out of the next block stay where they are
  if (full) {
    prog_[p1] = start_prog[p1];
    prog_[p2] = start_prog[p2];
  }
  prog_valid_ = true;
}

}  // namespace cell::interp::balt
