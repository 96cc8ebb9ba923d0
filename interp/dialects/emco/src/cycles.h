// Geometry shared by the EMCO cycles (interp_cycles.cpp, interp_thread.cpp): points of the work plane by
// axis role, and the cut-division laws. Axis 0 is Z, axis 1 is X (a radius), as in Vec2 (x = Z, y = X).
#pragma once

#include <cmath>
#include <vector>

#include "cell/interp/geometry/vec2.h"

namespace cell::interp::emco::cyc {

using geom::Vec2;

inline double Get(Vec2 v, int axis) {
  return axis == 0 ? v.x : v.y;
}
// The point with `a` on axis `axis` and `b` on the other.
inline Vec2 At(int axis, double a, double b) {
  return axis == 0 ? Vec2{a, b} : Vec2{b, a};
}
inline double Sign(double v) {
  return v < 0 ? -1.0 : 1.0;
}

// More cuts than this in one cycle block are refused (ALARM 240): the moves of a cycle are produced at once.
constexpr int kMaxCuts = 10000;

// Equal cuts of at most `max` over `total` (ln 3263-3281, 4746-4761: 7 mm by 2 mm is 4 cuts of 1.75).
inline int EqualCuts(double total, double max) {
  if (max <= 0) return 1;
  double n = std::ceil(std::fabs(total) / max - 1e-9);
  if (n > kMaxCuts) return kMaxCuts + 1;
  return n < 1 ? 1 : static_cast<int>(n);
}

// Cumulative thread depths (mm) of G85 (ln 3877-3917): D3 the first depth or the number of cuts (`count`),
// constant or decremental (the depth after cut k is proportional to sqrt(k), so the chip section stays the
// same), every cut but the last at least `min` (monitor S00). The last depth is `depth`.
std::vector<double> ThreadDepths(double depth, double d3, bool count, bool constant, double min);

// Peck depths (mm, each > 0, summing to `total`) of G87/G88 (ln 4616-4807): no first depth: one pass; a first
// depth without reduction: equal pecks of at most it; with a reduction of `percent`: each peck that much
// of the one before while it is not below `min`, then the rest in equal pecks of at most `min`.
std::vector<double> DrillPecks(double total, double first, double percent, double min);

}  // namespace cell::interp::emco::cyc
