// Binds the simulated machine to the bus: segments in (credit flow control), progress, probe
// results and axis state out. One loop thread owns the Machine (it is single-threaded).
#pragma once

#include <atomic>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "cell/bus/bus.h"
#include "cell/idl/motion.h"
#include "cell/idl/station.h"
#include "cell/servo/machine.h"

namespace cell::servo {

// IDL segment -> library segment (exposed for tests).
Segment FromWire(const cell::MotionSegment& m, uint64_t id);

class Service {
 public:
  Service(bus::Participant& p, MachineConfig cfg, ClockKind clock);
  ~Service();
  void Start();
  void Stop();
  bool Healthy() const { return alive_.load(); }

 private:
  void Loop(std::stop_token st);
  void HandleEvents();
  void PublishProgress();
  void PublishAxes();
  bool LookAheadStarved() const;
  bool Accept(const cell::MotionSegment& m);
  void ApplyControl();

  std::string station_;
  ClockKind clock_;
  const uint64_t boot_id_;  // this process, in every progress sample
  Machine machine_;
  std::atomic<bool> alive_{false};
  // Run bookkeeping (loop thread only).
  int32_t run_id_ = 0;
  uint64_t next_id_ = 0;
  std::map<uint64_t, uint64_t> seq_of_;    // machine segment id -> run seq
  std::map<uint64_t, bool> probe_;         // machine ids of probe segments
  std::deque<cell::MotionSegment> inbox_;  // received, not yet pushed (held while a run is abandoned)
  bool abandoning_ = false;                // aborting the previous run's leftovers
  bool end_received_ = false;              // the run's END segment has arrived
  std::chrono::steady_clock::time_point last_segment_at_{};
  uint64_t received_seq_ = 0;  // highest seq of this run taken in order (re-sent duplicates are dropped)
  uint64_t completed_seq_ = 0;
  std::optional<double> run_start_s_;
  double run_end_s_ = 0;
  Alarm alarm_;
  bool dirty_ = true;
  std::chrono::steady_clock::time_point last_axes_{};

  std::mutex tools_mu_;
  std::optional<tooltable::ToolTable> pending_tools_;
  std::optional<cell::ServoControl> pending_control_;  // guarded by tools_mu_
  bool feed_hold_ = false;                             // the operator's hold, re-applied after every reset
  int32_t aborted_run_ = 0;  // cancelled by the operator: its later segments are dropped

  bus::Reader<cell::MotionSegment> segments_;
  bus::Writer<cell::SegmentProgress> progress_;
  bus::Writer<cell::AxisState> axes_;
  bus::Writer<cell::ProbeResult> probe_w_;
  bus::Reader<cell::ToolTable> tools_r_;
  bus::Reader<cell::ServoControl> control_r_;
  std::jthread loop_;
};

}  // namespace cell::servo
