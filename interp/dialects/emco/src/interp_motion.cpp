// EMCO motion (manual ln 1027-1086, 1956-2149, 2302-2355, DC 5.10 ln 55-116): X as a diameter (or a radius,
// monitor O11 bit 0) with U and I as radius values, absolute and incremental mixed in one block, G00, G01,
// G02/G03 (clockwise seen with Z to the right and X up; one centre coordinate may be left for the control
// to derive), G33, the feed (G94 mm/min, G95 um/rev), chamfer/radius requests, and the pipeline that takes
// every command to the output: the look-ahead stages when they are engaged, the tool offset, the software
// limits.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "cell/interp/geometry/arc.h"
#include "interp_internal.h"

namespace cell::interp::emco {

Correction LookUp(const tooltable::ToolTable& tools, int corr) {
  Correction c;
  if (corr <= 0) return c;
  char name[12];
  std::snprintf(name, sizeof name, "%d", corr);
  if (const tooltable::ToolEntry* e = tools.Find(name)) {
    c.x = e->x_offset;
    c.z = e->z_offset;
    c.r = e->nose_radius;
    c.tip = e->tip;
  }
  return c;
}

Vec2 EmRun::Shift() const {
  return pso_[mode_.shift_a] + pso_[mode_.shift_b];
}

Vec2 EmRun::ToWork(Vec2 prog) const {
  if (scaling_) prog = scale_ref_ + scale_ * (prog - scale_ref_);
  return prog + Shift();
}

Vec2 EmRun::Target(const BlockWords& bw) const {
  Vec2 to = prog_;
  if (bw.x.set) to.y = bw.x_inc ? prog_.y + bw.x.v : ((mon_.o11 & 1) ? bw.x.v / 2 : bw.x.v);
  if (bw.z.set) to.x = bw.z_inc ? prog_.x + bw.z.v : bw.z.v;
  return to;
}

// The block's feed (ln 913-922, 4841-4855): G94 mm/min (1/100 in/min), G95 um/rev (1/10000 in/rev). A feed
// move needs F, and per revolution a turning spindle with S (ALARM 170).
double EmRun::FeedRate(const BlockWords& bw, int col, Feed& out) const {
  if (feed_ <= 0) Alarm(170, bw.f.set ? bw.f.col : col, "no F");
  out.exact_stop = mode_.exact_stop;
  if (mode_.per_min) {
    out.mode = FeedMode::kPerMinute;
    out.rate = mode_.metric ? feed_ : feed_ * 0.254;
  } else {
    if (mode_.spindle != 3 && mode_.spindle != 4)
      Alarm(170, col, "feed per revolution with the spindle stopped");
    if (speed_ <= 0) Alarm(170, col, "feed per revolution with S = 0");
    out.mode = FeedMode::kPerRev;
    out.rate = mode_.metric ? feed_ / 1000.0 : feed_ * 0.00254;
  }
  return out.rate;
}

// The pitch of G33/G85 in mm (F in um or 1/10000 inch, ln 2304, 3796); threads need a turning spindle.
double EmRun::Lead(const BlockWords& bw, int col) {
  if (pitch_ <= 0) Alarm(170, bw.f.set ? bw.f.col : col, "no thread pitch F");
  if ((mode_.spindle != 3 && mode_.spindle != 4) || speed_ <= 0) {
    Alarm(170, col, "thread cutting with the spindle stopped");
  }
  double lead = mode_.metric ? pitch_ / 1000.0 : pitch_ * 0.00254;
  return scaling_ ? lead * scale_ : lead;  // pitches are scaled too (ln 184-186)
}

void EmRun::MotionBlock(const BlockWords& bw, Motion motion) {
  int col = bw.pos_col();
  // After a T or zero shift change only G00 may move (ALARM 490, ln 1462-1478, 1629-1647).
  if (offset_changed_) {
    if (motion != Motion::kRapid) Alarm(490, col);
    offset_changed_ = false;
  }
  if (scale_first_move_) {
    if (bw.x_inc || bw.z_inc) Alarm(372, col);
    scale_first_move_ = false;
  }
  if (bw.x.set) used_ |= 1u << kX;
  if (bw.z.set) used_ |= 1u << kZ;
  Vec2 to = Target(bw);
  switch (motion) {
    case Motion::kRapid:
    case Motion::kLinear: {
      Move m;
      m.kind = motion == Motion::kRapid ? Move::kRapid : Move::kLinear;
      if (motion == Motion::kLinear) FeedRate(bw, col, m.feed);
      m.end = ToWork(to);
      m.used = used_;
      m.line = cur_line_;
      m.col = col;
      bool p0 = bw.p[0].set, p1 = bw.p[1].set;
      if (motion == Motion::kLinear && (p0 || p1)) {
        // DC 5.10: a radius (P0) or chamfer (P1) into the corner with the next G01 (ln 55-116).
        if (p0 && p1) Alarm(480, bw.p[1].col, "P0 and P1 in one block");
        const Val& p = p0 ? bw.p[0] : bw.p[1];
        if (!bw.x.set || !bw.z.set) Alarm(382, p.col, "the block needs both X(U) and Z(W)");
        if (p.v < 0) Alarm(391, p.col);
        Vec2 start = ToWork(prog_);
        prog_ = to;
        double size = scaling_ ? p.v * scale_ : p.v;
        if (size > 0) {
          corner_.Hold(std::move(m), start, size, p1);
          return;
        }
      }
      prog_ = to;
      EmitMove(std::move(m));
      return;
    }
    case Motion::kCw:
    case Motion::kCcw: {
      Feed f;
      FeedRate(bw, col, f);
      Arc(bw, motion == Motion::kCw, to, f);
      return;
    }
    case Motion::kThread:
      Thread33(bw, to);
      return;
    case Motion::kG84:
    case Motion::kG86:
    case Motion::kG87:
    case Motion::kG88: {
      Feed f;
      FeedRate(bw, col, f);
      if (motion == Motion::kG84) {
        G84(bw, to, f);
      } else if (motion == Motion::kG86) {
        G86(bw, to, f);
      } else {
        G87(bw, to, f, motion == Motion::kG88);
      }
      return;
    }
    case Motion::kG85:
      G85(bw, to);
      return;
    case Motion::kNone:
      return;
  }
}

// G02/G03 with I (radius) and K from the start point (ln 2050-2149). Both may be given (checked against each
// other), or only the one of the axis with the shorter travel; the other is derived (alarms 160/180).
void EmRun::Arc(const BlockWords& bw, bool cw, Vec2 to, const Feed& feed) {
  bool comp = comp_.on() || comp_request_ != 0;
  int bad = comp ? 540 : 160, wrong = comp ? 540 : 180, large = comp ? 560 : 190;
  Vec2 s = prog_;
  double dx = to.x - s.x, dy = to.y - s.y;  // Z travel, X travel (radius)
  int col = bw.i.set ? bw.i.col : (bw.k.set ? bw.k.col : bw.pos_col());
  double i = bw.i.v, k = bw.k.v;
  if (!bw.i.set && !bw.k.set) Alarm(bad, bw.pos_col(), "no centre coordinate");
  if (bw.i.set && !bw.k.set) {
    if (std::fabs(dy) > std::fabs(dx)) Alarm(wrong, col, "give K: Z has the shorter travel");
    if (std::fabs(dx) < 1e-9) Alarm(bad, col, "K cannot be derived");
    k = (dx * dx + dy * dy - 2 * i * dy) / (2 * dx);
  } else if (bw.k.set && !bw.i.set) {
    if (std::fabs(dx) > std::fabs(dy)) Alarm(wrong, col, "give I: X has the shorter travel");
    if (std::fabs(dy) < 1e-9) Alarm(bad, col, "I cannot be derived");
    i = (dx * dx + dy * dy - 2 * k * dx) / (2 * dy);
  }
  Vec2 c = s + Vec2{k, i};
  geom::ArcSolution a = geom::ArcFromCenter(s, to, c, cw, 0, 0.01);
  if (a.error == geom::ArcError::kRadiiDiffer) {
    Alarm(bad, col, fmt::format("start radius {:.3f}, end radius {:.3f}", a.radius_start, a.radius_end));
  }
  if (a.radius_start < 1e-6) Alarm(bad, col, "radius 0");
  if (a.radius_start > 9999.999) Alarm(large, col);
  Move m;
  m.kind = Move::kArc;
  m.feed = feed;
  m.end = ToWork(to);
  m.center = ToWork(c);
  m.cw = cw;
  m.sweep = a.sweep;
  used_ |= (1u << kX) | (1u << kZ);
  m.used = used_;
  m.line = cur_line_;
  m.col = bw.pos_col();
  prog_ = to;
  EmitMove(std::move(m));
}

// G33: one spindle-synchronised pass to the target (ln 2302-2355); F is the pitch along Z below 45 degrees
// of taper, along X above, which is the major axis of ThreadOp.
void EmRun::Thread33(const BlockWords& bw, Vec2 to) {
  Move m;
  m.kind = Move::kThread;
  m.lead = Lead(bw, bw.pos_col());
  m.end = ToWork(to);
  m.used = used_;
  m.line = cur_line_;
  m.col = bw.pos_col();
  prog_ = to;
  EmitMove(std::move(m));
}

// ---------------------------------------------------------------------------------------------------------
// The pipeline: executor -> chamfer/radius insertion -> nose radius compensation -> output. Each stage is
// skipped while it holds nothing (the common case costs one test).

void EmRun::EmitMove(Move&& m) {
  if (!corner_.engaged() && !comp_.engaged()) {
    WriteMove(m);  // no Item: building one zeroes its Canon too, for every move
    return;
  }
  Item it;
  it.m = std::move(m);
  Route(std::move(it), 0);
}

void EmRun::EmitOther(Canon&& c) {
  Item it;
  it.is_move = false;
  it.c = std::move(c);
  Route(std::move(it), 0);
}

void EmRun::Route(Item&& it, int stage) {
  if (stage < 1 && corner_.engaged()) {
    corner_.Take(std::move(it));
  } else if (stage < 2 && comp_.engaged()) {
    comp_.Take(std::move(it));
  } else {
    Write(std::move(it));
  }
}

void EmRun::Write(Item&& it) {
  if (it.is_move) {
    WriteMove(it.m);
    return;
  }
  EmitUnits();
  idle_ = 0;
  out_.push_back(std::move(it.c));
}

// Software limits R03/R06 (X, diameter) and R05/R08 (Z) of the slides (ALARM 440, ln 6914).
void EmRun::CheckLimits(double x, double z, int line, int col) const {
  (void)line;
  auto beyond = [](const std::optional<double>& lim, double v, bool plus) {
    return lim && (plus ? v > *lim + 1e-9 : v < *lim - 1e-9);
  };
  if (beyond(mon_.limit_x_plus, x, true) || beyond(mon_.limit_x_minus, x, false)) {
    Alarm(440, col, fmt::format("X{:.3f}", x));
  }
  if (beyond(mon_.limit_z_plus, z, true) || beyond(mon_.limit_z_minus, z, false)) {
    Alarm(440, col, fmt::format("Z{:.3f}", z));
  }
}

// Work position (Z, X radius) -> machine position: X on the diameter, the active tool correction added.
void EmRun::WriteMove(const Move& m) {
  double x = 2 * m.end.y + tool_off_.y;
  double z = m.end.x + tool_off_.x;
  bool same = out_known_ && std::fabs(x - out_x_) < 1e-9 && std::fabs(z - out_z_) < 1e-9;
  if (same && m.kind != Move::kArc) return;  // a block that commands the current position does not move
  CheckLimits(x, z, m.line, m.col);
  // Only a move that reaches the output counts as motion: a G27 loop of blocks to the current position is
  // still an endless loop without motion.
  idle_ = 0;
  EmitUnits();
  out_x_ = x;
  out_z_ = z;
  out_known_ = true;
  cell::interp::Target* to = nullptr;
  switch (m.kind) {
    case Move::kRapid:
      to = &out_.Emplace<RapidOp>(m.line).to;
      break;
    case Move::kLinear: {
      LinearOp& l = out_.Emplace<LinearOp>(m.line);
      l.feed = m.feed;
      to = &l.to;
      break;
    }
    case Move::kArc: {
      ArcOp& a = out_.Emplace<ArcOp>(m.line);
      a.feed = m.feed;
      a.center = {2 * m.center.y + tool_off_.y, 0, m.center.x + tool_off_.x};
      a.cw = m.cw;
      a.plane = {kZ, kX};
      a.angle = m.sweep;
      to = &a.to;
      break;
    }
    case Move::kThread: {
      ThreadOp& t = out_.Emplace<ThreadOp>(m.line);
      t.lead = m.lead;
      to = &t.to;
      break;
    }
  }
  to->pos[kX] = x;
  to->pos[kZ] = z;
  to->used = m.used;
}

}  // namespace cell::interp::emco
