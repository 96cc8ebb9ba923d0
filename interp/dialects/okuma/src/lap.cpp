// LAP tool paths (manual SECTION 8, seed ln 4939-6434), computed in a normalised frame: u along the cutting
// direction's axis (Z for longitudinal G81, X for transverse G82), v along the infeed axis, both flipped so
// that the AP start point lies at +u, +v of the contour (infeed toward -v, cutting toward -u). Each rough
// level cuts every interval where the final rough contour lies below it (pockets included), follows the
// contour up to the previous level, is relieved and returns; the last pass follows the whole final rough
// contour.
#include "lap.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "expr.h"

namespace cell::interp::okuma {
namespace {

using geom::Path;
using geom::Vec2;

constexpr double kEps = 1e-7;
constexpr double kPi = 3.14159265358979323846;
constexpr int kMaxSlopes = 10;  // ln 6239-6243

// The frame: machine plane (x = Z, y = X radius) <-> normalised (u, v).
struct Frame {
  bool transverse = false;
  double su = 1, sv = 1;
  Vec2 To(Vec2 p) const { return transverse ? Vec2{su * p.y, sv * p.x} : Vec2{su * p.x, sv * p.y}; }
  Vec2 From(Vec2 n) const { return transverse ? Vec2{sv * n.y, su * n.x} : Vec2{su * n.x, sv * n.y}; }
  bool FlipsTurn() const {
    const double det = transverse ? -su * sv : su * sv;
    return det < 0;
  }
};

struct Elem {
  Path p;
  double f = 0;  // roughing feed along it (E, else the call's F)
};

double Angle(Vec2 v) {
  return std::atan2(v.y, v.x);
}

// A point of an element at fraction t in [0, 1].
Vec2 At(const Path& p, double t) {
  if (!p.arc) return p.start + t * (p.end - p.start);
  const double r = geom::Norm(p.start - p.center);
  const double a0 = Angle(p.start - p.center);
  const double a = a0 + (p.cw ? -1 : 1) * t * p.sweep * kPi / 180.0;
  return p.center + r * Vec2{std::cos(a), std::sin(a)};
}

// The part of an element between fractions t0 < t1.
Path Sub(const Path& p, double t0, double t1) {
  Path s = p;
  s.start = At(p, t0);
  s.end = At(p, t1);
  if (p.arc) s.sweep = p.sweep * (t1 - t0);
  return s;
}

Vec2 TangentAt(const Path& p, double t) {
  if (!p.arc) {
    Vec2 d = p.end - p.start;
    const double n = geom::Norm(d);
    return n > 0 ? (1.0 / n) * d : Vec2{};
  }
  const Vec2 r = At(p, t) - p.center;
  return p.cw ? Vec2{r.y, -r.x} : Vec2{-r.y, r.x};
}

// Fractions where an element crosses the height v, in the element's order.
std::vector<double> Crossings(const Path& p, double v) {
  std::vector<double> out;
  if (!p.arc) {
    const double dy = p.end.y - p.start.y;
    if (std::fabs(dy) < kEps) return out;
    const double t = (v - p.start.y) / dy;
    if (t >= -kEps && t <= 1 + kEps) out.push_back(std::clamp(t, 0.0, 1.0));
    return out;
  }
  const double r = geom::Norm(p.start - p.center);
  const double s = (v - p.center.y) / r;
  if (s < -1 - 1e-12 || s > 1 + 1e-12) return out;
  const double base = std::asin(std::clamp(s, -1.0, 1.0));
  const double a0 = Angle(p.start - p.center);
  const double sweep = p.sweep * kPi / 180.0;
  for (double a : {base, kPi - base}) {
    double d = p.cw ? a0 - a : a - a0;
    d = std::fmod(d, 2 * kPi);
    if (d < 0) d += 2 * kPi;
    if (d > sweep + 1e-9 && d > 2 * kPi - 1e-9) d = 0;  // at the start point
    if (d <= sweep + 1e-9) out.push_back(std::clamp(d / sweep, 0.0, 1.0));
  }
  std::sort(out.begin(), out.end());
  if (out.size() == 2 && out[1] - out[0] < 1e-9) out.pop_back();
  return out;
}

double MaxV(const Path& p) {
  double m = std::max(p.start.y, p.end.y);
  if (p.arc) {
    const double r = geom::Norm(p.start - p.center);
    if (!Crossings(p, p.center.y + r - 1e-9).empty()) m = std::max(m, p.center.y + r);
  }
  return m;
}
double MinV(const Path& p) {
  double m = std::min(p.start.y, p.end.y);
  if (p.arc) {
    const double r = geom::Norm(p.start - p.center);
    if (!Crossings(p, p.center.y - r + 1e-9).empty()) m = std::min(m, p.center.y - r);
  }
  return m;
}

// A crossing of the contour with a level: element, fraction, point, and whether the contour rises there.
struct Cross {
  size_t e = 0;
  double t = 0;
  Vec2 at;
  bool rising = false;
};

std::vector<Cross> LevelCrossings(const std::vector<Elem>& c, double v) {
  std::vector<Cross> out;
  for (size_t i = 0; i < c.size(); ++i) {
    for (double t : Crossings(c[i].p, v)) {
      const Vec2 tan = TangentAt(c[i].p, t);
      if (std::fabs(tan.y) < 1e-12) continue;  // touching, not crossing
      Cross x{i, t, At(c[i].p, t), tan.y > 0};
      if (!out.empty() && geom::Norm(out.back().at - x.at) < 1e-9 && out.back().rising == x.rising) continue;
      out.push_back(x);
    }
  }
  return out;
}

class Builder {
 public:
  Builder(const Frame& fr, Vec2 at) : fr_(fr), at_(at) {}
  void Rapid(Vec2 to) { Add(LapMove::kRapid, to, 0); }
  void Feed(Vec2 to, double f) { Add(LapMove::kLinear, to, f); }
  void Position(Vec2 to, bool rapid, double f) { rapid ? Rapid(to) : Feed(to, f); }
  void Follow(const Path& p, double f) {
    if (!p.arc) {
      Feed(p.end, f);
      return;
    }
    if (p.sweep < 1e-9) return;
    LapMove m;
    m.kind = LapMove::kArc;
    m.to = fr_.From(p.end);
    m.f = f;
    m.center = fr_.From(p.center);
    m.cw = fr_.FlipsTurn() ? !p.cw : p.cw;
    m.sweep = p.sweep;
    moves_.push_back(m);
    at_ = p.end;
  }
  void Thread(Vec2 to, double lead, double lead_change, bool along_x) {
    LapMove m;
    m.kind = LapMove::kThread;
    m.to = fr_.From(to);
    m.lead = lead;
    m.lead_change = lead_change;
    m.lead_along_x = along_x;
    moves_.push_back(m);
    at_ = to;
  }
  Vec2 at() const { return at_; }
  std::vector<LapMove>& moves() { return moves_; }

