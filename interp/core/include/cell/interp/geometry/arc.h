// Circular interpolation geometry every dialect shares: the planes, the centre of an arc given by its
// radius (minor or major arc), the sweep of an arc given by its centre (full circles when the end is the
// start), and the checks a control makes (minimum radius, start and end radius agreeing). Helices are arcs
// with the normal axis moving along; the caller adds that axis to the end point.
#pragma once

#include "cell/interp/canon.h"
#include "cell/interp/geometry/vec2.h"

namespace cell::interp::geom {

// The arc planes by their G codes' meaning (G17, G18, G19): first and second axis and the normal, as
// RS274 and every dialect here define them (G18 is Z then X, so that cw is seen from +Y).
enum class Plane { kXY, kZX, kYZ };
struct PlaneAxesN {
  int first, second, normal;
};
PlaneAxesN AxesOf(Plane p);

enum class ArcError {
  kNone,
  kFullCircleWithRadius,  // the radius form cannot describe a full circle (end == start)
  kRadiusTooSmall,        // the radius is shorter than half the chord
  kBelowMinimum,          // the radius is below the control's smallest programmable arc
  kRadiiDiffer,           // start and end lie at different distances from the centre
};

struct ArcSolution {
  ArcError error = ArcError::kNone;
  Vec2 center;
  double sweep = 0;         // degrees swept in the arc's direction, (0, 360]
  double radius_start = 0;  // |start - center|
  double radius_end = 0;    // |end - center|
};

// The arc from `start` to `end` of radius `radius` (> 0) in direction cw (seen from the positive normal):
// the minor arc (sweep <= 180) unless `major`.
ArcSolution ArcFromRadius(Vec2 start, Vec2 end, double radius, bool cw, bool major, double min_radius);

// The arc from `start` to `end` about `center`; end == start (within 1e-6 mm) is a full circle. The radii
// at start and end may differ by at most `tolerance`.
ArcSolution ArcFromCenter(Vec2 start, Vec2 end, Vec2 center, bool cw, double min_radius, double tolerance);

// Sweep in degrees from `start` to `end` about `center` in direction cw, in (0, 360]; 360 when they are
// the same point.
double Sweep(Vec2 start, Vec2 end, Vec2 center, bool cw);

}  // namespace cell::interp::geom
