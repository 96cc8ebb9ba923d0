// KT-APL circular interpolation G02/G03 (manual ch. 2, 5; App. H co-axis planes) on the core's arc geometry:
// I/J/K centres (absolute or incremental), R arcs (G90 G17 only; negative R = the major arc), full circles,
// helices (the plane's normal axis moving along).
#include <fmt/format.h>

#include <cmath>

#include "interp_internal.h"

namespace cell::interp::ktapl {

geom::PlaneAxesN KtRun::PlaneAxes() const {
  // App. H: G18 is (Z, X); G20/G21 substitute the co-axes of the first and second axis.
  geom::PlaneAxesN p = geom::AxesOf(mode_.plane);
  auto coaxis = [](int a) { return a == kX ? kU : (a == kY ? kV : kW); };
  if (mode_.coaxis_first) p.first = coaxis(p.first);
  if (mode_.coaxis_second) p.second = coaxis(p.second);
  return p;
}

void KtRun::Arc(const Words& words, bool cw, int col, double feed, FeedMode fm) {
  const geom::PlaneAxesN axes = PlaneAxes();
  const int p1 = axes.first, p2 = axes.second, pn = axes.normal;
  auto centre_letter = [](int a) { return (a == kX || a == kU) ? 'I' : ((a == kY || a == kV) ? 'J' : 'K'); };
  const Word* w1 = nullptr;
  const Word* w2 = nullptr;
  const Word* wn = nullptr;
  const Word* c1 = nullptr;
  const Word* c2 = nullptr;
  const Word* r = nullptr;
  for (const auto& w : words) {
    int a = AxisOfLetter(w.letter);
    if (a == p1) w1 = &w;
    if (a == p2) w2 = &w;
    if (a == pn) wn = &w;
    if (a >= 0 && a != p1 && a != p2 && a != pn) Fail(w.col, "AXIS WORD NOT IN THE ARC PLANE");
    if (w.letter == centre_letter(p1)) c1 = &w;
    if (w.letter == centre_letter(p2)) c2 = &w;
    if (w.letter == 'R') r = &w;
  }
  auto target_of = [&](int a, const Word* w) {
    if (!w) return pos_[a];
    double v = ToMm(w->v);
    if ((a == kX && mir_x_) || (a == kY && mir_y_)) v = -v;
    double off = Offset(a);
    return (mode_.incremental ? pos_[a] - off + v : v) + off;
  };
  const geom::Vec2 start{pos_[p1], pos_[p2]};
  const geom::Vec2 end{target_of(p1, w1), target_of(p2, w2)};
  const double en = target_of(pn, wn);
  // ln 5501: "The minimum radius that can be programmed is .001" (.01 mm)", the maximum 1690.9320 in
  // (42949.672 mm), in the unit the program runs in.
  const double min_radius = MinArcRadiusMm(metric_);
  const char* const kBelow = "ARC RADIUS BELOW THE MINIMUM .001 IN (.01 MM)";
  geom::ArcSolution sol;
  if (r) {
    const bool g90_g17 =
        !mode_.incremental && mode_.plane == geom::Plane::kXY && !mode_.coaxis_first && !mode_.coaxis_second;
    const bool zu_plane = mode_.plane == geom::Plane::kZX && mode_.coaxis_second && !mode_.incremental;
    if (!g90_g17 && !zu_plane) Fail(r->col, "R CIRCLES ARE ALLOWED ONLY IN G90 G17");
    sol = geom::ArcFromRadius(start, end, ToMm(std::fabs(r->v)), cw, r->v < 0, min_radius);
    switch (sol.error) {
      case geom::ArcError::kFullCircleWithRadius:
        Fail(r->col, "R CIRCLES CANNOT BE FULL CIRCLES");
      case geom::ArcError::kBelowMinimum:
        Fail(r->col, kBelow);
      case geom::ArcError::kRadiusTooSmall:
        Fail(r->col, "ARC RADIUS TOO SMALL FOR THE END POINT");
      default:
        break;
    }
  } else {
    if (!c1 && !c2) Fail(col, "ARC NEEDS I/J/K CENTRE WORDS OR R");
    auto centre = [&](int a, const Word* c) {
      if (!c) return pos_[a];
      double v = ToMm(c->v);
      if ((a == kX && mir_x_) || (a == kY && mir_y_)) v = -v;
      if (mode_.incremental) return pos_[a] + v;
      return v + Offset(a);
    };
    // The control's tolerance for start and end radius: .0005 in (0.013 mm).
    sol = geom::ArcFromCenter(start, end, {centre(p1, c1), centre(p2, c2)}, cw, min_radius, 0.013);
    if (sol.error == geom::ArcError::kBelowMinimum) Fail(col, kBelow);
    if (sol.error == geom::ArcError::kRadiiDiffer) {
      Fail(col, fmt::format("ARC START AND END RADIUS DIFFER ({:.4f} / {:.4f})", FromMm(sol.radius_start),
                            FromMm(sol.radius_end)));
    }
  }
  if (sol.radius_start > MaxArcRadiusMm(metric_) + 1e-6) {
    Fail(r ? r->col : col, "ARC RADIUS ABOVE THE MAXIMUM 1690.9320 IN (42949.672 MM)");
  }
  AxisArray target = pos_;
  target[p1] = end.x;
  target[p2] = end.y;
  target[pn] = en;
  used_ |= (1u << p1) | (1u << p2);
  if (wn) used_ |= 1u << pn;
  AxisArray centre = pos_;
  centre[p1] = sol.center.x;
  centre[p2] = sol.center.y;
  pos_ = target;
  ArcOp& c = Out<ArcOp>();
  // A co-axis's centre is written in the slot of its parallel axis (U in x, V in y, W in z).
  c.center = {centre[kX], centre[kY], centre[kZ]};
  if (p1 == kU || p2 == kU) c.center[0] = centre[kU];
  if (p1 == kV || p2 == kV) c.center[1] = centre[kV];
  if (p1 == kW || p2 == kW) c.center[2] = centre[kW];
  c.to.pos = pos_;
  c.to.used = used_;
  c.feed = {feed, fm, !mode_.contouring};
  c.cw = cw;
  c.plane = {static_cast<std::int8_t>(p1), static_cast<std::int8_t>(p2)};
  c.angle = sol.sweep;
}

}  // namespace cell::interp::ktapl
