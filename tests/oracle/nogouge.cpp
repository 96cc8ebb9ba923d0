// `cell-oracle-gen prop --property nogouge` (issue 33 item 2, docs/testing.md "Properties"): no gouge under
// cutter radius compensation. A random star-shaped closed contour (5-14 corners, convex and concave, on the
// 0.001 mm grid; every other contour with arcs between some corners) cut with G41 (inside) or G42 (outside)
// once around and on to its second corner, with a tool of radius 2, 3 or 5:
// - Balt-System (G41/G42/G40, ln 3064-3264): the tools file's K is the diameter; arcs `G2/G3 X Y I J`, I J
//   absolute in G90.
// - KT-APL (G40-G42, ln 1599-1671, 6437-6696): the tools file's (TLD,T1D..) the diameter (ln 6447), taken at
//   the ramp-on (ktapl.md judgement call 45); arcs `G02/G03 X Y I J`, I J absolute in G90.
// The lathes, EMCO and Okuma (LatheCase): a random turned profile (profile.h) finished outside under G42 or,
// every other one, a bore under G41, with a nose radius of 0.2-1.6 mm and a tip code drawn for the side; both
// write the imaginary tip, so the checker takes the nose centre back from it by the code (NoseCentre). The
// tool centre of every move but the entry, the first and last contour blocks and the exit (whose corners
// depend on the approach and the dialect's ramp rule) keeps at least the radius less 2e-3 mm from every
// element of the contour, on the compensated side. A refusal makes no motion and gouges nothing; it is
// counted.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <iostream>

#include "cell/oracle/oracle.h"
#include "cell/oracle/rng.h"
#include "contour.h"
#include "profile.h"
#include "run.h"

namespace fs = std::filesystem;

namespace cell::oracle {
namespace {

double Norm(double a) {  // to [0, 2 pi)
  a = std::fmod(a, 2 * M_PI);
  return a < 0 ? a + 2 * M_PI : a;
}

double SegmentDistance(const P2& q, const P2& a, const P2& b) {
  double dx = b[0] - a[0], dy = b[1] - a[1], len2 = dx * dx + dy * dy;
  double t = len2 > 0 ? std::clamp(((q[0] - a[0]) * dx + (q[1] - a[1]) * dy) / len2, 0.0, 1.0) : 0;
  return std::hypot(q[0] - a[0] - t * dx, q[1] - a[1] - t * dy);
}

// The least distance from q to element i.
double ElementDistance(const P2& q, const CompContour& c, std::size_t i) {
  const P2 &a = c.p[i], &b = c.p[c.Next(i)];
  if (c.sweep[i] == 0) return SegmentDistance(q, a, b);
  const P2& o = c.centre[i];
  double a0 = std::atan2(a[1] - o[1], a[0] - o[0]), aq = std::atan2(q[1] - o[1], q[0] - o[0]);
  double along = c.sweep[i] > 0 ? Norm(aq - a0) : Norm(a0 - aq);
  double ends = std::min(std::hypot(q[0] - a[0], q[1] - a[1]), std::hypot(q[0] - b[0], q[1] - b[1]));
  if (along > std::fabs(c.sweep[i]) * M_PI / 180) return ends;
  return std::fabs(std::hypot(q[0] - o[0], q[1] - o[1]) - std::hypot(a[0] - o[0], a[1] - o[1]));
}

// Points along element i, both ends included.
std::vector<P2> Samples(const CompContour& c, std::size_t i, int n) {
  const P2 &a = c.p[i], &b = c.p[c.Next(i)];
  std::vector<P2> out;
  const P2& o = c.centre[i];
  double a0 = std::atan2(a[1] - o[1], a[0] - o[0]), rad = std::hypot(a[0] - o[0], a[1] - o[1]);
  for (int k = 0; k <= n; ++k) {
    double t = static_cast<double>(k) / n;
    if (c.sweep[i] == 0)
      out.push_back({a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])});
    else {
      double ang = a0 + t * c.sweep[i] * M_PI / 180;
      out.push_back({o[0] + rad * std::cos(ang), o[1] + rad * std::sin(ang)});
    }
  }
  return out;
}

