// EMCO turning, grooving and drilling cycles (manual ln 3165-3566 G84, 4406-4613 G86, 4616-4807 G87/G88).
// The block before the cycle brings the tool to the start point S; the cycle block gives the contour corner
// K (or the groove corner, the drill target); every cycle ends back at S. X before Z in the block selects
// the longitudinal variant, Z before X the face variant (ln 866-871). The movement diagrams of the manual
// are lost; the sequences here are the judgement calls of docs/dialects/emco.md.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "cell/interp/geometry/offset_path.h"
#include "cycles.h"
#include "interp_internal.h"

namespace cell::interp::emco {

using cyc::At;
using cyc::Get;
using cyc::Sign;

namespace cyc {

std::vector<double> ThreadDepths(double depth, double d3, bool count, bool constant, double min) {
  std::vector<double> out;
  if (depth <= 0) return out;
  int n = count ? std::max(1, static_cast<int>(d3)) : 0;
  double prev = 0;
  if (min <= 0) min = 1e-3;  // one increment at least: the depths must get there
  for (int k = 1; prev < depth - 1e-9 && k <= kMaxCuts + 1; ++k) {
    double c;
    if (count) {
      c = constant ? depth * k / n : depth * std::sqrt(static_cast<double>(k) / n);
    } else {
      c = constant ? d3 * k : d3 * std::sqrt(static_cast<double>(k));
    }
    if (c - prev < min) c = prev + min;  // the monitor's minimum infeed (S00)
    if (c > depth - 1e-9) c = depth;
    out.push_back(c);
    prev = c;
  }
  return out;
}

std::vector<double> DrillPecks(double total, double first, double percent, double min) {
  std::vector<double> out;
  if (first <= 0 || first >= total) {
    out.push_back(total);
    return out;
  }
  if (percent <= 0) {
    int n = EqualCuts(total, first);
    out.assign(n, total / n);
    return out;
  }
  if (min <= 0) min = 1e-3;  // one increment: a reduction to nothing would never get there
  double done = 0, d = first;
  while (done + d < total - 1e-9 && d >= min - 1e-9 && out.size() <= kMaxCuts) {
    out.push_back(d);
    done += d;
    d *= percent / 100.0;
  }
  double rest = total - done;
  if (rest > 1e-9) {
    int n = EqualCuts(rest, min);
    for (int i = 0; i < n && out.size() <= kMaxCuts; ++i) out.push_back(rest / n);
  }
  return out;
}

}  // namespace cyc

int EmRun::D(const BlockWords& bw, int i, int def) const {
  return bw.d[i].set ? static_cast<int>(bw.d[i].raw) : def;
}

double EmRun::DLen(const BlockWords& bw, int i, double def) const {
  if (!bw.d[i].set) return def;
  return bw.d[i].raw * (mode_.metric ? 0.001 : 0.0001 * kInch);
}

void EmRun::CycleMove(Move::Kind kind, Vec2 prog, const Feed* feed, double lead) {
  // One cycle move is at most 1FFFF hex = 131071 increments per axis (ALARM 230, ln 6751).
  if (std::fabs(prog.x - prog_.x) > 131.071 || std::fabs(prog.y - prog_.y) > 131.071) {
    Alarm(230, 1, "a cycle move is at most 131.071 mm per axis");
  }
  Move m;
  m.kind = kind;
  if (feed) m.feed = *feed;
  m.lead = lead;
  m.end = ToWork(prog);
  m.used = used_;
  m.line = cur_line_;
  prog_ = prog;
  EmitMove(std::move(m));
}

// G84 (ln 3165-3566). Longitudinal: the feed (infeed) axis is X, the cut runs along Z; face: the other way
// round. The contour is K's two lines: the "floor" along the cut axis, tilted by the feed-axis taper
// (P0 longitudinal, P2 face: its offset at the start point's end), and the "wall" along the feed axis,
// tilted by the other taper (its offset at the start point's level). Allowances D0 (X) and D2 (Z) move K
// toward S; D3 divides the infeed into equal cuts. Each pass: rapid infeed at S's cut-axis position, feed
// along the floor to the wall, feed along the wall out to S's level, rapid back to S.
void EmRun::G84(const BlockWords& bw, Vec2 k, const Feed& feed) {
  if (!bw.x.set || !bw.z.set) Alarm(480, bw.pos_col(), "G84 needs X(U) and Z(W)");
  const bool face = bw.z.order < bw.x.order;
  const int f = face ? 0 : 1, c = face ? 1 : 0;  // feed axis, cut axis
  const Vec2 s = prog_;
  const Val& pf = face ? bw.p[2] : bw.p[0];  // taper in the feed axis
  const Val& pc = face ? bw.p[0] : bw.p[2];  // taper in the cut axis
  double feed_len = Get(k, f) - Get(s, f), cut_len = Get(k, c) - Get(s, c);
  const double eps = 1e-9;
  // ALARM 230: the same coordinate in one axis needs that axis's taper, and then none in the other.
  bool flat_f = std::fabs(feed_len) < eps, flat_c = std::fabs(cut_len) < eps;
  if (flat_f && flat_c) Alarm(230, bw.pos_col(), "S and K are the same point");
  if (flat_f && (!pf.set || pc.set)) Alarm(230, bw.pos_col(), "no feed without a feed-axis taper");
  if (flat_c && (!pc.set || pf.set)) Alarm(230, bw.pos_col(), "no cut length without a cut-axis taper");
  if (bw.d[3].set && bw.d[3].raw == 0) Alarm(240, bw.d[3].col, "D3 = 0");
  if ((bw.d[0].set || bw.d[2].set) && !bw.d[3].set)
    Alarm(240, bw.d[0].set ? bw.d[0].col : bw.d[2].col, "allowance without D3");
  double ax = DLen(bw, 0, 0), az = DLen(bw, 2, 0);  // D0 in X, D2 in Z (the format list, ln 3404-3405)
  double a_f = face ? az : ax, a_c = face ? ax : az;
  if (a_f > std::fabs(feed_len) + eps) Alarm(220, (face ? bw.d[2] : bw.d[0]).col);
  if (a_c > std::fabs(cut_len) + eps && !flat_c) Alarm(220, (face ? bw.d[0] : bw.d[2]).col);
  double tf = pf.set ? pf.v : 0, tc = pc.set ? pc.v : 0;
  // ALARM 210 (ln 6736-6742).
  if (pf.set && tf != 0 && !flat_f) {
    bool against = Sign(tf) != Sign(feed_len);
    if (bw.d[3].set && against) Alarm(210, pf.col, "the feed-axis taper must have the sign of the feed");
    if (!bw.d[3].set && against && std::fabs(tf) > std::fabs(feed_len)) Alarm(210, pf.col);
  }
  if (pc.set && tc != 0 && !flat_c && Sign(tc) != Sign(cut_len) && std::fabs(tc) > std::fabs(cut_len)) {
    Alarm(210, pc.col, "the taper is longer than the distance it shortens");
  }
  // With compensation the cuts must be at least twice the nose radius (ln 3050-3070).
  Correction corr = LookUp(tools_, t_ % 100);
  if (comp_.on() && bw.d[3].set && DLen(bw, 3, 0) < 2 * corr.r - eps && !(mon_.o40 & 64)) {
    Alarm(570, bw.d[3].col, "D3 smaller than twice the nose radius");
  }
  used_ |= (1u << kX) | (1u << kZ);
  // K with the allowances left on it.
  double kf = Get(k, f) - (flat_f ? 0 : Sign(feed_len) * a_f);
  double kc = Get(k, c) - (flat_c ? 0 : Sign(cut_len) * a_c);
  double sf = Get(s, f), sc = Get(s, c);
  double depth = kf - sf;
  int n = bw.d[3].set ? cyc::EqualCuts(depth, DLen(bw, 3, 0)) : 1;
  if (n > cyc::kMaxCuts) Alarm(240, bw.d[3].col, "more than 10000 cuts");
  // The wall: from K' to (sf, kc + tc).
  Vec2 wall_a = At(f, kf, kc), wall_b = At(f, sf, kc + tc);
  Vec2 wall_d = wall_b - wall_a;
  for (int i = 1; i <= n; ++i) {
    double level = sf + depth * i / n;  // the pass's feed-axis position at K'
    Vec2 start = At(f, level + tf, sc);
    Vec2 at_k = At(f, level, kc);
    Vec2 end;
    if (geom::Norm(wall_d) < eps) {
      end = at_k;
    } else {
      Vec2 d = at_k - start;
      if (geom::Norm(d) < eps) d = At(c, 0, 1);  // flat cut axis: the pass is the wall's level
      double den = geom::Cross(d, wall_d);
      if (std::fabs(den) < 1e-12) Alarm(230, bw.pos_col(), "the pass does not meet the wall");
      double t = geom::Cross(wall_a - start, wall_d) / den;
      end = start + t * d;
    }
    // A shallow pass under a steep floor taper can leave the part (reach the start point's level) before it
    // meets the wall: it ends there, and goes back without following the wall.
    bool leaves = (Get(end, f) - sf) * Sign(depth) < -eps;
    if (leaves) {
      double df = Get(at_k, f) - Get(start, f);
      double u = std::fabs(df) < eps ? 0 : (sf - Get(start, f)) / df;
      end = start + u * (at_k - start);
    }
    CycleMove(Move::kRapid, start, nullptr);
    CycleMove(Move::kLinear, end, &feed);
    if (!leaves) CycleMove(Move::kLinear, wall_b, &feed);
    CycleMove(Move::kRapid, s, nullptr);
  }
}

// G86 (ln 4406-4613): plunges of the tool width D5 with the measured edge facing the start point (the right
// edge for a groove along Z, ln 4443-4453); a wider groove is cut as the first groove plus equal partial
// grooves overlapping by at least 0.1 mm (ln 4455-4457). D3 divides each plunge into equal pecks with a
// retract of S02 between them, D4 dwells at the bottom.
void EmRun::G86(const BlockWords& bw, Vec2 k, const Feed& feed) {
  if (!bw.x.set || !bw.z.set) Alarm(480, bw.pos_col(), "G86 needs X(U) and Z(W)");
  const bool face = bw.z.order < bw.x.order;
  const int f = face ? 0 : 1, c = face ? 1 : 0;  // plunge axis, width axis
  const Vec2 s = prog_;
  double depth = Get(k, f) - Get(s, f), width = Get(k, c) - Get(s, c);
  if (std::fabs(depth) < 1e-9 || std::fabs(width) < 1e-9)
    Alarm(230, bw.pos_col(), "S and K share a coordinate");
  if (!bw.d[5].set) Alarm(250, bw.pos_col(), "G86 needs the tool width D5");
  double w = DLen(bw, 5, 0);
  if (w > std::fabs(width) + 1e-9) Alarm(200, bw.d[5].col, "D5 is wider than the groove");
  if (w <= 0.1 && w < std::fabs(width) - 1e-9) Alarm(200, bw.d[5].col, "D5 must exceed the 0.1 mm overlap");
  if (bw.d[3].set && (bw.d[3].raw == 0 || DLen(bw, 3, 0) > std::fabs(depth) + 1e-9)) Alarm(240, bw.d[3].col);
  if (bw.d[4].set && bw.d[4].raw > 10000) Alarm(200, bw.d[4].col, "D4 is at most 10000");
  used_ |= (1u << kX) | (1u << kZ);
  double sf = Get(s, f), sc = Get(s, c);
  double hi = std::max(sc, Get(k, c)), lo = std::min(sc, Get(k, c));
  bool from_hi = sc >= hi - 1e-9;
  double first = from_hi ? hi : lo + w, last = from_hi ? lo + w : hi;
  int extra = std::fabs(last - first) < 1e-9 ? 0 : cyc::EqualCuts(last - first, w - 0.1);
  int pecks = bw.d[3].set ? cyc::EqualCuts(depth, DLen(bw, 3, 0)) : 1;
  if ((extra + 1) * pecks > cyc::kMaxCuts) Alarm(240, bw.pos_col(), "more than 10000 plunges");
  double retract = mon_.s02 * (mode_.metric ? 0.001 : 0.0001 * kInch);
  for (int j = 0; j <= extra; ++j) {
    double p = extra == 0 ? first : first + (last - first) * j / extra;
    CycleMove(Move::kRapid, At(f, sf, p), nullptr);
    for (int q = 1; q <= pecks; ++q) {
      CycleMove(Move::kLinear, At(f, sf + depth * q / pecks, p), &feed);
      if (q < pecks) {
        double back = sf + depth * q / pecks - Sign(depth) * retract;
        if ((back - sf) * Sign(depth) < 0) back = sf;
        CycleMove(Move::kRapid, At(f, back, p), nullptr);
      }
    }
    if (bw.d[4].set && bw.d[4].raw > 0) {
      Canon d;
      d.line = cur_line_;
      d.Set<DwellOp>().seconds = bw.d[4].raw / 10.0;
      EmitOther(std::move(d));
    }
    CycleMove(Move::kRapid, At(f, sf, p), nullptr);
  }
  CycleMove(Move::kRapid, s, nullptr);
}

// G87 chip breaking (retract S02 after each peck) and G88 redrawing (back to the start point after each peck)
// (ln 4616-4807): Z only, the drill on the centre line, pecks by D3/D5/D6, D4 dwell at the target.
void EmRun::G87(const BlockWords& bw, Vec2 k, const Feed& feed, bool redraw) {
  if (bw.x.set) Alarm(480, bw.x.col, "G87/G88 take Z(W) only");
  if (std::fabs(prog_.y) > 1e-6)
    Alarm(260, bw.pos_col(), fmt::format("X{:.3f}", (mon_.o11 & 1) ? 2 * prog_.y : prog_.y));
  const Vec2 s = prog_;
  double total = k.x - s.x;
  if (std::fabs(total) < 1e-9) Alarm(230, bw.pos_col(), "no drilling path");
  if (bw.d[5].set && bw.d[5].raw > 100) Alarm(200, bw.d[5].col, "D5 is at most 100 %");
  if (bw.d[4].set && bw.d[4].raw > 10000) Alarm(200, bw.d[4].col, "D4 is at most 10000");
  used_ |= 1u << kZ;
  double unit = mode_.metric ? 0.001 : 0.0001 * kInch;
  double min = bw.d[6].set ? DLen(bw, 6, 0) : mon_.s00 * unit;
  std::vector<double> pecks =
      cyc::DrillPecks(std::fabs(total), bw.d[3].set ? DLen(bw, 3, 0) : 0, bw.d[5].set ? bw.d[5].raw : 0, min);
  if (pecks.size() > cyc::kMaxCuts) Alarm(240, bw.pos_col(), "more than 10000 pecks");
  double dir = Sign(total), retract = mon_.s02 * unit;
  double done = 0;
  for (std::size_t i = 0; i < pecks.size(); ++i) {
    if (redraw && i > 0) {
      // Back into the hole to just before the last depth, then drill on.
      double again = s.x + dir * std::max(0.0, done - retract);
      CycleMove(Move::kRapid, Vec2{again, s.y}, nullptr);
    }
    done += pecks[i];
    CycleMove(Move::kLinear, Vec2{s.x + dir * done, s.y}, &feed);
    if (i + 1 < pecks.size()) {
      if (redraw) {
        CycleMove(Move::kRapid, s, nullptr);
      } else {
        CycleMove(Move::kRapid, Vec2{s.x + dir * std::max(0.0, done - retract), s.y}, nullptr);
      }
    }
  }
  if (bw.d[4].set && bw.d[4].raw > 0) {
    Canon d;
    d.line = cur_line_;
    d.Set<DwellOp>().seconds = bw.d[4].raw / 10.0;
    EmitOther(std::move(d));
  }
  CycleMove(Move::kRapid, s, nullptr);
}

}  // namespace cell::interp::emco
