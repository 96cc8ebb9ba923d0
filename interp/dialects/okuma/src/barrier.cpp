// Okuma chuck and tailstock barriers (manual ln 1951-1956, 9020-9110; data ln 7764-7777, 10039-10046):
// M25/M24 and M21/M20 switch them; while on, every move the run is about to send is checked against them and
// one that would enter a barrier stops the run with the barrier alarm before it moves (judgement 47).
#include <fmt/format.h>

#include <array>
#include <cmath>
#include <limits>

#include "interp_internal.h"

namespace cell::interp::okuma {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kEps = 1e-6;

// An axis-aligned region of the Z-X plane (program coordinates, X a diameter).
struct Box {
  double z0, z1, x0, x1;
};

// Whether the segment a-b passes through the open interior of the box (Liang-Barsky clipping): touching a
// barrier's edge is not entering it.
bool Enters(geom::Vec2 a, geom::Vec2 b, const Box& r) {
  double t0 = 0, t1 = 1;
  const double dz = b.x - a.x, dx = b.y - a.y;
  const std::array<std::array<double, 2>, 4> pq = {{{-dz, a.x - (r.z0 + kEps)},
                                                    {dz, (r.z1 - kEps) - a.x},
                                                    {-dx, a.y - (r.x0 + kEps)},
                                                    {dx, (r.x1 - kEps) - a.y}}};
  for (const auto& [p, q] : pq) {
    if (std::fabs(p) < 1e-15) {
      if (q < 0) return false;
      continue;
    }
    const double t = q / p;
    if (p < 0) {
      t0 = std::max(t0, t);
    } else {
      t1 = std::min(t1, t);
    }
    if (t0 > t1) return false;
  }
  return true;
}

}  // namespace

double OkRun::BarrierDatum(const char* name) const {
  auto it = system_.find({PackName(name), 0});
  return it == system_.end() ? 0.0 : it->second;
}

// M25/M24 chuck barrier on/off, M21/M20 tailstock barrier on/off (ln 9071-9079). A barrier without its data
// cannot protect anything: switching it on is refused.
void OkRun::BarrierCode(int m, int col) {
  if (m == 25 && BarrierDatum("VCHKX") <= 0) {
    Fail(col, "M25: no chuck barrier data (VCHKX, the chuck gripping diameter CX, is not set)");
  }
  if (m == 21 && BarrierDatum("VTSDA") <= 0 && BarrierDatum("VTSDB") <= 0) {
    Fail(col, "M21: no tailstock barrier data (VTSDA/VTSDB, the tailstock diameters, are not set)");
  }
  // On from its own block; off after its own block: the barrier covers both (ln 9104).
  if (m == 25) modal_.chuck_barrier = true;
  if (m == 21) modal_.tail_barrier = true;
  if (m == 24) barrier_off_ |= 1;
  if (m == 20) barrier_off_ |= 2;
}

void OkRun::BarrierOffAfterBlock() {
  if (barrier_off_ & 1) modal_.chuck_barrier = false;
  if (barrier_off_ & 2) modal_.tail_barrier = false;
  barrier_off_ = 0;
}

