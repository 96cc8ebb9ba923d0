#include "cell/servo/service.h"

#include <spdlog/spdlog.h>

#include "cell/bus/topics.h"
#include "cell/health/health.h"

namespace cell::servo {

namespace {
constexpr auto kAxisPeriod = std::chrono::milliseconds(20);  // 50 Hz in wall time, whatever the clock
}

Segment FromWire(const cell::MotionSegment& m, uint64_t id) {
  Segment s;
  s.id = id;
  switch (m.kind()) {
    case cell::SEGMENT_RAPID: s.kind = SegmentKind::kRapid; break;
    case cell::SEGMENT_LINEAR: s.kind = SegmentKind::kLinear; break;
    case cell::SEGMENT_ARC: s.kind = SegmentKind::kArc; break;
    case cell::SEGMENT_DWELL: s.kind = SegmentKind::kDwell; break;
    case cell::SEGMENT_TOOL_CHANGE: s.kind = SegmentKind::kToolChange; break;
    case cell::SEGMENT_SPINDLE: s.kind = SegmentKind::kSpindle; break;
    case cell::SEGMENT_COOLANT: s.kind = SegmentKind::kCoolant; break;
    case cell::SEGMENT_PALLET: s.kind = SegmentKind::kPalletChange; break;
    case cell::SEGMENT_PROBE: s.kind = SegmentKind::kProbe; break;
    case cell::SEGMENT_STOP: s.kind = SegmentKind::kDwell; break;  // a program stop holds nothing here
    case cell::SEGMENT_END: s.kind = SegmentKind::kEnd; break;
  }
  for (int i = 0; i < kNumAxes; ++i) s.end[static_cast<size_t>(i)] = m.target()[static_cast<size_t>(i)];
  s.axes = static_cast<uint8_t>(m.axis_mask() & 0x3f);
  s.feed = m.feed();
  s.feed_mode = m.feed_mode() == 1 ? FeedMode::kPerRevolution
                : m.feed_mode() == 2 ? FeedMode::kInverseTime
                                     : FeedMode::kPerMinute;
  s.exact_stop = m.exact_stop();
  s.center = {m.center()[0], m.center()[1], m.center()[2]};
  s.plane = m.plane() == cell::PLANE_ZX ? ArcPlane::kZX : m.plane() == cell::PLANE_YZ ? ArcPlane::kYZ : ArcPlane::kXY;
  s.direction = m.ccw() ? ArcDirection::kCCW : ArcDirection::kCW;
  s.turns = static_cast<uint32_t>(std::max(0, m.turns()));
  s.dwell_s = m.dwell_s();
  s.tool = m.tool().to_string();
  s.spindle_rpm = m.spindle_rpm();
  s.spindle_dir = m.spindle_mode() == 1   ? SpindleDirection::kCW
                  : m.spindle_mode() == 2 ? SpindleDirection::kCCW
                  : m.spindle_mode() == 3 ? SpindleDirection::kOrient
                                          : SpindleDirection::kStop;
  s.coolant = m.coolant() == 0 ? CoolantMode::kOff : m.coolant() == 2 ? CoolantMode::kMist : CoolantMode::kFlood;
  s.pallet = m.pallet();
  return s;
}

Service::Service(bus::Participant& p, MachineConfig cfg, ClockKind clock)
    : station_(cfg.station_id),
      machine_(std::move(cfg), clock),
      segments_(p, bus::topics::Segments(station_), bus::QosKind::kStream),
      progress_(p, bus::topics::kProgress, bus::QosKind::kState),
      axes_(p, bus::topics::kAxisState, bus::QosKind::kTelemetry),
      probe_w_(p, bus::topics::Probe(station_), bus::QosKind::kCommand),
      tools_r_(p, bus::topics::kToolTable, bus::QosKind::kState,
               [this](const cell::ToolTable& t, const bus::SampleInfo&) {
                 if (t.station() != station_) return;
                 std::vector<ToolSlot> slots;
                 for (auto& e : t.tools())
                   if (e.socket() > 0) slots.push_back({e.tool().to_string(), e.socket()});
                 std::lock_guard lk(tools_mu_);
                 pending_tools_ = std::move(slots);
               }) {}

Service::~Service() { Stop(); }

void Service::Start() {
  PublishProgress();
  loop_ = std::jthread([this](std::stop_token st) { Loop(st); });
}

void Service::Stop() {
  if (loop_.joinable()) {
    loop_.request_stop();
    loop_.join();
  }
}

void Service::Loop(std::stop_token st) {
  alive_ = true;
  while (!st.stop_requested()) {
    {
      std::lock_guard lk(tools_mu_);
      if (pending_tools_) {
        machine_.SetToolTable(*pending_tools_);
        pending_tools_.reset();
      }
    }
    // Segments in: a new run id starts a new run (its first segment is seq 1).
    while (auto m = segments_.Take(std::chrono::milliseconds(0))) {
      if (m->run_id() != run_id_) {
        run_id_ = m->run_id();
        completed_seq_ = 0;
        seq_of_.clear();
        probe_.clear();
        run_start_s_.reset();
        run_end_s_ = machine_.machine_time();
        if (machine_.alarm().code != AlarmCode::kNone) machine_.Reset();  // a new run starts clean
        alarm_ = Alarm{};
        dirty_ = true;
      }
      uint64_t id = ++next_id_;
      seq_of_[id] = m->seq();
      spdlog::debug("segment run {} seq {} kind {} at machine {:.3f} s", m->run_id(), m->seq(),
                    static_cast<int>(m->kind()), machine_.machine_time());
      if (m->kind() == cell::SEGMENT_PROBE) probe_[id] = true;
      try {
        machine_.Push(FromWire(*m, id));
      } catch (const Error& e) {
        alarm_ = Alarm{AlarmCode::kInvalidSegment, e.what()};
        dirty_ = true;
      }
    }
    bool stepped = machine_.Step();
    HandleEvents();
    if (dirty_) PublishProgress();
    if (std::chrono::steady_clock::now() - last_axes_ >= kAxisPeriod) PublishAxes();
    // Idle on the virtual clock: yield instead of spinning (the real clock sleeps inside Step()).
    if (!stepped) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  alive_ = false;
}

void Service::HandleEvents() {
  for (const Event& e : machine_.TakeEvents()) {
    auto it = seq_of_.find(e.segment_id);
    switch (e.kind) {
      case EventKind::kStarted:
        if (!run_start_s_) run_start_s_ = e.machine_time;
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
            for (int i = 0; i < kNumAxes; ++i) r.position()[static_cast<size_t>(i)] = e.probe.position[i];
            probe_w_.Write(r);
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

void Service::PublishProgress() {
  cell::SegmentProgress p;
  p.station(station_);
  p.run_id(run_id_);
  p.completed_seq(completed_seq_);
  // One credit per free queue slot: segments in flight or queued never exceed the capacity.
  p.credit_seq(completed_seq_ + machine_.capacity());
  p.machine_s(machine_.machine_time());
  p.run_machine_s(run_start_s_ ? run_end_s_ - *run_start_s_ : 0.0);
  if (alarm_.code != AlarmCode::kNone) {
    p.alarm(true);
    p.alarm_code(std::to_string(static_cast<int>(alarm_.code)));
    p.alarm_text(alarm_.text.substr(0, 255));
  }
  progress_.Write(p);
  dirty_ = false;
}

void Service::PublishAxes() {
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
  a.wall_ns(health::WallNs());
  axes_.Write(a);
  last_axes_ = std::chrono::steady_clock::now();
}

}  // namespace cell::servo
