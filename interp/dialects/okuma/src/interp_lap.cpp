// The executor's side of LAP (manual SECTION 8, seed ln 4939-6434): G85/G86/G88 find the contour definition
// by its sequence name and run its blocks with their motion captured (CALLs, variables and G75/G76 inside the
// contour work as anywhere else), G84 change points on continuation lines, G87 runs the contour as written;
// the rough tool path is computed at G80 (lap.cpp) and the modes in force at the call are restored (ln 6202-
// 6237). No LAP inside LAP, none in nose radius compensation mode, a turret change inside is an alarm.
#include <fmt/format.h>

#include <cmath>

#include "interp_internal.h"

namespace cell::interp::okuma {

void OkRun::LapCall(const BlockWords& w, const Block& b, int g, int col) {
  if (lap_.active || lap_.finish) Fail(col, "LAP cannot be nested");
  if (modal_.comp != 40 || comp_.on()) Fail(col, "LAP called in nose radius compensation mode (G41/G42)");
  if (w.Has('S') || w.Has('T')) Fail(w.Has('S') ? w.Col('S') : w.Col('T'), "no S or T in a LAP call block");
  for (const auto& m : w.m) {
    const bool allowed =
        m.code == 85 || (g == 88 && ((m.code >= 32 && m.code <= 34) || (m.code >= 73 && m.code <= 75)));
    if (!allowed) Fail(m.col, fmt::format("M{} is not allowed in a G{} block", m.code, g));
  }
  LapParams p;
  p.transverse = false;  // known at G81/G82
  p.relief = lap_relief_;
  p.clearance = lap_clearance_;
  p.m85 = w.HasM(85);
  if (g != 87) {
    if (!w.Has('D') || w.Get('D') <= 0)
      Fail(w.Has('D') ? w.Col('D') : col, fmt::format("G{} needs D > 0", g));
    p.d = w.Get('D');
  }
  if (w.Has('F')) {
    if (w.Get('F') <= 0) Fail(w.Col('F'), "the LAP feed F must be positive");
  }
  p.f = f_;
  if (p.f <= 0 && (g == 85 || g == 86)) Fail(col, "no feedrate for the rough cycle (F)");
  for (char a : {'U', 'W'}) {
    if (w.Has(a) && w.Get(a) < 0) Fail(w.Col(a), fmt::format("{} must not be negative", a));
  }
  p.u = w.Has('U') ? w.Get('U') : 0;
  p.w = w.Has('W') ? w.Get('W') : 0;
  if (g == 88) {
    if (!w.Has('H') || w.Get('H') <= 0)
      Fail(w.Has('H') ? w.Col('H') : col, "G88 needs the thread height H > 0");
    p.h = w.Get('H');
    p.tip_angle = w.Has('B') ? w.Get('B') : 0;
    if (p.tip_angle < 0 || p.tip_angle > 180) Fail(w.Col('B'), "B is 0-180 degrees");
    p.thread_mode = modal_.thread_mode;
    p.infeed = modal_.infeed;
  }
  // G84 change points (continuation lines of the call): XA= DA= FA= / XB= DB= FB= (ZA=, ZB= transverse).
  auto change = [&](LapChange& c, int xi, int zi, int di, int fi, char ab) {
    if (w.HasExt(xi) || w.HasExt(zi)) {
      c.set = true;
      c.at = w.HasExt(xi) ? ToMachine(kX, w.ext[static_cast<size_t>(xi)]) / 2
                          : ToMachine(kZ, w.ext[static_cast<size_t>(zi)]);
      c.axis_x = w.HasExt(xi);
    }
    if (w.HasExt(di)) c.d = w.ext[static_cast<size_t>(di)];
    // FA/FB are feeds like F and E, in the unit system's feed unit (ln 1048-1059, 5087-5088).
    if (w.HasExt(fi)) c.f = Scale('F', w.ext[static_cast<size_t>(fi)], modal_.per_rev);
    for (int i : {di, fi}) {
      if (w.HasExt(i) && w.ext[static_cast<size_t>(i)] <= 0) {
        Fail(w.ext_col[static_cast<size_t>(i)],
             fmt::format("{}{} must be positive", i == di ? 'D' : 'F', ab));
      }
    }
  };
  change(p.a, 7, 9, 3, 5, 'A');
  change(p.b, 8, 10, 4, 6, 'B');
  auto found = FindSequence(b.label, true);
  if (!found) Fail(b.label_col, fmt::format("LAP contour {} not found in this program", b.label));
  lap_ = LapState();
  lap_.g = g;
  lap_.call_line = cur_line_;
  lap_.params = p;
  lap_.start = pos_;
  lap_.modal = modal_;
  lap_.f = f_;
  lap_.e = e_;
  lap_.used = used_;
  if (g == 87) {
    lap_.finish = true;
  } else {
    lap_.active = true;
  }
  EndBlockStages(false);
  auto& top = frames_->top();
  const int call_line = cur_line_;
  TextSpan span{top.span.text, found->pos, top.span.end, found->line, true};
  const bool own = top.report_own;
  const int modin_limit = top.data.modin_limit;
  const size_t begin = top.data.program_begin;
  const int begin_line = top.data.program_begin_line;
  auto& f = frames_->Push(std::move(span), b.label);
  // The rough cycle's commands carry the calling block's line; G87 runs the contour's own blocks.
  f.report_own = g == 87 ? own : false;
  f.call_line = call_line;
  f.data.kind = FrameData::kLap;
  f.data.modin_limit = modin_limit;
  f.data.program_begin = begin;
  f.data.program_begin_line = begin_line;
  f.data.tape_started = true;
  lap_.depth = frames_->depth();
}

void OkRun::LapBlock(const Block& b, const BlockWords& w) {
  if (frames_->depth() != lap_.depth) Fail(b.seq_col, "a contour definition cannot start inside another one");
  const bool g83 = w.HasG(83);
  if (g83) {
    if (lap_.have_contour || lap_.blank) Fail(b.seq_col, "G83 (blank shape) must come before G81/G82");
    if (lap_.finish) {
      // G87 on the blank's name: the blank shape is ignored (ln 6246).
      int first = cur_line_;
      for (;;) {
        const Block* n = ReadBlock(&first);
        if (!n) Fail(1, "blank shape (G83) without G81/G82");
        bool start = false;
        for (const Word& wd : n->words) {
          if (wd.addr == MakeAddr('G') && !wd.expr && (wd.num == 81 || wd.num == 82)) start = true;
        }
        if (start) {
          BlockWords ww;
          CollectWords(*n, ww);
          lap_.transverse = ww.HasG(82);
          lap_.have_contour = true;
          lap_.first_block_seen = false;
          return;
        }
      }
    }
    lap_.blank = true;
    lap_.first_block_seen = false;
    lap_.capture_started = false;
    pos_ = lap_.start;
    return;
  }
  if (lap_.have_contour) Fail(b.seq_col, "a second contour definition before G80");
  lap_.transverse = w.HasG(82);
  lap_.blank = false;
  lap_.have_contour = true;
  lap_.first_block_seen = false;
  lap_.capture_started = false;
  if (lap_.active) pos_ = lap_.start;
  EndBlockStages(false);
}

void OkRun::LapCapture(Staged& q) {
  if (!IsMove(q.c.op())) return;
  const Target& t = *q.c.target();
  const geom::Vec2 end = PlaneOf(t.pos);
  if (!lap_.capture_started) {
    // The first block of a shape positions at its start point.
    lap_.capture_started = true;
    lap_.capture_at = end;
    lap_.first_block_seen = true;
    if (!lap_.blank) lap_.first_rapid = q.c.op() == Op::kRapid;
    return;
  }
  LapElement e;
  e.path.start = lap_.capture_at;
  e.path.end = end;
  if (const ArcOp* a = q.c.If<ArcOp>()) {
    e.path.arc = true;
    e.path.center = {a->center[2], a->center[0] / 2};
    e.path.cw = a->cw;
    e.path.sweep = a->angle;
    e.f = a->feed.rate;
  } else if (const LinearOp* l = q.c.If<LinearOp>()) {
    e.f = l->feed.rate;
  } else if (const ThreadOp* th = q.c.If<ThreadOp>()) {
    e.thread = true;
    e.lead = th->lead;
    e.lead_change = th->lead_change;
  } else {
    e.rapid = true;
  }
  e.e = q.efeed;
  if (geom::Norm(e.path.end - e.path.start) < 1e-9 && !e.path.arc) return;
  (lap_.blank ? lap_.blank_shape : lap_.contour).push_back(e);
  lap_.capture_at = end;
}

void OkRun::LapEndCapture(int col) {
  if (frames_->depth() != lap_.depth) Fail(col, "G80 inside a subprogram called from the contour definition");
  if (!lap_.have_contour) Fail(col, "G80 without G81/G82");
  if (modal_.comp != 40) Fail(col, "cancel nose radius compensation (G40) at or before G80");
  PopLocals(static_cast<int>(frames_->depth()));
  frames_->Pop();
  if (lap_.finish) {
    lap_.finish = false;
    LapRestore();
    return;
  }
  if (staged_) Commit();
  corner_.Finish();
  lap_.active = false;
  LapParams p = lap_.params;
  p.transverse = lap_.transverse;
  const int g = lap_.g;
  const bool x_infeed = !p.transverse;
  // The words of the call in the plane's units: X values (D, U) as radii on the X axis.
  if (x_infeed) p.d /= 2;
  p.u /= 2;
  for (LapChange* c : {&p.a, &p.b}) {
    if (c->set && c->axis_x != x_infeed) {
      Fail(col, p.transverse ? "XA/XB change points are for longitudinal contours: use ZA/ZB"
                             : "ZA/ZB change points are for transverse contours: use XA/XB");
    }
    if (x_infeed) c->d /= 2;
  }
  if (lap_.contour.empty()) {
    // A contour of one block: its positioning is its only element.
    Fail(col, "LAP: the contour definition has no element after its first block");
  }
  if (!lap_.contour.empty()) lap_.contour.front().rapid = lap_.first_rapid;
  std::vector<LapMove> moves;
  const geom::Vec2 start = PlaneOf(lap_.start);
  if (g == 88) {
    const bool has_u = p.transverse ? lap_.params.w > 0 : lap_.params.u > 0;
    const double h = lap_.params.h, u = p.transverse ? lap_.params.w : lap_.params.u;
    std::vector<double> depths =
        InfeedDepths(p.d * (x_infeed ? 2 : 1), h, u, p.infeed, p.thread_mode, has_u, col);
    for (double& d : depths) d = x_infeed ? d / 2 : d;
    p.h = x_infeed ? h / 2 : h;
    moves = LapThread(p, start, lap_.contour, depths);
  } else {
    p.mode = g == 85 ? (lap_.blank_shape.empty() ? 1 : 4) : (lap_.blank_shape.empty() ? 2 : 5);
    moves = LapRough(p, start, lap_.contour, lap_.blank_shape);
  }
  // The rough cycle's commands, on the calling block's line, in the modes in force at the call.
  LapRestore();
  pos_ = lap_.start;
  const int saved_line = cur_line_;
  const bool saved_own = cur_own_;
  cur_line_ = lap_.call_line;
  for (const LapMove& m : moves) {
    AxisArray t = pos_;
    SetPlane(t, m.to);
    const uint32_t xz = (1u << kX) | (1u << kZ);
    switch (m.kind) {
      case LapMove::kRapid:
        EmitMove(t, xz, true, 0, FeedModeNow(), {}, 0, nullptr);
        break;
      case LapMove::kLinear:
        EmitMove(t, xz, false, m.f, FeedModeNow(), {}, 0, nullptr);
        break;
      case LapMove::kThread:
        EmitThread(t, m.lead, m.lead_change, m.start_angle, m.lead_along_x);
        break;
      case LapMove::kArc: {
        used_ |= xz;
        pos_ = t;
        ArcOp& a = Out<ArcOp>();
        a.to.pos = pos_;
        a.to.used = used_;
        a.feed = {m.f, FeedModeNow(), modal_.droop};
        a.center = {2 * m.center.y, pos_[kY], m.center.x};
        a.cw = m.cw;
        a.plane = {static_cast<std::int8_t>(kZ), static_cast<std::int8_t>(kX)};
        a.angle = m.sweep;
        break;
      }
    }
  }
  cur_line_ = saved_line;
  cur_own_ = saved_own;
}

void OkRun::LapRestore() {
  // ln 6220-6231: the modes in force at the call come back after the LAP.
  const Modal m = lap_.modal;
  modal_.motion = m.motion;
  modal_.incremental = m.incremental;
  modal_.per_rev = m.per_rev;
  modal_.css = m.css;
  modal_.droop = m.droop;
  f_ = lap_.f;
  chain_.active = false;
}

}  // namespace cell::interp::okuma