// Checks the commands waiting to go out, in order. At the first move that would enter an active barrier the
// queue is cut before it and the run ends with the alarm at that move's line. Returns false then.
bool OkRun::CheckBarriers() {
  if (!modal_.chuck_barrier && !modal_.tail_barrier) {
    // No barrier on (the common case, every block): only where the next check starts from.
    for (size_t i = out_.size(); i-- > 0;) {
      if (const Target* to = out_.at(i).target()) {
        barrier_from_ = to->pos;
        break;
      }
    }
    return true;
  }
  std::array<Box, 4> boxes{};
  size_t n = 0;
  if (modal_.chuck_barrier) {
    // The jaws grip at diameter CX with their front face at Z = CZ; the gripping step is L1 long and D1 high
    // (radial), the jaw and chuck body lie behind it (the figure is lost, judgement 47). Both sides of the
    // centre line (turret B moves on the negative side).
    const double cx = BarrierDatum("VCHKX"), cz = BarrierDatum("VCHKZ");
    const double l1 = BarrierDatum("VCHKL"), d1 = BarrierDatum("VCHKD");
    boxes[n++] = {cz - l1, cz, cx, cx + 2 * d1};
    boxes[n++] = {-kInf, cz - l1, cx, kInf};
    boxes[n++] = {cz - l1, cz, -cx - 2 * d1, -cx};
    boxes[n++] = {-kInf, cz - l1, -kInf, -cx};
  }
  std::array<Box, 2> tail{};
  size_t nt = 0;
  if (modal_.tail_barrier) {
    // The centre (diameter D3) projects L2 from the work's end face WR; the quill (diameter D2) behind it.
    const double wr = BarrierDatum("VWKR"), l2 = BarrierDatum("VTSL");
    const double d2 = BarrierDatum("VTSDA"), d3 = BarrierDatum("VTSDB");
    tail[nt++] = {wr, wr + l2, -d3, d3};
    tail[nt++] = {wr + l2, kInf, -d2, d2};
  }
  auto prog = [&](const AxisArray& m) {
    return geom::Vec2{ToProgram(kZ, m[static_cast<size_t>(kZ)]), ToProgram(kX, m[static_cast<size_t>(kX)])};
  };
  auto hits = [&](geom::Vec2 a, geom::Vec2 b) -> const char* {
    for (size_t i = 0; i < n; ++i) {
      if (Enters(a, b, boxes[i])) return "chuck";
    }
    for (size_t i = 0; i < nt; ++i) {
      if (Enters(a, b, tail[i])) return "tailstock";
    }
    return nullptr;
  };
  for (size_t i = 0; i < out_.size(); ++i) {
    Canon& c = out_.at(i);
    const Target* to = c.target();
    if (!to) continue;
    const AxisArray from = barrier_from_;
    barrier_from_ = to->pos;
    if (n == 0 && nt == 0) continue;
    const geom::Vec2 a = prog(from), b = prog(to->pos);
    const char* what = nullptr;
    if (const ArcOp* arc = c.If<ArcOp>()) {
      // The arc as chords no more than 1 um inside it (at least 64 per turn; radius coordinates, so the
      // circle stays round): a bulge into a barrier is not cut off by the polygon.
      AxisArray ctr{};
      ctr[static_cast<size_t>(kX)] = arc->center[0];
      ctr[static_cast<size_t>(kZ)] = arc->center[2];
      const geom::Vec2 cp = prog(ctr);
      const geom::Vec2 c0{cp.x, cp.y / 2}, s0{a.x - c0.x, a.y / 2 - c0.y};
      const double r = std::hypot(s0.x, s0.y);
      const double step = r > 0.001 ? std::min(2 * kPi / 64, 2 * std::acos(1 - 0.001 / r)) : 2 * kPi / 64;
      const int steps = std::max(1, static_cast<int>(std::ceil(arc->angle * kPi / 180.0 / step)));
      const double sweep = (arc->cw != modal_.turret_b ? -1.0 : 1.0) * arc->angle * kPi / 180.0;
      geom::Vec2 p = a;
      for (int k = 1; k <= steps && !what; ++k) {
        const double t = sweep * k / steps;
        geom::Vec2 q = k == steps ? b
                                  : geom::Vec2{c0.x + s0.x * std::cos(t) - s0.y * std::sin(t),
                                               2 * (c0.y + s0.x * std::sin(t) + s0.y * std::cos(t))};
        what = hits(p, q);
        p = q;
      }
    } else {
      what = hits(a, b);
    }
    if (!what) continue;
    out_.truncate(i);
    Diagnostic d;
    d.program = opt_.program_name;
    d.line = c.line;
    d.col = 1;
    d.text =
        fmt::format("{} barrier: the move to X{:.3f} Z{:.3f} would enter the {} barrier ({} on, ln 9081)",
                    what[0] == 'c' ? "Chuck" : "Tailstock", b.y, b.x, what, what[0] == 'c' ? "M25" : "M21");
    EndWithError(std::move(d));
    return false;
  }
  return true;
}

}  // namespace cell::interp::okuma
