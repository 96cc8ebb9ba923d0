// `cell-oracle-gen check --comp` (issue 33 item 1, docs/testing.md "Cutter radius compensation"): the
// LinuxCNC differential under G41/G42. The no-gouge property's random closed contours (contour.h: lines and
// arcs, convex and concave corners; G17 or G18 (rs274 compensates in no other plane), mm or inch) in
// Balt-System or KT-APL, and their NGC twin with G41.1/G42.1 D<the diameter> (rs274 needs no tool table
// then). The entry (ramp-on) and exit (ramp-off) rules differ, so only the moves strictly between the first
// and the second cut of element 0 are compared (every corner there is made of two whole offset elements): end
// points, arc centres and senses, 1e-3 mm (2e-3 in inch), in order, anchored by geometry (the moves on
// element 0's offset), not by index. Balt-System's outside corner is the intersection of the offsets (balt.md
// judgement call 50), and KT-APL's under G46 (every other set of eight of its contours; ktapl.md judgement
// call 39, the same rule): the LinuxCNC path is rewritten to it before the comparison (see Expected). The
// lathes, EMCO and Okuma: the no-gouge property's turned profile (LatheCase, nogouge.cpp), outside under G42
// and every other one a bore under G41, with a tip code drawn for its side, every other pair in inch, and its
// NGC twin in G18 G7 (mm) with tool 1 of a lathe tool table (D the diameter, the orientation LinuxCNC numbers
// that tip code with: LatheNgc); both state the imaginary tip, so both are compared as nose centres
// (NoseFromTip), in (Z, X as a radius), element 0 the 2 mm lead and the last the 3 mm behind the last
// shoulder. Okuma's every corner is the offsets' intersection
// (okuma.md judgement call 61; OkumaExpected), EMCO's outside corner LinuxCNC's fill-in arc (emco.md
// judgement call 33). Debugging: COMP_ONLY=<program seed> runs that contour alone; COMP_DEBUG=1 prints both
// move lists of a finding and LinuxCNC's as compared.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>

#include "cell/oracle/oracle.h"
#include "contour.h"
#include "run.h"

namespace fs = std::filesystem;

