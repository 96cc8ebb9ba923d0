// A random turned outside profile (X a radius, Z), the one model of the lathe properties that cut a profile
// (rapids.cpp's Okuma LAP contour, nogouge.cpp's lathe finishing pass).
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
  // from +X to -Z about (z - R, r) of its start (a shoulder's rounded edge, convex).
  std::vector<int> kind;
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

}  // namespace cell::oracle