// The direction of element k at its start or end, radians.
double Tangent(const CompContour& c, std::size_t k, bool at_end) {
  const P2 &a = c.p[k], &b = c.p[c.Next(k)];
  if (c.sweep[k] == 0) return std::atan2(b[1] - a[1], b[0] - a[0]);
  const P2& q = at_end ? b : a;
  return std::atan2(q[1] - c.centre[k][1], q[0] - c.centre[k][0]) + (c.sweep[k] > 0 ? M_PI / 2 : -M_PI / 2);
}

// The turn at the end of element k, radians, left positive.
double Turn(const CompContour& c, std::size_t k) {
  return Norm(Tangent(c, c.Next(k), false) - Tangent(c, k, true) + M_PI) - M_PI;
}

// The arc of element i stays if it keeps more than a cutter diameter (and 0.5 mm) from every element but its
// neighbours, and they from it: an arc adds no narrow neck that no compensation looking one element ahead can
// cut (balt.md judgement call 49), and the contour stays simple.
bool ArcFits(const CompContour& c, std::size_t i) {
  std::size_t n = c.p.size();
  const double clear = 2 * c.r + 0.5;
  for (std::size_t j = 0; j < n; ++j) {
    if (j == i || j == c.Next(i) || c.Next(j) == i) continue;
    for (const P2& q : Samples(c, i, 24))
      if (ElementDistance(q, c, j) < clear) return false;
    for (const P2& q : Samples(c, j, 24))
      if (ElementDistance(q, c, i) < clear) return false;
  }
  // The corners at its ends turn by less than 165 degrees (no fold back onto its neighbour), and the contour
  // stays simple.
  for (std::size_t k : {(i + n - 1) % n, i})
    if (std::fabs(Turn(c, k)) > 165 * M_PI / 180) return false;
  std::vector<P2> poly;
  for (std::size_t k = 0; k < n; ++k) {
    auto s = Samples(c, k, 24);
    poly.insert(poly.end(), s.begin(), s.end() - 1);
  }
  auto cross = [](const P2& o, const P2& a, const P2& b) {
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
  };
  std::size_t m = poly.size();
  for (std::size_t a = 0; a < m; ++a)
    for (std::size_t b = a + 2; b < m; ++b) {
      if (a == 0 && b == m - 1) continue;  // neighbours across the start
      const P2 &p1 = poly[a], &p2 = poly[(a + 1) % m], &q1 = poly[b], &q2 = poly[(b + 1) % m];
      if (cross(p1, p2, q1) * cross(p1, p2, q2) < 0 && cross(q1, q2, p1) * cross(q1, q2, p2) < 0)
        return false;
    }
  return true;
}

}  // namespace

