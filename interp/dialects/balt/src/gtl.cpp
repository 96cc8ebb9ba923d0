// GTL geometry (see gtl.h). The forms of Table 5.7 (ln 4505-4513) and the selection rules of ln 4600-5047:
// a line tangent to a circle touches it where both run the same way; a circle tangent to two elements runs
// from the first to the second with the smaller central angle; s2 selects the second intersection.
#include "gtl.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace cell::interp::balt::gtl {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kTol = 1e-6;  // mm: below this two points, or a distance and a radius, are the same

Vec2 Unit(Vec2 v) {
  double n = Norm(v);
  return n < 1e-12 ? Vec2{1, 0} : Vec2{v.x / n, v.y / n};
}
Vec2 LeftNormal(Vec2 d) {
  return {-d.y, d.x};
}
Vec2 FromAngle(double deg) {
  return {std::cos(deg * kPi / 180), std::sin(deg * kPi / 180)};
}

[[noreturn]] void Undefined(const std::string& why) {
  throw GeomError{77, why};
}

Element MakeLine(Vec2 p, Vec2 d) {
  Element e;
  e.kind = Element::kLine;
  e.p = p;
  e.d = Unit(d);
  return e;
}
Element MakeCircle(Vec2 c, double r) {
  if (std::fabs(r) < kTol) Undefined("circle of zero radius");
  Element e;
  e.kind = Element::kCircle;
  e.p = c;
  e.r = r;
  return e;
}

// Signed distance of q from a line, positive on its left.
double LeftDistance(const Element& l, Vec2 q) {
  return Dot(q - l.p, LeftNormal(l.d));
}

// The line offset by `dist` to its left.
Element OffsetLine(const Element& l, double dist) {
  return MakeLine(l.p + dist * LeftNormal(l.d), l.d);
}

int LineLine(const Element& a, const Element& b, Vec2* out) {
  double den = Cross(a.d, b.d);
  if (std::fabs(den) < 1e-12) return 0;
  double t = Cross(b.p - a.p, b.d) / den;
  out[0] = a.p + t * a.d;
  return 1;
}

// Points of a line on a circle (centre c, radius r >= 0), in the order of the line's direction.
int LineCircle(const Element& l, Vec2 c, double r, Vec2 out[2]) {
  double t0 = Dot(c - l.p, l.d);
  Vec2 foot = l.p + t0 * l.d;
  double h = Norm(c - foot);
  if (h > r + kTol) return 0;
  if (std::fabs(h - r) <= kTol) {
    out[0] = foot;
    return 1;
  }
  double s = std::sqrt(std::max(0.0, r * r - h * h));
  out[0] = foot + (-s) * l.d;
  out[1] = foot + s * l.d;
  return 2;
}

// Points of two circles: left, then right of the line from c1 to c2.
int CircleCircle(Vec2 c1, double r1, Vec2 c2, double r2, Vec2 out[2]) {
  Vec2 dc = c2 - c1;
  double d = Norm(dc);
  if (d < 1e-12) return 0;
  if (d > r1 + r2 + kTol || d < std::fabs(r1 - r2) - kTol) return 0;
  double a = (r1 * r1 - r2 * r2 + d * d) / (2 * d);
  double h2 = r1 * r1 - a * a;
  Vec2 u{dc.x / d, dc.y / d};
  Vec2 base = c1 + a * u;
  if (h2 <= kTol * kTol * 4 || std::fabs(d - (r1 + r2)) <= kTol ||
      std::fabs(d - std::fabs(r1 - r2)) <= kTol) {
    out[0] = base;
    return 1;
  }
  double h = std::sqrt(h2);
  out[0] = base + h * LeftNormal(u);
  out[1] = base + (-h) * LeftNormal(u);
  return 2;
}

// Degrees a circle of signed radius r about c turns from a to b (in its own direction), in [0, 360).
double SweepOn(Vec2 c, double r, Vec2 a, Vec2 b) {
  double a0 = std::atan2(a.y - c.y, a.x - c.x), a1 = std::atan2(b.y - c.y, b.x - c.x);
  double ccw = (a1 - a0) * 180 / kPi;
  while (ccw < 0) ccw += 360;
  while (ccw >= 360) ccw -= 360;
  double s = r > 0 ? ccw : 360 - ccw;
  if (s >= 360 - 1e-9) s = 0;
  return s;
}

