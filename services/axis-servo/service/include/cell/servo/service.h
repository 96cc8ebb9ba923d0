// cell-axis-servo's bus binding: the Receiver (cell/servo/receiver.h) on DDS. Segments, the station's tool
// table and its panel come in through readers; progress, probe results and axis state go out; one loop
// thread owns the machine.
#pragma once

#include <atomic>
#include <thread>

#include "cell/bus/bus.h"
#include "cell/idl/motion.h"
#include "cell/idl/station.h"
#include "cell/servo/receiver.h"

namespace cell::servo {

class Service final : public ReceiverSink {
 public:
  Service(bus::Participant& p, machine::MachineConfig cfg, ClockKind clock);
  ~Service() override;
  void Start();
  void Stop();
  bool Healthy() const { return alive_.load(); }

  void Progress(const cell::SegmentProgress& p) override { progress_.Write(p); }
  void Probe(const cell::ProbeResult& r) override { probe_w_.Write(r); }
  void Axes(const cell::AxisState& a) override { axes_.Write(a); }

 private:
  void Loop(std::stop_token st);

  bus::Writer<cell::SegmentProgress> progress_;
  bus::Writer<cell::AxisState> axes_;
  bus::Writer<cell::ProbeResult> probe_w_;
  Receiver rx_;  // after the writers it reports to, before the readers that feed it
  bus::Reader<cell::MotionSegment> segments_;
  bus::Reader<cell::ToolTable> tools_r_;
  bus::Reader<cell::ServoControl> control_r_;
  bus::Reader<cell::PartModel> part_r_;
  std::atomic<bool> alive_{false};
  std::jthread loop_;
};

}  // namespace cell::servo
