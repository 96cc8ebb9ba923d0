// The random closed contour under cutter radius compensation and its Balt-System and KT-APL programs, and the
// lathes' turned profile under tool-nose compensation (nogouge.cpp): the no-gouge property (nogouge.cpp) and
// the compensated differential (comp.cpp) cut the same contours.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "cell/oracle/oracle.h"

namespace cell::oracle {

using P2 = std::array<double, 2>;

// Element i runs from p[i] to p[i+1]: a line, or (sweep != 0) an arc about centre[i], ccw when sweep > 0.
// The corners go counterclockwise about the origin, so the part is on the left: a ccw arc bulges out
// (convex), a cw arc in (concave).
struct CompContour {
  std::vector<P2> p;
  std::vector<double> sweep;  // degrees, signed
  std::vector<P2> centre;
  double r = 0;
  bool left = true;
  bool open = false;  // a lathe's profile (nogouge.cpp): no element from the last point back to the first
  // The plane the contour is cut in (comp.cpp): 17 (x y) = (X, Y), 18 = (Z, X), 19 = (Y, Z), the first axis
  // to the right and the second up seen from the plane's normal, so a G41 stays on the left; and the unit
  // (inch: p and centre lie on the 0.0001 in grid, still stated in mm; a lathe's NGC twin stays in mm).
  int plane = 17;
  bool inch = false;
  int tip = 3;  // a lathe's tip code (NoseFromTip)
  // KT-APL's G46 in the G41/G42 block: fill-in blocks bypassed (ktapl.md judgement call 39).
  bool bypass = false;
  std::size_t Next(std::size_t i) const { return (i + 1) % p.size(); }
  std::size_t Elements() const { return open ? p.size() - 1 : p.size(); }
};

// 5-14 corners on the 0.001 mm grid, a tool of radius 2, 3 or 5, G41 or G42; `arcs`: some sides arcs.
CompContour RandomContour(std::uint64_t seed, bool arcs);

// The program in the dialect and its tools file: from X100 Y0 a compensated line to p[0], the elements
// 0 .. n-1 and element 0 again, a G40 line back to X100 Y0. `first`/`last`: the lines of the first contour
// block and of the block that ends the second time at the second corner.
struct ContourProgram {
  std::string text, tools, params;  // params: cell-interp's --params file (Okuma's unit system), if any
  int first = 0, last = 0;
};
ContourProgram WriteContour(const std::string& dialect, const CompContour& c);
// A lathe's finishing pass (nogouge.cpp): a random turned profile (profile.h) as an open contour in (Z, X as
// a radius), outside under G42 or (`inside`) a bore under G41, with a tip code drawn for that side and a nose
// radius of 0.2-1.6 mm, and its EMCO or Okuma program, in mm or (`inch`) inch. The no-gouge property
// (nogouge.cpp) and the lathes' compensated differential (comp.cpp) cut the same profiles.
struct LatheContour {
  CompContour c;
  ContourProgram w;
};
LatheContour LatheCase(const std::string& dialect, std::uint64_t seed, bool inside, bool inch);
// The nose centre of a move whose points are the imaginary tip of tip code `tip` (0-9; nogouge.cpp cites
// the manuals): end and arc centre moved back from the tip to the centre by the code's direction times r, in
// Z and in X (a radius), machine coordinates.
Move NoseFromTip(const Move& m, double r, int tip);
// The machine axes (x 0, y 1, z 2) of a plane's first, second and normal axis: G17 X Y Z, G18 Z X Y, G19 Y Z
// X.
std::array<int, 3> PlaneAxes(int plane);

}  // namespace cell::oracle