namespace cell::oracle {
namespace {

// 1e-3 mm; 2e-3 mm in inch (rs274 prints four decimals of an inch, 1.27e-3 mm; a lathe's twin is in mm,
// LatheNgc, so its inch contour keeps 1e-3).
double Tol(const CompContour& k) {
  return k.inch && !k.open ? 2e-3 : 1e-3;
}
// Which offset element a move runs on: the contour's arc centres are on the 0.001 mm grid, so an arc's radii
// at its two ends differ by up to 1.5e-3 mm; in inch its points are on the 0.0001 in grid (2.54e-3 mm) and
// rs274 prints four decimals of an inch: 1e-2 mm.
double OnTol(const CompContour& k) {
  return k.inch && !k.open ? 1e-2 : 5e-3;
}

// One feed move in the plane: a line, or an arc about c.
struct Seg {
  bool arc = false;
  P2 a{}, b{}, c{};
  bool cw = false;
  double z = 0;
  // LinuxCNC bent this corner (RestoreFillIns): the end (start) point is not compared.
  bool loose_end = false, loose_start = false;
  double slack_end = 0, slack_start = 0;  // added to the tolerance of that point (ArcJointSlack)
};

double Dist(const P2& p, const P2& q) {
  return std::hypot(p[0] - q[0], p[1] - q[1]);
}

// The moves in the contour's plane: its first and second axis, z the normal one (an arc's sense is seen from
// the plane's normal on both sides, so it is kept).
std::vector<Seg> Segs(const std::vector<Move>& moves, int plane) {
  const auto ax = PlaneAxes(plane);
  std::vector<Seg> out;
  P2 at{};
  for (const Move& m : moves) {
    P2 e{m.end[ax[0]], m.end[ax[1]]};
    if (m.kind == MoveKind::kLine || m.kind == MoveKind::kArc)
      out.push_back(
          {m.kind == MoveKind::kArc, at, e, {m.center[ax[0]], m.center[ax[1]]}, m.cw, m.end[ax[2]]});
    at = e;
  }
  return out;
}

// The unit direction of s at its end (or start).
P2 Direction(const Seg& s, bool at_end) {
  if (!s.arc) {
    double l = Dist(s.a, s.b);
    return {(s.b[0] - s.a[0]) / l, (s.b[1] - s.a[1]) / l};
  }
  const P2& q = at_end ? s.b : s.a;
  double l = Dist(q, s.c), x = (q[0] - s.c[0]) / l, y = (q[1] - s.c[1]) / l;
  return s.cw ? P2{y, -x} : P2{-y, x};
}

// Whether s runs on the offset of contour element i (the tool on the left for G41); `start_tol`: how far its
// start may be off (a corner LinuxCNC bent, RestoreFillIns; 0: OnTol). An end or a start not compared
// (loose_end, loose_start: an intersection at a small turn taken between the two offset points, Expected) may
// be off by as much: on the last element it had hidden the window's end (seed 1, Balt-System).
bool OnElement(const Seg& s, const CompContour& k, std::size_t i, double start_tol = 0) {
  if (start_tol == 0) start_tol = OnTol(k);
  const double end_tol = s.loose_end ? std::max(start_tol, 0.5) : OnTol(k);
  if (s.loose_start) start_tol = std::max(start_tol, 0.5);
  const P2 &p = k.p[i], &q = k.p[k.Next(i)];
  double side = k.left ? 1 : -1;
  if (k.sweep[i] == 0) {
    if (s.arc) return false;
    double l = Dist(p, q);
    auto offset = [&](const P2& x) {  // signed distance, left positive
      return ((q[0] - p[0]) * (x[1] - p[1]) - (q[1] - p[1]) * (x[0] - p[0])) / l;
    };
    return std::fabs(offset(s.a) - side * k.r) < start_tol && std::fabs(offset(s.b) - side * k.r) < end_tol;
  }
  // A ccw arc has the part, its centre, on the left.
  double want = Dist(p, k.centre[i]) - side * k.r * (k.sweep[i] > 0 ? 1 : -1);
  return s.arc && s.cw == (k.sweep[i] < 0) && Dist(s.c, k.centre[i]) < Tol(k) &&
         std::fabs(Dist(s.b, s.c) - want) < end_tol;
}

// A fill-in arc: the cutter radius about a corner of the contour.
bool FillIn(const Seg& s, const CompContour& k) {
  if (!s.arc || std::fabs(Dist(s.a, s.c) - k.r) > Tol(k)) return false;
  for (const P2& p : k.p)
    if (Dist(s.c, p) < Tol(k)) return true;
  return false;
}

// Balt-System (balt.md judgement call 50, ln 3082, 3186-3190) and KT-APL under G46 (ktapl.md judgement call
// 39, the same rule): at an outside corner the tool goes to the
// intersection X of the two offset elements' tangents there, no fill-in arc. Two lines run to and from X; an
// arc ends (starts) at its own offset point and a straight line joins it to X. Where the offset elements do
// not meet ahead of both ends and an arc is one of them, the fill-in arc stays (call 50): that choice is not
// re-derived here; the corner is taken either way, as the cell's path has it (a move of it ending at X).
std::vector<Seg> Expected(const std::vector<Seg>& ngc, const std::vector<Seg>& cell, const CompContour& k,
                          int* bent) {
  std::vector<Seg> out;
  for (std::size_t i = 0; i < ngc.size(); ++i) {
    const Seg& s = ngc[i];
    if (!FillIn(s, k) || out.empty() || i + 1 >= ngc.size()) {
      out.push_back(s);
      continue;
    }
    Seg& before = out.back();
    const Seg& after = ngc[i + 1];
    // The directions of LinuxCNC's own moves (a start moved to the previous X would tilt a line).
    P2 d1 = Direction(ngc[i - 1], true), d2 = Direction(after, false);
    double den = d1[0] * d2[1] - d1[1] * d2[0];  // before.b + t d1 = after.a - u d2
    P2 w{after.a[0] - before.b[0], after.a[1] - before.b[1]};
    double t = (w[0] * d2[1] - w[1] * d2[0]) / (std::fabs(den) > 1e-12 ? den : 1e-12);
    double u = (d1[0] * w[1] - d1[1] * w[0]) / (std::fabs(den) > 1e-12 ? den : 1e-12);
    // At a small turn X moves along the path by the inputs' last digits over the sine of the turn (1.2e-3 mm
    // from rs274's four decimals at a 1.3 degree turn; t and u may even change sign): there X is taken
    // between the two offset points and not compared (`bent` counts it).
    bool small = std::fabs(den) < 0.1;
    P2 x = small ? P2{(before.b[0] + after.a[0]) / 2, (before.b[1] + after.a[1]) / 2}
                 : P2{before.b[0] + t * d1[0], before.b[1] + t * d1[1]};
    bool ahead = small || (t > 0 && u > 0);
    // cell-interp's path took X: a line joins the arc's own offset point and X.
    // In inch rs274 prints its points to 1.27e-3 mm in each axis (four decimals of an inch; in mm 1e-4 mm,
    // within the tolerance at any turn compared): X moves by both offset points' error (e) over the sine of
    // the turn, and by each direction's error (2e over the length of the move it is taken from, or the arc's
    // radius) times X's distance from that move's end.
    double digits = 0;
    if (k.inch) {
      const double e = 1.27e-3 * std::sqrt(2.0);
      auto span = [](const Seg& m, bool at_end) {
        return m.arc ? Dist(at_end ? m.b : m.a, m.c) : Dist(m.a, m.b);
      };
      digits = 2 * e / std::fabs(den) + 2 * e * std::fabs(t) / span(ngc[i - 1], true) +
               2 * e * std::fabs(u) / span(after, false);
    }
    double near = small ? 0.05 : Tol(k) / std::fabs(den) + digits;
    bool reached = false;
    for (const Seg& c : cell)
      reached = reached || (!c.arc && (before.arc ? Dist(c.a, before.b) < OnTol(k) && Dist(c.b, x) < near
                                                  : Dist(c.b, after.a) < OnTol(k) && Dist(c.a, x) < near));
    if (!ahead || ((before.arc || after.arc) && !reached)) {
      out.push_back(s);
      continue;
    }
    *bent += small;
    if (before.arc)
      out.push_back({false, before.b, x, {}, false, s.z});
    else
      before.b = x;
    out.back().loose_end = out.back().loose_end || small;
    out.back().slack_end = std::max(out.back().slack_end, digits);
    if (after.arc) {
      out.push_back({false, x, after.a, {}, false, s.z});
    } else {  // the line after the corner, from X
      out.push_back(after);
      out.back().a = x;
      ++i;
    }
    out.back().loose_start = out.back().loose_start || small;
    out.back().slack_start = std::max(out.back().slack_start, digits);
  }
  return out;
}

// The contour's arc centres are on the 0.001 mm grid, so an arc's radii at its two ends differ by up to
// 1.5e-3 mm (`slack`, the most of the program) and each side may offset either: where an arc meets another
// element at an angle theta (an intersection: not a fill-in arc's tangent joint) the corner may move along
// the path by slack / sin(theta), and an arc's own end point (a tangent joint) by slack. That is added to the
// tolerance of that point.
void ArcJointSlack(std::vector<Seg>& s, const CompContour& k, double slack) {
  for (std::size_t i = 0; i + 1 < s.size(); ++i) {
    if (!(s[i].arc && !FillIn(s[i], k)) && !(s[i + 1].arc && !FillIn(s[i + 1], k))) continue;
    P2 d1 = Direction(s[i], true), d2 = Direction(s[i + 1], false);
    double sine = std::fabs(d1[0] * d2[1] - d1[1] * d2[0]);
    double extra = sine < 1e-3 ? slack : slack / std::max(sine, 0.05);  // tangent: a joint
    s[i].slack_end = std::max(s[i].slack_end, extra);
    s[i + 1].slack_start = std::max(s[i + 1].slack_start, extra);
  }
}

// Where the offset elements on both sides of a corner meet (lines and the arcs' circles): the point nearest
// to `near`; none where they do not meet.
std::optional<P2> Meet(const Seg& u, const Seg& v, const P2& near) {
  std::vector<P2> xs;
  auto on_line = [](const Seg& l, const Seg& c, std::vector<P2>* out) {  // a line and a circle
    P2 d = Direction(l, true);
    double fx = l.a[0] - c.c[0], fy = l.a[1] - c.c[1], rad = Dist(c.b, c.c);
    double b = fx * d[0] + fy * d[1], disc = b * b - (fx * fx + fy * fy - rad * rad);
    if (disc < 0) return;
    for (double sg : {-1.0, 1.0}) {
      double t = -b + sg * std::sqrt(disc);
      out->push_back({l.a[0] + t * d[0], l.a[1] + t * d[1]});
    }
  };
  if (!u.arc && !v.arc) {
    P2 d1 = Direction(u, true), d2 = Direction(v, false);
    double den = d1[0] * d2[1] - d1[1] * d2[0];
    if (std::fabs(den) < 1e-12) return std::nullopt;
    P2 w{v.a[0] - u.a[0], v.a[1] - u.a[1]};
    double t = (w[0] * d2[1] - w[1] * d2[0]) / den;
    xs.push_back({u.a[0] + t * d1[0], u.a[1] + t * d1[1]});
  } else if (!u.arc || !v.arc) {
    on_line(u.arc ? v : u, u.arc ? u : v, &xs);
  } else {
    double r1 = Dist(u.b, u.c), r2 = Dist(v.a, v.c), d = Dist(u.c, v.c);
    if (d < 1e-12 || d > r1 + r2 || d < std::fabs(r1 - r2)) return std::nullopt;
    double a = (r1 * r1 - r2 * r2 + d * d) / (2 * d), h = std::sqrt(std::max(0.0, r1 * r1 - a * a));
    P2 e{(v.c[0] - u.c[0]) / d, (v.c[1] - u.c[1]) / d}, m{u.c[0] + a * e[0], u.c[1] + a * e[1]};
    xs.push_back({m[0] - h * e[1], m[1] + h * e[0]});
    xs.push_back({m[0] + h * e[1], m[1] - h * e[0]});
  }
  if (xs.empty()) return std::nullopt;
  return *std::min_element(xs.begin(), xs.end(),
                           [&](const P2& p, const P2& q) { return Dist(p, near) < Dist(q, near); });
}

// Okuma (okuma.md judgement call 61, ln 2298-2324): the nose centre's every corner is the intersection of the
// two offset elements, lines and offset circles, outside corners too, where LinuxCNC goes round the corner on
// a fill-in arc: the move before ends at the intersection (an arc along its own circle), the one after starts
// there. At a small turn (the directions within 5.7 degrees) the intersection moves along the path by the
// inputs' last digits over the sine of the turn: the point is taken between the two offset points and not
// compared (`bent` counts it). Where the offsets do not meet the fill-in arc stays (Okuma refuses such a
// path, ln 2669, 2748).
std::vector<Seg> OkumaExpected(const std::vector<Seg>& ngc, const CompContour& k, int* bent) {
  std::vector<Seg> out;
  for (std::size_t i = 0; i < ngc.size(); ++i) {
    const Seg& s = ngc[i];
    if (!FillIn(s, k) || out.empty() || i + 1 >= ngc.size()) {
      out.push_back(s);
      continue;
    }
    Seg& before = out.back();
    Seg after = ngc[i + 1];
    P2 d1 = Direction(before, true), d2 = Direction(after, false);
    bool small = std::fabs(d1[0] * d2[1] - d1[1] * d2[0]) < 0.1 && d1[0] * d2[0] + d1[1] * d2[1] > 0;
    std::optional<P2> x =
        small ? P2{(before.b[0] + after.a[0]) / 2, (before.b[1] + after.a[1]) / 2} : Meet(before, after, s.c);
    if (!x) {
      out.push_back(s);
      continue;
    }
    *bent += small;
    before.b = *x;
    before.loose_end = before.loose_end || small;
    after.a = *x;
    after.loose_start = after.loose_start || small;
    out.push_back(after);
    ++i;
  }
  return out;
}

// Whether two offset elements of LinuxCNC's path do not meet at a corner it goes round (a fill-in arc): there
// Okuma's path is discontinuous (ln 2669, 2748), its alarm.
bool Unmet(const std::vector<Seg>& ngc, const CompContour& k) {
  for (std::size_t i = 1; i + 1 < ngc.size(); ++i)
    if (FillIn(ngc[i], k) && !Meet(ngc[i - 1], ngc[i + 1], ngc[i].c)) return true;
  return false;
}

std::string Show(const Seg& s) {
  char buf[200];
  if (s.arc)
    std::snprintf(buf, sizeof buf, "arc (%.4f, %.4f) to (%.4f, %.4f) centre (%.4f, %.4f) %s", s.a[0], s.a[1],
                  s.b[0], s.b[1], s.c[0], s.c[1], s.cw ? "cw" : "ccw");
  else
    std::snprintf(buf, sizeof buf, "line (%.4f, %.4f) to (%.4f, %.4f)", s.a[0], s.a[1], s.b[0], s.b[1]);
  return buf;
}

// The most an arc of the contour's radii at its two ends differ (its centre is on the 0.001 mm grid).
double Slack(const CompContour& k) {
  double most = 0;
  for (std::size_t i = 0; i < k.p.size(); ++i)
    if (k.sweep[i] != 0)
      most = std::max(most, std::fabs(Dist(k.p[i], k.centre[i]) - Dist(k.p[k.Next(i)], k.centre[i])));
  return most;
}

std::optional<std::string> Differs(const Seg& c, const Seg& n, double tol) {
  if (c.arc != n.arc) return "kind";
  double ts = tol + n.slack_start, te = tol + n.slack_end;
  if (!n.loose_start && std::fabs(c.a[0] - n.a[0]) > ts) return "start x";
  if (!n.loose_start && std::fabs(c.a[1] - n.a[1]) > ts) return "start y";
  if (!n.loose_end && std::fabs(c.b[0] - n.b[0]) > te) return "end x";
  if (!n.loose_end && std::fabs(c.b[1] - n.b[1]) > te) return "end y";
  if (std::fabs(c.z - n.z) > tol) return "end z";
  if (c.arc && Dist(c.c, n.c) > tol) return "centre";
  if (c.arc && c.cw != n.cw) return "direction";
  return std::nullopt;
}

// The moves after the first cut of element 0 and before the move on element n-1: the exit (G40 after the
// second cut of element 0) moves LinuxCNC's corner at the contour's start, so that corner is not compared.
bool Window(const std::vector<Seg>& s, const CompContour& k, std::size_t* from, std::size_t* to) {
  std::size_t n = k.Elements(), first = s.size(), last = s.size();
  for (std::size_t i = 0; i < s.size() && first == s.size(); ++i)
    if (OnElement(s[i], k, 0, 0.5)) first = i;  // its start is the entry's (LinuxCNC: up to 5e-3 mm off)
  // The entry may run on element 0's offset too (the contour's element 0 points at the start X100 Y0).
  while (first + 1 < s.size() && OnElement(s[first + 1], k, 0, 0.5)) ++first;
  for (std::size_t i = first + 1; i < s.size(); ++i)
    if (OnElement(s[i], k, n - 1)) last = i;
  if (first == s.size() || last == s.size()) return false;
  *from = first + 1;
  *to = last;
  return *from < *to;
}

// Lines shorter than 0.01 mm (a joint to an intersection a few micrometres from an arc's end): merged into
// the move after them, which starts where they started. Not on a lathe profile's element 0: LinuxCNC's entry
// may end micrometres before its corner (a 2 mm lead, a nose of 1.4 mm), and that line is the window's
// anchor.
void MergeShortLines(std::vector<Seg>& s, const CompContour& k) {
  std::vector<Seg> out;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (!s[i].arc && Dist(s[i].a, s[i].b) < 0.01 && i + 1 < s.size() && !(k.open && OnElement(s[i], k, 0))) {
      s[i + 1].a = s[i].a;
      continue;
    }
    out.push_back(s[i]);
  }
  s.swap(out);
}

// Where the offset of element i meets the contour point p (one of its ends): the point at the cutter radius
// on the tool's side.
P2 OffsetPoint(const CompContour& k, std::size_t i, const P2& p) {
  double side = k.left ? 1 : -1;
  if (k.sweep[i] == 0) {
    const P2 &a = k.p[i], &b = k.p[k.Next(i)];
    double l = Dist(a, b);
    return {p[0] - side * k.r * (b[1] - a[1]) / l, p[1] + side * k.r * (b[0] - a[0]) / l};
  }
  const P2& o = k.centre[i];
  double rad = Dist(p, o), want = rad - side * k.r * (k.sweep[i] > 0 ? 1 : -1);
  return {o[0] + (p[0] - o[0]) * want / rad, o[1] + (p[1] - o[1]) * want / rad};
}

// At a small turn LinuxCNC may bend the corner: the move before it ends at its own offset end point and the
// next starts there, up to a few micrometres off its offset element, so the corner point moves along the path
// by up to a tenth of a millimetre. At an outside turn the fill-in arc it left out is put back (the next move
// starting on its offset element), so both sides have the same corners; at an inside turn (where the offsets'
// intersection is the corner) that point is not compared (`bent` counts them) and a line after it starts at
// its element's offset point.
void RestoreFillIns(std::vector<Seg>& s, const CompContour& k, int* bent) {
  std::vector<Seg> out;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (!out.empty() && !FillIn(out.back(), k) && !FillIn(s[i], k))
      for (std::size_t e = 0; e < k.Elements(); ++e) {
        std::size_t en = k.Next(e);
        if (!OnElement(out.back(), k, e) || !OnElement(s[i], k, en, 0.05)) continue;
        P2 end = OffsetPoint(k, e, k.p[en]), start = OffsetPoint(k, en, k.p[en]);
        if (Dist(out.back().b, end) < Tol(k) && Dist(s[i].a, start) > Tol(k) && Dist(s[i].a, start) < 0.5) {
          P2 d1 = Direction(out.back(), true), d2 = Direction(s[i], false);
          bool left_turn = d1[0] * d2[1] - d1[1] * d2[0] > 0;
          if (left_turn != k.left) {
            out.push_back({true, out.back().b, start, k.p[en], k.left, s[i].z});
            s[i].a = start;
          } else {
            out.back().loose_end = s[i].loose_start = true;
            // A line from its own offset start point: its direction is its element's, not tilted by the
            // bend (a few micrometres over its length), for Expected's intersection at its end (0.0016 mm
            // off at a 20 degree turn after a 5 mm line, seed 1, Balt-System).
            if (!s[i].arc) s[i].a = start;
            ++*bent;
          }
        }
        break;
      }
    out.push_back(s[i]);
  }
  s.swap(out);
}

