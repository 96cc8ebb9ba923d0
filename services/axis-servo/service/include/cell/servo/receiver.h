// The receiving side of the axis servo (docs/axis-servo.md, "Over DDS"), without DDS: segments of the
// station's stream taken in seq order (each once; a run joined only at seq 1; a new run aborts what is left
// of an abandoned one), credits and progress, probe results, the operator panel (ServoControl), the magazine
// from the station's tool table, and telemetry on the wall clock. The service feeds it bus samples and
// publishes what it reports; tests drive it with injected times.
//
// Threads: OnSegment, OnTools, OnControl and OnPartModel from any thread; Tick and WaitForSegment from the
// loop thread, which alone touches the Machine.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "cell/idl/motion.h"
#include "cell/idl/station.h"
#include "cell/servo/machine.h"
#include "cell/tooltable/tooltable.h"

namespace cell::servo {

// IDL segment -> library segment.
Segment FromWire(const cell::MotionSegment& m, uint64_t id);

// Where the receiver's reports go (the service: bus writers).
class ReceiverSink {
 public:
  virtual ~ReceiverSink() = default;
  virtual void Progress(const cell::SegmentProgress& p) = 0;
  virtual void Probe(const cell::ProbeResult& r) = 0;
  virtual void Axes(const cell::AxisState& a) = 0;
};

class Receiver {
 public:
  using TimePoint = std::chrono::steady_clock::time_point;
  static constexpr auto kAxisPeriod =
      std::chrono::milliseconds(20);  // 50 Hz in wall time, whatever the clock, while anything moves
  // A machine at rest (nothing moves, the spindle stopped) repeats its unchanged axis state at 4 Hz: 32
  // resting servos at 50 Hz were a third of an idle 32-station cell's CPU (issue 43). The first sample at
  // rest goes out at once, so the position it stopped at is never late.
  static constexpr auto kRestAxisPeriod = std::chrono::milliseconds(250);
  // Virtual clock: how long (wall) the machine waits for the producer to refill a look-ahead queue that is
  // less than half full before it runs on with what it has, unless the producer said it waits for the
  // machine (see LookAheadStarved()). Was 5 ms, which a producer short of CPU overran (a thread chain cut
  // in two: Okuma G34/G35 0.973 against its prediction under a load of 12 on 2 cores).
  static constexpr auto kLookAheadWait = std::chrono::milliseconds(250);
  static constexpr std::size_t kMaxCutTools = 128;  // SegmentProgress.cutting's bound

  Receiver(machine::MachineConfig cfg, ClockKind clock, std::uint64_t boot_id, ReceiverSink& sink);

  // ---- from the bus (any thread) ----
  void OnSegment(cell::MotionSegment m);
  void OnTools(const cell::ToolTable& t);
  void OnControl(const cell::ServoControl& c);
  // The workpiece of a run (its pallet map named a part model); acknowledged in progress (part_run_id).
  void OnPartModel(const cell::PartModel& p);

  // ---- the loop thread ----
  struct Turn {
    bool stepped = false;  // the machine ran a servo period
    bool waiting = false;  // the look-ahead waits for the producer's refill (virtual clock): WaitForSegment
    // Real clock, nothing moves (Machine::Resting): WaitForSegment, the periods run later.
    bool resting = false;
  };
  // One turn at wall time `now`: tools and panel applied, arrived segments taken, one servo period, events
  // reported.
  Turn Tick(TimePoint now);
  // Waits up to `d` for a segment, tools, a part model or a panel command to arrive.
  void WaitForSegment(std::chrono::steady_clock::duration d);
  // When the next axis sample is due (a resting loop sleeps until then unless something arrives).
  TimePoint AxesDue() const { return last_axes_ + (quiet_ ? kRestAxisPeriod : kAxisPeriod); }
  // Reports progress now (at start-up: run 0).
  void PublishProgress();

  const Machine& machine() const { return machine_; }
  std::int32_t run_id() const { return run_id_; }

 private:
  void TakeArrived(TimePoint now);
  bool Accept(const cell::MotionSegment& m);
  void RefuseAbsentAxes(const cell::MotionSegment& m);
  void StartRun(std::int32_t run_id);
  void ApplyControl();
  bool LookAheadStarved(TimePoint now) const;
  bool AwaitingProducer() const;
  void HandleEvents();
  void PublishAxes(TimePoint now);

  const std::string station_;
  const ClockKind clock_;
  const std::uint64_t boot_id_;  // this process, in every progress sample
  ReceiverSink& sink_;
  Machine machine_;

  // Filled by the bus threads.
  std::mutex in_mu_;
  std::condition_variable in_cv_;
  std::deque<cell::MotionSegment> arrived_;
  std::optional<tooltable::ToolTable> pending_tools_;
  std::optional<cell::ServoControl> pending_control_;
  struct RunPart {
    std::int32_t run_id = 0;
    partmodel::PartModel model;
  };
  std::optional<RunPart> pending_part_;
  bool wake_ = false;            // something besides a segment arrived: the resting loop turns now
  std::optional<RunPart> part_;  // the loop thread's: applied when its run starts

  // The loop thread's run bookkeeping.
  std::int32_t run_id_ = 0;
  std::uint64_t next_id_ = 0;
  std::map<std::uint64_t, std::uint64_t> seq_of_;  // machine segment id -> run seq
  std::set<std::uint64_t> probe_;                  // machine ids of probe segments
  std::vector<Event> events_;  // HandleEvents()'s buffer, swapped with the machine's (no allocation per take)
  std::deque<cell::MotionSegment> inbox_;  // taken, not yet pushed (held while a run is abandoned)
  bool abandoning_ = false;                // aborting the previous run's leftovers
  bool arriving_ = false;      // taking the machine to the state a pallet arrives in (Machine::ToArrival)
  bool end_received_ = false;  // the run's END segment has arrived
  TimePoint last_segment_at_{};
  std::uint64_t received_seq_ = 0;  // highest seq of this run taken in order (re-sent duplicates are dropped)
  std::uint64_t completed_seq_ = 0;
  std::uint64_t waits_seq_ = 0;  // the producer waits for the machine once this seq is done (.waits)
  std::optional<double> run_start_s_;
  double run_end_s_ = 0;
  Alarm alarm_;
  bool dirty_ = true;
  TimePoint last_axes_{};
  bool resting_ = false;          // the last turn found the machine resting
  bool quiet_ = false;            // the last turn moved nothing (resting, or idle on the virtual clock)
  bool feed_hold_ = false;        // the operator's hold, re-applied after every reset
  std::int32_t aborted_run_ = 0;  // cancelled by the operator: its later segments are dropped
};

}  // namespace cell::servo