// The line-only contour of a seed is the one this property drew before arcs (the same draws): seeds found
// then still name the same contour. `arcs`: a second stream from the seed turns some sides into arcs, convex
// and concave, of 20-120 degrees and a radius at least the cutter's plus 0.5 mm (an inside arc no larger than
// the cutter is KT-APL's [0004] and Balt-System's refusal, not a gouge), where they fit.
CompContour RandomContour(std::uint64_t seed, bool arcs) {
  Rng rng(seed);
  CompContour c;
  static const double radii[] = {2, 3, 5};
  c.r = radii[rng.Int(0, 2)];
  c.left = rng.Int(0, 1) == 1;
  int n = rng.Int(5, 14);
  for (int i = 0; i < n; ++i) {
    double a = 2 * M_PI * (i + rng.Int(-30, 30) / 100.0) / n;
    double rho = rng.Int(8000, 60000) / 1000.0;
    c.p.push_back({std::round(rho * std::cos(a) * 1000) / 1000, std::round(rho * std::sin(a) * 1000) / 1000});
  }
  c.sweep.assign(c.p.size(), 0);
  c.centre.assign(c.p.size(), P2{0, 0});
  if (!arcs) return c;
  Rng more(seed ^ 0xA5C3u);
  for (std::size_t i = 0; i < c.p.size(); ++i) {
    if (!more.Chance(60)) continue;
    double sweep = more.Int(20, 120) * (more.Chance(50) ? 1 : -1);
    const P2 &a = c.p[i], &b = c.p[c.Next(i)];
    double chord = std::hypot(b[0] - a[0], b[1] - a[1]), h = std::fabs(sweep) * M_PI / 360;
    double rad = chord / (2 * std::sin(h)), d = rad * std::cos(h);
    if (rad < c.r + 0.5) continue;
    double s = sweep > 0 ? 1 : -1;  // the centre on the left of the chord for a ccw arc
    P2 o{(a[0] + b[0]) / 2 - s * d * (b[1] - a[1]) / chord,
         (a[1] + b[1]) / 2 + s * d * (b[0] - a[0]) / chord};
    c.centre[i] = {std::round(o[0] * 1000) / 1000, std::round(o[1] * 1000) / 1000};
    c.sweep[i] = sweep;
    if (!ArcFits(c, i)) c.sweep[i] = 0;
  }
  return c;
}

namespace {

// The contour as a polygon (arcs in pieces of at most 5 degrees), a lathe's profile closed down the axis (the
// part's region outside, the hole's in a bore), for the side a point is on.
std::vector<P2> Outline(const CompContour& c) {
  std::vector<P2> poly;
  for (std::size_t k = 0; k < c.Elements(); ++k) {
    auto s = Samples(c, k, 24);
    poly.insert(poly.end(), s.begin(), s.end() - 1);
  }
  if (c.open) poly.insert(poly.end(), {c.p.back(), {c.p.back()[0], 0}, {c.p.front()[0], 0}});
  return poly;
}

bool Inside(const P2& q, const std::vector<P2>& poly) {
  bool in = false;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++)
    if ((poly[i][1] > q[1]) != (poly[j][1] > q[1]) &&
        q[0] < poly[j][0] + (q[1] - poly[j][1]) * (poly[i][0] - poly[j][0]) / (poly[i][1] - poly[j][1]))
      in = !in;
  return in;
}

// The least distance from the points of a move (from `from`) to the contour's elements, and to element `near`
// (the move's own) and its neighbours; negative for a point on the side away from the compensation's (inside
// the contour under G42, outside under G41: the mills' contours run counterclockwise; a lathe's profile is
// closed down to the axis, the part under an outside profile and the bore's air under a bore's, where the
// G41 nose is), so the radius is kept "on the compensated side".
struct Distance {
  double all = 1e9, own = 1e9;  // own: to `near` and its neighbours
};
Distance MoveDistance(const Move& m, const Vec3& from, const CompContour& c, const std::vector<P2>& outline,
                      std::size_t near) {
  Distance best;
  std::size_t n = c.Elements();
  for (int k = 0; k <= 32; ++k) {
    double t = k / 32.0;
    P2 q{from[0] + t * (m.end[0] - from[0]), from[1] + t * (m.end[1] - from[1])};
    if (m.kind == MoveKind::kArc) {
      double a0 = std::atan2(from[1] - m.center[1], from[0] - m.center[0]);
      double a1 = std::atan2(m.end[1] - m.center[1], m.end[0] - m.center[0]);
      double sweep = m.cw ? a0 - a1 : a1 - a0;
      while (sweep <= 1e-12) sweep += 2 * M_PI;
      double a = a0 + (m.cw ? -1 : 1) * t * sweep,
             rad = std::hypot(from[0] - m.center[0], from[1] - m.center[1]);
      q = {m.center[0] + rad * std::cos(a), m.center[1] + rad * std::sin(a)};
    }
    const double sign = Inside(q, outline) == c.left ? 1 : -1;
    for (std::size_t i = 0; i < n; ++i) {
      double d = sign * ElementDistance(q, c, i);
      best.all = std::min(best.all, d);
      bool neighbour = c.open ? i + 1 >= near && i <= near + 1
                              : i == near || i == (near + 1) % n || i == (near + n - 1) % n;
      if (neighbour) best.own = std::min(best.own, d);
    }
  }
  return best;
}

