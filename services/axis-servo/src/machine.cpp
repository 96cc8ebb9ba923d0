#include "cell/servo/machine.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <thread>
#include <type_traits>

#include "cell/error/error.h"

namespace cell::servo {

using machine::AxisConfig;
using machine::AxisType;
using machine::MachineConfig;
namespace {

bool IsPathMotion(SegmentKind k) {
  return k == SegmentKind::kRapid || k == SegmentKind::kLinear || k == SegmentKind::kArc ||
         k == SegmentKind::kThread;
}

}  // namespace

const char* SegmentKindName(SegmentKind k) {
  switch (k) {
    case SegmentKind::kRapid:
      return "rapid";
    case SegmentKind::kLinear:
      return "linear";
    case SegmentKind::kArc:
      return "arc";
    case SegmentKind::kDwell:
      return "dwell";
    case SegmentKind::kToolChange:
      return "tool_change";
    case SegmentKind::kSpindle:
      return "spindle";
    case SegmentKind::kCoolant:
      return "coolant";
    case SegmentKind::kPalletChange:
      return "pallet_change";
    case SegmentKind::kProbe:
      return "probe";
    case SegmentKind::kEnd:
      return "end";
    case SegmentKind::kThread:
      return "thread";
  }
  return "?";
}

namespace {

// Tool numbers may carry a data-set suffix ("33412.5"): the physical tool is the part before the dot.
std::string BaseTool(const std::string& t) {
  return t.substr(0, t.find('.'));
}

// The magazine's `tool` in `socket` is what tool change `s` asks for: the same physical tool, in the socket
// the control chose when it named one (an alternate).
bool IsRequested(const Segment& s, int socket, const std::string& tool) {
  return (tool == s.tool || BaseTool(tool) == BaseTool(s.tool)) &&
         (s.tool_socket <= 0 || socket == s.tool_socket);
}

}  // namespace

const char* ExecutionName(Execution e) {
  switch (e) {
    case Execution::kReady:
      return "READY";
    case Execution::kActive:
      return "ACTIVE";
    case Execution::kFeedHold:
      return "FEED_HOLD";
    case Execution::kStopped:
      return "STOPPED";
  }
  return "?";
}

static PlannerLimits MakeLimits(const MachineConfig& c, int* filter_n) {
  PlannerLimits l;
  double n = 1;
  for (int i = 0; i < kNumAxes; ++i) {
    const AxisConfig& a = c.axes[i];
    l.present[i] = a.present;
    if (!a.present) continue;
    l.max_velocity[i] = a.max_velocity / 60.0;
    l.rapid[i] = a.rapid / 60.0;
    l.max_acceleration[i] = a.max_acceleration;
    n = std::max(n, std::ceil(2 * a.max_acceleration / (a.max_jerk * c.servo_period_s) - 1e-9));
  }
  l.period = c.servo_period_s;
  l.path_tolerance = c.path_tolerance;
  l.filter_time = n * c.servo_period_s;
  *filter_n = static_cast<int>(n);
  return l;
}

Machine::Machine(MachineConfig config, ClockKind clock)
    : cfg_(std::move(config)),
      clock_kind_(clock),
      limits_([&] {
        int n;
        return MakeLimits(cfg_, &n);
      }()),
      planner_(limits_, 2 * static_cast<std::size_t>(cfg_.queue_capacity) + 8) {
  int n = 1;
  MakeLimits(cfg_, &n);
  co_axes_ = cfg_.axes[kU].present || cfg_.axes[kV].present || cfg_.axes[kW].present;
  filter_.Configure(n, co_axes_);
  AxisVector home = AxisVector::Zero();
  for (int i = 0; i < kNumAxes; ++i) {
    present_[i] = cfg_.axes[i].present;
    if (!present_[i]) continue;
    axes_[num_axes_++] = i;
    home[i] = std::clamp(0.0, cfg_.axes[i].min, cfg_.axes[i].max);
    servos_[i].Configure(cfg_.axes[i], cfg_.servo_period_s);
    servos_[i].Reset(home[i]);
  }
  planner_.Flush(home);
  filter_.Reset(home);
  spindle_.Configure(cfg_.spindle_max_rpm, cfg_.spindle_accel_rpm_s);
  live_tool_.Configure(cfg_.live_tool_max_rpm, cfg_.live_tool_accel_rpm_s);
  c_is_spindle_ = cfg_.kind == "lathe" && present_[kC];
  prev_cmd_ = home;
  SetToolTable(cfg_.tools);
  for (const auto& ref : cfg_.part_models) parts_[ref.pallet] = partmodel::LoadPartModel(ref.file);
  events_.reserve(64);
}

void Machine::SetToolTable(const tooltable::ToolTable& table) {
  magazine_.clear();
  for (const auto& e : table.entries()) {
    if (e.socket <= 0) continue;  // a manual tool, or not loaded
    // The spindle tool's socket stays empty until it goes back (an alternate of it in another socket is
    // there).
    if (spindle_tool_.empty() || e.tool != spindle_tool_ || e.socket != spindle_tool_socket_)
      magazine_[e.socket] = e.tool;
  }
}

void Machine::ChargeCutting(double seconds) {
  if (cut_index_ < 0) {
    for (std::size_t i = 0; i < cutting_.size(); ++i)
      if (cutting_[i].tool == spindle_tool_ && cutting_[i].socket == spindle_tool_socket_)
        cut_index_ = static_cast<int>(i);
    if (cut_index_ < 0) {
      cutting_.push_back({spindle_tool_, spindle_tool_socket_, 0.0});
      cut_index_ = static_cast<int>(cutting_.size()) - 1;
    }
  }
  cutting_[static_cast<std::size_t>(cut_index_)].cutting_s += seconds;
}

bool Machine::SpindleToolBroken() const {
  if (spindle_tool_.empty()) return false;  // nothing to check: the post sees no edge missing
  const int sock = spindle_tool_socket_;
  auto has = [sock](const std::vector<int>& v) { return std::find(v.begin(), v.end(), sock) != v.end(); };
  return has(cfg_.broken_sockets) || has(broken_commanded_);
}

void Machine::SetBrokenSockets(const std::vector<int>& sockets) {
  broken_commanded_ = sockets;
}

void Machine::ResetCutting() {
  cutting_.clear();
  cut_index_ = -1;
}

void Machine::SetPartModel(int pallet, partmodel::PartModel model) {
  parts_[pallet] = std::move(model);
}
void Machine::SetPallets(int on_table, int on_shuttle) {
  pallet_table_ = on_table;
  pallet_shuttle_ = on_shuttle;
}

// Shortest way round the magazine (or the turret) from where it stands to `socket`.
int Machine::MagazineSteps(int socket) const {
  const int n = std::max(1, cfg_.magazine_sockets);
  const int steps = std::abs(socket - magazine_at_) % n;
  return std::min(steps, n - steps);
}

std::vector<Segment> Machine::ToArrival() const {
  std::vector<Segment> out;
  auto add = [&](SegmentKind kind) -> Segment& {
    Segment& s = out.emplace_back();
    s.kind = kind;
    return s;
  };
  // The axes at the zero; an index table's B on its own (an index move is a move of B alone).
  const bool index_b = present_[kB] && cfg_.axes[kB].type == AxisType::kIndex;
  std::uint16_t path = 0, b = 0;
  const AxisVector& at = planner_.EndOfPath();
  for (int i = 0; i < kNumAxes; ++i) {
    if (!present_[i] || (std::abs(at[i]) <= 1e-9 && std::abs(servos_[i].position()) <= 1e-9)) continue;
    (i == kB && index_b ? b : path) |= static_cast<std::uint16_t>(1u << i);
  }
  // A lathe positions C only joined; it powers up released (the spindle in speed control).
  const bool join = c_is_spindle_ && !c_joined_ && (path >> kC & 1);
  // The spindle stopped at its index mark (oriented), where it stands at power-up: where a thread's index
  // pulse comes, and so its wait, is then the same on every run (docs/predict.md judgement call 4). A spindle
  // joined as C (or to be joined to bring C to 0) is released at C 0 below, then oriented.
  if (!c_joined_ && !join && (spindle_.Active() || spindle_.angle() != 0.0))
    add(SegmentKind::kSpindle).spindle_dir = SpindleDirection::kOrient;
  if (live_tool_.Active()) add(SegmentKind::kSpindle).live_tool = true;
  if (coolant_ != CoolantMode::kOff) add(SegmentKind::kCoolant);  // kOff
  if (join) add(SegmentKind::kSpindle).spindle_dir = SpindleDirection::kAxis;
  if (path) add(SegmentKind::kRapid).axes = path;  // end{} is the zero
  if (b) add(SegmentKind::kRapid).axes = b;
  if (c_joined_ || join) {
    add(SegmentKind::kSpindle);  // kStop: released
    add(SegmentKind::kSpindle).spindle_dir = SpindleDirection::kOrient;
  }
  if (!spindle_tool_.empty() || magazine_at_ != 1) add(SegmentKind::kToolChange).tool_socket = 1;
  return out;
}

void Machine::Push(const Segment& segment) {
  if (alarm_.code != AlarmCode::kNone)
    throw Error(Errc::kFailedPrecondition, fmt::format("segment {} refused: alarm {} active, reset first",
                                                       segment.id, static_cast<int>(alarm_.code)));
  if (queue_.size() >= capacity())
    throw Error(Errc::kFailedPrecondition,
                fmt::format("segment {} refused: no credit (queue of {} full)", segment.id, capacity()));
  bool finite = std::isfinite(segment.feed) & std::isfinite(segment.dwell_s) &
                std::isfinite(segment.spindle_rpm) & std::isfinite(segment.css_surface_speed) &
                std::isfinite(segment.spindle_max_rpm) & std::isfinite(segment.thread_lead) &
                std::isfinite(segment.thread_lead_change) & std::isfinite(segment.thread_start_angle);
  for (double v : segment.end) finite &= std::isfinite(v);
  for (double v : segment.center) finite &= std::isfinite(v);
  if (!finite)
    throw Error(Errc::kInvalidArgument,
                fmt::format("segment {} refused: a value is not a finite number", segment.id));
  if (segment.feed < 0 || segment.dwell_s < 0)
    throw Error(Errc::kInvalidArgument,
                fmt::format("segment {} refused: negative feed or dwell", segment.id));
  if (segment.css_surface_speed < 0 || segment.spindle_max_rpm < 0 || segment.thread_lead < 0)
    throw Error(
        Errc::kInvalidArgument,
        fmt::format("segment {} refused: negative surface speed, spindle limit or thread lead", segment.id));
  Segment& s = queue_.emplace_back(Entry{segment, false}).seg;
  if (cfg_.axes[kX].diameter) {
    s.end[kX] *= 0.5;
    s.center[kX] *= 0.5;
  }
}

AxisVector Machine::EndOf(const Segment& s, const AxisVector& start) const {
  AxisVector p = start;
  for (int n = 0; n < num_axes_; ++n)
    if (const int i = axes_[n]; s.axes >> i & 1) p[i] = s.end[i];
  return p;
}

Feed Machine::FeedOf(const Segment& s, double length) const {
  switch (s.feed_mode) {
    case FeedMode::kPerMinute:
      return Feed(s.feed / 60.0);
    case FeedMode::kPerRevolution:  // the planner follows the spindle's actual speed
      return Feed(s.feed, true);
    case FeedMode::kInverseTime:
      return Feed(s.feed * length / 60.0);
  }
  return Feed(0);
}

double Machine::FeedNow(const Segment& s, double length) const {
  const Feed f = FeedOf(s, length);
  return f.per_rev ? f.rate * std::abs(spindle_.rpm()) / 60.0 : f.rate;
}

bool Machine::SoftLimitCheck(const Segment& s, const AxisVector& start, std::string& why) const {
  const AxisVector end = EndOf(s, start);
  AxisVector lo = start.cwiseMin(end), hi = start.cwiseMax(end);
  if (s.kind == SegmentKind::kArc) {
    PathElement e;
    std::string ignored;
    if (planner_.MakeArc(start, end, s.center, s.plane, s.direction, s.turns, e, ignored)) {
      const double rmax = std::max(e.r0, e.r0 + e.dr * e.sweep);
      for (int i = 0; i < kNumAxes; ++i) {
        const double amp = std::hypot(e.e1[i], e.e2[i]);
        if (amp < 1e-12) continue;
        double ph = std::atan2(e.e2[i], e.e1[i]);  // angle of the maximum
        for (int side = 0; side < 2; ++side) {
          double p = std::fmod(ph + side * M_PI + 4 * M_PI, 2 * M_PI);
          if (p <= e.sweep) {
            const double v = e.c[i] + (side ? -1 : 1) * rmax * amp;
            lo[i] = std::min(lo[i], v);
            hi[i] = std::max(hi[i], v);
          }
        }
      }
    }
  }
  for (int n = 0; n < num_axes_; ++n) {
    const int i = axes_[n];
    const AxisConfig& a = cfg_.axes[i];
    const double f = a.diameter ? 2.0 : 1.0;
    if (hi[i] > a.max + 1e-9) {
      why = fmt::format("{}+ soft limit: {:.4f} > {:.4f}", static_cast<char>(std::toupper(kAxisNames[i])),
                        hi[i] * f, a.max * f);
      return false;
    }
    if (lo[i] < a.min - 1e-9) {
      why = fmt::format("{}- soft limit: {:.4f} < {:.4f}", static_cast<char>(std::toupper(kAxisNames[i])),
                        lo[i] * f, a.min * f);
      return false;
    }
  }
  return true;
}

void Machine::Emit(EventKind kind, std::uint64_t seg, const Alarm* alarm, const ProbeResult* probe) {
  Event& ev = events_.emplace_back();  // in place: an Event carries a string and a probe result
  ev.kind = kind;
  ev.segment_id = seg;
  ev.machine_time = machine_time();
  if (alarm) ev.alarm = *alarm;
  if (probe) ev.probe = *probe;
}

std::vector<Event> Machine::TakeEvents() {
  std::vector<Event> out;
  out.swap(events_);
  events_.reserve(64);
  return out;
}

void Machine::TakeEvents(std::vector<Event>& into) {
  into.clear();
  into.swap(events_);
}

void Machine::RaiseAlarm(AlarmCode code, const std::string& text, std::uint64_t seg) {
  alarm_ = {code, text};
  alarm_seg_ = seg;
  alarm_pending_ = false;
  Emit(EventKind::kAlarm, seg, &alarm_);
  FlushAll();
  // Alarms found before a segment starts leave the machine where it is (no motion, the servo keeps
  // settling on its last command). A following-error alarm or one raised while moving stops the axes
  // where they are.
  if (code != AlarmCode::kFollowingError && planner_.Speed() == 0) {
    planner_.Flush(planner_.Position());
    return;
  }
  const AxisVector act = actual();
  // Motion stops: the command holds where the axes are.
  planner_.Flush(act);
  filter_.Reset(act);
  prev_cmd_ = act;
  prev_vel_.setZero();
}

void Machine::FlushAll() {
  for (const auto& e : queue_) Emit(EventKind::kFlushed, e.seg.id);
  queue_.clear();
  next_ = 0;
  pending_.clear();
  op_ = Op{};
  probing_ = false;
  aborting_ = false;
  planner_.SetHold(false);
}

void Machine::Complete(std::uint64_t seg, const ProbeResult* probe) {
  // Segments complete in queue order; the head is the one.
  if (!queue_.empty() && queue_.front().seg.id == seg) {
    queue_.pop_front();
    if (next_ > 0) --next_;
  }
  Emit(EventKind::kCompleted, seg, nullptr, probe);
}

bool Machine::InPosition(const AxisVector& target, double tol) const {
  if (tol <= 0) tol = cfg_.in_position;
  for (int n = 0; n < num_axes_; ++n) {
    const int i = axes_[n];
    if (std::abs(filter_.Output()[i] - target[i]) > tol) return false;
    if (std::abs(servos_[i].position() - target[i]) > tol) return false;
  }
  return true;
}

AxisVector Machine::actual() const {
  AxisVector a = AxisVector::Zero();
  for (int n = 0; n < num_axes_; ++n) a[axes_[n]] = servos_[axes_[n]].position();
  return a;
}

AxisVector Machine::following_error() const {
  AxisVector a = AxisVector::Zero();
  for (int i = 0; i < kNumAxes; ++i)
    if (present_[i]) a[i] = servos_[i].following_error();
  return a;
}

void Machine::FeedPlanner() {
  if (alarm_.code != AlarmCode::kNone || aborting_ || alarm_pending_) return;
  while (next_ < queue_.size() && op_.phase == OpPhase::kNone) {
    Entry& e = queue_[next_];
    const Segment& s = e.seg;
    // A full planner waits (most ticks of a long program): checked before anything is computed. A barrier
    // (an index move among them) would wait too, as the planner is not idle.
    if (IsPathMotion(s.kind) && planner_.Full()) break;
    const AxisVector start = planner_.EndOfPath();
    const bool index_move = IsPathMotion(s.kind) && present_[kB] && cfg_.axes[kB].type == AxisType::kIndex &&
                            (s.axes >> kB & 1) && std::abs(s.end[kB] - start[kB]) > 1e-9;
    // An alarm found while planning ahead is raised once everything before the segment has run.
    auto defer = [&](AlarmCode code, const std::string& why) {
      alarm_pending_ = true;
      alarm_ = {};
      pending_alarm_ = {code, fmt::format("segment {}: {}", s.id, why)};
      alarm_seg_ = s.id;
    };
    // Feeds per revolution need a running spindle (they follow its actual speed from then on).
    auto feed_ok = [&](const Feed& f) {
      if (!(f.rate > 0)) return defer(AlarmCode::kInvalidSegment, "feed is zero"), false;
      if (f.per_rev && spindle_.TargetAt(XDiameter()) == 0)
        return defer(AlarmCode::kInvalidSegment, "feed per revolution with the spindle stopped"), false;
      return true;
    };
    if (IsPathMotion(s.kind) && (!index_move || s.kind == SegmentKind::kThread)) {
      // A lathe's C is its spindle: it turns as an axis only joined (segments after a joint or a release
      // are planned once it is done: it is a barrier).
      if (c_is_spindle_ && !c_joined_ && (s.axes >> kC & 1) && std::abs(s.end[kC] - start[kC]) > 1e-9) {
        defer(AlarmCode::kInvalidSegment,
              fmt::format("C {:.4f} while the C axis is not joined (M110): the spindle is in speed control",
                          s.end[kC]));
        break;
      }
      std::string why;
      if (!SoftLimitCheck(s, start, why)) {
        defer(AlarmCode::kSoftLimit, why);
        break;
      }
      const AxisVector end = EndOf(s, start);
      if (s.kind == SegmentKind::kRapid) {
        planner_.AddLine(end, 0, true, true, s.id);
      } else if (s.kind == SegmentKind::kThread) {
        if (!PlanThread(s, start, end, why)) {
          defer(AlarmCode::kInvalidSegment, why);
          break;
        }
      } else if (s.kind == SegmentKind::kLinear) {
        const double len = PathLength(end - start);
        const Feed f = FeedOf(s, len);
        if (len > 1e-9 && !feed_ok(f)) break;
        planner_.AddLine(end, f, false, s.exact_stop, s.id);
      } else {
        PathElement arc;
        std::string err;
        if (!planner_.MakeArc(start, end, s.center, s.plane, s.direction, s.turns, arc, err)) {
          defer(AlarmCode::kInvalidSegment, err);
          break;
        }
        const Feed f = FeedOf(s, arc.len);
        if (!feed_ok(f)) break;
        planner_.AddArc(arc, f, s.exact_stop, s.id);
      }
      e.planned = true;
      ++next_;
      continue;
    }
    // A barrier: everything before it must be complete and the machine in position.
    if (next_ != 0 || !planner_.Idle() || op_.phase != OpPhase::kNone || !pending_.empty()) break;
    if (!InPosition(planner_.Position())) break;
    e.planned = true;
    ++next_;
    StartBarrier(e);
    break;
  }
}

bool Machine::StartBarrier(Entry& e) {
  const Segment& s = e.seg;
  Emit(EventKind::kStarted, s.id);
  op_ = Op{};
  op_.seg = s.id;
  op_.s = s;
  const double now = machine_time();
  auto timer = [&](double d) {
    op_.phase = OpPhase::kTimer;
    op_.until = now + d;
    op_.t0 = now;
  };
  switch (s.kind) {
    case SegmentKind::kDwell:
      if (!(s.dwell_s >= 0)) {
        RaiseAlarm(AlarmCode::kInvalidSegment, fmt::format("segment {}: negative dwell", s.id), s.id);
        return false;
      }
      timer(s.dwell_s);
      break;
    case SegmentKind::kSpindle: {
      if (s.live_tool) {
        if (!StartLiveTool(s)) return false;
        // Complete when the live tool is at speed, as the work spindle's command.
        timer(std::abs(live_tool_.TargetAt(0) - live_tool_.rpm()) / cfg_.live_tool_accel_rpm_s);
        break;
      }
      if (c_is_spindle_ && (c_joined_ || s.spindle_dir == SpindleDirection::kAxis)) {
        double t = 0;
        if (!StartJoint(s, t)) return false;
        timer(t);
        break;
      }
      if (!StartSpindle(s)) return false;
      // Complete when the spindle is at speed (the ramp runs in Step()).
      double t = std::abs(spindle_.TargetAt(XDiameter()) - spindle_.rpm()) / cfg_.spindle_accel_rpm_s;
      if (s.spindle_dir == SpindleDirection::kOrient) t += cfg_.spindle_orient_time;
      spindle_oriented_ = false;
      timer(t);
      break;
    }
    case SegmentKind::kCoolant:
      timer(cfg_.coolant_time);
      break;
    case SegmentKind::kToolChange: {
      if (s.tool.empty() || s.tool == "0") {  // empty the spindle
        double t = spindle_tool_.empty() ? 0.0 : cfg_.tool_change_time;
        if (s.tool_socket > 0) t += MagazineSteps(s.tool_socket) * cfg_.magazine_index_time;
        timer(t);
        break;
      }
      // Already in the spindle (the same physical tool: an alternate in another socket is another one).
      if (!spindle_tool_.empty() && BaseTool(spindle_tool_) == BaseTool(s.tool) &&
          (s.tool_socket <= 0 || s.tool_socket == spindle_tool_socket_)) {
        timer(0);
        break;
      }
      int socket = 0;
      for (const auto& [sock, tool] : magazine_)
        if (IsRequested(s, sock, tool)) socket = sock;
      if (socket == 0) {
        RaiseAlarm(AlarmCode::kToolNotInMagazine,
                   fmt::format("segment {}: tool {} is not in the magazine", s.id, s.tool), s.id);
        return false;
      }
      double t = cfg_.tool_change_time + MagazineSteps(socket) * cfg_.magazine_index_time;
      // A machining centre stops the spindle to change tools; a lathe's turret indexes while it turns.
      if (cfg_.kind != "lathe") {
        t += std::abs(spindle_.rpm()) / cfg_.spindle_accel_rpm_s;
        spindle_.SetRpm(0);
      }
      timer(t);
      break;
    }
    case SegmentKind::kPalletChange:
      timer(cfg_.pallet_change_time);
      break;
    case SegmentKind::kEnd:
      timer(0);
      break;
    case SegmentKind::kProbe: {
      if (s.tool_check) {
        // G38: the detection post's switches see the edges go by in one revolution of the spindle (at
        // least half a second); the axes stay where the block before put them.
        const double rpm = std::abs(spindle_.rpm());
        timer(std::max(0.5, rpm > 0 ? 60.0 / rpm : 0.0));
        break;
      }
      const AxisVector start = planner_.EndOfPath();
      std::string why;
      if (!SoftLimitCheck(s, start, why)) {
        RaiseAlarm(AlarmCode::kSoftLimit, fmt::format("segment {}: {}", s.id, why), s.id);
        return false;
      }
      const AxisVector end = EndOf(s, start);
      double f = std::min(FeedNow(s, PathLength(end - start)), cfg_.probe_max_feed / 60.0);
      if (!(f > 0)) {
        RaiseAlarm(AlarmCode::kInvalidSegment, fmt::format("segment {}: probe feed is zero", s.id), s.id);
        return false;
      }
      probe_break_ = s.probe_break;
      probe_length_ = s.probe_length;
      probe_prev_ = actual();
      const partmodel::PartModel* part = PartOnTable();
      const double ball = 0.5 * cfg_.probe_ball_diameter;
      // Already in the requested state (touching for G22, clear for G23): no motion, nothing latched.
      const bool touching = part && part->Distance(PoseOf(probe_prev_)) <= ball;
      if (touching != probe_break_) {
        ProbeResult r;
        r.already = true;
        r.position = ToSegmentUnits(probe_prev_);
        const std::uint64_t seg = s.id;
        op_ = Op{};
        Complete(seg, &r);
        return true;
      }
      planner_.AddLine(end, f, false, true, s.id, true);
      op_.phase = OpPhase::kMotion;
      probing_ = true;
      probe_tripped_ = false;
      break;
    }
    default: {  // path motion with a B index move
      const AxisConfig& b = cfg_.axes[kB];
      const double q = s.end[kB] / b.index_increment;
      std::string why;
      if (std::abs(q - std::round(q)) > 1e-6) {
        RaiseAlarm(AlarmCode::kInvalidSegment,
                   fmt::format("segment {}: B {:.4f} is not a multiple of the index increment {:g}", s.id,
                               s.end[kB], b.index_increment),
                   s.id);
        return false;
      }
      if (!SoftLimitCheck(s, planner_.EndOfPath(), why)) {
        RaiseAlarm(AlarmCode::kSoftLimit, fmt::format("segment {}: {}", s.id, why), s.id);
        return false;
      }
      // A full-circle index table turns the shortest way (positions stay in [min, max] between moves).
      op_.index_target = s.end[kB];
      if (b.max - b.min >= 360.0 - b.index_increment - 1e-9) {
        const double direct = s.end[kB] - planner_.EndOfPath()[kB];
        const double d = std::remainder(direct, 360.0);
        if (std::abs(d - direct) > 1e-6) op_.index_target = planner_.EndOfPath()[kB] + d;
      }
      op_.phase = OpPhase::kIndexUnclamp;
      op_.until = now + b.unclamp_time;
      b_clamped_ = false;
      break;
    }
  }
  return true;
}

void Machine::StepOp() {
  const double now = machine_time() + 1e-12;
  switch (op_.phase) {
    case OpPhase::kNone:
      return;
    case OpPhase::kTimer: {
      const Segment& s = op_.s;
      if (s.kind == SegmentKind::kDwell && planner_.Holding() && !aborting_) {  // feed hold pauses a dwell
        op_.until += cfg_.servo_period_s;
        op_.t0 += cfg_.servo_period_s;
        return;
      }
      if (now < op_.until) return;
      switch (s.kind) {
        case SegmentKind::kSpindle:
          if (s.live_tool) {
            live_tool_.Snap(0);
            break;
          }
          spindle_.Snap(XDiameter());
          spindle_oriented_ = s.spindle_dir == SpindleDirection::kOrient;
          if (spindle_oriented_) spindle_.Orient();
          if (c_is_spindle_) c_joined_ = s.spindle_dir == SpindleDirection::kAxis;
          break;
        case SegmentKind::kCoolant:
          coolant_ = s.coolant;
          break;
        case SegmentKind::kToolChange:
          spindle_.Snap(XDiameter());
          if (!spindle_tool_.empty()) magazine_[spindle_tool_socket_] = spindle_tool_;
          spindle_tool_.clear();
          spindle_tool_socket_ = 0;
          cut_index_ = -1;
          if (s.tool.empty() || s.tool == "0") {
            if (s.tool_socket > 0) magazine_at_ = s.tool_socket;
          } else {
            for (auto it = magazine_.begin(); it != magazine_.end(); ++it)
              if (IsRequested(s, it->first, it->second)) {
                spindle_tool_ = it->second;
                spindle_tool_socket_ = magazine_at_ = it->first;
                magazine_.erase(it);
                break;
              }
          }
          break;
        case SegmentKind::kPalletChange: {
          const int old = pallet_table_;
          if (s.pallet == 0 || s.pallet == pallet_shuttle_) {
            pallet_table_ = pallet_shuttle_;
          } else {
            pallet_table_ = s.pallet;
          }
          pallet_shuttle_ = old;
          break;
        }
        default:
          break;
      }
      const std::uint64_t seg = op_.seg;
      if (s.kind == SegmentKind::kProbe) {  // a G38 tool check (the only timed probe segment)
        ProbeResult r;
        r.contact = !SpindleToolBroken();
        r.position = ToSegmentUnits(planner_.Position());
        op_ = Op{};
        Complete(seg, &r);
        return;
      }
      op_ = Op{};
      Complete(seg);
      return;
    }
    case OpPhase::kMotion:
      if (!planner_.Idle()) return;
      {
        ProbeResult r;
        r.contact = probe_tripped_;
        r.position = probe_tripped_ ? probe_trip_ : planner_.Position();
        r.position = ToSegmentUnits(r.position);
        probing_ = false;
        const std::uint64_t seg = op_.seg;
        op_ = Op{};
        Complete(seg, &r);
      }
      return;
    case OpPhase::kIndexUnclamp:
      if (now < op_.until) return;
      {
        AxisVector p = planner_.EndOfPath();
        p[kB] = op_.index_target;
        planner_.AddLine(p, 0, true, true, op_.seg);
        op_.phase = OpPhase::kIndexMove;
      }
      return;
    case OpPhase::kIndexMove:
      if (!planner_.Idle()) return;
      op_.phase = OpPhase::kIndexClamp;
      op_.until = machine_time() + cfg_.axes[kB].clamp_time;
      return;
    case OpPhase::kIndexClamp: {
      if (now < op_.until) return;
      b_clamped_ = true;
      const double wrap = 360.0 * std::round((op_.s.end[kB] - op_.index_target) / 360.0);
      if (wrap != 0 && filter_.Settled()) {
        // Renumber the table position into [min, max]: the same physical angle.
        AxisVector p = planner_.Position();
        p[kB] += wrap;
        planner_.Flush(p);
        filter_.Reset(p);
        prev_cmd_[kB] += wrap;
        servos_[kB].Shift(wrap);
      }
      Segment rest = op_.s;
      const AxisVector start = planner_.EndOfPath();
      const AxisVector end = EndOf(rest, start);
      if ((end - start).norm() < 1e-9) {
        const std::uint64_t seg = op_.seg;
        op_ = Op{};
        Complete(seg);
        return;
      }
      if (rest.kind == SegmentKind::kRapid) {
        planner_.AddLine(end, 0, true, true, op_.seg);
      } else if (rest.kind == SegmentKind::kLinear) {
        planner_.AddLine(end, std::max(FeedNow(rest, PathLength(end - start)), 1e-3), false, true, op_.seg);
      } else {
        PathElement arc;
        std::string err;
        if (!planner_.MakeArc(start, end, rest.center, rest.plane, rest.direction, rest.turns, arc, err)) {
          RaiseAlarm(AlarmCode::kInvalidSegment, fmt::format("segment {}: {}", rest.id, err), rest.id);
          return;
        }
        planner_.AddArc(arc, std::max(FeedNow(rest, arc.len), 1e-3), true, op_.seg);
      }
      op_.phase = OpPhase::kIndexRest;
      return;
    }
    case OpPhase::kIndexRest:
      if (!planner_.Idle()) return;
      {
        const std::uint64_t seg = op_.seg;
        op_ = Op{};
        Complete(seg);
      }
      return;
  }
}

const partmodel::PartModel* Machine::PartOnTable() const {
  if (run_part_) return run_part_->empty() ? nullptr : &*run_part_;
  auto it = parts_.find(pallet_table_);
  return it == parts_.end() || it->second.empty() ? nullptr : &it->second;
}

partmodel::Pose Machine::PoseOf(const AxisVector& v) const {
  return {v[kX], v[kY], v[kZ] - probe_length_ + 0.5 * cfg_.probe_ball_diameter, v[kA], v[kB], v[kC]};
}

// Each tick: did the probe trip between the last actual position and this one? The trip point is latched
// on that step (the part model's bisection), the move then decelerates at the element's limit; the stylus
// deflects meanwhile, and a deflection past probe.overtravel is alarm 602.
void Machine::ProbeCheck() {
  if (!probing_) return;
  const AxisVector now = actual();
  const partmodel::PartModel* part = PartOnTable();
  const double ball = 0.5 * cfg_.probe_ball_diameter;
  if (!probe_tripped_ && part) {
    const partmodel::Trip t = part->Probe(!probe_break_, PoseOf(probe_prev_), PoseOf(now), ball);
    if (t.kind != partmodel::Trip::kNone) {
      probe_trip_ = probe_prev_ + t.t * (now - probe_prev_);
      probe_tripped_ = true;
      planner_.StopOnCurrent();
    }
  }
  if (probe_tripped_ && !probe_break_ && part) {
    const double depth = ball - part->Distance(PoseOf(now));
    if (depth > cfg_.probe_overtravel) {
      probing_ = false;
      RaiseAlarm(AlarmCode::kProbeOvertravel,
                 fmt::format("segment {}: probe overtravel: stylus deflected {:.3f} mm > {:.3f} mm", op_.seg,
                             depth, cfg_.probe_overtravel),
                 op_.seg);
      return;
    }
  }
  probe_prev_ = now;
}

bool Machine::Idle() const {
  const bool held_dwell =
      op_.phase == OpPhase::kTimer && op_.s.kind == SegmentKind::kDwell && planner_.Holding() && !aborting_;
  if ((op_.phase != OpPhase::kNone && !held_dwell) || !pending_.empty()) return false;
  const bool nothing_to_do = (queue_.empty() && planner_.Idle()) || alarm_.code != AlarmCode::kNone ||
                             (planner_.Holding() && planner_.Speed() == 0 && !aborting_);
  if (!nothing_to_do || alarm_pending_) return false;
  if (!filter_.Settled() || !spindle_.AtSpeed()) return false;  // constant surface speed still ramping
  for (int n = 0; n < num_axes_; ++n) {
    const int i = axes_[n];
    if (std::abs(servos_[i].following_error()) > 1e-5 || std::abs(servos_[i].velocity()) > 1e-3) return false;
  }
  return true;
}

bool Machine::Resting() const {
  return clock_kind_ == ClockKind::kReal && !spindle_.Active() && !live_tool_.Active() && Idle();
}

std::uint64_t Machine::CatchUp() {
  if (clock_kind_ != ClockKind::kReal) return 0;
  std::uint64_t n = 0;
  while (NextDeadline() <= std::chrono::steady_clock::now()) {
    const std::uint64_t before = overruns_;
    StepNow();
    overruns_ = before;  // due while resting, not late
    ++n;
  }
  return n;
}

std::chrono::steady_clock::time_point Machine::NextDeadline() {
  const auto now = std::chrono::steady_clock::now();
  if (!wall_started_) {
    wall_started_ = true;
    wall_start_ = now - std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(machine_time()));
  }
  auto at = [&] {
    return wall_start_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                             std::chrono::duration<double>((ticks_ + 1) * cfg_.servo_period_s));
  };
  // More than 100 ms behind (the caller stopped stepping, or the host stalled): re-anchor instead of
  // running the missed periods in a burst. The machine does not move while it is not stepped.
  if (now - at() > std::chrono::milliseconds(100)) {
    wall_start_ = now - std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                            std::chrono::duration<double>(ticks_ * cfg_.servo_period_s));
    ++overruns_;
  }
  return at();
}

