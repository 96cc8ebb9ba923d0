// `cell-oracle-gen prop --property corners` (issue 33 item 2, docs/testing.md "Properties"): a chamfer or
// radius inserted between two elements stays inside the corner it replaces. Random two-element corners in
// each dialect that has corner insertion, a random chamfer or radius that fits, cell-interp's moves checked
// against the manual's rule:
// - EMCO (DC 5.10, ln 55-116): P1 a chamfer "laid symmetrically into the edge, i.e. length P1 is identical
//   on both enclosing straight lines" (ln 79), P0 a radius, on the first of two G01 lines, the first stating
//   exactly two position parameters (ln 91); between two straight lines only (ln 77).
// - Okuma (G75/G76, ln 1302-1496): "chamfering the corner at 45 degrees with a size of" L (ln 1322), "Radius
//   of rounding circle" L (ln 1383, "a 1/4 circle", ln 1397) between an X move and a Z move (the L sign is
//   the direction of the second move, ln 1332, 1387; L no longer than the move, ln 1342); at any angle the
//   first line by A "in reference to the Z-axis" (ln 1449) with X, L the length on each leg (okuma.md
//   judgement call 14); between two lines only (ln 1493).
// - Balt-System (r / b, ln 3160-3200): b "the distance from the intersection between the lines" (ln 3190),
//   r the radius linking the elements (ln 3162); a radius also "between straight lines or circles" (the GTL
//   profiles, ln 5195), so between a line and an arc here too. KT-APL has no corner insertion: the property
//   does not apply.
// Checked: the inserted element starts and ends on the two original elements (1e-3 mm) and the moves before
// and after it run on them to the programmed end; every point of it lies inside the corner it replaces (on
// the turn's side of both original elements and on the corner's side of the chord between its ends,
// 1e-3 mm); a radius is an arc of the programmed radius tangent to both
// elements (its centre the radius from each); a chamfer's legs from the corner are its length.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <iostream>

#include "cell/oracle/oracle.h"
#include "cell/oracle/rng.h"
#include "run.h"

namespace fs = std::filesystem;