struct Tally {
  long moves = 0;    // compensated moves checked
  int reversed = 0;  // Okuma: too close on a step the nose runs back along (okuma.md judgement call 67)
  int contours = 0, with_arcs = 0, arcs = 0, refused = 0, refused_with_arcs = 0, before_refusal = 0, far = 0;
  int bores = 0;     // a lathe's inside profiles (G41)
  int bypassed = 0;  // KT-APL's contours under G46
};

}  // namespace

std::array<int, 3> PlaneAxes(int plane) {
  return plane == 18   ? std::array<int, 3>{2, 0, 1}
         : plane == 19 ? std::array<int, 3>{1, 2, 0}
                       : std::array<int, 3>{0, 1, 2};
}

ContourProgram WriteContour(const std::string& dialect, const CompContour& c) {
  bool kt = dialect == "ktapl";
  const double unit = c.inch ? 25.4 : 1;
  const int decimals = c.inch ? 4 : 3;
  auto num = [&](double v) { return Num(v / unit, decimals, kt); };
  const auto ax = PlaneAxes(c.plane);
  const char* letters = "XYZ";
  // A point of the plane as axis words in X Y Z order (the normal axis left out).
  auto xy = [&](const P2& p) {
    std::string s;
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 2; ++k)
        if (ax[static_cast<std::size_t>(k)] == i)
          s += (s.empty() ? "" : " ") + std::string(1, letters[i]) + num(p[k]);
    return s;
  };
  // The start X100 Y0 (in the plane), the normal axis at 0.
  std::string start = xy({100, 0}) + " " + letters[ax[2]] + (kt ? "0." : "0");
  // The centre: KT-APL by axis letter (I J K of X Y Z), Balt-System the plane's abscissa and ordinate (I J).
  auto centre = [&](const P2& o) {
    if (!kt) return " I" + num(o[0]) + " J" + num(o[1]);
    std::string s;
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 2; ++k)
        if (ax[static_cast<std::size_t>(k)] == i) s += " " + std::string(1, "IJK"[i]) + num(o[k]);
    return s;
  };
  std::string plane = c.plane == 17 ? "" : "G" + std::to_string(c.plane);
  ContourProgram w;
  std::vector<std::string> lines;
  if (kt) {
    lines = {
        "! no-gouge property (tests/oracle)", std::string(c.inch ? "G70" : "G71") + plane + " T1", "M06",
        "G90 G0 " + start + " F0",
        std::string("G1 ") + (c.left ? "G41 " : "G42 ") + (c.bypass ? "G46 " : "") + xy(c.p[0]) + " F200."};
    w.tools = "G71\n(TLD,T1D" + Num(2 * c.r, 3, true) + ")\n";
  } else {
    lines = {"; no-gouge property (tests/oracle)", "T1.1 M6", "S1000 M3"};
    if (c.inch) lines.push_back("G70");
    if (!plane.empty()) lines.push_back(plane);  // alone in its block (ln 2936-2956)
    lines.push_back("G " + start);
    lines.push_back(std::string("G1 ") + (c.left ? "G41 " : "G42 ") + xy(c.p[0]) +
                    (c.inch ? " F8" : " F200"));
    w.tools = "1 Z0 K" + Num(2 * c.r, 3) + "\n";
  }
  w.first = static_cast<int>(lines.size()) + 1;
  std::size_t n = c.p.size();
  for (std::size_t k = 0; k <= n; ++k) {  // elements 0 .. n-1, then element 0 again
    std::size_t i = k % n;
    const P2& e = c.p[c.Next(i)];
    if (c.sweep[i] == 0) {
      lines.push_back("G1 " + xy(e));
    } else {
      std::string g = c.sweep[i] > 0 ? (kt ? "G03 " : "G3 ") : (kt ? "G02 " : "G2 ");
      lines.push_back(g + xy(e) + centre(c.centre[i]));
    }
  }
  w.last = static_cast<int>(lines.size());
  lines.push_back("G1 G40 " + xy({100, 0}));
  lines.push_back(kt ? "M30" : "M2");
  for (const auto& l : lines) w.text += l + "\n";
  return w;
}