// A fill-in arc that stays within the tolerance of its chord: LinuxCNC leaves it out at a small turn (the
// next move starts where the arc would have), cell-interp may write it; not compared, the move after it
// starts where it started. Its chord is taken between the two elements' exact offset points at a corner
// within the window, so both sides decide alike: with each side's own printed points an arc at the threshold
// was dropped on one side only (a sagitta of 1.99e-3 and 2.02e-3 mm in inch, KT-APL seed 3). Not at p[0]:
// the entry's corner, where the move before is no element; nor where the arc's own chord is not that one
// (a wrong arc stays seen).
void DropTinyFillIns(std::vector<Seg>& s, const CompContour& k) {
  auto chord = [&](const Seg& a) {
    double own = Dist(a.a, a.b);
    for (std::size_t j = 1; j < k.Elements(); ++j)
      if (Dist(a.c, k.p[j]) < Tol(k)) {
        double exact = Dist(OffsetPoint(k, j - 1, k.p[j]), OffsetPoint(k, j, k.p[j]));
        return std::fabs(exact - own) < OnTol(k) ? exact : own;
      }
    return own;
  };
  std::vector<Seg> out;
  for (std::size_t i = 0; i < s.size(); ++i) {
    double half = FillIn(s[i], k) ? chord(s[i]) / 2 : 0;
    if (FillIn(s[i], k) && k.r - std::sqrt(k.r * k.r - half * half) < Tol(k) && i + 1 < s.size()) {
      s[i + 1].a = s[i].a;
      continue;
    }
    out.push_back(s[i]);
  }
  s.swap(out);
}

