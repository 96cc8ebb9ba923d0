#include "cell/station/to_segment.h"

#include <cmath>

namespace cell::station {

namespace {

void SetTarget(cell::MotionSegment& s, const interp::Target& t) {
  uint16_t mask = 0;
  for (int i = 0; i < interp::kAxisCount; ++i) {
    s.target()[static_cast<size_t>(i)] = t.pos[static_cast<size_t>(i)];
    if (t.used & (1u << i)) mask = static_cast<uint16_t>(mask | (1u << i));
  }
  s.axis_mask(mask);
}

void SetFeed(cell::MotionSegment& s, const interp::Feed& f) {
  s.feed(f.rate);
  s.feed_mode(f.mode == interp::FeedMode::kPerRev ? 1 : f.mode == interp::FeedMode::kInverseTime ? 2 : 0);
  s.exact_stop(f.exact_stop);
}

}  // namespace

std::optional<cell::MotionSegment> ToSegment(const interp::Canon& c) {
  cell::MotionSegment s;
  s.line(c.line);
  switch (c.op()) {
    case interp::Op::kRapid:
      s.kind(cell::SEGMENT_RAPID);
      SetTarget(s, c.As<interp::RapidOp>().to);
      s.exact_stop(true);
      return s;
    case interp::Op::kLinear: {
      const auto& l = c.As<interp::LinearOp>();
      s.kind(cell::SEGMENT_LINEAR);
      SetTarget(s, l.to);
      SetFeed(s, l.feed);
      return s;
    }
    case interp::Op::kArc: {
      const auto& a = c.As<interp::ArcOp>();
      s.kind(cell::SEGMENT_ARC);
      SetTarget(s, a.to);
      SetFeed(s, a.feed);
      s.center({a.center[0], a.center[1], a.center[2]});
      // Exactly the canonical arc: its two axes in the program's order and its sense in that frame.
      s.plane_first(static_cast<uint16_t>(a.plane.first));
      s.plane_second(static_cast<uint16_t>(a.plane.second));
      s.ccw(!a.cw);
      // A one-block full circle sweeps 360 degrees with end == start: no extra turn.
      s.turns(a.angle > 360.0 + 1e-6 ? static_cast<int32_t>(std::floor((a.angle - 1e-6) / 360.0)) : 0);
      return s;
    }
    case interp::Op::kThread: {
      // Spindle-synchronised: the lead along the major axis, from the start angle (docs/axis-servo.md).
      const auto& t = c.As<interp::ThreadOp>();
      s.kind(cell::SEGMENT_THREAD);
      SetTarget(s, t.to);
      s.exact_stop(t.exact_stop);
      s.thread_lead(t.lead);
      s.thread_lead_change(t.lead_change);
      s.thread_start_angle(t.start_angle);
      return s;
    }
    case interp::Op::kDwell:
      s.kind(cell::SEGMENT_DWELL);
      s.dwell_s(c.As<interp::DwellOp>().seconds);
      return s;
    case interp::Op::kSpindle: {
      const auto& sp = c.As<interp::SpindleOp>();
      s.kind(cell::SEGMENT_SPINDLE);
      // A lathe's live-tool (M-tool) spindle: its own speed and direction (Okuma M13/M14/M12, SB=).
      s.live_tool(sp.spindle == interp::SpindleId::kLiveTool);
      s.spindle_rpm(sp.rpm);
      s.spindle_mode(sp.dir == interp::SpindleDir::kCw       ? 1
                     : sp.dir == interp::SpindleDir::kCcw    ? 2
                     : sp.dir == interp::SpindleDir::kOrient ? 3
                     : sp.dir == interp::SpindleDir::kAxis   ? 4
                                                             : 0);
      // The whole spindle state on every spindle segment: constant surface speed and the spindle limit.
      s.css_surface_speed(sp.css);
      s.spindle_max_rpm(sp.max_rpm);
      return s;
    }
    case interp::Op::kCoolant: {
      interp::CoolantMode m = c.As<interp::CoolantOp>().mode;
      s.kind(cell::SEGMENT_COOLANT);
      s.coolant(m == interp::CoolantMode::kOff ? 0 : m == interp::CoolantMode::kMist ? 2 : 1);
      return s;
    }
    case interp::Op::kToolChange:
      s.kind(cell::SEGMENT_TOOL_CHANGE);
      s.tool(c.As<interp::ToolChangeOp>().tool);
      s.tool_socket(c.As<interp::ToolChangeOp>().socket);
      return s;
    case interp::Op::kPallet:
      s.kind(cell::SEGMENT_PALLET);
      return s;
    case interp::Op::kEnd:
      s.kind(cell::SEGMENT_END);
      return s;
    default:
      return std::nullopt;
  }
}

void RotaryUnwrap::Apply(const interp::Canon& c, cell::MotionSegment& s) {
  const interp::Target* t = c.If<interp::RapidOp>()    ? &c.As<interp::RapidOp>().to
                            : c.If<interp::LinearOp>() ? &c.As<interp::LinearOp>().to
                            : c.If<interp::ArcOp>()    ? &c.As<interp::ArcOp>().to
                            : c.If<interp::ThreadOp>() ? &c.As<interp::ThreadOp>().to
                                                       : nullptr;
  if (!t) return;
  const int axes[2] = {interp::kA, interp::kC};
  for (int i = 0; i < 2; ++i) {
    const auto a = static_cast<size_t>(axes[i]);
    if (!(t->used & (1u << a))) continue;
    double sent = t->pos[a] + offset_[i];
    if (t->travel_mask & (1u << a)) {
      sent = last_[i] + t->travel[a];
      offset_[i] = sent - t->pos[a];
    }
    s.target()[a] = sent;
    last_[i] = sent;
  }
}

}  // namespace cell::station