// A lathe's finishing pass: a random turned profile (profile.h) with 3 mm more along -Z at the start diameter
// behind its last shoulder (so that shoulder and its top corner are checked), cut outside under G42 (the tool
// above the part moving toward -Z: EMCO E42 ln 2586-2755, Okuma E-22 ln 2337-2361) or, `inside`, a bore
// under G41 (the tool below the bore's wall moving toward -Z, the part on its right: G41 is "the tool ...
// left of the workpiece, when viewed in the direction of the relative tool movement", EMCO ln 2559-2566,
// Okuma ln 2332), with a nose radius of 0.2-1.6 mm and a tip code drawn for the side. X is a radius here
// (the program writes diameters). `inch`: the program in inch (EMCO G70 in its first block, ln 3141-3163;
// Okuma's inch unit system, ln 1033-1093, in `w.params`), its points on the 0.0001 in grid; the tools files
// stay mm (the cell's tool table).
LatheContour LatheCase(const std::string& dialect, std::uint64_t seed, bool inside, bool inch) {
  Rng g(seed);
  LatheContour l;
  CompContour& c = l.c;
  c.r = Grid(g.Real(0.2, 1.6), 0.001);
  c.left = inside;
  c.open = true;
  bool emco = dialect == "emco";
  // A fillet (the tool inside the arc) larger than the nose radius: EMCO ALARM 570 (ln 3022-3040); at least
  // twice it on Okuma ("R >= 2 x R_N", ln 2718-2723); 0.2 mm more.
  const double least_fillet = (emco ? 1 : 2) * c.r + 0.2;
  TurnedProfile t = inside ? RandomBoredProfile(g, least_fillet) : RandomTurnedProfile(g, least_fillet);
  // The tip code from a stream of its own, so an outside profile of a seed is the one drawn before tip codes.
  // The tip on the side of the nose that faces the wall (below the centre outside, above it in a bore) or
  // level with it, and the centre codes: EMCO's L1-L9 ("nine positions", ln 2508-2553; L0 the centre as L9,
  // emco.md), Okuma's patterns 0-9 (okuma.md judgement call 25).
  static const int outside_tips[] = {3, 4, 8, 5, 7, 0, 9}, inside_tips[] = {2, 1, 6, 5, 7, 0, 9};
  Rng tg(seed ^ 0x71Bu);
  c.tip = (inside ? inside_tips : outside_tips)[tg.Int(0, 6)];
  for (const auto& q : t.contour) c.p.push_back({q[0], q[1]});
  c.p.push_back({c.p.back()[0] - 3, c.p.back()[1]});
  if (inch) {  // each step rounded to the 0.0001 in grid, so a quarter arc stays one and a line stays level
    const double u = 25.4e-4;
    std::array<long long, 2> at{std::llround(c.p[0][0] / u), std::llround(c.p[0][1] / u)};
    std::vector<P2> q{{static_cast<double>(at[0]) * u, static_cast<double>(at[1]) * u}};
    for (std::size_t i = 1; i < c.p.size(); ++i) {
      for (std::size_t a = 0; a < 2; ++a) at[a] += std::llround((c.p[i][a] - c.p[i - 1][a]) / u);
      q.push_back({static_cast<double>(at[0]) * u, static_cast<double>(at[1]) * u});
    }
    c.p = q;
    c.inch = true;
  }
  c.sweep.assign(c.p.size(), 0);
  c.centre.assign(c.p.size(), P2{0, 0});
  const double up = inside ? -1 : 1;  // +X outside, -X in a bore (profile.h)
  for (std::size_t i = 0; i + 1 < t.contour.size(); ++i) {
    int k = t.kind[i + 1];
    double rad = c.p[i][0] - c.p[i + 1][0];
    // A fillet is G02 outside, G03 in a bore; a rounded edge G03 outside, G02 in a bore (X up, Z right).
    if (k == 1) c.sweep[i] = -90 * up, c.centre[i] = {c.p[i][0], c.p[i][1] + up * rad};
    if (k == 2) c.sweep[i] = 90 * up, c.centre[i] = {c.p[i][0] - rad, c.p[i][1]};
  }
  const double unit = inch ? 25.4 : 1;
  const int decimals = inch ? 4 : 3;
  auto num = [&](double v) { return Num(v / unit, decimals, true); };
  auto xz = [&](const P2& q) { return "X" + num(2 * q[1]) + " Z" + num(q[0]); };
  const P2 &front = c.p.front(), &back = c.p.back();
  const P2 entry{front[0] + 5, front[1] + 5 * up};
  const std::string comp = inside ? "G41" : "G42", tip = std::to_string(c.tip);
  std::vector<std::string> lines;
  if (emco) {
    lines = {"%", std::string(inch ? "G70 " : "") + "G95 M03 S1000 F200", "T0101 G00 " + xz(entry),
             comp + " G01 " + xz(front)};
    l.w.tools = "T0101 X0 Z0 R" + Num(c.r, 3, true) + " L" + tip + "\n";
  } else {
    lines = {"(no-gouge property, tests/oracle)", "G00 " + xz(entry) + " S1000 T010101 M3", "G95",
             comp + " G01 " + xz(front) + " F0.2"};
    l.w.tools = "VTOFX[1]=0 VTOFZ[1]=0 VNSRX[1]=" + Num(c.r, 3, true) + " VNSRZ[1]=" + Num(c.r, 3, true) +
                " VNSRP[1]=" + tip + "\n";
    if (inch) l.w.params = "UNIT_SYSTEM=INCH\n";
  }
  l.w.first = static_cast<int>(lines.size()) + 1;
  for (std::size_t i = 0; i + 1 < c.p.size(); ++i) {
    const P2 &a = c.p[i], &e = c.p[i + 1];
    if (c.sweep[i] == 0) {
      lines.push_back("G01 " + xz(e));
    } else {  // I (a radius) and K incremental from the start (EMCO ln 909-911, Okuma ln 1204-1300)
      lines.push_back((c.sweep[i] < 0 ? "G02 " : "G03 ") + xz(e) + " I" + num(c.centre[i][1] - a[1]) + " K" +
                      num(c.centre[i][0] - a[0]));
    }
  }
  l.w.last = static_cast<int>(lines.size());
  lines.push_back("G40 G01 X" + num(2 * (back[1] + 3 * up)));
  lines.push_back(emco ? "M30" : "M02");
  for (std::size_t i = 1; emco && i < lines.size(); ++i) {  // EMCO numbers its blocks (N0010, N0020, ...)
    char n[16];
    std::snprintf(n, sizeof n, "N%04d ", static_cast<int>(10 * i));
    lines[i] = n + lines[i];
  }
  for (const auto& q : lines) l.w.text += q + "\n";
  return l;
}

