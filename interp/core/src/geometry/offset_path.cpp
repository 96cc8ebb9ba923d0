// Offset-path geometry (see offset_path.h).
#include "cell/interp/geometry/offset_path.h"

#include <algorithm>

namespace cell::interp::geom {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = 180.0 / kPi;

Vec2 Unit(Vec2 v) {
  double n = Norm(v);
  if (n < 1e-12) return {1, 0};
  return {v.x / n, v.y / n};
}

// Angle of v in radians, and the difference of two angles wrapped to (-pi, pi].
double Angle(Vec2 v) {
  return std::atan2(v.y, v.x);
}
double Wrap(double a) {
  while (a <= -kPi) a += 2 * kPi;
  while (a > kPi) a -= 2 * kPi;
  return a;
}

double ArcSign(const Path& p) {
  return p.cw ? -1.0 : 1.0;
}

Vec2 ArcTangent(const Path& p, Vec2 at) {
  Vec2 v = Unit(at - p.center);
  return p.cw ? Vec2{v.y, -v.x} : Vec2{-v.y, v.x};
}

// Intersections of the offset paths of `a` (near its end) and `b` (near its start).
int IntersectOffsets(const Path& a, const Path& b, double r, int side, Vec2 out[2]) {
  Vec2 ap = OffsetEnd(a, r, side), bp = OffsetStart(b, r, side);
  double ar = a.arc ? OffsetRadiusAtEnd(a, r, side) : 0;
  double br = b.arc ? OffsetRadiusAtStart(b, r, side) : 0;
  if ((a.arc && ar <= 0) || (b.arc && br <= 0)) return 0;
  if (!a.arc && !b.arc) return IntersectLineLine(ap, EndTangent(a), bp, StartTangent(b), out);
  if (!a.arc) return IntersectLineCircle(ap, EndTangent(a), b.center, br, out);
  if (!b.arc) return IntersectLineCircle(bp, StartTangent(b), a.center, ar, out);
  return IntersectCircleCircle(a.center, ar, b.center, br, out);
}

// How far `a` is cut back at its end, and `b` at its start, when they meet at x (mm / degrees).
double TrimEnd(const Path& a, double r, int side, Vec2 x) {
  Vec2 e = OffsetEnd(a, r, side);
  if (!a.arc) return Dot(e - x, EndTangent(a));
  return ArcSign(a) * Wrap(Angle(e - a.center) - Angle(x - a.center)) * kDeg;
}
double TrimStart(const Path& b, double r, int side, Vec2 x) {
  Vec2 s = OffsetStart(b, r, side);
  if (!b.arc) return Dot(x - s, StartTangent(b));
  return ArcSign(b) * Wrap(Angle(x - b.center) - Angle(s - b.center)) * kDeg;
}

}  // namespace

Vec2 StartTangent(const Path& p) {
  return p.arc ? ArcTangent(p, p.start) : Unit(p.end - p.start);
}

Vec2 EndTangent(const Path& p) {
  return p.arc ? ArcTangent(p, p.end) : Unit(p.end - p.start);
}

bool InsideArc(const Path& p, int side) {
  return p.cw ? side == kRight : side == kLeft;
}

double OffsetRadiusAtStart(const Path& p, double r, int side) {
  return Norm(p.start - p.center) + (InsideArc(p, side) ? -r : r);
}

double OffsetRadiusAtEnd(const Path& p, double r, int side) {
  return Norm(p.end - p.center) + (InsideArc(p, side) ? -r : r);
}

Vec2 OffsetStart(const Path& p, double r, int side) {
  return p.start + r * SideNormal(StartTangent(p), side);
}

Vec2 OffsetEnd(const Path& p, double r, int side) {
  return p.end + r * SideNormal(EndTangent(p), side);
}

double Extent(const Path& p) {
  return p.arc ? p.sweep : Norm(p.end - p.start);
}

double RemainingLength(const Path& p, double r, int side, double trim_start, double trim_end) {
  double left = Extent(p) - trim_start - trim_end;
  if (!p.arc) return left;
  double radius = (OffsetRadiusAtStart(p, r, side) + OffsetRadiusAtEnd(p, r, side)) / 2;
  return left / kDeg * std::fabs(radius);
}

int IntersectLineLine(Vec2 p, Vec2 d, Vec2 q, Vec2 e, Vec2* out) {
  double den = Cross(d, e);
  if (std::fabs(den) < 1e-12) return 0;
  double t = Cross(q - p, e) / den;
  out[0] = p + t * d;
  return 1;
}

int IntersectLineCircle(Vec2 p, Vec2 d, Vec2 c, double r, Vec2 out[2]) {
  Vec2 w = p - c;
  double b = Dot(w, d);
  double disc = b * b - (Dot(w, w) - r * r);
  if (disc < -1e-9 * (1 + r * r)) return 0;
  double s = std::sqrt(std::max(0.0, disc));
  out[0] = p + (-b - s) * d;
  if (s < 1e-12) return 1;
  out[1] = p + (-b + s) * d;
  return 2;
}