bool Machine::Step() {
  if (clock_kind_ == ClockKind::kReal) std::this_thread::sleep_until(NextDeadline());
  return StepNow();
}

bool Machine::StepNow() {
  if (clock_kind_ == ClockKind::kReal) {
    const auto deadline = NextDeadline();
    if (std::chrono::steady_clock::now() > deadline + std::chrono::duration<double>(cfg_.servo_period_s))
      ++overruns_;
  } else if (Idle()) {
    return false;
  }
  ++ticks_;

  if (alarm_pending_ && next_ == 0 && planner_.Idle() && pending_.empty() && op_.phase == OpPhase::kNone) {
    const std::uint64_t seg = alarm_seg_;
    alarm_pending_ = false;
    RaiseAlarm(pending_alarm_.code, pending_alarm_.text, seg);
  }
  FeedPlanner();
  StepOp();

  // The spindle turns during the period; a thread in progress holds its speed, a thread waiting for its
  // index pulse takes it (at the exact fraction of the period) once the spindle is at speed. A spindle
  // that stands still (and was told to) costs nothing: threads and feeds per revolution need it running.
  if (spindle_.Active()) [[unlikely]] {
    spindle_.Step(cfg_.servo_period_s, XDiameter(), planner_.InThread());
    planner_.SetSpindle(spindle_.turned(), std::abs(spindle_.rpm()) * (1.0 / 60.0));
    if (double angle; planner_.AwaitingIndex(&angle) && spindle_.AtSpeed()) {
      const double at = spindle_.Crossing(angle);
      if (at >= 0) planner_.IndexPulse(at);
    }
  }
  if (live_tool_.Active()) [[unlikely]]
    live_tool_.Step(cfg_.servo_period_s, 0, false);
  const bool op_motion =
      op_.phase == OpPhase::kMotion || op_.phase == OpPhase::kIndexMove || op_.phase == OpPhase::kIndexRest;
  // Cutting time: a feed move of the program (not a probe or index move) with the spindle turning (the work
  // spindle, or a lathe's live tool).
  if ((spindle_.rpm() != 0 || live_tool_.rpm() != 0) && !op_motion && planner_.OnFeedMove() &&
      !spindle_tool_.empty()) [[unlikely]]
    ChargeCutting(cfg_.servo_period_s);
  const AxisVector& pre = planner_.Tick();
  for (const auto& m : planner_.Marks()) {
    if (op_motion && m.seg == op_.seg) continue;
    if (!m.finished) {
      Emit(EventKind::kStarted, m.seg);
    } else {
      pending_.push_back({m.seg, ticks_ + static_cast<std::uint64_t>(filter_.length()), m.wait_in_position});
    }
  }

  const AxisVector& cmd = filter_.Push(pre);
  const double ts = cfg_.servo_period_s;
  // Velocity and acceleration feed-forward, six wide on a machine without U V W (which do not move there).
  const auto step_servos = [&](auto width) {
    constexpr int N = decltype(width)::value;
    const Eigen::Matrix<double, N, 1> vel = (cmd.head<N>() - prev_cmd_.head<N>()) / ts;
    const Eigen::Matrix<double, N, 1> acc = (vel - prev_vel_.head<N>()) / ts;
    prev_cmd_.head<N>() = cmd.head<N>();
    prev_vel_.head<N>() = vel;
    for (int n = 0; n < num_axes_; ++n) {
      const int i = axes_[n];
      servos_[i].Step(cmd[i], vel[i], acc[i]);
    }
  };
  if (co_axes_)
    step_servos(std::integral_constant<int, kNumAxes>{});
  else
    step_servos(std::integral_constant<int, kU>{});

  // Following-error supervision ("DIFF over").
  if (alarm_.code == AlarmCode::kNone) {
    for (int n = 0; n < num_axes_; ++n) {
      const int i = axes_[n];
      const double fe = servos_[i].following_error();
      if (std::abs(fe) > cfg_.axes[i].following_error_limit) {
        std::uint64_t seg = 0;
        double frac;
        planner_.Current(seg, frac);
        RaiseAlarm(AlarmCode::kFollowingError,
                   fmt::format("DIFF over {}: following error {:.4f} > limit {:.4f}",
                               static_cast<char>(std::toupper(kAxisNames[i])), std::abs(fe),
                               cfg_.axes[i].following_error_limit),
                   seg);
        return true;
      }
    }
  }

  ProbeCheck();

  if (planner_.Waiting() && InPosition(planner_.Position(), planner_.WaitTolerance())) {
    planner_.Release();
    if (!pending_.empty() && pending_.front().wait_in_position) {
      const std::uint64_t seg = pending_.front().seg;
      pending_.pop_front();
      Complete(seg);
    }
  }
  while (!pending_.empty() && !pending_.front().wait_in_position && pending_.front().release_tick <= ticks_) {
    const std::uint64_t seg = pending_.front().seg;
    pending_.pop_front();
    Complete(seg);
  }

  if (aborting_ && planner_.Speed() == 0) {
    planner_.Flush(planner_.Position());
    FlushAll();
  }
  return true;
}