// LinuxCNC's twin: G41.1/G42.1 D the diameter (in the program's unit); the centre from the start (I J in
// G17, I K in G18); G20 for inch.
std::string Ngc(const CompContour& k) {
  const double unit = k.inch ? 25.4 : 1;
  const int d = k.inch ? 4 : 3;
  const auto ax = PlaneAxes(k.plane);
  auto words = [&](const P2& p, const char* letters) {
    std::string s;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 2; ++j)
        if (ax[static_cast<std::size_t>(j)] == i)
          s += (s.empty() ? "" : " ") + std::string(1, letters[i]) + Num(p[j] / unit, d);
    return s;
  };
  auto xy = [&](const P2& p) { return words(p, "XYZ"); };
  std::string t = std::string(k.inch ? "G20" : "G21") + " G90 G94 G40 G" + std::to_string(k.plane) + "\nG0 " +
                  xy({100, 0}) + " " + "XYZ"[ax[2]] + "0\nG1 " + (k.left ? "G41.1" : "G42.1") + " D" +
                  Num(2 * k.r / unit, 6) + " " + xy(k.p[0]) + " F200\n";
  std::size_t n = k.p.size();
  for (std::size_t j = 0; j <= n; ++j) {
    std::size_t i = j % n;
    const P2 &a = k.p[i], &e = k.p[k.Next(i)];
    if (k.sweep[i] == 0)
      t += "G1 " + xy(e) + "\n";
    else
      t += std::string(k.sweep[i] > 0 ? "G3 " : "G2 ") + xy(e) + " " +
           words({k.centre[i][0] - a[0], k.centre[i][1] - a[1]}, "IJK") + "\n";
  }
  return t + "G1 G40 " + xy({100, 0}) + "\nM2\n";
}