int IntersectCircleCircle(Vec2 c1, double r1, Vec2 c2, double r2, Vec2 out[2]) {
  Vec2 dc = c2 - c1;
  double d = Norm(dc);
  if (d < 1e-12) return 0;
  double tol = 1e-9 * (1 + r1 + r2);
  if (d > r1 + r2 + tol || d < std::fabs(r1 - r2) - tol) return 0;
  double a = (r1 * r1 - r2 * r2 + d * d) / (2 * d);
  double h = std::sqrt(std::max(0.0, r1 * r1 - a * a));
  Vec2 u{dc.x / d, dc.y / d};
  Vec2 base = c1 + a * u;
  Vec2 perp{-u.y, u.x};
  out[0] = base + h * perp;
  if (h < 1e-12) return 1;
  out[1] = base + (-h) * perp;
  return 2;
}

Corner ComputeCorner(const Path& a, const Path& b, double r, int side, bool bypass_fill_in) {
  Corner k;
  k.a_end = OffsetEnd(a, r, side);
  k.b_start = OffsetStart(b, r, side);
  if (Norm(k.a_end - k.b_start) < kTiny) return k;  // tangent paths (or no offset): they meet
  Vec2 ta = EndTangent(a), tb = StartTangent(b);
  double turn = Cross(ta, tb);
  bool reversal = std::fabs(turn) < 1e-9 && Dot(ta, tb) < 0;
  bool toward = !reversal && side * turn > 0;
  Vec2 corner = a.end;
  if (toward || bypass_fill_in) {
    Vec2 pts[2];
    int n = IntersectOffsets(a, b, r, side, pts);
    if (n > 0) {
      Vec2 x = pts[0];
      if (n == 2 && Norm(pts[1] - corner) < Norm(pts[0] - corner)) x = pts[1];
      double at = TrimEnd(a, r, side, x), bt = TrimStart(b, r, side, x);
      if (toward || (at <= kTiny && bt <= kTiny)) {
        k.kind = toward ? Corner::kToward : Corner::kAway;
        k.a_end = k.b_start = x;
        k.a_trim = at;
        k.b_trim = bt;
        return k;
      }
    } else if (toward) {
      k.kind = Corner::kToward;
      k.intersects = false;
      return k;
    }
  }
  k.kind = Corner::kAway;
  k.fill_in = true;
  k.fill_cw = side == kLeft;  // the cutter goes round the corner on the outside of the turn
  double from = Angle(k.a_end - corner), to = Angle(k.b_start - corner);
  double sweep = (k.fill_cw ? from - to : to - from) * kDeg;
  while (sweep <= 0) sweep += 360.0;
  while (sweep > 360.0) sweep -= 360.0;
  k.fill_sweep = sweep;
  return k;
}

Corner TangentCorner(const Path& a, const Path& b, double r, int side, std::optional<Vec2>* via) {
  Path ta, tb;  // the tangent lines, ending / starting at the corner (their length does not matter)
  ta.end = a.end;
  ta.start = a.end - EndTangent(a);
  tb.start = b.start;
  tb.end = b.start + StartTangent(b);
  Corner k = ComputeCorner(ta, tb, r, side, true);
  if (k.fill_in) return k;  // the same fill-in arc as ComputeCorner(a, b) without the intersection
  *via = k.a_end;
  if (a.arc) {
    k.a_end = OffsetEnd(a, r, side);
    k.a_trim = 0;
  }
  if (b.arc) {
    k.b_start = OffsetStart(b, r, side);
    k.b_trim = 0;
  }
  return k;
}

int CenterSlot(int axis) {
  if (axis == kX || axis == kU) return 0;
  if (axis == kY || axis == kV) return 1;
  return 2;
}

Canon FillInMove(const Corner& k, Target to, Vec2 corner, int p1, int p2, const Feed* feed, int line) {
  to.pos[p1] = k.b_start.x;
  to.pos[p2] = k.b_start.y;
  Canon f;
  f.line = line;
  if (!feed) {
    f.Set<RapidOp>().to = to;
    return f;
  }
  ArcOp& arc = f.Set<ArcOp>();
  arc.to = to;
  arc.feed = *feed;
  arc.cw = k.fill_cw;
  arc.angle = k.fill_sweep;
  arc.plane = {static_cast<std::int8_t>(p1), static_cast<std::int8_t>(p2)};
  arc.center = {to.pos[kX], to.pos[kY], to.pos[kZ]};
  arc.center[CenterSlot(p1)] = corner.x;
  arc.center[CenterSlot(p2)] = corner.y;
  return f;
}

Canon StraightMove(Target to, Vec2 at, int p1, int p2, const Feed* feed, int line) {
  to.pos[p1] = at.x;
  to.pos[p2] = at.y;
  Canon c;
  c.line = line;
  if (feed) {
    LinearOp& l = c.Set<LinearOp>();
    l.to = to;
    l.feed = *feed;
  } else {
    c.Set<RapidOp>().to = to;
  }
  return c;
}

}  // namespace cell::interp::geom