// Where the nose centre S is for a written (theoretical tip) point P: P = S + the tip direction of the code
// times the radius, (Z, X) seen with X up and Z right:
//        2   6   1
//        7  0/9  5
//        3   8   4
// Code 3 (-Z, -X) is the outside tool turning toward the chuck: EMCO "cutter position L3" for a left-hand
// side tool (ln 2510-2514; P against S, ln 2553) and E42's tip "0.8 below and behind" (ln 2586-2755), Okuma
// pattern 3 (E-22's tip at the centre + [-0.8, -0.8], ln 2337-2361); code 2 (-Z, +X) EMCO's internal copying
// tool (ln 2516-2518). The rest walk round the centre: EMCO's table of shapes (ln 2544-2551: L3 L8 L4 L5 L1
// L6 L2 L7, the order of the positions round S) and Okuma's patterns (the manual has none: okuma.md judgement
// call 25); 0 and 9 are the centre.
Move NoseFromTip(const Move& m, double r, int tip) {
  static const int dz[10] = {0, 1, -1, -1, 1, 1, 0, -1, 0, 0}, dx[10] = {0, 1, 1, -1, -1, 0, 1, 0, -1, 0};
  const std::size_t t = tip >= 0 && tip <= 9 ? static_cast<std::size_t>(tip) : 0;
  Move c = m;
  c.end[0] -= dx[t] * r, c.end[2] -= dz[t] * r;
  c.center[0] -= dx[t] * r, c.center[2] -= dz[t] * r;
  return c;
}