namespace cell::oracle {
namespace {

using P2 = std::array<double, 2>;

P2 Sub(P2 a, P2 b) {
  return {a[0] - b[0], a[1] - b[1]};
}
double Dot(P2 a, P2 b) {
  return a[0] * b[0] + a[1] * b[1];
}
double Cross(P2 a, P2 b) {
  return a[0] * b[1] - a[1] * b[0];
}
double Len(P2 a) {
  return std::hypot(a[0], a[1]);
}

// One corner: the first element from `a` to `c`, the second from `c` to `b` (a line, or a Balt-System arc
// about `o`, `cw`), in plane coordinates (mill: x y; lathe: z and x as a radius, so an arc's sense is the
// one seen from +Y, as DESIGN states it).
struct Corner {
  P2 a{}, c{}, b{};
  bool arc = false, cw = false;
  P2 o{};
  bool chamfer = false;
  double v = 0;                     // the chamfer's leg or the radius
  std::vector<std::string> blocks;  // the rapid to `a`, then the corner's blocks
  // EMCO chains (P words on two blocks in a row, emco.md judgement call 27): `chained` is the first corner,
  // whose second element goes on into the next insertion; `tail` the second corner (its blocks are the
  // first's).
  bool chained = false;
  std::vector<Corner> tail;
  int first = 0, last = 0;  // the program lines of the corner's blocks (cell-interp counts from 1)
};

// The plane point of a move's end (lathe: z and the radius).
P2 PlaneOf(const Vec3& v, bool lathe) {
  return lathe ? P2{v[2], v[0]} : P2{v[0], v[1]};
}

double LineDistance(P2 q, P2 a, P2 b) {
  P2 d = Sub(b, a);
  return std::fabs(Cross(d, Sub(q, a))) / Len(d);
}

// The points of a move from `from`: 33 along a line or the arc in its sense.
std::vector<P2> Samples(P2 from, P2 to, bool arc, P2 o, bool cw) {
  std::vector<P2> out;
  double a0 = std::atan2(from[1] - o[1], from[0] - o[0]), a1 = std::atan2(to[1] - o[1], to[0] - o[0]);
  double sweep = cw ? a0 - a1 : a1 - a0;
  while (sweep < 0) sweep += 2 * M_PI;
  double rad = Len(Sub(from, o));
  for (int k = 0; k <= 32; ++k) {
    double t = k / 32.0;
    if (!arc)
      out.push_back({from[0] + t * (to[0] - from[0]), from[1] + t * (to[1] - from[1])});
    else {
      double a = a0 + (cw ? -1 : 1) * t * sweep;
      out.push_back({o[0] + rad * std::cos(a), o[1] + rad * std::sin(a)});
    }
  }
  return out;
}

// The tangent of the second element at c.
P2 SecondTangent(const Corner& k) {
  if (!k.arc) {
    P2 d = Sub(k.b, k.c);
    return {d[0] / Len(d), d[1] / Len(d)};
  }
  P2 r = Sub(k.c, k.o);
  double l = Len(r);
  return k.cw ? P2{r[1] / l, -r[0] / l} : P2{-r[1] / l, r[0] / l};
}

// Where a point lies with respect to the second element: its distance from it (negative beyond its ends is
// not needed: the fit keeps the insertion well inside) and whether it is on the turn's side.
double SecondSide(const Corner& k, P2 q, double turn) {
  if (!k.arc) return turn * Cross(Sub(k.b, k.c), Sub(q, k.c)) / Len(Sub(k.b, k.c));
  // An arc: the turn's side is toward its centre for a turn the arc's way, away from it otherwise.
  double rad = Len(Sub(k.c, k.o)), d = rad - Len(Sub(q, k.o));
  bool toward = (turn > 0) == !k.cw;
  return toward ? d : -d;
}

// Writes the program and returns false with a message when the inserted element breaks the rule.
struct Outcome {
  bool ok = true, refused = false;
  std::string why;
};

Outcome Check(const Corner& k, const std::vector<Move>& all, bool lathe, bool plant) {
  Outcome out;
  const double tol = 1e-3;
  std::vector<Move> moves;
  for (const Move& m : all)
    if (m.line >= k.first && m.line <= k.last) moves.push_back(m);
  if (k.chained && moves.size() > 3) moves.resize(3);  // the line, the insertion, the middle line
  if (moves.size() != 3) {
    out.ok = false;
    out.why = "expected three moves from the corner's first block on (the line, the " +
              std::string(k.chamfer ? "chamfer" : "radius") + ", the line), got " +
              std::to_string(moves.size());
    return out;
  }
  P2 p1 = PlaneOf(moves[0].end, lathe), p2 = PlaneOf(moves[1].end, lathe), end = PlaneOf(moves[2].end, lathe);
  P2 t1 = Sub(k.c, k.a);
  t1 = {t1[0] / Len(t1), t1[1] / Len(t1)};
  P2 t2 = SecondTangent(k);
  double turn = Cross(t1, t2) > 0 ? 1 : -1;
  auto fail = [&](const std::string& why) {
    out.ok = false;
    out.why = why;
    return out;
  };
  char buf[256];
  // The first element is cut to p1 and the second from p2 to its end.
  if (LineDistance(p1, k.a, k.c) > tol || Dot(Sub(p1, k.a), t1) < -tol || Dot(Sub(k.c, p1), t1) < -tol) {
    std::snprintf(buf, sizeof buf, "starts at %.4f %.4f, off the first element", p1[0], p1[1]);
    return fail(buf);
  }
  double off2 = k.arc ? std::fabs(Len(Sub(p2, k.o)) - Len(Sub(k.c, k.o))) : LineDistance(p2, k.c, k.b);
  if (off2 > tol) {
    std::snprintf(buf, sizeof buf, "ends at %.4f %.4f, %.4f mm off the second element", p2[0], p2[1], off2);
    return fail(buf);
  }
  if ((!k.chained && Len(Sub(end, k.b)) > tol) || moves[2].kind != (k.arc ? MoveKind::kArc : MoveKind::kLine))
    return fail("the second element does not run on to its programmed end");
  if (k.arc && Len(Sub(PlaneOf(moves[2].center, lathe), k.o)) > tol)
    return fail("the second element's centre moved");
  // Inside the corner: every point on the turn's side of both elements.
  bool arc = moves[1].kind == MoveKind::kArc;
  P2 o = PlaneOf(moves[1].center, lathe);
  bool cw = moves[1].cw != plant;  // --plant: the radius turned the other way round (outside the corner)
  // The corner is bounded by the chord from p1 to p2 as well: the whole circle of a radius tangent to
  // both lines lies between them, and only its short arc toward the corner replaces the corner.
  P2 chord = Sub(p2, p1);
  double corner_side = Cross(chord, Sub(k.c, p1)) > 0 ? 1 : -1, chord_len = std::max(Len(chord), 1e-9);
  for (P2 q : Samples(p1, p2, arc, o, cw)) {
    double s1 = turn * Cross(t1, Sub(q, k.a)), s2 = SecondSide(k, q, turn);
    double s3 = corner_side * Cross(chord, Sub(q, p1)) / chord_len;
    if (s1 < -tol || s2 < -tol || s3 < -tol) {
      std::snprintf(buf, sizeof buf, "passes %.4f %.4f, %.4f mm outside the corner", q[0], q[1],
                    -std::min({s1, s2, s3}));
      return fail(buf);
    }
  }
  if (k.chamfer) {
    if (arc) return fail("a chamfer cut as an arc");
    double l1 = Len(Sub(k.c, p1)), l2 = Len(Sub(k.c, p2));
    double want = k.v + (plant ? 0.01 : 0);  // --plant: a leg 0.01 mm longer
    if (std::fabs(l1 - want) > tol || std::fabs(l2 - want) > tol) {
      std::snprintf(buf, sizeof buf, "legs %.4f and %.4f from the corner, the chamfer is %.4f", l1, l2, want);
      return fail(buf);
    }
    return out;
  }
  if (!arc) return fail("a radius cut as a line");
  double r1 = Len(Sub(p1, o)), r2 = Len(Sub(p2, o)), d1 = LineDistance(o, k.a, k.c);
  double d2 = k.arc ? std::fabs(Len(Sub(o, k.o)) - Len(Sub(k.c, k.o))) : LineDistance(o, k.c, k.b);
  if (std::fabs(r1 - k.v) > tol || std::fabs(r2 - k.v) > tol || std::fabs(d1 - k.v) > tol ||
      std::fabs(d2 - k.v) > tol) {
    std::snprintf(
        buf, sizeof buf,
        "radius %.4f/%.4f, centre %.4f and %.4f from the elements: not a radius %.4f tangent to both", r1, r2,
        d1, d2, k.v);
    return fail(buf);
  }
  return out;
}

std::string Fixed(double v, int decimals = 3, bool point = false) {
  return Num(v, decimals, point);
}

// A line-line corner with legs of 10-60 mm turning by 20-160 degrees either way, in a box of the plane.
// `lathe`: the plane's second coordinate (x, a radius) stays in 5-60 mm.
bool RandomLines(Rng& g, Corner& k, bool lathe) {
  for (int tries = 0; tries < 100; ++tries) {
    double h1 = g.Real(-M_PI, M_PI), turn = g.Real(20, 160) * M_PI / 180 * (g.Int(0, 1) ? 1 : -1);
    double l1 = g.Real(10, 60), l2 = g.Real(10, 60);
    P2 c{Grid(g.Real(-40, 40), 0.001), Grid(lathe ? g.Real(10, 55) : g.Real(-40, 40), 0.001)};
    k.c = c;
    k.a = {Grid(c[0] - l1 * std::cos(h1), 0.001), Grid(c[1] - l1 * std::sin(h1), 0.001)};
    k.b = {Grid(c[0] + l2 * std::cos(h1 + turn), 0.001), Grid(c[1] + l2 * std::sin(h1 + turn), 0.001)};
    if (!lathe) return true;
    if (std::min({k.a[1], k.b[1]}) >= 5 && std::max({k.a[1], k.b[1]}) <= 60) return true;
  }
  return false;
}

// The size that fits: a chamfer leg or radius whose trim from the corner is 5-80 % of the shorter element
// (the manuals refuse one longer than an element: EMCO ALARM 389, ln 84; Okuma ln 1342; Balt FILMS4 77).
double RandomSize(Rng& g, const Corner& k, double turn_deg) {
  double shorter = std::min(Len(Sub(k.c, k.a)), Len(Sub(k.b, k.c)));
  double trim = g.Real(0.05, 0.8) * shorter;
  double v = k.chamfer ? trim : trim / std::tan(turn_deg * M_PI / 360);
  return std::max(0.1, Grid(v, 0.001));
}

double TurnDeg(const Corner& k) {
  P2 t1 = Sub(k.c, k.a), t2 = SecondTangent(k);
  return std::fabs(std::atan2(Cross(t1, t2), Dot(t1, t2))) * 180 / M_PI;
}

// EMCO: G01 X.. Z.. P1=v (chamfer) or P0=v (radius), then G01 X.. Z.. (ln 55-116, 91); decimal points, X a
// diameter. One in four draws a chain: a P word on the second line too, the third line closing the second
// corner (judgement call 27: each insertion in its own corner, both on the middle line, so each trims at
// most 45 % of it here).
bool EmcoCorner(Rng& g, Corner& k) {
  if (!RandomLines(g, k, true)) return false;
  k.chamfer = g.Int(0, 1) == 1;
  auto xz = [](P2 p) { return "X" + Fixed(2 * p[1], 3, true) + " Z" + Fixed(p[0], 3, true); };
  auto word = [](const Corner& c) { return (c.chamfer ? " P1=" : " P0=") + Fixed(c.v, 3, true); };
  if (g.Int(0, 3) == 0) {
    Corner k2;
    k2.a = k.c, k2.c = k.b;
    double h = std::atan2(k.b[1] - k.c[1], k.b[0] - k.c[0]);
    double turn = g.Real(20, 160) * M_PI / 180 * (g.Int(0, 1) ? 1 : -1), l3 = g.Real(10, 60);
    k2.b = {Grid(k2.c[0] + l3 * std::cos(h + turn), 0.001), Grid(k2.c[1] + l3 * std::sin(h + turn), 0.001)};
    if (k2.b[1] < 5 || k2.b[1] > 60) return false;
    k2.chamfer = g.Int(0, 1) == 1;
    double middle = Len(Sub(k.b, k.c));
    auto size = [&](Corner& c, double other) {
      double trim = g.Real(0.05, 0.45) * std::min(middle, other);
      c.v = std::max(0.1, Grid(c.chamfer ? trim : trim / std::tan(TurnDeg(c) * M_PI / 360), 0.001));
    };
    size(k, Len(Sub(k.c, k.a)));
    size(k2, l3);
    k.chained = true;
    k.blocks = {"G00 " + xz(k.a), "G01 " + xz(k.c) + word(k), "G01 " + xz(k2.c) + word(k2),
                "G01 " + xz(k2.b)};
    k.tail.push_back(k2);
    return true;
  }
  k.v = RandomSize(g, k, TurnDeg(k));
  k.blocks = {"G00 " + xz(k.a), "G01 " + xz(k.c) + word(k), "G01 " + xz(k.b)};
  return true;
}

// Okuma: G75 (chamfer) / G76 (radius) on an X or Z move, the next move along the other axis, L signed as
// the second move goes (ln 1332, 1387); or (odd draws) the first line at an angle A from +Z (ln 1449) with X,
// then Z. X a diameter.
bool OkumaCorner(Rng& g, Corner& k) {
  k.chamfer = g.Int(0, 1) == 1;
  const char* word = k.chamfer ? "G75" : "G76";
  bool angled = g.Int(0, 1) == 1;
  double z0 = Grid(g.Real(-40, 40), 0.001), x0 = Grid(g.Real(8, 50), 0.001);
  k.a = {z0, x0};
  std::string first;
  if (angled) {
    int deg = g.Int(20, 160) * (g.Int(0, 1) ? 1 : -1);
    double dx = (deg > 0 ? 1 : -1) * Grid(g.Real(10, 40), 0.0005);
    if (x0 + dx < 5) dx = -dx, deg = -deg;
    double a = deg * M_PI / 180;
    k.c = {z0 + dx * std::cos(a) / std::sin(a), x0 + dx};
    first = word + std::string(" G01 A") + std::to_string(deg) + " X" + Fixed(2 * k.c[1], 3, true);
    double dz = (g.Int(0, 1) ? 1 : -1) * Grid(g.Real(10, 40), 0.001);
    k.b = {Grid(k.c[0] + dz, 0.001), k.c[1]};
  } else if (g.Int(0, 1)) {  // X first, then Z
    double dx = (g.Int(0, 1) ? 1 : -1) * Grid(g.Real(10, 40), 0.0005);
    if (x0 + dx < 5) dx = -dx;
    k.c = {z0, x0 + dx};
    double dz = (g.Int(0, 1) ? 1 : -1) * Grid(g.Real(10, 40), 0.001);
    k.b = {z0 + dz, k.c[1]};
    first = word + std::string(" G01 X") + Fixed(2 * k.c[1], 3, true);
  } else {  // Z first, then X
    double dz = (g.Int(0, 1) ? 1 : -1) * Grid(g.Real(10, 40), 0.001);
    k.c = {z0 + dz, x0};
    double dx = (g.Int(0, 1) ? 1 : -1) * Grid(g.Real(10, 40), 0.0005);
    if (x0 + dx < 5) dx = -dx;
    k.b = {k.c[0], x0 + dx};
    first = word + std::string(" G01 Z") + Fixed(k.c[0], 3, true);
  }
  k.v = RandomSize(g, k, TurnDeg(k));
  bool second_x = k.b[1] != k.c[1];
  double sign = second_x ? (k.b[1] > k.c[1] ? 1 : -1) : (k.b[0] > k.c[0] ? 1 : -1);
  std::string second = second_x ? "X" + Fixed(2 * k.b[1], 3, true) : "Z" + Fixed(k.b[0], 3, true);
  k.blocks = {"G00 X" + Fixed(2 * k.a[1], 3, true) + " Z" + Fixed(k.a[0], 3, true),
              first + " L" + Fixed(sign * k.v, 3, true), second};
  return true;
}

// Balt-System: G1 to the corner, a block of r (radius, either sign: balt.md judgement call 24) or b (bevel),
// then the second element: a line, or (radius, odd draws) a G2/G3 arc by its centre I J.
bool BaltCorner(Rng& g, Corner& k) {
  if (!RandomLines(g, k, false)) return false;
  k.chamfer = g.Int(0, 1) == 1;
  k.arc = !k.chamfer && g.Int(0, 1) == 1;
  if (k.arc) {
    // An arc from c to b: its centre on either side of the chord, far enough out for a short arc.
    P2 m{(k.c[0] + k.b[0]) / 2, (k.c[1] + k.b[1]) / 2}, d = Sub(k.b, k.c);
    double chord = Len(d), off = g.Real(0.2, 2.0) * chord * (g.Int(0, 1) ? 1 : -1);
    k.o = {Grid(m[0] - off * d[1] / chord, 0.001), Grid(m[1] + off * d[0] / chord, 0.001)};
    k.cw = g.Int(0, 1) == 1;
    // b moved onto the circle through c (on the grid to 1e-3: the interpreter mends a radius off by less).
    double rad = Len(Sub(k.c, k.o)), ab = std::atan2(k.b[1] - k.o[1], k.b[0] - k.o[0]);
    k.b = {Grid(k.o[0] + rad * std::cos(ab), 0.001), Grid(k.o[1] + rad * std::sin(ab), 0.001)};
    if (std::fabs(Len(Sub(k.b, k.o)) - rad) > 2e-4) return false;
    // The arc must leave c turning away from the first line by 20-160 degrees and be short enough that the
    // radius fits within its first half.
    double t = TurnDeg(k);
    if (t < 20 || t > 160) return false;
    double a0 = std::atan2(k.c[1] - k.o[1], k.c[0] - k.o[0]);
    double sweep = k.cw ? a0 - ab : ab - a0;
    while (sweep < 0) sweep += 2 * M_PI;
    if (sweep > M_PI) return false;
    double shorter = std::min(Len(Sub(k.c, k.a)), sweep * rad);
    // A fillet of radius v takes at most about v tan(turn/2) plus the arc's curvature effect: keep it small.
    k.v = std::max(0.1, Grid(g.Real(0.05, 0.3) * shorter / std::tan(t * M_PI / 360) *
                                 std::min(1.0, rad / (rad + shorter)),
                             0.001));
  } else {
    k.v = RandomSize(g, k, TurnDeg(k));
  }
  auto xy = [](P2 p) { return "X" + Fixed(p[0]) + " Y" + Fixed(p[1]); };
  std::string corner = k.chamfer ? "b" + Fixed(k.v) : "r" + Fixed(k.v * (g.Int(0, 1) ? 1 : -1));
  std::string second =
      k.arc ? std::string(k.cw ? "G2 " : "G3 ") + xy(k.b) + " I" + Fixed(k.o[0]) + " J" + Fixed(k.o[1])
            : xy(k.b);
  k.blocks = {"G " + xy(k.a), "G1 " + xy(k.c), corner, second};
  return true;
}

}  // namespace

// The program around a dialect's corners: its header and end.
struct Frame {
  std::string head, end;
};
Frame FrameOf(const std::string& dialect) {
  if (dialect == "emco")
    return {"(corner property, tests/oracle/corners.cpp)\n%\nG95 M03 S1000 F100\n", "M30\n"};
  if (dialect == "okuma")
    return {"(corner property, tests/oracle/corners.cpp)\nG95 S500 M03\nF0.1\n", "M02\n"};
  return {"; corner property (tests/oracle/corners.cpp)\nG X0 Y0 Z0\nF200\n", "M2\n"};
}

int Corners(const PropRun& o, const std::string& dialect, const fs::path& dir) {
  bool (*make)(Rng&, Corner&) = dialect == "emco"    ? EmcoCorner
                                : dialect == "okuma" ? OkumaCorner
                                : dialect == "balt"  ? BaltCorner
                                                     : nullptr;
  if (!make) {
    std::printf("%s corners: does not apply\n", dialect.c_str());
    return 0;
  }
  bool lathe = dialect != "balt";
  Frame frame = FrameOf(dialect);
  int corners = 0, failing = 0, refused = 0, chamfers = 0, radii = 0, arcs = 0, programs = 0, chains = 0;
  // One corner per ten blocks of --blocks, ten corners to a program (one cell-interp run).
  const int per_program = 10;
  for (int i = 0, total = std::max(1, o.blocks / 10); i < total; i += per_program, ++programs) {
    std::uint64_t seed = ProgramSeed(o.seed, dialect + "/corners", i);
    Rng g(seed);
    std::vector<Corner> ks;
    std::string text = frame.head;
    int line = static_cast<int>(std::count(text.begin(), text.end(), '\n'));
    for (int j = 0; j < per_program && i + j < total; ++j) {
      Corner k;
      bool made = false;
      for (int tries = 0; tries < 50 && !made; ++tries) made = make(g, k = Corner{});
      if (!made) continue;
      k.first = line + 2;  // after its rapid to `a`
      for (const std::string& b : k.blocks) text += b + "\n";
      line += static_cast<int>(k.blocks.size());
      k.last = line;
      if (k.chained) {  // the first corner's moves run into the second's lines; the second's from its block
        Corner k2 = k.tail.front();
        k.last = k.first + 1;
        k2.first = k.first + 1, k2.last = k.first + 2;
        ks.push_back(k);
        ks.push_back(k2);
        ++chains;
        continue;
      }
      ks.push_back(k);
    }
    text += frame.end;
    fs::path prog = dir / ("corner." + dialect), out = dir / "corner.out", err = dir / "corner.err";
    Spit(prog, text);
    int rc = Shell(Quote(o.interp) + " --dialect " + dialect + " " + Quote(prog) + " >" + Quote(out) + " 2>" +
                   Quote(err));
    std::string error;
    auto moves = ParseCellInterp(Slurp(out), lathe, &error);
    bool kept = true;
    for (std::size_t j = 0; j < ks.size(); ++j) {
      const Corner& k = ks[j];
      ++corners;
      (k.chamfer ? chamfers : radii) += 1;
      arcs += k.arc;
      Outcome r;
      if (!error.empty())
        r = {false, true, "cell-interp's output: " + error};
      else if (rc != 0 &&
               std::none_of(moves.begin(), moves.end(), [&](const Move& m) { return m.line > k.last; }))
        r = {false, true, "refused: " + Slurp(err)};  // the refusal is at this corner or before it
      else
        r = Check(k, moves, lathe, o.plant);
      if (r.ok) continue;
      ++failing;
      refused += r.refused;
      kept = false;
      std::cout << dialect << " corners: program seed " << seed << ", "
                << (k.chamfer ? "chamfer " : "radius ") << Fixed(k.v) << (k.arc ? " line-arc" : " line-line")
                << " at line " << k.first << ": " << r.why << "\n";
      if (r.refused) {
        failing += static_cast<int>(ks.size() - j - 1), corners += static_cast<int>(ks.size() - j - 1);
        break;  // the rest of the program did not run
      }
    }
    if (!kept && !o.keep.empty()) {
      fs::create_directories(o.keep);
      Spit(fs::path(o.keep) / (dialect + "-corners-" + std::to_string(seed) + "." + dialect), text);
    }
  }
  std::printf(
      "%s corners: %d of %d corners keep the property (%d chamfers, %d radii, %d of them line-arc, %d "
      "chains of two; %d refused; %d programs)\n",
      dialect.c_str(), corners - failing, corners, chamfers, radii, arcs, chains, refused, programs);
  return failing;
}

}  // namespace cell::oracle