// Where a circle (centre c, signed radius r) touches an element it is tangent to.
Vec2 Touch(Vec2 c, double r, const Operand& o) {
  switch (o.kind) {
    case Operand::kPoint:
      return o.e.p;
    case Operand::kLine: {
      double dist = LeftDistance(o.e, c);
      return c - dist * LeftNormal(o.e.d);
    }
    default: {
      // Circles tangent with the same direction at the contact point: |c - c'| = |R - r| (signed radii);
      // the contact lies on the line of the centres.
      double R = o.e.r;
      double k = std::fabs(R - r) < 1e-12 ? 0 : R / (R - r);
      return o.e.p + k * (c - o.e.p);
    }
  }
}

// Of the candidate centres for a circle of radius r tangent to (or through) a then b, the one whose arc
// from a to b is the shorter (ln 4826-4858).
Element PickMinor(const Vec2* cand, int n, double r, const Operand& a, const Operand& b) {
  if (n == 0) Undefined("no circle of this radius is tangent to both elements");
  int best = 0;
  double best_sweep = 1e9;
  for (int i = 0; i < n; ++i) {
    double s = SweepOn(cand[i], r, Touch(cand[i], r, a), Touch(cand[i], r, b));
    if (s < best_sweep - 1e-9) {
      best_sweep = s;
      best = i;
    }
  }
  return MakeCircle(cand[best], r);
}

// Centres at distance |r| from the operand (offset line, circle of radius |R - r|, circle about a point).
struct Locus {
  bool line = false;
  Element l;  // line
  Vec2 c;     // circle centre
  double rad = 0;
};
Locus LocusOf(const Operand& o, double r) {
  Locus s;
  switch (o.kind) {
    case Operand::kLine:
      s.line = true;
      s.l = OffsetLine(o.e, r);  // a circle runs with the line when its centre is on the line's left by r
      return s;
    case Operand::kCircle:
      s.c = o.e.p;
      s.rad = std::fabs(o.e.r - r);
      return s;
    default:
      s.c = o.e.p;
      s.rad = std::fabs(r);
      return s;
  }
}
int IntersectLoci(const Locus& a, const Locus& b, Vec2 out[2]) {
  if (a.line && b.line) return LineLine(a.l, b.l, out);
  if (a.line) return LineCircle(a.l, b.c, b.rad, out);
  if (b.line) return LineCircle(b.l, a.c, a.rad, out);
  return CircleCircle(a.c, a.rad, b.c, b.rad, out);
}

// A line through a point tangent to a circle (ln 4700-4706): `circle_first` gives the direction.
Element LineCirclePoint(const Element& c, Vec2 p, bool circle_first) {
  Vec2 D = c.p - p;
  double dist = Norm(D);
  if (dist < std::fabs(c.r) - kTol) Undefined("the point is inside the circle");
  double phi = std::atan2(D.y, D.x);
  double alpha = std::acos(std::clamp(c.r / dist, -1.0, 1.0));
  for (double sgn : {1.0, -1.0}) {
    double an = phi + sgn * alpha;
    Vec2 n{std::cos(an), std::sin(an)};
    Vec2 d{n.y, -n.x};
    Vec2 t = c.p + (-c.r) * n;
    double along = circle_first ? Dot(d, p - t) : Dot(d, t - p);
    if (along > kTol || (Norm(p - t) <= kTol && sgn > 0)) return MakeLine(t, d);
  }
  Undefined("no tangent line runs from the circle through the point in its direction");
}

bool Is(const std::vector<Operand>& ops, std::initializer_list<Operand::Kind> kinds) {
  if (ops.size() != kinds.size()) return false;
  std::size_t i = 0;
  for (auto k : kinds) {
    if (ops[i++].kind != k) return false;
  }
  return true;
}

}  // namespace

Vec2 TouchPoint(const Element& circle, const Element& e) {
  Operand o;
  o.kind = e.kind == Element::kLine ? Operand::kLine : Operand::kCircle;
  o.e = e;
  return Touch(circle.p, circle.r, o);
}

Element Element::Reversed() const {
  Element e = *this;
  if (kind == kLine) e.d = Vec2{-d.x, -d.y};
  if (kind == kCircle) e.r = -r;
  return e;
}

double Element::AngleDeg() const {
  return std::atan2(d.y, d.x) * 180 / kPi;
}

Vec2 Tangent(const Element& e, Vec2 at) {
  if (e.kind == Element::kLine) return e.d;
  Vec2 v = Unit(at - e.p);
  return e.r > 0 ? Vec2{-v.y, v.x} : Vec2{v.y, -v.x};
}