namespace {

// The nose centre in the mills' plane: x = Z, y = X as a radius, X up and Z to the right, where G02 is
// clockwise (EMCO ln 2116-2149).
Move NoseCentre(const Move& m, double r, int tip) {
  Move c = NoseFromTip(m, r, tip);
  c.end = {c.end[2], c.end[0], 0};
  c.center = {c.center[2], c.center[0], 0};
  return c;
}

// One contour: true when it keeps the property. A refused program's moves before the refusal are counted in
// `before_refusal` when they come too close (the element too short for the radius is read after the corner
// before it was cut: docs/testing.md), not failed.
bool Check(const PropRun& o, const std::string& dialect, std::uint64_t seed, bool arcs, bool bypass,
           const fs::path& dir, Tally* tally) {
  const bool lathe = dialect == "emco" || dialect == "okuma";
  CompContour c;
  ContourProgram w;
  if (lathe) {
    LatheContour l = LatheCase(dialect, seed, arcs, false);  // the odd ones a bore
    c = std::move(l.c);
    w = std::move(l.w);
  } else {
    c = RandomContour(seed, arcs);
    c.bypass = bypass;
    tally->bypassed += bypass;
    w = WriteContour(dialect, c);
  }
  int arc_count = static_cast<int>(std::count_if(c.sweep.begin(), c.sweep.end(), [](double s) { return s; }));
  ++tally->contours;
  tally->bores += lathe && c.left;
  tally->arcs += arc_count;
  if (arc_count) ++tally->with_arcs;
  fs::path prog = dir / ("gouge." + dialect), tools = dir / "gouge.tools";
  Spit(prog, w.text);
  Spit(tools, w.tools);
  int rc = Shell(Quote(o.interp) + " --dialect " + dialect + " --tools " + Quote(tools) + " " + Quote(prog) +
                 " >" + Quote(dir / "gouge.out") + " 2>" + Quote(dir / "gouge.err"));
  std::string error;
  auto written = ParseCellInterp(Slurp(dir / "gouge.out"), lathe, &error);
  auto moves = written;  // the tool centre's moves
  if (lathe)
    for (Move& m : moves) m = NoseCentre(m, c.r, c.tip);
  auto keep = [&] {  // --keep: the program of a failing or refused contour
    if (o.keep.empty()) return;
    fs::create_directories(o.keep);
    std::string stem = dialect + "-nogouge-" + std::to_string(seed);
    Spit(fs::path(o.keep) / (stem + "." + dialect), w.text);
    Spit(fs::path(o.keep) / (stem + ".tools"), w.tools);
  };
  if (rc != 0) {
    keep();
    ++tally->refused;
    if (arc_count) ++tally->refused_with_arcs;
  }
  const double need = c.r - 2e-3 + (o.plant ? 0.1 : 0);  // --plant: 0.1 mm more than the radius
  const std::vector<P2> outline = Outline(c);
  Vec3 from{};
  bool back = false, was_back = false;  // this move, the one before, runs back against its line element
  for (std::size_t i = 0; i < moves.size(); ++i) {
    const Move& m = moves[i];
    bool checked = m.line > w.first && m.line < w.last;
    tally->moves += checked;
    std::size_t e = static_cast<std::size_t>(m.line - w.first) % c.p.size();
    Distance d = checked ? MoveDistance(m, from, c, outline, e) : Distance{};
    was_back = back;
    back = checked && m.kind != MoveKind::kArc && c.sweep[e] == 0 &&
           (m.end[0] - from[0]) * (c.p[c.Next(e)][0] - c.p[e][0]) +
                   (m.end[1] - from[1]) * (c.p[c.Next(e)][1] - c.p[e][1]) <
               -1e-9;
    if (d.all < need && dialect == "okuma" && (back || was_back)) {
      // A step shorter than the nose needs: Okuma's intersection runs the nose back along it and into the
      // surface before ("it might cause the cutting tool to move in the opposite direction ... and cut into
      // the N1 - N2 surface", ln 2524-2526; okuma.md judgement call 67). The manual's; counted, not failed.
      ++tally->reversed;
      std::cout << dialect << " nogouge: program seed " << seed << ", line " << m.line
                << " (the nose runs back along a step shorter than it needs): the tool centre comes " << d.all
                << " mm from the contour, radius " << c.r << "\n";
      keep();
      return true;
    }
    if (d.all < need && rc != 0) {  // reported, not failed
      ++tally->before_refusal;
      std::cout << dialect << " nogouge: program seed " << seed << " (refused: " << Slurp(dir / "gouge.err")
                << "), line " << m.line << " before the refusal comes " << d.all
                << " mm from the contour, radius " << c.r << "\n";
      return true;
    }
    if (d.all < need) {
      // Too close to an element the move's own element does not meet: the offset reaching a part of the
      // contour further on, which compensation looking one element ahead does not see (balt.md judgement call
      // 49); reported, not failed. Too close to its own element or a neighbour is a wrong corner: failed.
      bool far_only = d.own >= need;
      std::cout << dialect << " nogouge: program seed " << seed << ", line " << m.line
                << (far_only ? " (a non-adjacent element)" : "") << ": the tool centre comes " << d.all
                << " mm from the contour, radius " << c.r << "\n  " << Describe(written[i]) << "\n";
      keep();
      if (far_only) {
        ++tally->far;
        return true;
      }
      return false;
    }
    from = m.end;
  }
  return true;
}

}  // namespace

