// What a plot keeps of a run: its moves in X Y Z (X as a radius) and its annotations. Drawing is svg.cpp.
#include <cmath>

#include <fmt/format.h>

#include "cell/interp/plot.h"

namespace cell::interp {

namespace {

// "90", "12.5", "-0.125": a value as a person writes it (at most 3 decimals).
std::string Short(double v) {
  std::string s = fmt::format("{:.3f}", v);
  while (s.back() == '0') s.pop_back();
  if (s.back() == '.') s.pop_back();
  return s == "-0" ? "0" : s;
}

// The plane of an arc as X Y Z indices, or -1 when one of its axes is a rotary or a co-axis (U V W): the
// plot tracks X Y Z only, so such an arc is drawn as its chord.
int PlotAxis(int axis) {
  return axis >= kX && axis <= kZ ? axis : -1;
}

}  // namespace

ViewArc ToViewArc(double sx, double sy, double cx, double cy, bool ccw, double angle) {
  ViewArc a;
  a.r = std::hypot(sx - cx, sy - cy);
  a.large = angle > 180;
  // Counter-clockwise with the second axis up is counter-clockwise on the page too, and SVG's sweep-flag 1
  // is the clockwise sense on the page (its y axis points down).
  a.sweep = !ccw;
  return a;
}

Plot::Plot(PlotOptions options) : options_(std::move(options)) {}

std::array<double, 3> Plot::Point(const Target& t) const {
  return {diameter_ ? t.pos[kX] / 2 : t.pos[kX], t.pos[kY], t.pos[kZ]};
}

void Plot::AddLabel(std::string text) {
  if (started_)
    labels_.push_back({at_, std::move(text)});
  else
    pending_.push_back(std::move(text));
}

void Plot::AddMove(const Canon& c, MoveKind kind, const Target& to) {
  const std::array<double, 3> p = Point(to);
  if (!started_) {
    started_ = true;
    start_ = at_ = p;
    for (auto& text : pending_) labels_.push_back({p, std::move(text)});
    pending_.clear();
    return;
  }
  Move m;
  m.kind = kind;
  m.line = c.line;
  m.block = block_;
  m.from = at_;
  m.to = p;
  if (const auto* arc = c.If<ArcOp>()) {
    m.center = {diameter_ ? arc->center[0] / 2 : arc->center[0], arc->center[1], arc->center[2]};
    m.first = PlotAxis(arc->plane.first);
    m.second = PlotAxis(arc->plane.second);
    m.cw = arc->cw;
    m.angle = arc->angle;
  }
  if (const auto* probe = c.If<ProbeOp>()) m.contact = probe->result == ProbeOutcome::kContact;
  moves_.push_back(m);
  at_ = p;
}

void Plot::Add(const Canon& c) {
  if (c.line != last_line_) {
    last_line_ = c.line;
    ++block_;
  }
  switch (c.op()) {
    case Op::kUnits:
      diameter_ = c.As<UnitsOp>().x_mode == XMode::kDiameter;
      break;
    case Op::kRapid: {
      const Target& t = c.As<RapidOp>().to;
      AddMove(c, MoveKind::kRapid, t);
      // An index of a rotary axis turns the part: what follows is drawn in the new orientation.
      for (int a : {kA, kB, kC})
        if (t.travel_mask & (1u << a))
          AddLabel(fmt::format("{}{}°", static_cast<char>('A' + a - kA), Short(t.pos[a])));
      break;
    }
    case Op::kLinear:
      AddMove(c, MoveKind::kFeed, c.As<LinearOp>().to);
      break;
    case Op::kArc:
      AddMove(c, MoveKind::kArc, c.As<ArcOp>().to);
      break;
    case Op::kThread:
      AddMove(c, MoveKind::kThread, c.As<ThreadOp>().to);
      break;
    case Op::kProbe:
      AddMove(c, MoveKind::kProbe, c.As<ProbeOp>().to);
      break;
    case Op::kRegrid:
      // The position registers are reloaded: the same place has new coordinates, no motion.
      at_ = Point(c.As<RegridOp>().to);
      break;
    case Op::kToolChange: {
      const auto& t = c.As<ToolChangeOp>();
      AddLabel(t.offset > 0 ? fmt::format("T{} (offset {})", t.tool, t.offset) : "T" + t.tool);
      break;
    }
    default:
      break;
  }
}

int Plot::Drawn(MoveKind kind) const {
  int n = 0;
  for (const Move& m : moves_) n += m.kind == kind;
  return n;
}

}  // namespace cell::interp
