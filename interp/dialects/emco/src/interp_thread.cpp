// EMCO G85 thread-cutting cycle (manual ln 3568-4404): longitudinal (X before Z, taper below 45 degrees: the
// infeed is in X, the thread runs along Z) or transverse (Z before X: the other way round). The block gives
// the thread end point K (minor diameter) or N (nominal, D7 bit 1); D6 the thread depth; D3 the first depth
// or the number of cuts (D7 bit 2), constant or decremental infeed (D7 bit 0) with the monitor's minimum
// S00; D5 the thread angle for flank infeed; D4 idle passes (monitor S01); P0/P2 the taper and the oblique
// run-out; F the pitch. Each pass: rapid infeed from S, the thread, the run-out or a rapid retract, rapid
// back to S.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "cycles.h"
#include "interp_internal.h"

namespace cell::interp::emco {

using cyc::At;
using cyc::Get;
using cyc::Sign;

void EmRun::G85(const BlockWords& bw, Vec2 k) {
  if (!bw.x.set || !bw.z.set) Alarm(480, bw.pos_col(), "G85 needs X(U) and Z(W)");
  const bool transverse = bw.z.order < bw.x.order;
  const int f = transverse ? 0 : 1, c = transverse ? 1 : 0;  // infeed axis, thread axis
  const Val& taper = transverse ? bw.p[2] : bw.p[0];
  const Val& runout = transverse ? bw.p[0] : bw.p[2];
  const Vec2 s = prog_;
  double feed_len = Get(k, f) - Get(s, f), len = Get(k, c) - Get(s, c);
  if (std::fabs(feed_len) < 1e-9 || std::fabs(len) < 1e-9)
    Alarm(230, bw.pos_col(), "S and K share a coordinate");
  if (!bw.d[3].set) Alarm(250, bw.pos_col(), "G85 needs D3");
  if (bw.d[3].raw == 0) Alarm(200, bw.d[3].col, "D3 = 0");
  if (!bw.d[6].set) Alarm(250, bw.pos_col(), "G85 needs the thread depth D6");
  int d5 = D(bw, 5, 0), d7 = D(bw, 7, 0), d4 = D(bw, 4, mon_.s01);
  double angle = 0;
  switch (d5) {
    case 0:
      break;
    case 40:
      angle = 19;
      break;
    case 55:
      angle = 26;
      break;
    case 60:
      angle = 29;
      break;
    case 80:
      angle = 39;
      break;
    default:
      Alarm(200, bw.d[5].col, "D5 is 0, 40, 55, 60 or 80");
  }
  if (d7 > 7) Alarm(200, bw.d[7].col, "D7 is 0-7");
  if (d4 > 20) Alarm(200, bw.d[4].col, "D4 is 0-20");
  const bool constant = d7 & 1, nominal = d7 & 2, count = d7 & 4;
  const double unit = mode_.metric ? 0.001 : 0.0001 * kInch;
  double depth = DLen(bw, 6, 0);
  if (depth <= 0) Alarm(200, bw.d[6].col, "D6 = 0");
  if (depth > std::fabs(len) + 1e-9) Alarm(200, bw.d[6].col, "D6 is larger than the thread length");
  if (!count && (DLen(bw, 3, 0) > depth + 1e-9 || DLen(bw, 3, 0) > std::fabs(len) + 1e-9)) {
    Alarm(240, bw.d[3].col, "D3 is larger than D6");
  }
  double lead = Lead(bw, bw.pos_col());
  used_ |= (1u << kX) | (1u << kZ);

  double dir_f = Sign(feed_len), dir_c = Sign(len);
  double sf = Get(s, f), sc = Get(s, c);
  // The thread's surface (nominal) at K's end and at S's end; the taper is K's offset from S's end (the
  // reading under which both printed forms of the transverse example ln 4380-4402 start outside the part).
  double root_k = Get(k, f) + (nominal ? dir_f * depth : 0);
  double surf_k = root_k - dir_f * depth;
  double surf_s = surf_k - (taper.set ? taper.v : 0);
  if ((surf_s - sf) * dir_f < -1e-9)
    Alarm(210, taper.col, "the taper puts the thread's start end beyond the start point");
  double kc = Get(k, c);
  double out = runout.set ? std::fabs(runout.v) : 0;  // the magnitude (printed signs disagree, ln 4215-4235)
  double tan_a = std::tan(angle * kPi / 180);

  std::vector<double> cuts =
      cyc::ThreadDepths(depth, count ? bw.d[3].raw : DLen(bw, 3, 0), count, constant, mon_.s00 * unit);
  if (cuts.size() > cyc::kMaxCuts) Alarm(240, bw.d[3].col, "more than 10000 cuts");
  for (int i = 0; i < d4; ++i) cuts.push_back(depth);  // idle passes at the full depth
  for (double cum : cuts) {
    double fs = surf_s + dir_f * cum, fk = surf_k + dir_f * cum;
    // Flank infeed: the pass starts shifted along the thread by the depth times tan(infeed angle).
    double shift = dir_c * cum * tan_a;
    double c0 = sc + shift;
    double f0 = fs + (fk - fs) * (c0 - sc) / (kc - sc);
    CycleMove(Move::kRapid, At(f, f0, c0), nullptr);
    CycleMove(Move::kThread, At(f, fk, kc), nullptr, lead);
    if (out > 0) {
      CycleMove(Move::kThread, At(f, sf, kc + dir_c * out), nullptr, lead);
    } else {
      CycleMove(Move::kRapid, At(f, sf, kc), nullptr);
    }
    CycleMove(Move::kRapid, s, nullptr);
  }
}

}  // namespace cell::interp::emco
