// A random turned outside profile (X a radius, Z), the one model of the lathe properties that cut a profile
// (rapids.cpp's Okuma LAP contour, nogouge.cpp's lathe finishing pass), and its mirror in X, a bore.
#pragma once

#include <array>
#include <vector>

#include "cell/oracle/rng.h"

namespace cell::oracle {

// From a point 2 mm in front of its face (index 0) to the start diameter at the back, the radius
// non-decreasing as Z decreases: lines along -Z, shoulders up (+X), tapers, and quarter arcs.
struct TurnedProfile {
  std::vector<std::array<double, 2>> contour;  // z, r
  // How each element reaches contour[i] from contour[i - 1]: 0 a line, 1 a quarter arc from -Z to +X about
  // (z, r + R) of its start (a fillet at a shoulder's foot, concave: Okuma E-59's G02 I), 2 a quarter arc
  // from +X to -Z about (z - R, r) of its start (a shoulder's rounded edge, convex). In a bore (`inside`) X
  // is mirrored: 1 from -Z to -X about (z, r - R), 2 from -X to -Z about (z - R, r); still concave, convex.
  std::vector<int> kind;
  bool inside = false;
};

// 2-6 elements after the 2 mm lead along -Z, then the last shoulder up to the start diameter; arcs of radius
// 0.5-5 mm, a fillet at least `least_fillet` (a concave arc no larger than a nose radius is a lathe's
// refusal). The draws are those rapids.cpp made before this was shared (a seed names the same profile).
inline TurnedProfile RandomTurnedProfile(Rng& g, double least_fillet = 0.5) {
  TurnedProfile l;
  double z = Grid(g.Real(0, 60), 0.001), r = Grid(g.Real(5, 20), 0.0005);
  l.contour = {{z + 2, r}, {z, r}};  // G00 to 2 mm in front of the face, G01 onto it
  l.kind = {0, 0};
  int n = g.Int(2, 6);
  for (int i = 0; i < n; ++i) {
    int kind = g.Int(0, 4);  // along -Z, up a shoulder, a taper, a fillet, a rounded edge
    if (kind >= 3) {
      double rad = Grid(g.Real(kind == 3 ? least_fillet : 0.5, 5), 0.001);
      z -= rad, r += rad;
      l.contour.push_back({z, r});
      l.kind.push_back(kind - 2);
      continue;
    }
    double dz = kind == 1 ? 0 : Grid(g.Real(3, 20), 0.001), dr = kind == 0 ? 0 : Grid(g.Real(1, 8), 0.0005);
    z -= dz, r += dr;
    l.contour.push_back({z, r});
    l.kind.push_back(0);
  }
  double rs = Grid(r + g.Real(2, 10), 0.0005);
  l.contour.push_back({z, rs});  // the last shoulder up to the start diameter
  l.kind.push_back(0);
  return l;
}

// A bore (the tool inside the part, the radius non-increasing as Z decreases: shoulders down, the diameters
// falling toward the chuck; EMCO's "internal turning from right to left", ln 3209-3211, with the internal
// copying tool, ln 2516-2518; Okuma's ID cutting from a start inside and in front, ln 5376, 6278): the
// outside profile of the same draws mirrored in X about a level drawn after them, so that the last shoulder's
// foot is at a radius of 4-10 mm (room for the nose and the move down after G40).
inline TurnedProfile RandomBoredProfile(Rng& g, double least_fillet = 0.5) {
  TurnedProfile l = RandomTurnedProfile(g, least_fillet);
  const double level = l.contour.back()[1] + Grid(g.Real(4, 10), 0.0005);
  for (auto& q : l.contour) q[1] = level - q[1];
  l.inside = true;
  return l;
}

}  // namespace cell::oracle
