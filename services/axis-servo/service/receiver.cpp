#include "cell/servo/receiver.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

#include "cell/error/error.h"
#include "cell/tooltable/wire.h"

namespace cell::servo {

using machine::MachineConfig;

Segment FromWire(const cell::MotionSegment& m, uint64_t id) {
  Segment s;
  s.id = id;
  switch (m.kind()) {
    case cell::SEGMENT_RAPID:
      s.kind = SegmentKind::kRapid;
      break;
    case cell::SEGMENT_LINEAR:
      s.kind = SegmentKind::kLinear;
      break;
    case cell::SEGMENT_ARC:
      s.kind = SegmentKind::kArc;
      break;
    case cell::SEGMENT_DWELL:
      s.kind = SegmentKind::kDwell;
      break;
    case cell::SEGMENT_TOOL_CHANGE:
      s.kind = SegmentKind::kToolChange;
      break;
    case cell::SEGMENT_SPINDLE:
      s.kind = SegmentKind::kSpindle;
      break;
    case cell::SEGMENT_COOLANT:
      s.kind = SegmentKind::kCoolant;
      break;
    case cell::SEGMENT_PALLET:
      s.kind = SegmentKind::kPalletChange;
      break;
    case cell::SEGMENT_PROBE:
      s.kind = SegmentKind::kProbe;
      s.probe_break = m.probe_break();
      s.probe_length = m.probe_length();
      s.tool_check = m.tool_check();
      break;
    case cell::SEGMENT_STOP:
      s.kind = SegmentKind::kDwell;
      break;  // a program stop holds nothing here
    case cell::SEGMENT_END:
      s.kind = SegmentKind::kEnd;
      break;
    case cell::SEGMENT_THREAD:
      s.kind = SegmentKind::kThread;
      break;
  }
  for (int i = 0; i < kNumAxes; ++i) s.end[static_cast<size_t>(i)] = m.target()[static_cast<size_t>(i)];
  s.axes = static_cast<uint16_t>(m.axis_mask() & 0x1ff);
  s.feed = m.feed();
  s.feed_mode = m.feed_mode() == 1   ? FeedMode::kPerRevolution
                : m.feed_mode() == 2 ? FeedMode::kInverseTime
                                     : FeedMode::kPerMinute;
  s.exact_stop = m.exact_stop();
  s.center = {m.center()[0], m.center()[1], m.center()[2]};
  // Out-of-range indices stay out of range: the planner refuses the arc rather than guess its plane.
  s.plane = {static_cast<uint8_t>(std::min<unsigned>(m.plane_first(), 255)),
             static_cast<uint8_t>(std::min<unsigned>(m.plane_second(), 255))};
  s.direction = m.ccw() ? ArcDirection::kCCW : ArcDirection::kCW;
  s.turns = static_cast<uint32_t>(std::max(0, m.turns()));
  s.dwell_s = m.dwell_s();
  s.tool = m.tool().to_string();
  s.tool_socket = m.tool_socket();
  s.spindle_rpm = m.spindle_rpm();
  s.spindle_dir = m.spindle_mode() == 1   ? SpindleDirection::kCW
                  : m.spindle_mode() == 2 ? SpindleDirection::kCCW
                  : m.spindle_mode() == 3 ? SpindleDirection::kOrient
                  : m.spindle_mode() == 4 ? SpindleDirection::kAxis
                                          : SpindleDirection::kStop;
  s.coolant = m.coolant() == 0   ? CoolantMode::kOff
              : m.coolant() == 2 ? CoolantMode::kMist
                                 : CoolantMode::kFlood;
  s.pallet = m.pallet();
  s.css_surface_speed = m.css_surface_speed();
  s.spindle_max_rpm = m.spindle_max_rpm();
  s.live_tool = m.live_tool();
  s.thread_lead = m.thread_lead();
  s.thread_lead_change = m.thread_lead_change();
  s.thread_start_angle = m.thread_start_angle();
  return s;
}

Receiver::Receiver(MachineConfig cfg, ClockKind clock, std::uint64_t boot_id, ReceiverSink& sink)
    : station_(cfg.station_id),
      clock_(clock),
      boot_id_(boot_id),
      sink_(sink),
      machine_(std::move(cfg), clock) {}

void Receiver::OnSegment(cell::MotionSegment m) {
  std::lock_guard lk(in_mu_);
  arrived_.push_back(std::move(m));
  in_cv_.notify_all();
}

void Receiver::OnTools(const cell::ToolTable& t) {
  if (t.station() != station_) return;
  tooltable::ToolTable table = tooltable::FromWire(t);
  std::lock_guard lk(in_mu_);
  pending_tools_ = std::move(table);
  wake_ = true;
  in_cv_.notify_all();
}

void Receiver::OnControl(const cell::ServoControl& c) {
  if (c.station() != station_) return;
  std::lock_guard lk(in_mu_);
  pending_control_ = c;
  wake_ = true;
  in_cv_.notify_all();
}

void Receiver::OnPartModel(const cell::PartModel& p) {
  if (p.station() != station_) return;
  RunPart part{p.run_id(), {}};
  try {
    part.model = partmodel::ParsePartModel(p.text().to_string(), p.name().to_string());
  } catch (const Error& e) {
    // The station parsed it before sending it; a model this servo cannot read is not acknowledged, so the
    // station's run fails with the reason instead of probing air.
    spdlog::error("part model {} for run {} refused: {}", p.name().to_string(), p.run_id(), e.what());
    return;
  }
  std::lock_guard lk(in_mu_);
  pending_part_ = std::move(part);
  wake_ = true;
  in_cv_.notify_all();
}

void Receiver::WaitForSegment(std::chrono::steady_clock::duration d) {
  std::unique_lock lk(in_mu_);
  in_cv_.wait_for(lk, d, [&] { return !arrived_.empty() || wake_; });
}

Receiver::Turn Receiver::Tick(TimePoint now) {
  if (resting_) machine_.CatchUp();  // the periods slept through, before anything new applies
  {
    std::lock_guard lk(in_mu_);
    wake_ = false;
    if (pending_tools_) {
      machine_.SetToolTable(*pending_tools_);
      pending_tools_.reset();
    }
    if (pending_part_) {
      part_ = std::move(pending_part_);
      pending_part_.reset();
      if (part_->run_id == run_id_) machine_.SetRunPart(part_->model);
      dirty_ = true;  // the station waits for the acknowledgement
    }
  }
  ApplyControl();
  TakeArrived(now);
  Turn turn;
  if (LookAheadStarved(now)) {
    // Virtual clock only: wait (wall time) for the refill instead of running the machine into a stop
    // that the segments in flight would have avoided.
    turn.waiting = true;
  } else if (machine_.Resting()) {
    turn.resting = true;
  } else if (AwaitingProducer()) {
    // Virtual clock, every segment of the run completed: no machine time passes until the producer sends
    // the next one (the loop sleeps as when idle).
  } else {
    // Every step: a reset (new run, alarm cleared) releases the planner's hold, never the operator's.
    if (feed_hold_) machine_.FeedHold();
    turn.stepped = machine_.Step();
    HandleEvents();
  }
  if (dirty_) PublishProgress();
  // Axis state at a rate in wall time (DESIGN §3): 50 Hz while anything moves, 4 Hz at rest, and the first
  // sample at rest at once (the position the machine stopped at).
  const bool quiet = turn.resting || (!turn.stepped && !turn.waiting);
  if ((quiet && !quiet_) || now - last_axes_ >= (quiet ? kRestAxisPeriod : kAxisPeriod)) PublishAxes(now);
  quiet_ = quiet;
  resting_ = turn.resting;
  return turn;
}

// Segments in: a new run id starts a new run (its first segment is seq 1).
void Receiver::TakeArrived(TimePoint now) {
  {
    std::lock_guard lk(in_mu_);
    if (!arrived_.empty()) last_segment_at_ = now;
    while (!arrived_.empty()) {
      inbox_.push_back(std::move(arrived_.front()));
      arrived_.pop_front();
    }
  }
  while (!inbox_.empty()) {
    if (arriving_) {
      // The run's segments wait until the machine stands as a pallet arrives: they neither run from
      // elsewhere nor take the credits of the segments that bring it there.
      if (!machine_.Idle() && machine_.alarm().code == AlarmCode::kNone) break;
      arriving_ = false;
    }
    if (const cell::MotionSegment& w = inbox_.front();
        w.waits() && w.run_id() == run_id_ && w.seq() <= received_seq_) {
      // The producer now waits for what it sent (SegmentStream::WaitDrained): the flag, not a duplicate.
      waits_seq_ = std::max(waits_seq_, w.seq());
      inbox_.pop_front();
      continue;
    }
    if (!Accept(inbox_.front())) {
      inbox_.pop_front();
      continue;
    }
    if (inbox_.front().run_id() != run_id_) {
      if (!seq_of_.empty() && machine_.alarm().code == AlarmCode::kNone) {
        // The previous run was abandoned with segments still queued or running (the producer moved on
        // without an END): abort them (motion decelerates along the path) and hold the new run's segments
        // until the abort has flushed the old ones, so they neither run nor take its credits.
        if (!abandoning_) {
          spdlog::warn("run {} abandoned with {} segments queued: aborting it for run {}", run_id_,
                       seq_of_.size(), inbox_.front().run_id());
          machine_.Abort();
          abandoning_ = true;
        }
        break;
      }
      StartRun(inbox_.front().run_id());
      if (arriving_) continue;
    }
    cell::MotionSegment m = std::move(inbox_.front());
    inbox_.pop_front();
    received_seq_ = m.seq();
    if (m.waits()) waits_seq_ = m.seq();
    dirty_ = true;  // the producer learns what arrived (it re-sends what did not)
    if (alarm_.code != AlarmCode::kNone || machine_.alarm().code != AlarmCode::kNone) {
      // The run is stopped by an alarm: later segments of it (sent within their credits before the
      // producer saw the alarm) are dropped; they must not replace the alarm that stopped the run.
      spdlog::debug("segment run {} seq {} dropped: alarm active", m.run_id(), m.seq());
      continue;
    }
    const uint64_t id = ++next_id_;
    seq_of_[id] = m.seq();
    spdlog::debug("segment run {} seq {} kind {} at machine {:.3f} s", m.run_id(), m.seq(),
                  static_cast<int>(m.kind()), machine_.machine_time());
    if (m.kind() == cell::SEGMENT_PROBE) probe_.insert(id);
    if (m.kind() == cell::SEGMENT_END) end_received_ = true;
    try {
      RefuseAbsentAxes(m);
      machine_.Push(FromWire(m, id));
    } catch (const Error& e) {
      seq_of_.erase(id);
      probe_.erase(id);
      // A refused segment (no credit, not a finite number) stops the run: running on without it would
      // join its neighbours with a straight move nobody programmed.
      machine_.Abort();
      alarm_ = Alarm{AlarmCode::kInvalidSegment, e.what()};
      spdlog::error("alarm {}: {}", static_cast<int>(alarm_.code), alarm_.text);
    }
  }
}

// An axis the station does not have stands at 0: a segment that puts one elsewhere (a U-head program on a KT
// station without the head, ktapl.md call 89; a B word on a machine without B) stops the run with
// its refusal. Dropping the axis would run the rest of the move as a toolpath nobody programmed
// (docs/axis-servo.md, "Axes a station lacks").
void Receiver::RefuseAbsentAxes(const cell::MotionSegment& m) {
  static constexpr char kNames[] = "XYZABCUVW";
  const auto& axes = machine_.config().axes;
  for (std::size_t i = 0; i < m.target().size(); ++i) {
    if (!(m.axis_mask() >> i & 1) || (i < axes.size() && axes[i].present)) continue;
    const double to = m.target()[i];
    if (std::abs(to) > 1e-6)
      throw Error(Errc::kInvalidArgument,
                  fmt::format("segment {} refused: the station has no {} axis ({} {:.4f} commanded, line {})",
                              m.seq(), kNames[i], kNames[i], to, m.line()));
  }
}

void Receiver::StartRun(std::int32_t run_id) {
  const bool aborted = abandoning_;
  abandoning_ = false;
  run_id_ = run_id;
  received_seq_ = 0;
  completed_seq_ = 0;
  waits_seq_ = 0;
  seq_of_.clear();
  probe_.clear();
  run_start_s_.reset();
  run_end_s_ = machine_.machine_time();
  machine_.ResetCutting();
  end_received_ = false;
  machine_.SetRunPart(part_ && part_->run_id == run_id ? std::optional(part_->model) : std::nullopt);
  // A new run starts clean. After an abort too: Machine::Abort() on a machine that is already at rest
  // (everything flushed at once) stays "aborting" on the virtual clock, where an idle Step() does not run,
  // and would refuse to move; Reset() at rest ends it without moving the axes.
  if (aborted || machine_.alarm().code != AlarmCode::kNone || alarm_.code != AlarmCode::kNone)
    machine_.Reset();
  alarm_ = Alarm{};
  dirty_ = true;
  // A run (a pallet's map, or an operator's START) starts from the state a pallet arrives in, as its cycle
  // time is predicted (docs/predict.md judgement call 4): the way there is the pallet change's, not the
  // run's, so its segments are not the run's (no seq, no kStarted counted) and the run's wait for them.
  try {
    for (Segment& s : machine_.ToArrival()) {
      s.id = ++next_id_;
      machine_.Push(s);
      arriving_ = true;
    }
  } catch (const Error& e) {  // not expected: the queue is empty and no alarm is active here
    spdlog::error("run {}: the machine cannot be brought to the pallet's start state: {}", run_id, e.what());
  }
}

// Segments arrive in order within one DDS match, but a producer that lost the match (this process stopped
// past the lease, say) re-sends everything not yet completed once it matches again. Taking only the next seq
// makes that safe: duplicates are dropped, and so is anything after a gap (the re-send fills it in order).
// A run is only ever joined at its first segment: a servo restarted mid-run never moves a run from the
// middle (from wherever the axes are to a point the program reached from elsewhere); the producer sees the
// new boot_id and fails the run.
bool Receiver::Accept(const cell::MotionSegment& m) {
  if (m.run_id() == aborted_run_) return false;  // a cancelled run: nothing more of it runs
  const bool next = m.run_id() == run_id_ ? m.seq() == received_seq_ + 1 : m.seq() == 1;
  if (next) return true;
  if (m.run_id() == run_id_ && m.seq() <= received_seq_) {
    spdlog::debug("segment run {} seq {} dropped: already received", m.run_id(), m.seq());
  } else if (m.run_id() == run_id_) {
    spdlog::warn("segment run {} seq {} dropped: expected seq {} (waiting for the re-send)", m.run_id(),
                 m.seq(), received_seq_ + 1);
  } else {
    spdlog::warn("segment run {} seq {} dropped: this servo did not receive the run's start", m.run_id(),
                 m.seq());
  }
  return false;
}

// The operator's panel (ServoControl from the station's interpreter): applied between steps.
void Receiver::ApplyControl() {
  std::optional<cell::ServoControl> c;
  {
    std::lock_guard lk(in_mu_);
    c.swap(pending_control_);
  }
  if (!c) return;
  if (c->abort_run() != 0 && c->abort_run() == run_id_ && aborted_run_ != run_id_) {
    // The run was cancelled: stop it as the abandon of a run does (decelerate along the path, flush the
    // rest); the next run resets the machine.
    aborted_run_ = run_id_;
    spdlog::warn("run {} cancelled: aborting it with {} segments queued", run_id_, seq_of_.size());
    if (!seq_of_.empty() && machine_.alarm().code == AlarmCode::kNone) {
      machine_.Abort();
      abandoning_ = true;
    }
  }
  if (c->feed_hold() != feed_hold_) {
    feed_hold_ = c->feed_hold();
    if (feed_hold_) {
      machine_.FeedHold();
    } else {
      machine_.Resume();
    }
    spdlog::info("feed hold {}", feed_hold_ ? "on" : "released");
  }
  machine_.SetBrokenSockets(std::vector<int>(c->broken_sockets().begin(), c->broken_sockets().end()));
  machine_.SetFeedOverride(c->feed_override());
  machine_.SetRapidOverride(c->rapid_override());
  dirty_ = true;
}

// On the virtual clock the machine runs ~1000x faster than real time, so a look-ahead queue starved by the
// credit round trip (the producer refills it only after it has seen the progress) or by a producer short of
// CPU would make the planner brake for a stop that a real-time machine never sees, and the cycle time would
// depend on DDS latency and the machine's load. While a run is under way (no END yet), the queue is less
// than half full and the producer has not said it waits for the machine (MotionSegment.waits: a drain, a
// probe), the machine waits for the refill, up to kLookAheadWait of wall time after the last segment (a
// producer that waits for something else: a file written, the program store). That bound costs wall time,
// no machine time.
bool Receiver::LookAheadStarved(TimePoint now) const {
  if (clock_ != ClockKind::kVirtual || end_received_ || abandoning_ || seq_of_.empty()) return false;
  if (alarm_.code != AlarmCode::kNone || machine_.alarm().code != AlarmCode::kNone) return false;
  if (waits_seq_ >= received_seq_) return false;
  if (machine_.credits() <= machine_.capacity() / 2) return false;
  return now - last_segment_at_ < kLookAheadWait;
}

// Virtual clock: the run is under way (no END yet) and every segment it sent has completed. The producer is
// working out the next block, or waiting for something off the machine (the operator's cycle start, an
// input, a file written, the program store). A real-time machine would have that block queued long before
// (the interpreter takes microseconds, the motion seconds) or would stand where the last one left it; on a
// machine ~1000x faster than the wall clock, running on meanwhile would turn the producer's wall time into
// machine time (the axes settling for as long as a file write took: KT-APL FWR cost 0.22 s in a 1.2 s
// program, and a turning spindle's phase at the next thread moved with it). So time stands still until the
// next segment, as the prediction's model does (docs/predict.md, "What is run, and how").
bool Receiver::AwaitingProducer() const {
  if (clock_ != ClockKind::kVirtual || end_received_ || abandoning_ || arriving_ || run_id_ == 0)
    return false;
  if (alarm_.code != AlarmCode::kNone || machine_.alarm().code != AlarmCode::kNone) return false;
  return seq_of_.empty() && machine_.credits() == machine_.capacity();
}

void Receiver::HandleEvents() {
  machine_.TakeEvents(events_);
  for (const Event& e : events_) {
    auto it = seq_of_.find(e.segment_id);
    switch (e.kind) {
      case EventKind::kStarted:
        if (!run_start_s_ && it != seq_of_.end()) run_start_s_ = e.machine_time;
        break;
      case EventKind::kCompleted:
        if (it != seq_of_.end()) {
          completed_seq_ = std::max(completed_seq_, it->second);
          spdlog::debug("completed seq {} at machine {:.3f} s", it->second, e.machine_time);
          run_end_s_ = e.machine_time;
          if (probe_.count(e.segment_id)) {
            cell::ProbeResult r;
            r.station(station_);
            r.run_id(run_id_);
            r.seq(it->second);
            r.contact(e.probe.contact);
            r.already(e.probe.already);
            for (int i = 0; i < kNumAxes; ++i) r.position()[static_cast<size_t>(i)] = e.probe.position[i];
            sink_.Probe(r);
            probe_.erase(e.segment_id);
          }
          seq_of_.erase(it);
          dirty_ = true;
        }
        break;
      case EventKind::kFlushed:
        if (it != seq_of_.end()) seq_of_.erase(it);
        break;
      case EventKind::kAlarm:
        alarm_ = e.alarm;
        spdlog::error("alarm {}: {}", static_cast<int>(e.alarm.code), e.alarm.text);
        dirty_ = true;
        break;
    }
  }
}

void Receiver::PublishProgress() {
  cell::SegmentProgress p;
  p.station(station_);
  p.run_id(run_id_);
  p.completed_seq(completed_seq_);
  p.received_seq(received_seq_);
  // One credit per free queue slot: segments in flight or queued never exceed the capacity.
  p.credit_seq(completed_seq_ + machine_.capacity());
  p.machine_s(machine_.machine_time());
  p.run_machine_s(run_start_s_ ? run_end_s_ - *run_start_s_ : 0.0);
  if (alarm_.code != AlarmCode::kNone) {
    p.alarm(true);
    p.alarm_code(std::to_string(static_cast<int>(alarm_.code)));
    p.alarm_text(alarm_.text.substr(0, 255));
  }
  p.feed_hold(feed_hold_);
  p.boot_id(boot_id_);
  p.part_run_id(part_ ? part_->run_id : 0);
  // Cumulative per tool, so a sample the station misses (a state topic keeps the last) loses nothing.
  const auto& cut = machine_.Cutting();
  const std::size_t n = std::min<std::size_t>(cut.size(), kMaxCutTools);
  p.cutting().resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    p.cutting()[i].tool(cut[i].tool.substr(0, 16));
    p.cutting()[i].socket(cut[i].socket);
    p.cutting()[i].cutting_s(cut[i].cutting_s);
  }
  sink_.Progress(p);
  dirty_ = false;
}

void Receiver::PublishAxes(TimePoint now) {
  AxisState s = machine_.State();
  cell::AxisState a;
  a.station(station_);
  for (int i = 0; i < kNumAxes; ++i) {
    a.commanded()[static_cast<size_t>(i)] = s.commanded[i];
    a.actual()[static_cast<size_t>(i)] = s.actual[i];
    a.velocity()[static_cast<size_t>(i)] = s.velocity[i];
    a.following_error()[static_cast<size_t>(i)] = s.following_error[i];
  }
  a.machine_s(s.machine_time);
  a.spindle_rpm(s.spindle_rpm);
  a.path_feed(s.path_feed);
  a.live_tool_rpm(s.live_tool_rpm);
  a.c_joined(s.c_joined);
  a.wall_ns(std::chrono::duration_cast<std::chrono::nanoseconds>(
                std::chrono::system_clock::now().time_since_epoch())
                .count());
  sink_.Axes(a);
  last_axes_ = now;
}

}  // namespace cell::servo