// The lathes' twin (EMCO, Okuma): G18 G7 (X a diameter, I a radius), tool 1 of the tool table under G42 (a
// bore: G41), the profile's elements once, G40 with a move up (a bore: down). rs274 states the tool's
// controlled point, which for a lathe tool with an orientation is the imaginary tip (found by experiment:
// with Q0 and Q9 it states the nose centre, with Q1-Q8 that centre moved by the radius in X, in Z or both).
// LinuxCNC numbers its orientations its own way (found by experiment, a 10 mm shoulder outside under G42 and
// inside under G41, nose R0.8, every Q; docs/testing.md): the dialects' tip code c is its Q kLinuxQ[c]. The
// tool table is read in inch by rs274 without an ini (D1.6 was 40.6 mm): D is the diameter in inch, to 1e-9
// in.
constexpr int kLinuxQ[10] = {0, 4, 3, 2, 1, 5, 8, 7, 6, 9};
std::string LatheNgc(const CompContour& k) {
  auto xz = [](const P2& q) { return "X" + Num(2 * q[1], 6) + " Z" + Num(q[0], 6); };
  const P2 &front = k.p.front(), &back = k.p.back();
  const double up = k.left ? -1 : 1;  // a bore's entry and exit are below the profile
  std::string t = "G21 G18 G7 G90 G94 G40\nT1 M6 G43\nG0 " + xz({front[0] + 5, front[1] + 5 * up}) + "\nG1 " +
                  (k.left ? "G41 " : "G42 ") + xz(front) + " F200\n";
  for (std::size_t i = 0; i < k.Elements(); ++i) {
    const P2 &a = k.p[i], &e = k.p[i + 1];
    if (k.sweep[i] == 0)
      t += "G1 " + xz(e) + "\n";
    else
      t += std::string(k.sweep[i] > 0 ? "G3 " : "G2 ") + xz(e) + " I" + Num(k.centre[i][1] - a[1], 6) + " K" +
           Num(k.centre[i][0] - a[0], 6) + "\n";
  }
  return t + "G40 G1 X" + Num(2 * (back[1] + 3 * up), 6) + "\nM2\n";
}
std::string LatheToolTable(const CompContour& k) {
  return "T1 P1 D" + Num(2 * k.r / 25.4, 9) + " Q" + std::to_string(kLinuxQ[k.tip]) + "\n";
}