std::uint64_t Machine::RunUntilIdle(double max_machine_s) {
  const std::uint64_t limit = ticks_ + static_cast<std::uint64_t>(max_machine_s / cfg_.servo_period_s);
  std::uint64_t n = 0;
  while (ticks_ < limit && !Idle()) {
    Step();
    ++n;
  }
  return n;
}

void Machine::FeedHold() {
  planner_.SetHold(true);
}
void Machine::Resume() {
  if (!aborting_) planner_.SetHold(false);
}

void Machine::Abort() {
  // Unstarted segments go at once; the motion in progress decelerates along the path, then the rest goes.
  while (queue_.size() > next_) {
    Emit(EventKind::kFlushed, queue_.back().seg.id);
    queue_.pop_back();
  }
  alarm_pending_ = false;
  if (op_.phase == OpPhase::kTimer) op_ = Op{};
  aborting_ = true;
  planner_.SetHold(true);
  planner_.BreakSync();
}

void Machine::Reset() {
  const bool resync = alarm_.code == AlarmCode::kFollowingError || planner_.Speed() > 0;
  alarm_ = {};
  alarm_pending_ = false;
  FlushAll();
  b_clamped_ = true;
  if (!resync) {  // at rest on a valid command: keep it
    planner_.Flush(planner_.Position());
    return;
  }
  const AxisVector act = actual();
  planner_.Flush(act);
  filter_.Reset(act);
  for (int i = 0; i < kNumAxes; ++i)
    if (present_[i]) servos_[i].Reset(act[i]);
  prev_cmd_ = act;
  prev_vel_.setZero();
  b_clamped_ = true;
}

