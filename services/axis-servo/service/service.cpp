#include "cell/servo/service.h"

#include <algorithm>

#include "cell/bus/topics.h"
#include "cell/health/health.h"

namespace cell::servo {

using machine::MachineConfig;

Service::Service(bus::Participant& p, MachineConfig cfg, ClockKind clock)
    : progress_(p, bus::topics::Progress(cfg.station_id), bus::QosKind::kState),
      axes_(p, bus::topics::kAxisState, bus::QosKind::kTelemetry),
      probe_w_(p, bus::topics::Probe(cfg.station_id), bus::QosKind::kCommand),
      rx_(cfg, clock, static_cast<uint64_t>(health::WallNs()), *this),
      segments_(p, bus::topics::Segments(cfg.station_id), bus::QosKind::kStream,
                [this](const cell::MotionSegment& m, const bus::SampleInfo&) { rx_.OnSegment(m); }),
      tools_r_(p, bus::topics::ServoTools(cfg.station_id), bus::QosKind::kState,
               [this](const cell::ToolTable& t, const bus::SampleInfo&) { rx_.OnTools(t); }),
      control_r_(p, bus::topics::ServoControl(cfg.station_id), bus::QosKind::kState,
                 [this](const cell::ServoControl& c, const bus::SampleInfo&) { rx_.OnControl(c); }),
      part_r_(p, bus::topics::Part(cfg.station_id), bus::QosKind::kState,
              [this](const cell::PartModel& m, const bus::SampleInfo&) { rx_.OnPartModel(m); }) {}

Service::~Service() {
  Stop();
}

void Service::Start() {
  rx_.PublishProgress();
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
    const Receiver::Turn turn = rx_.Tick(std::chrono::steady_clock::now());
    if (turn.waiting) {
      rx_.WaitForSegment(std::chrono::milliseconds(1));
    } else if (turn.resting || !turn.stepped) {
      // Nothing moves (idle on the virtual clock, resting on the real one): sleep until something arrives
      // (a segment, tools, a part model or a panel command wakes it) or the next axis sample is due,
      // instead of turning 1000 times a second.
      const auto now = std::chrono::steady_clock::now();
      rx_.WaitForSegment(std::clamp<std::chrono::steady_clock::duration>(
          rx_.AxesDue() - now, std::chrono::milliseconds(1), Receiver::kRestAxisPeriod));
    }
  }
  alive_ = false;
}

}  // namespace cell::servo