 private:
  void Add(LapMove::Kind k, Vec2 to, double f) {
    if (geom::Norm(to - at_) < 1e-9) return;
    LapMove m;
    m.kind = k;
    m.to = fr_.From(to);
    m.f = f;
    moves_.push_back(m);
    at_ = to;
  }
  const Frame& fr_;
  Vec2 at_;
  std::vector<LapMove> moves_;
};

// Follows the contour from crossing `from` (element e, fraction t) upward until the height `stop`, a local
// maximum, or the contour's end; returns where it stopped.
Vec2 FollowUp(Builder& b, const std::vector<Elem>& c, size_t e, double t, double stop) {
  for (size_t i = e; i < c.size(); ++i) {
    const Path& p = c[i].p;
    const double t0 = i == e ? t : 0.0;
    // Stop at the level `stop` inside this element?
    double t_stop = 2;
    for (double x : Crossings(p, stop)) {
      if (x > t0 + 1e-9) {
        t_stop = x;
        break;
      }
    }
    // Stop where the contour starts to descend (a local maximum) inside this element.
    double t_top = 2;
    if (p.arc) {
      for (double x : Crossings(p, MaxV(p) - 1e-12)) {
        if (x > t0 + 1e-9 && x < 1 - 1e-9) t_top = std::min(t_top, x);
      }
    }
    const double t_end = std::min({t_stop, t_top, 1.0});
    if (TangentAt(p, t0 + 1e-9 < 1 ? t0 + 1e-9 : t0).y < -1e-9) return b.at();  // descending: a local max
    b.Follow(Sub(p, t0, t_end), c[i].f);
    if (t_end < 1) return b.at();
  }
  return b.at();
}

// The final rough contour: the finish contour shifted away from the part by the allowances.
std::vector<Elem> Shifted(const std::vector<Elem>& c, Vec2 by) {
  std::vector<Elem> out = c;
  for (auto& e : out) {
    e.p.start = e.p.start + by;
    e.p.end = e.p.end + by;
    e.p.center = e.p.center + by;
  }
  return out;
}

void CheckCutDirection(const std::vector<Elem>& c, const char* what) {
  // The contour is defined in the cutting direction (toward -u); a contour running back toward the start
  // point is the manual's "direction opposite to the cutting direction" alarm (ln 5851, 6198).
  if (c.empty()) return;
  if (c.back().p.end.x > c.front().p.start.x + kEps) {
    Fail(1, fmt::format("LAP: the {} runs opposite to the cutting direction", what));
  }
}

}  // namespace

namespace {

struct Setup {
  Frame fr;
  Vec2 s;                    // AP start point (normalised)
  std::vector<Elem> finish;  // final rough contour (allowances added)
  std::vector<Elem> blank;
  Vec2 a;  // its start
  bool first_rapid = true;
  double du = 0.1, dv = 0.1;  // relief on each axis
};

Setup Prepare(const LapParams& p, Vec2 start, const std::vector<LapElement>& contour,
              const std::vector<LapElement>& blank) {
  if (contour.empty()) Fail(1, "LAP: the contour definition has no element");
  Setup st;
  st.fr.transverse = p.transverse;
  const Vec2 a_m = contour.front().path.start;
  // Machine plane: x = Z, y = X radius. Infeed axis: X (longitudinal) / Z (transverse).
  const double s_in = p.transverse ? start.x : start.y;
  const double a_in = p.transverse ? a_m.x : a_m.y;
  const double s_cut = p.transverse ? start.y : start.x;
  const double a_cut = p.transverse ? a_m.y : a_m.x;
  if (std::fabs(s_in - a_in) < kEps) {
    Fail(1,
         "LAP cycle operation error: the start point and the contour start have the same infeed coordinate");
  }
  st.fr.sv = s_in > a_in ? 1 : -1;
  st.fr.su = s_cut >= a_cut ? 1 : -1;
  st.s = st.fr.To(start);
  auto conv = [&](const std::vector<LapElement>& in) {
    std::vector<Elem> out;
    for (const auto& e : in) {
      Elem x;
      x.p.arc = e.path.arc;
      x.p.start = st.fr.To(e.path.start);
      x.p.end = st.fr.To(e.path.end);
      x.p.center = st.fr.To(e.path.center);
      x.p.cw = st.fr.FlipsTurn() ? !e.path.cw : e.path.cw;
      x.p.sweep = e.path.sweep;
      x.f = e.e > 0 ? e.e : p.f;
      out.push_back(x);
    }
    return out;
  };
  // Allowances away from the part: +v by U (X) or W (Z) on the infeed axis, +u by the other.
  const double a_v = p.transverse ? p.w : p.u;
  const double a_u = p.transverse ? p.u : p.w;
  st.finish = Shifted(conv(contour), {a_u, a_v});
  st.blank = conv(blank);
  st.a = st.finish.front().p.start;
  st.first_rapid = contour.front().rapid;
  st.du = p.transverse ? p.relief / 2 : p.relief;  // X relief is a diameter value
  st.dv = p.transverse ? p.relief : p.relief / 2;
  if (st.s.y <= st.a.y + kEps) {
    Fail(1, "LAP: the finishing allowance puts the contour start beyond the AP start point");
  }
  return st;
}

// The depth of cut and feed at a level (G84 change points: after XA / ZA the second set, after XB the third;
// ln 5145-5173).
void LevelConditions(const LapParams& p, const Frame& fr, double v, double* d, double* f) {
  *d = p.d;
  *f = p.f;
  auto passed = [&](const LapChange& c) {
    if (!c.set) return false;
    const Vec2 n = fr.To(p.transverse ? Vec2{c.at, 0} : Vec2{0, c.at});
    return v <= (p.transverse ? n.y : n.y) + kEps;
  };
  if (passed(p.a)) {
    *d = p.a.d > 0 ? p.a.d : *d;
    *f = p.a.f > 0 ? p.a.f : *f;
  }
  if (passed(p.b)) {
    *d = p.b.d > 0 ? p.b.d : *d;
    *f = p.b.f > 0 ? p.b.f : *f;
  }
}

void FinalPass(Builder& b, const Setup& st, const LapParams& p) {
  b.Position(st.a, st.first_rapid, p.f);
  for (const auto& e : st.finish) b.Follow(e.p, e.f);
  const Vec2 end = b.at();
  b.Rapid({end.x + st.du, end.y + st.dv});
  if (p.m85) return;
  // Back to the start point. AP mode II: Z to the start point's Z, then X (ln 5579; the contour ends at its
  // largest diameter, ln 6263, so X first or both together could cross the part); transverse: the same with
  // the axes exchanged. Otherwise both axes together when the contour begins with G00, else X first (ln
  // 5419-5426).
  if (p.mode == 2) {
    b.Rapid({st.s.x, b.at().y});
    b.Rapid(st.s);
  } else if (st.first_rapid) {
    b.Rapid(st.s);
  } else {
    const Vec2 cur = b.at();
    const Vec2 x_first = p.transverse ? Vec2{st.s.x, cur.y} : Vec2{cur.x, st.s.y};
    b.Rapid(x_first);
    b.Rapid(st.s);
  }
}

// Where the blank lies above the level v between u_right and u_left (u_left < u_right): material intervals.
std::vector<std::pair<double, double>> BlankIntervals(const std::vector<Elem>& blank, double v, double u_left,
                                                      double u_right) {
  std::vector<std::pair<double, double>> out;
  if (blank.empty()) {
    out.push_back({u_left, u_right});
    return out;
  }
  // Sample the blank's crossings: between consecutive crossings (in u) material is where the blank is above
  // v.
  std::vector<double> us{u_left, u_right};
  for (const auto& x : LevelCrossings(blank, v)) {
    if (x.at.x > u_left && x.at.x < u_right) us.push_back(x.at.x);
  }
  std::sort(us.begin(), us.end());
  auto blank_above = [&](double u) {
    // The blank's height at u: the highest point of the blank over u (vertical line).
    double best = -1e300;
    for (const auto& e : blank) {
      const Path& p = e.p;
      if (!p.arc) {
        const double lo = std::min(p.start.x, p.end.x), hi = std::max(p.start.x, p.end.x);
        if (u < lo - kEps || u > hi + kEps || hi - lo < kEps) continue;
        const double t = (u - p.start.x) / (p.end.x - p.start.x);
        best = std::max(best, p.start.y + t * (p.end.y - p.start.y));
      } else {
        for (int k = 0; k <= 64; ++k) {
          const Vec2 q = At(p, k / 64.0);
          if (std::fabs(q.x - u) < (std::fabs(p.end.x - p.start.x) + 1) / 32) best = std::max(best, q.y);
        }
      }
    }
    return best > v + kEps;
  };
  for (size_t i = 0; i + 1 < us.size(); ++i) {
    if (us[i + 1] - us[i] < kEps) continue;
    if (blank_above(0.5 * (us[i] + us[i + 1]))) {
      if (!out.empty() && std::fabs(out.back().first - us[i + 1]) < kEps) {
        out.back().first = us[i];
      } else {
        out.push_back({us[i], us[i + 1]});
      }
    }
  }
  return out;
}

// Where a pocket's descending wall is entered for the level below `prev`: its crossing with the previous
// level, or, when the wall begins lower, the top of the wall (the local maximum before the crossing `r`).
Vec2 WallEntry(const std::vector<Elem>& c, const Cross& r, double prev) {
  size_t i0 = r.e;
  while (i0 > 0 && TangentAt(c[i0 - 1].p, 1).y < -1e-12) --i0;
  for (const Cross& x : LevelCrossings(c, prev)) {
    if (x.rising || x.e < i0) continue;
    if (x.e < r.e || (x.e == r.e && x.t < r.t)) return x.at;
  }
  return c[i0].p.start;
}

// Follows the contour from the point `from` (on it) forward to the crossing `r`.
void FollowDown(Builder& b, const std::vector<Elem>& c, Vec2 from, const Cross& r) {
  bool started = false;
  for (size_t i = 0; i <= r.e; ++i) {
    const Path& pth = c[i].p;
    double t0 = 0;
    if (!started) {
      bool found = false;
      for (int k = 0; k <= 512 && !found; ++k) {
        const double t = k / 512.0;
        if (geom::Norm(At(pth, t) - from) < 1e-6) {
          t0 = t;
          found = true;
        }
      }
      for (double t : Crossings(pth, from.y)) {
        if (geom::Norm(At(pth, t) - from) < 1e-6) {
          t0 = t;
          found = true;
        }
      }
      if (!found) continue;
      started = true;
    }
    const double t1 = i == r.e ? r.t : 1.0;
    if (t1 > t0 + 1e-12) b.Follow(Sub(pth, t0, t1), c[i].f);
  }
  if (geom::Norm(b.at() - r.at) > 1e-6) b.Feed(r.at, c[r.e].f);
}

// AP modes I and IV: bar turning by levels.
std::vector<LapMove> BarTurning(const LapParams& p, const Setup& st, bool lap4) {
  Builder b(st.fr, st.s);
  const auto& c = st.finish;
  const double lc = p.clearance;
  double top = st.s.y;
  if (lap4) {
    if (st.blank.empty()) Fail(1, "LAP4: no blank shape");
    top = -1e300;
    for (const auto& e : st.blank) top = std::max(top, MaxV(e.p));
    for (const auto& e : c) top = std::max(top, MaxV(e.p));
  }
  double lowest = st.a.y;
  for (const auto& e : c) lowest = std::min(lowest, MinV(e.p));
  int slopes = 0;
  for (size_t i = 0; i < c.size(); ++i) {
    const Vec2 t0 = TangentAt(c[i].p, 0);
    if (t0.y < -1e-9 && (i == 0 || TangentAt(c[i - 1].p, 1).y >= -1e-9)) ++slopes;
  }
  if (slopes > kMaxSlopes) Fail(1, fmt::format("LAP: {} descending slopes (at most {})", slopes, kMaxSlopes));
  auto u_start = [&](double v) {
    // On the line from the start point to the final rough contour's start (ln 5373).
    if (std::fabs(st.s.y - st.a.y) < kEps) return st.s.x;
    return st.s.x + (st.a.x - st.s.x) * (st.s.y - v) / (st.s.y - st.a.y);
  };
  double d = 0, f = 0;
  LevelConditions(p, st.fr, top, &d, &f);
  double v = top - d;
  double prev = top;
  int guard = 0;
  while (v > lowest + kEps) {
    if (++guard > 10000) Fail(1, "LAP: more than 10000 levels: the depth of cut D is too small");
    const std::vector<Cross> xs = LevelCrossings(c, v);
    // Intervals at this level: from the start side (when the contour starts below the level) to the first
    // rising crossing, then from each descending crossing to the next rising one.
    struct Interval {
      bool from_start;
      Cross right, left;
      bool open_left;  // the contour ends below the level
    };
    std::vector<Interval> ivs;
    bool below = st.a.y < v - kEps;
    Cross entry{};
    bool have_entry = below;
    bool from_start = below;
    for (const Cross& x : xs) {
      if (x.rising && have_entry) {
        ivs.push_back({from_start, entry, x, false});
        have_entry = false;
        from_start = false;
      } else if (!x.rising) {
        entry = x;
        have_entry = true;
        from_start = false;
      }
    }
    if (have_entry) {
      Cross end{c.size() - 1, 1.0, c.back().p.end, true};
      ivs.push_back({from_start, entry, end, true});
    }
    for (const Interval& iv : ivs) {
      const Vec2 left = iv.left.at;
      if (iv.from_start) {
        const double us = lap4 ? u_start(v) : u_start(v);
        Vec2 start{us, v};
        if (lap4) {
          // LAP4: air at rapid, cutting from Lc before the blank to Lc after it (ln 5873-5963).
          auto mats = BlankIntervals(st.blank, v, left.x, us);
          if (mats.empty()) continue;
          b.Position({std::min(us, mats.back().second + lc), v}, true, f);
          for (auto it = mats.rbegin(); it != mats.rend(); ++it) {
            const double in = std::min(us, it->second + lc), out = std::max(left.x, it->first - lc);
            if (b.at().x > in + kEps) b.Rapid({in, v});
            b.Feed({out, v}, f);
          }
          if (b.at().x > left.x + kEps) b.Feed({left.x, v}, f);
        } else {
          b.Position(start, st.first_rapid, f);
          b.Feed({left.x, v}, f);
        }
      } else {
        // A pocket (descending slope, ln 5402-5414): over the contour before it, down its descending wall
        // from the previous level (or from the wall's top), across at this level, up the ascending wall.
        const Cross& r = iv.right;
        Vec2 from = WallEntry(c, r, prev);
        double hump = from.y;
        for (size_t i = 0; i <= r.e; ++i) hump = std::max(hump, MaxV(c[i].p));
        b.Rapid({b.at().x, std::max(b.at().y, hump + st.dv)});
        b.Rapid({from.x + st.du, std::max(b.at().y, hump + st.dv)});
        b.Rapid(from);
        FollowDown(b, c, from, r);
        b.Feed({left.x, v}, f);
      }
      // Up the contour to the previous level, relief, and back (ln 5390-5400).
      Vec2 up = b.at();
      if (!iv.open_left) up = FollowUp(b, c, iv.left.e, iv.left.t, prev);
      b.Rapid({up.x + st.du, up.y + st.dv});
      if (&iv == &ivs.back()) {
        // Back along the cut axis to where this level began, then on to the next level (ln 5397-5400).
        const double back = ivs.front().from_start ? u_start(v) : ivs.front().right.at.x;
        b.Rapid({std::max(back, b.at().x), b.at().y});
      }
    }
    prev = v;
    LevelConditions(p, st.fr, v, &d, &f);
    v -= d;
  }
  FinalPass(b, st, p);
  return std::move(b.moves());
}

// AP mode II: copy turning, the contour shifted toward the start point (ln 5438-5591).
std::vector<LapMove> CopyTurning(const LapParams& p, const Setup& st) {
  Builder b(st.fr, st.s);
  const double span = st.s.y - st.a.y;
  double f = p.f, d = p.d;
  int guard = 0;
  for (int n = 1;; ++n) {
    if (++guard > 10000) Fail(1, "LAP: more than 10000 passes: the depth of cut D is too small");
    LevelConditions(p, st.fr, st.s.y - (n - 1) * d, &d, &f);
    const double vp = st.s.y - n * d;
    if (vp <= st.a.y + kEps) break;
    const double up = st.a.x + (st.s.x - st.a.x) * (1 - n * d / span);
    const Vec2 off{up - st.a.x, vp - st.a.y};
    b.Position({up, vp}, st.first_rapid, f);
    for (const auto& e : st.finish) {
      Path q = e.p;
      q.start = q.start + off;
      q.end = q.end + off;
      q.center = q.center + off;
      b.Follow(q, e.f);
    }
    b.Rapid({b.at().x + st.du, b.at().y + st.dv});
    b.Rapid({st.s.x, b.at().y});
  }
  FinalPass(b, st, p);
  return std::move(b.moves());
}

// AP mode V: bar copying, passes parallel to the blank shifted by n*D until they meet the final rough
// contour (ln 5967-6198).
std::vector<LapMove> BarCopying(const LapParams& p, const Setup& st) {
  if (st.blank.empty()) Fail(1, "LAP4: no blank shape");
  CheckCutDirection(st.blank, "blank shape");
  Builder b(st.fr, st.s);
  std::vector<Elem> blank = st.blank;
  // The first blank element is raised to the second one's height when it is lower (ln 6107-6135).
  if (blank.size() >= 2 && !blank[0].p.arc && blank[0].p.start.y < blank[1].p.start.y) {
    blank[0].p.start.y = blank[1].p.start.y;
    blank[0].p.end.y = blank[1].p.start.y;
  }
  double blank_top = -1e300;
  for (const auto& e : blank) blank_top = std::max(blank_top, MaxV(e.p));
  double contour_low = 1e300;
  for (const auto& e : st.finish) contour_low = std::min(contour_low, MinV(e.p));
  double d = p.d, f = p.f;
  // The contour's height over u (the highest contour point on the vertical line at u).
  auto contour_at = [&](double u) {
    double best = -1e300;
    for (const auto& e : st.finish) {
      for (int k = 0; k <= 32; ++k) {
        const Vec2 q = At(e.p, k / 32.0);
        const Vec2 q2 = At(e.p, std::min(1.0, (k + 1) / 32.0));
        const double lo = std::min(q.x, q2.x), hi = std::max(q.x, q2.x);
        if (u >= lo - kEps && u <= hi + kEps) {
          const double t = hi - lo > kEps ? (u - q.x) / (q2.x - q.x) : 0;
          best = std::max(best, q.y + t * (q2.y - q.y));
        }
      }
    }
    return best;
  };
  // Whether the straight line a-b stays on or above the contour (sampled as contour_at is).
  auto clear_of_contour = [&](Vec2 a, Vec2 c) {
    for (int k = 0; k <= 32; ++k) {
      const double t = k / 32.0;
      const Vec2 q{a.x + (c.x - a.x) * t, a.y + (c.y - a.y) * t};
      if (q.y < contour_at(q.x) - kEps) return false;
    }
    return true;
  };
  int guard = 0;
  for (int n = 1;; ++n) {
    if (++guard > 10000) Fail(1, "LAP: more than 10000 passes: the depth of cut D is too small");
    LevelConditions(p, st.fr, blank_top - (n - 1) * d, &d, &f);
    const double shift = n * d;
    if (blank_top - shift <= contour_low + kEps) break;
    bool cutting = false;
    const Vec2 s0 = blank.front().p.start + Vec2{0, -shift};
    b.Rapid({st.s.x, b.at().y});
    b.Rapid({s0.x + p.clearance, std::max(s0.y, b.at().y)});
    b.Rapid({s0.x + p.clearance, s0.y});
    for (const auto& e : blank) {
      for (int k = 0; k < 16; ++k) {
        const Path seg = Sub(e.p, k / 16.0, (k + 1) / 16.0);
        Path q = seg;
        q.start.y -= shift;
        q.end.y -= shift;
        q.center.y -= shift;
        const bool above = q.end.y > contour_at(q.end.x) + kEps && q.start.y > contour_at(q.start.x) - kEps;
        if (above) {
          if (!cutting) {
            // A pass that starts (or starts again) past the blank's start reaches the first point above the
            // contour from over the blank: a straight feed from the approach point could cross the part.
            if (!clear_of_contour(b.at(), q.start)) {
              const double top = std::max(b.at().y, blank_top + 0.1);
              b.Rapid({b.at().x, top});
              b.Rapid({q.start.x, top});
            }
            if (geom::Norm(b.at() - q.start) > kEps) b.Feed(q.start, f);
            cutting = true;
          }
          b.Follow(q, f);
        } else if (cutting) {
          b.Rapid({b.at().x + st.du, b.at().y + st.dv});
          b.Rapid({b.at().x, blank_top + 0.1});
          cutting = false;
        }
      }
    }
    if (cutting) b.Rapid({b.at().x + st.du, b.at().y + st.dv});
    b.Rapid({b.at().x, std::max(b.at().y, blank_top + 0.1)});
  }
  b.Rapid({st.s.x, b.at().y});
  FinalPass(b, st, p);
  return std::move(b.moves());
}

}  // namespace

std::vector<LapMove> LapRough(const LapParams& p, Vec2 start, const std::vector<LapElement>& contour,
                              const std::vector<LapElement>& blank) {
  if (p.d <= 0) Fail(1, "LAP: the depth of cut D must be positive");
  if (p.f <= 0) Fail(1, "LAP: no feedrate F for the rough cycle");
  if (p.u < 0 || p.w < 0) Fail(1, "LAP: the finishing allowances U and W must not be negative");
  Setup st = Prepare(p, start, contour, blank);
  CheckCutDirection(st.finish, "finish contour");
  switch (p.mode) {
    case 1:
      return BarTurning(p, st, false);
    case 4:
      return BarTurning(p, st, true);
    case 2:
      return CopyTurning(p, st);
    case 5:
      return BarCopying(p, st);
    default:
      Fail(1, "LAP: unknown AP mode");
  }
}

std::vector<LapMove> LapThread(const LapParams& p, Vec2 start, const std::vector<LapElement>& contour,
                               const std::vector<double>& depths) {
  // AP mode III (ln 5593-5653): each pass follows the thread contour moved out by what is left of the thread
  // height, with the flank shift of the infeed angle B, then the infeed axis returns to the start point and
  // the cutting axis follows.
  if (contour.empty()) Fail(1, "LAP: the contour definition has no element");
  Frame fr;
  fr.transverse = p.transverse;
  const Vec2 a_m = contour.front().path.start;
  const double s_in = p.transverse ? start.x : start.y;
  const double a_in = p.transverse ? a_m.x : a_m.y;
  fr.sv = s_in >= a_in ? 1 : -1;
  const double s_cut = p.transverse ? start.y : start.x;
  const double a_cut = p.transverse ? a_m.y : a_m.x;
  fr.su = s_cut >= a_cut ? 1 : -1;
  const Vec2 s = fr.To(start);
  Builder b(fr, s);
  const double tan_half = std::tan(p.tip_angle / 2 * kPi / 180.0);
  const double h = p.h;
  for (size_t n = 0; n < depths.size(); ++n) {
    const double depth = depths[n];
    const double out = h - depth;  // infeed-axis units (radius for X)
    double flank = depth * tan_half;
    if (p.thread_mode == 32 || (p.thread_mode == 33 && n % 2 == 0)) flank = -flank;
    const Vec2 off{flank, out};
    bool first = true;
    for (const auto& e : contour) {
      Vec2 a = fr.To(e.path.start) + off, z = fr.To(e.path.end) + off;
      if (first) {
        b.Rapid({s.x, a.y});
        b.Rapid(a);
        first = false;
      }
      if (e.thread) {
        b.Thread(z, e.lead, e.lead_change, e.lead_along_x);
      } else if (e.rapid) {
        b.Rapid(z);
      } else {
        b.Feed(z, e.f > 0 ? e.f : p.f);
      }
    }
    b.Rapid({b.at().x, s.y});
    b.Rapid(s);
  }
  return std::move(b.moves());
}

}  // namespace cell::interp::okuma