int Intersect(const Element& a, const Element& b, Vec2 out[2]) {
  if (a.kind == Element::kLine && b.kind == Element::kLine) return LineLine(a, b, out);
  if (a.kind == Element::kLine) return LineCircle(a, b.p, std::fabs(b.r), out);
  if (b.kind == Element::kLine) return LineCircle(b, a.p, std::fabs(a.r), out);
  return CircleCircle(a.p, std::fabs(a.r), b.p, std::fabs(b.r), out);
}

Element Define(char kind, const std::vector<Operand>& ops) {
  using K = Operand;
  bool s2 = !ops.empty() && ops.back().kind == K::kS2;
  std::vector<Operand> o(ops.begin(), ops.end() - (s2 ? 1 : 0));
  auto bad = [&]() -> Element {
    throw GeomError{11,
                    fmt::format("no GTL form for this {} definition (Table 5.7)", kind == 'p'   ? "point"
                                                                                  : kind == 'l' ? "line"
                                                                                  : kind == 'c' ? "circle"
                                                                                                : "origin")};
  };
  if (s2 && !(kind == 'p' || kind == 'c')) return bad();
  switch (kind) {
    case 'o': {
      if (o.empty() || o[0].kind != K::kPoint || !o[0].literal || o.size() > 2) return bad();
      Element e;
      e.kind = Element::kOrigin;
      e.p = o[0].e.p;
      if (o.size() == 2) {
        if (o[1].kind != K::kAngle) return bad();
        e.a = o[1].v;
      }
      return e;
    }
    case 'p': {
      if (Is(o, {K::kPoint}) && !s2) return o[0].e;
      if (o.size() != 2) return bad();
      const bool lines = o[0].kind == K::kLine && o[1].kind == K::kLine;
      const bool mixed = (o[0].kind == K::kLine && o[1].kind == K::kCircle) ||
                         (o[0].kind == K::kCircle && o[1].kind == K::kLine);
      const bool circles = o[0].kind == K::kCircle && o[1].kind == K::kCircle;
      if (!(lines || mixed || circles) || (lines && s2)) return bad();
      Vec2 pts[2];
      int n = Intersect(o[0].e, o[1].e, pts);
      if (n == 0) Undefined("the elements do not intersect");
      Element e;
      e.kind = Element::kPoint;
      e.p = (s2 && n == 2) ? pts[1] : pts[0];
      return e;
    }
    case 'l': {
      if (o.size() != 2) return bad();
      if (o[0].kind == K::kPoint && o[1].kind == K::kPoint) {
        if (Norm(o[1].e.p - o[0].e.p) < kTol) Undefined("a line through two equal points");
        return MakeLine(o[0].e.p, o[1].e.p - o[0].e.p);
      }
      if (o[0].kind == K::kPoint && o[1].kind == K::kAngle) return MakeLine(o[0].e.p, FromAngle(o[1].v));
      if (o[0].kind == K::kCircle && o[1].kind == K::kAngle) {
        // Tangent where the circle runs in the line's direction: the centre is on the line's left by r.
        Vec2 d = FromAngle(o[1].v);
        return MakeLine(o[0].e.p + (-o[0].e.r) * LeftNormal(d), d);
      }
      if (o[0].kind == K::kCircle && o[1].kind == K::kCircle) {
        const Element& c1 = o[0].e;
        const Element& c2 = o[1].e;
        Vec2 D = c2.p - c1.p;
        double dist = Norm(D);
        if (dist < kTol || std::fabs(c2.r - c1.r) > dist + kTol)
          Undefined("no common tangent of the circles");
        double alpha = std::acos(std::clamp((c2.r - c1.r) / dist, -1.0, 1.0));
        double an = std::atan2(D.y, D.x) + alpha;
        Vec2 n{std::cos(an), std::sin(an)};
        return MakeLine(c1.p + (-c1.r) * n, Vec2{n.y, -n.x});
      }
      if (o[0].kind == K::kCircle && o[1].kind == K::kPoint) return LineCirclePoint(o[0].e, o[1].e.p, true);
      if (o[0].kind == K::kPoint && o[1].kind == K::kCircle) return LineCirclePoint(o[1].e, o[0].e.p, false);
      if (o[0].kind == K::kLine && o[1].kind == K::kDistance) return OffsetLine(o[0].e, o[1].v);
      return bad();
    }
    case 'c': {
      if (o.size() == 1 && o[0].kind == K::kCircle && o[0].literal && !s2) return o[0].e;
      if (o.size() == 3 && o[2].kind == K::kRadius && !s2) {
        double r = o[2].v;
        if (std::fabs(r) < kTol) Undefined("circle of zero radius");
        if (o[0].kind == K::kAngle || o[1].kind == K::kAngle || o[0].kind == K::kDistance ||
            o[1].kind == K::kDistance || o[0].kind == K::kRadius || o[1].kind == K::kRadius) {
          return bad();
        }
        if (o[0].kind == K::kPoint && o[1].kind == K::kPoint) {
          // Through two points: the shorter arc from the first to the second (Fig 5.78).
          Vec2 cand[2];
          int n = CircleCircle(o[0].e.p, std::fabs(r), o[1].e.p, std::fabs(r), cand);
          return PickMinor(cand, n, r, o[0], o[1]);
        }
        Vec2 cand[2];
        int n = IntersectLoci(LocusOf(o[0], r), LocusOf(o[1], r), cand);
        if (o[0].kind == K::kLine && o[1].kind == K::kLine) {
          if (n == 0) Undefined("parallel lines");
          return MakeCircle(cand[0], r);
        }
        return PickMinor(cand, n, r, o[0], o[1]);
      }
      if (o.size() == 2 && o[0].kind == K::kPoint && o[1].kind == K::kLine && !s2) {
        double r = LeftDistance(o[1].e, o[0].e.p);
        return MakeCircle(o[0].e.p, r);
      }
      if (o.size() == 2 && o[0].kind == K::kPoint && o[1].kind == K::kCircle) {
        // Centre at the point, tangent to the circle: r = R -/+ distance; s2 the larger (Fig 5.80).
        double d = Norm(o[0].e.p - o[1].e.p);
        double R = o[1].e.r;
        double a = R - d, b = R + d;
        bool a_small = std::fabs(a) <= std::fabs(b);
        double r = (a_small != s2) ? a : b;
        return MakeCircle(o[0].e.p, r);
      }
      if (Is(o, {K::kPoint, K::kPoint, K::kPoint}) && !s2) {
        Vec2 a = o[0].e.p, b = o[1].e.p, c = o[2].e.p;
        double den = 2 * Cross(b - a, c - a);
        if (std::fabs(den) < 1e-9) Undefined("three points on a line");
        double a2 = Dot(a, a), b2 = Dot(b, b), c2 = Dot(c, c);
        Vec2 centre{(a2 * (b.y - c.y) + b2 * (c.y - a.y) + c2 * (a.y - b.y)) / den,
                    (a2 * (c.x - b.x) + b2 * (a.x - c.x) + c2 * (b.x - a.x)) / den};
        double r = Norm(a - centre);
        return MakeCircle(centre, Cross(b - a, c - b) > 0 ? r : -r);
      }
      if (Is(o, {K::kPoint, K::kRadius}) && !s2) return MakeCircle(o[0].e.p, o[1].v);
      if (Is(o, {K::kCircle, K::kDistance}) && !s2) {
        double r = o[0].e.r - o[1].v;  // positive distance: on the circle's left (inside a CCW circle)
        if (r * o[0].e.r <= 0) Undefined("the concentric circle would have no radius");
        return MakeCircle(o[0].e.p, r);
      }
      return bad();
    }
    default:
      return bad();
  }
}

std::array<Element, Geometry::kMaxIndex + 1>* Geometry::Table(char kind) {
  switch (kind) {
    case 'o':
      return &o_;
    case 'p':
      return &p_;
    case 'l':
      return &l_;
    case 'c':
      return &c_;
    default:
      return nullptr;
  }
}

const std::array<Element, Geometry::kMaxIndex + 1>* Geometry::Table(char kind) const {
  return const_cast<Geometry*>(this)->Table(kind);
}

const Element* Geometry::Get(char kind, int index) const {
  const auto* t = Table(kind);
  if (!t || index < 0 || index > kMaxIndex) return nullptr;
  const Element& e = (*t)[static_cast<std::size_t>(index)];
  return e.kind == Element::kNone ? nullptr : &e;
}

void Geometry::Set(char kind, int index, const Element& e) {
  auto* t = Table(kind);
  if (t && index >= 0 && index <= kMaxIndex) (*t)[static_cast<std::size_t>(index)] = e;
}

void Geometry::Clear() {
  o_ = {};
  p_ = {};
  l_ = {};
  c_ = {};
}

}  // namespace cell::interp::balt::gtl
