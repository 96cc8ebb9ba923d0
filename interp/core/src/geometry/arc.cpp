#include "cell/interp/geometry/arc.h"

#include <algorithm>
#include <cmath>

namespace cell::interp::geom {
namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

PlaneAxesN AxesOf(Plane p) {
  switch (p) {
    case Plane::kXY:
      return {kX, kY, kZ};
    case Plane::kZX:
      return {kZ, kX, kY};
    case Plane::kYZ:
      return {kY, kZ, kX};
  }
  return {kX, kY, kZ};
}

double Sweep(Vec2 start, Vec2 end, Vec2 center, bool cw) {
  double a0 = std::atan2(start.y - center.y, start.x - center.x);
  double a1 = std::atan2(end.y - center.y, end.x - center.x);
  double ccw = (a1 - a0) * 180.0 / kPi;
  while (ccw < 0) ccw += 360.0;
  while (ccw >= 360.0) ccw -= 360.0;
  if (Norm(end - start) < 1e-6) return 360.0;
  double sweep = cw ? 360.0 - ccw : ccw;
  if (sweep <= 0) sweep += 360.0;
  return sweep;
}

ArcSolution ArcFromRadius(Vec2 start, Vec2 end, double radius, bool cw, bool major, double min_radius) {
  ArcSolution out;
  Vec2 d = end - start;
  double chord = Norm(d);
  if (chord < 1e-9) {
    out.error = ArcError::kFullCircleWithRadius;
    return out;
  }
  if (radius < min_radius) {
    out.error = ArcError::kBelowMinimum;
    return out;
  }
  double half = chord / 2;
  double h2 = radius * radius - half * half;
  if (h2 < -1e-4 * radius) {
    out.error = ArcError::kRadiusTooSmall;
    return out;
  }
  double h = std::sqrt(std::max(0.0, h2));
  Vec2 mid = 0.5 * (start + end);
  Vec2 n{-d.y / chord, d.x / chord};
  // Of the two centres, the one that gives the wanted arc (minor or major) in direction cw.
  double best_sweep = -1;
  for (int sgn : {1, -1}) {
    Vec2 c = mid + (sgn * h) * n;
    double a0 = std::atan2(start.y - c.y, start.x - c.x), a1 = std::atan2(end.y - c.y, end.x - c.x);
    double ccw = (a1 - a0) * 180.0 / kPi;
    while (ccw <= 0) ccw += 360.0;
    while (ccw > 360.0) ccw -= 360.0;
    double sw = cw ? 360.0 - ccw : ccw;
    bool is_major = sw > 180.0 + 1e-9;
    if (best_sweep < 0 || is_major == major) {
      out.center = c;
      best_sweep = sw;
      if (is_major == major) break;
    }
  }
  out.sweep = best_sweep;
  out.radius_start = Norm(start - out.center);
  out.radius_end = Norm(end - out.center);
  return out;
}

ArcSolution ArcFromCenter(Vec2 start, Vec2 end, Vec2 center, bool cw, double min_radius, double tolerance) {
  ArcSolution out;
  out.center = center;
  out.radius_start = Norm(start - center);
  out.radius_end = Norm(end - center);
  if (out.radius_start < min_radius) {
    out.error = ArcError::kBelowMinimum;
    return out;
  }
  if (std::fabs(out.radius_start - out.radius_end) > tolerance) {
    out.error = ArcError::kRadiiDiffer;
    return out;
  }
  out.sweep = Sweep(start, end, center, cw);
  return out;
}

}  // namespace cell::interp::geom
