// Balt-System probing (manual §5.8.10, §5.20, ln 3646-3683, 6983-7534): (DPT,Qa,Qs,Vm); G72 measures a
// point (probe-radius compensated), G73 a hole's centre and radius in the plane, G74 the deviation of a
// tool against a fixed probe. Each point: rapid to Qa before the nominal point, probe at Vm up to Qs past it,
// rapid back. Results in E parameters in axis order, in the characterized unit; with ERR=1 a failed cycle
// sets IOSTA (1 no contact, 2 probe not released) and the program goes on. The trigger position comes from
// the Environment (offline --probe-model; on a station the axis servo).
#include <fmt/format.h>

#include <bit>
#include <cmath>

#include "interp_internal.h"

namespace cell::interp::balt {
namespace {

struct Dir {
  AxisArray u{};
  double len = 0;
};

Dir Direction(const AxisArray& from, const AxisArray& to) {
  Dir d;
  for (int a = 0; a < kAxisCount; ++a) {
    if (IsRotaryAxis(a)) continue;
    d.u[a] = to[a] - from[a];
    d.len += d.u[a] * d.u[a];
  }
  d.len = std::sqrt(d.len);
  if (d.len > 1e-12) {
    for (double& v : d.u) v /= d.len;
  }
  return d;
}

AxisArray Along(const AxisArray& p, const AxisArray& u, double k) {
  AxisArray r = p;
  for (int a = 0; a < kAxisCount; ++a) r[a] += k * u[a];
  return r;
}

// The circle through points in the least-squares sense (exact for points on a circle).
bool FitCircle(const std::vector<geom::Vec2>& pts, geom::Vec2* c, double* r) {
  double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0, sz = 0, sxz = 0, syz = 0;
  const double n = static_cast<double>(pts.size());
  for (auto p : pts) {
    double z = p.x * p.x + p.y * p.y;
    sx += p.x;
    sy += p.y;
    sxx += p.x * p.x;
    syy += p.y * p.y;
    sxy += p.x * p.y;
    sz += z;
    sxz += p.x * z;
    syz += p.y * z;
  }
  // [sxx sxy sx; sxy syy sy; sx sy n] [D E F]' = -[sxz syz sz]'
  double m[3][4] = {{sxx, sxy, sx, -sxz}, {sxy, syy, sy, -syz}, {sx, sy, n, -sz}};
  for (int i = 0; i < 3; ++i) {
    int piv = i;
    for (int k = i + 1; k < 3; ++k) {
      if (std::fabs(m[k][i]) > std::fabs(m[piv][i])) piv = k;
    }
    if (std::fabs(m[piv][i]) < 1e-12) return false;
    for (int k = 0; k < 4; ++k) std::swap(m[i][k], m[piv][k]);
    for (int k = 0; k < 3; ++k) {
      if (k == i) continue;
      double f = m[k][i] / m[i][i];
      for (int l = 0; l < 4; ++l) m[k][l] -= f * m[i][l];
    }
  }
  double D = m[0][3] / m[0][0], E = m[1][3] / m[1][1], F = m[2][3] / m[2][2];
  *c = {-D / 2, -E / 2};
  double r2 = c->x * c->x + c->y * c->y - F;
  if (r2 <= 0) return false;
  *r = std::sqrt(r2);
  return true;
}

}  // namespace

// (DPT,Qa,Qs,Vm): approach and safety distances (mm) and the measuring feed (mm/min) (ln 7018-7035).
void BaltRun::CmdDpt(const Command& c) {
  CheckOperands(c, 3, 3);
  double qa = OperandNumber(c.ops[0]), qs = OperandNumber(c.ops[1]), vm = OperandNumber(c.ops[2]);
  if (qa < 0) Fail(c.ops[0].col, 13, "Qa is not negative");
  if (qs <= 0) Fail(c.ops[1].col, 13, "Qs is positive");
  if (vm <= 0) Fail(c.ops[2].col, 13, "Vm is positive");
  dpt_ = true;
  dpt_qa_ = qa;
  dpt_qs_ = qs;
  dpt_vm_ = vm;
}

void BaltRun::ProbeFailed(int code, int col) {
  if (err_ == 1) {
    iosta_ = code == 8 ? 1 : 2;  // ln 7451-7461
    return;
  }
  Fail(col, code,
       code == 8 ? "no contact within the safety distance Qs" : "the probe was touching at the start");
}

// One probe move: `from` to `to` (machine coordinates of the point that touches); true with `hit` set on
// contact. Emits the probe op at the probe's centre (the touching point less `lead` along the move).
bool BaltRun::ProbeMove(int g, const AxisArray& from, const AxisArray& to, double lead, AxisArray* hit) {
  Dir d = Direction(from, to);
  interp::ProbeMove move;
  move.from = from;
  move.to = to;
  ProbeResult pr = env_->Probe(move);
  ProbeOp& op = Out<ProbeOp>();
  op.g = g;
  op.feed = {dpt_vm_, FeedMode::kPerMinute, true};
  AxisArray stop = pr.already ? from : (pr.event ? pr.at : to);
  for (int a = 0; a < kAxisCount; ++a) {
    if (IsRotaryAxis(a)) stop[a] = from[a];
  }
  op.result = pr.already ? ProbeOutcome::kAlready : (pr.event ? ProbeOutcome::kContact : ProbeOutcome::kNone);
  AxisArray centre = Along(stop, d.u, -lead);
  for (int a = 0; a < kAxisCount; ++a) {
    if (!IsRotaryAxis(a) && std::fabs(d.u[a]) > 1e-12) used_ |= 1u << a;
  }
  op.to.pos = centre;
  op.to.used = used_;
  pos_ = centre;
  FrameChanged();
  if (pr.event && !pr.already) {
    *hit = stop;
    return true;
  }
  return false;
}

void BaltRun::Probe(const ParsedBlock& pb, const BlockG& g, const Targets& t) {
  const int col = g.first_col;
  if (contour_.engaged() || gtl_profile_) Fail(col, 25, "probing with compensation or in a GTL profile");
  if (mode_.cycle != 80) Fail(col, 25, "probing in a fixed cycle");
  if (!dpt_) Fail(col, 30, "program (DPT,Qa,Qs,Vm) first");
  if (pb.result_e < 0) Fail(col, 12, fmt::format("G{} needs the E parameter for its results", g.probe));
  const double out_unit = basic_metric_ ? 1.0 : kInch;    // results in the characterized unit (ln 3281)
  const double rb = g.probe == 74 ? 0.0 : tool_dia_ / 2;  // the probe ball (the offset's K)
  const AxisArray start = pos_;
  const AxisArray start_prog = Prog();
  iosta_ = 0;
  auto store = [&](int k, double v) { SetParam(pb.result_e + k, v / out_unit, pb.result_col); };
  auto rapid_to = [&](const AxisArray& m) {
    geom::Path none;
    none.start = {pos_[mode_.p1], pos_[mode_.p2]};
    none.end = {m[mode_.p1], m[mode_.p2]};
    std::uint32_t moved = 0;
    for (int a = 0; a < kAxisCount; ++a) {
      if (!IsRotaryAxis(a) && std::fabs(m[a] - pos_[a]) > 1e-9) moved |= 1u << a;
    }
    EmitMotion(Op::kRapid, m, moved, Feed{}, none, {}, 0, 0);
  };

  if (g.probe == 73) {
    const Word* r = nullptr;
    for (const Word& w : pb.words) {
      if (w.letter == 'r' || w.letter == 'R') r = &w;  // ln 703 prints R100, ln 7084 r50: both read
      if (AxisOfLetter(w.letter) >= 0) Fail(w.col, 24, "G73 starts at the hole's centre: no axes");
    }
    if (!r) Fail(col, 12, "G73 needs the nominal radius r");
    const double nominal = ValueOf(r->v, r->col) * UnitFactor();
    if (nominal <= 0) Fail(r->col, 13, "the nominal radius is positive");
    std::vector<geom::Vec2> pts;
    static constexpr double kDirs[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
    for (const auto& dv : kDirs) {
      AxisArray pa = start_prog, pe = start_prog;
      double from_r = std::max(0.0, nominal - dpt_qa_);
      pa[mode_.p1] += from_r * dv[0];
      pa[mode_.p2] += from_r * dv[1];
      pe[mode_.p1] += (nominal + dpt_qs_) * dv[0];
      pe[mode_.p2] += (nominal + dpt_qs_) * dv[1];
      AxisArray ma = ToMachine(pa), me = ToMachine(pe);
      Dir d = Direction(ma, me);
      rapid_to(ma);
      AxisArray hit;
      bool ok = ProbeMove(73, Along(ma, d.u, rb), Along(me, d.u, rb), rb, &hit);
      rapid_to(start);
      if (!ok) {
        ProbeFailed(8, col);
        prog_ = start_prog;
        prog_valid_ = true;
        return;
      }
      AxisArray p = ToProgram(hit);
      pts.push_back({p[mode_.p1], p[mode_.p2]});
    }
    geom::Vec2 c;
    double radius = 0;
    if (!FitCircle(pts, &c, &radius)) Fail(col, 77, "the measured points give no circle");
    store(0, c.x - rta_);
    store(1, c.y - rto_);
    store(2, radius);
    prog_ = start_prog;
    prog_valid_ = true;
    return;
  }

  if (t.mask == 0) Fail(col, 12, fmt::format("G{} needs the nominal coordinates", g.probe));
  if (std::popcount(t.mask) > 3) Fail(col, 23, "at most 3 axes");
  AxisArray nominal = ToMachine(t.prog);
  Dir d = Direction(start, nominal);
  if (d.len < 1e-9) Fail(col, 77, "the probe is at the nominal point: no direction to measure in");
  AxisArray pa = Along(nominal, d.u, -dpt_qa_), pe = Along(nominal, d.u, dpt_qs_);
  rapid_to(pa);
  AxisArray hit;
  bool ok = ProbeMove(g.probe, Along(pa, d.u, rb), Along(pe, d.u, rb), rb, &hit);
  rapid_to(start);
  prog_ = start_prog;
  prog_valid_ = true;
  if (!ok) {
    ProbeFailed(8, col);
    return;
  }
  AxisArray measured = ToProgram(hit);
  int k = 0;
  for (int a = 0; a < kAxisCount; ++a) {
    if (!(t.mask & (1u << a))) continue;
    double v = measured[a];
    if (g.probe == 74) {
      v -= t.prog[a];  // the deviation from the nominal coordinate (ln 706-714)
    } else if (a == mode_.p1) {
      v -= rta_;
    } else if (a == mode_.p2) {
      v -= rto_;
    }
    store(k++, v);
  }
}

}  // namespace cell::interp::balt