int NoGouge(const PropRun& o, const std::string& dialect, const fs::path& dir) {
  int failing = 0;
  Tally t;
  // One contour per ten blocks; the odd ones with arcs (a lathe's: a bore under G41); KT-APL's every other
  // pair under G46 (its corners intersections, ktapl.md judgement call 39).
  for (int done = 0, i = 0; done < o.blocks; done += 10, ++i)
    if (!Check(o, dialect, ProgramSeed(o.seed, dialect + "/nogouge", i), i % 2 == 1,
               dialect == "ktapl" && (i / 2) % 2 == 1, dir, &t))
      ++failing;
  bool lathe = dialect == "emco" || dialect == "okuma";
  std::printf(
      "%s nogouge: %d of %d %s keep the property (%ld compensated moves checked; %d with %d arcs; %d "
      "refused, "
      "%d of them with arcs, %d too close before the refusal; %d too close to a non-adjacent element only; "
      "%d "
      "too close on a step run back along)\n",
      dialect.c_str(), t.contours - failing, t.contours, lathe ? "profiles" : "contours", t.moves,
      t.with_arcs, t.arcs, t.refused, t.refused_with_arcs, t.before_refusal, t.far, t.reversed);
  if (lathe) std::printf("%s nogouge: %d of the profiles bores (G41)\n", dialect.c_str(), t.bores);
  if (dialect == "ktapl") std::printf("ktapl nogouge: %d of the contours under G46\n", t.bypassed);
  return failing;
}

}  // namespace cell::oracle