// A lathe's refusal that its manual names for the path, where LinuxCNC goes on (a documented difference,
// counted, not failed): EMCO ALARM 570, a step shorter than the nose radius at an inside corner (ln
// 3005-3020); Okuma's discontinuous path where two offsets do not meet (ln 2669, 2748) and an arc smaller
// than the nose needs (ln 2716, 2748; okuma.md judgement call 68).
// `unmet`: LinuxCNC's path has a corner whose offsets do not meet (Unmet), the discontinuous path confirmed.
bool ManualAlarm(const std::string& dialect, const std::string& err, bool unmet) {
  if (dialect == "emco") return err.find("570") != std::string::npos;
  return (unmet && err.find("the offset path is discontinuous") != std::string::npos) ||
         err.find("is too large for the arc") != std::string::npos;
}

// An inch contour: its points and centres on the 0.0001 in grid (stated in mm), so both programs state them
// exactly.
void ToInchGrid(CompContour& k) {
  auto snap = [](P2& p) {
    for (double& v : p) v = std::round(v / 25.4 * 1e4) / 1e4 * 25.4;
  };
  for (P2& p : k.p) snap(p);
  for (P2& c : k.centre) snap(c);
  k.inch = true;
}

}  // namespace

CompTally CompCheck(const PropRun& o, const std::string& rs274, const std::string& dialect,
                    const fs::path& dir, int show) {
  CompTally t;
  const bool lathe = dialect == "emco" || dialect == "okuma";
  for (int i = 0; t.blocks < o.blocks; ++i) {
    std::uint64_t seed = ProgramSeed(o.seed, dialect + "/comp", i);
    CompContour k;
    ContourProgram w;
    if (lathe) {
      // The no-gouge property's turned profile (nogouge.cpp), in (Z, X as a radius): G18's axes.
      // Every other profile a bore under G41, every other such pair in inch: outside mm, bore mm, outside
      // inch, bore inch.
      LatheContour l = LatheCase(dialect, seed, i % 2 == 1, (i / 2) % 2 == 1);
      k = std::move(l.c);
      w = std::move(l.w);
      k.plane = 18;
    } else {
      k = RandomContour(seed, i % 2 == 1);
      // Every other pair of contours in G18 (LinuxCNC compensates in G17 and G18 only, so G19 is not
      // compared), every other such pair in inch: G17 mm, G18 mm, G17 inch, G18 inch.
      k.plane = (i / 2) % 2 ? 18 : 17;
      if ((i / 4) % 2) ToInchGrid(k);
      // KT-APL's every other set of those eight under G46 (fill-in blocks bypassed: the corners become
      // intersections, ktapl.md judgement call 39).
      k.bypass = dialect == "ktapl" && (i / 8) % 2;
      t.bypassed += k.bypass;
      w = WriteContour(dialect, k);
    }
    t.blocks += static_cast<int>(k.Elements()) + (lathe ? 0 : 1);
    if (std::getenv("COMP_ONLY") && std::to_string(seed) != std::getenv("COMP_ONLY")) continue;
    t.programs++;
    const std::string ngc_text = lathe ? LatheNgc(k) : Ngc(k);
    fs::path prog = dir / ("comp." + dialect), tools = dir / "comp.tools";
    Spit(prog, w.text);
    Spit(tools, w.tools);
    Spit(dir / "comp.ngc", ngc_text);
    fs::path params = dir / "comp.params";
    Spit(params, w.params);
    int rc = Shell(Quote(o.interp) + " --dialect " + dialect + " --tools " + Quote(tools) +
                   (w.params.empty() ? "" : " --params " + Quote(params)) + " " + Quote(prog) + " >" +
                   Quote(dir / "comp.out") + " 2>" + Quote(dir / "comp.err"));
    Spit(dir / "tool.tbl", lathe ? LatheToolTable(k) : "");
    Spit(dir / "rs274ngc.var", "");
    Shell("cd " + Quote(dir) + " && HOME=" + Quote(dir) + " " + Quote(rs274) +
          " -g -t tool.tbl -v rs274ngc.var comp.ngc comp.canon >comp.log 2>&1");
    std::string err, log = Slurp(dir / "comp.log");
    auto cm = ParseCellInterp(Slurp(dir / "comp.out"), lathe, &err);
    auto nm = ParseRs274(Slurp(dir / "comp.canon"), lathe, &err);
    if (lathe)  // both sides state the imaginary tip of the tip code: compared as nose centres
      for (auto* moves : {&cm, &nm})
        for (Move& m : *moves) m = NoseFromTip(m, k.r, k.tip);
    DropStill(cm);
    DropStill(nm);
    std::vector<Seg> cell = Segs(cm, k.plane), ngc = Segs(nm, k.plane);
    int bent = 0;
    RestoreFillIns(ngc, k, &bent);  // LinuxCNC's; a dialect's joint line to an intersection is no bent corner
    std::string kind, detail;
    std::size_t cf = 0, ct = 0, nf = 0, nt = 0;
    std::vector<Seg> want;  // LinuxCNC's path with what the comparer knows
    if (!err.empty()) {
      kind = "output", detail = err;
    } else if (log.find_first_not_of("executing\n") != std::string::npos) {
      kind = "rs274 refused", detail = log;
      t.rs274_refused++;
    } else if (rc != 0 && lathe && ManualAlarm(dialect, Slurp(dir / "comp.err"), Unmet(ngc, k))) {
      kind = "the manual's alarm", detail = Slurp(dir / "comp.err");
      t.cell_alarm++;
    } else if (rc != 0) {
      kind = "cell-interp refused", detail = Slurp(dir / "comp.err");
      t.cell_refused++;
    } else {
      want = dialect == "balt" || k.bypass ? Expected(ngc, cell, k, &bent)
             : dialect == "okuma"          ? OkumaExpected(ngc, k, &bent)
                                           : ngc;
      DropTinyFillIns(cell, k);
      DropTinyFillIns(want, k);
      MergeShortLines(cell, k);
      MergeShortLines(want, k);
      ArcJointSlack(want, k, Slack(k));
      if (!Window(cell, k, &cf, &ct) || !Window(want, k, &nf, &nt)) {
        kind = "element 0 or element n-1 not found";
      } else {
        // --plant: one compensated point of LinuxCNC's moved by 0.01 mm (the third move of the window).
        if (o.plant && nf + 2 < nt) want[nf + 2].b[0] += 0.01, want[nf + 3].a[0] += 0.01;
        std::size_t n = std::min(ct - cf, nt - nf);
        for (std::size_t m = 0; m < n && kind.empty(); ++m) {
          t.moves++;
          if (auto f = Differs(cell[cf + m], want[nf + m], Tol(k))) {
            kind = *f + " differs at move " + std::to_string(m + 1) + " of the contour";
            detail = "cell-interp: " + Show(cell[cf + m]) + "\n  rs274:       " + Show(want[nf + m]);
          }
        }
        if (kind.empty() && ct - cf != nt - nf)
          kind = "move count",
          detail = "cell-interp " + std::to_string(ct - cf) + " moves, rs274 " + std::to_string(nt - nf);
      }
    }
    t.bent += bent;
    if (kind.empty()) {
      t.agreeing++;
      continue;
    }
    if (kind != "rs274 refused" && kind != "cell-interp refused" && kind != "the manual's alarm")
      t.disagreeing++;
    if (t.shown++ < show) {
      if (std::getenv("COMP_DEBUG")) {
        for (const Seg& s : cell) std::cout << "C " << Show(s) << (OnElement(s, k, 0) ? " *" : "") << "\n";
        for (const Seg& s : ngc) std::cout << "N " << Show(s) << (OnElement(s, k, 0) ? " *" : "") << "\n";
        for (const Seg& s : want)  // as compared; * on element 0, + on the last element
          std::cout << "W " << Show(s) << (OnElement(s, k, 0) ? " *" : "")
                    << (OnElement(s, k, k.Elements() - 1) ? " +" : "") << "\n";
      }
      std::cout << dialect << " comp: program seed " << seed << " (" << (k.left ? "G41" : "G42") << ", r "
                << k.r << (lathe ? ", tip " + std::to_string(k.tip) : "") << ", " << k.p.size()
                << " corners, G" << k.plane << (k.inch ? " inch" : " mm") << "): " << kind << "\n  " << detail
                << "\n";
      if (!o.keep.empty()) {
        fs::create_directories(o.keep);
        std::string stem = dialect + "-comp-" + std::to_string(seed);
        Spit(fs::path(o.keep) / (stem + "." + dialect), w.text);
        Spit(fs::path(o.keep) / (stem + ".tools"), w.tools);
        if (!w.params.empty()) Spit(fs::path(o.keep) / (stem + ".params"), w.params);
        Spit(fs::path(o.keep) / (stem + ".ngc"), ngc_text);
        if (lathe) Spit(fs::path(o.keep) / (stem + ".tbl"), LatheToolTable(k));
        std::cout << "  kept as " << (fs::path(o.keep) / stem).string() << ".*\n";
      }
    }
  }
  return t;
}

}  // namespace cell::oracle