void Machine::SetFeedOverride(double fraction) {
  feed_ovr_ = std::clamp(fraction, 0.0, 2.0);
  planner_.SetOverrides(feed_ovr_, rapid_ovr_);
}
void Machine::SetRapidOverride(double fraction) {
  rapid_ovr_ = std::clamp(fraction, 0.0, 1.0);
  planner_.SetOverrides(feed_ovr_, rapid_ovr_);
}

AxisVector Machine::ToSegmentUnits(AxisVector v) const {
  if (cfg_.axes[kX].diameter) v[kX] *= 2;
  return v;
}

Execution Machine::execution() const {
  if (alarm_.code != AlarmCode::kNone) return Execution::kStopped;
  if (planner_.Holding() && !aborting_) return Execution::kFeedHold;
  if (queue_.empty() && planner_.Idle() && op_.phase == OpPhase::kNone) return Execution::kReady;
  return Execution::kActive;
}

AxisState Machine::State() const {
  AxisState s;
  s.machine_time = machine_time();
  s.commanded = ToSegmentUnits(filter_.Output());
  s.actual = ToSegmentUnits(actual());
  for (int i = 0; i < kNumAxes; ++i)
    if (present_[i]) s.velocity[i] = servos_[i].velocity() * 60.0 * (cfg_.axes[i].diameter ? 2 : 1);
  s.following_error = following_error();
  s.path_feed = planner_.Speed() * 60.0;
  s.execution = execution();
  s.alarm = alarm_;
  double frac = 0;
  if (op_.phase != OpPhase::kNone) {
    s.segment_id = op_.seg;
    s.fraction = op_.phase == OpPhase::kTimer && op_.until > op_.t0
                     ? std::clamp((machine_time() - op_.t0) / (op_.until - op_.t0), 0.0, 1.0)
                     : 0.0;
  } else if (planner_.Current(s.segment_id, frac)) {
    s.fraction = frac;
  }
  s.spindle_rpm = spindle_.rpm();
  s.spindle_angle = spindle_.angle();
  s.spindle_revolutions = spindle_.position();
  s.spindle_oriented = spindle_oriented_;
  s.c_joined = c_joined_;
  s.live_tool_rpm = live_tool_.rpm();
  s.coolant = coolant_;
  s.tool = spindle_tool_;
  s.pallet_on_table = pallet_table_;
  s.pallet_on_shuttle = pallet_shuttle_;
  s.b_clamped = b_clamped_;
  return s;
}

}  // namespace cell::servo
