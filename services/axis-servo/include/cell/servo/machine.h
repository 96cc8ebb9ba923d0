// The simulated machine: segment queue with credits, planner, jerk filter, servo loop and plant, devices
// (tool changer, pallet shuttle, spindle, coolant, B index table) and probe, on a real or virtual clock.
//
// Threading: a Machine is used from one thread at a time (the service serialises access, e.g. one loop
// thread that drains its DDS inputs between Step() calls).
#pragma once

#include <chrono>
#include <cmath>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "cell/machine/machine_config.h"
#include "cell/partmodel/part_model.h"
#include "cell/servo/planner.h"
#include "cell/servo/segment.h"
#include "cell/servo/servo.h"
#include "cell/servo/spindle.h"

namespace cell::servo {

enum class ClockKind {
  kReal,     // one servo period per wall-clock period; machine time runs with the wall clock
  kVirtual,  // as fast as the CPU allows; machine time advances only while the machine is active
};

// Station execution state in the MTConnect vocabulary used by the cell.
enum class Execution { kReady, kActive, kFeedHold, kStopped };

struct AxisState {
  double machine_time = 0;                          // s
  AxisVector commanded = AxisVector::Zero();        // after the jerk filter (segment convention)
  AxisVector actual = AxisVector::Zero();           // plant position (segment convention)
  AxisVector velocity = AxisVector::Zero();         // actual, units/min
  AxisVector following_error = AxisVector::Zero();  // commanded - actual, axis units (radius on X)
  double path_feed = 0;                             // interpolator speed, units/min
  Execution execution = Execution::kReady;
  Alarm alarm;
  std::uint64_t segment_id = 0;    // segment being interpolated (0: none)
  double fraction = 0;             // of that segment, 0..1
  double spindle_rpm = 0;          // signed: + cw, - ccw
  double spindle_angle = 0;        // degrees from the index mark, [0, 360), clockwise
  double spindle_revolutions = 0;  // signed, since start-up (+ cw)
  bool spindle_oriented = false;
  bool c_joined = false;     // a lathe's work spindle is joined as the C axis (Okuma M110)
  double live_tool_rpm = 0;  // a lathe's live-tool (M-tool) spindle, signed: + cw (M13), - ccw (M14)
  CoolantMode coolant = CoolantMode::kOff;
  std::string tool;  // in the spindle ("" none)
  int pallet_on_table = 0, pallet_on_shuttle = 0;
  bool b_clamped = true;
};

class Machine {
 public:
  Machine(machine::MachineConfig config, ClockKind clock);

  const machine::MachineConfig& config() const { return cfg_; }
  ClockKind clock() const { return clock_kind_; }
  double period() const { return cfg_.servo_period_s; }

  // ---- Flow control: one credit per free queue slot. A slot frees when its segment completes.
  std::size_t capacity() const { return static_cast<std::size_t>(cfg_.queue_capacity); }
  std::size_t credits() const { return capacity() - queue_.size(); }
  // Queues a segment. Throws cell::Error(kFailedPrecondition) when no credit is left, or while an alarm is
  // active (Reset first); kInvalidArgument for non-finite numbers or a negative feed or dwell.
  void Push(const Segment& segment);

  // ---- Running. Step() runs one servo period and returns true, or returns false without advancing time
  // when the virtual clock has nothing to do (idle). On the real clock it first sleeps until the period's
  // wall-clock deadline and always advances.
  bool Step();
  // Step() without the real clock's sleep: for callers that wait for NextDeadline() themselves (outside a
  // lock, as Runner does). On the virtual clock the same as Step().
  bool StepNow();
  // Real clock: wall-clock time at which the next period is due.
  std::chrono::steady_clock::time_point NextDeadline();
  // Steps until idle (queue empty, everything settled), an alarm, or `max_machine_s` more machine time.
  // Returns the number of periods run.
  std::uint64_t RunUntilIdle(double max_machine_s = 1e9);
  bool Idle() const;  // nothing queued, executing or settling
  // Real clock, idle, spindle stopped: nothing moves, so a caller may sleep longer than a period and then
  // CatchUp() (an idle servo woke 1000 times a second: with 24 stations, half a core for standing still).
  bool Resting() const;
  // Real clock: runs every period already due, without sleeping and without counting them as overruns.
  // Machine time keeps running with the wall clock while the caller rests. Returns the periods run.
  std::uint64_t CatchUp();
  double machine_time() const { return static_cast<double>(ticks_) * cfg_.servo_period_s; }
  std::uint64_t ticks() const { return ticks_; }
  std::uint64_t overruns() const { return overruns_; }  // real clock: periods that started late

  // ---- Operator controls.
  void FeedHold();  // decelerate along the path and stop on it
  void Resume();    // continue along the path
  void Abort();     // flush the queue and stop (motion decelerates along the path first)
  void Reset();     // clear alarms, flush; after DIFF over (or if moving) the command re-syncs to actual
  void SetFeedOverride(double fraction);   // 0..2 (0%..200%)
  void SetRapidOverride(double fraction);  // 0..1

  // ---- Devices and probing.
  void SetToolTable(const tooltable::ToolTable& table);  // magazine contents: the station table's sockets
  void SetPartModel(int pallet, partmodel::PartModel model);
  // The workpiece of the run now going on, when its pallet map named one (PartModel topic): probed instead
  // of the table pallet's model until cleared (nullopt) at the next run.
  void SetRunPart(std::optional<partmodel::PartModel> model) { run_part_ = std::move(model); }
  void SetPallets(int on_table, int on_shuttle);
  // The tools the operator says are broken (ServoControl), beside the station file's [magazine] broken: a
  // G38 check of such a tool finds it broken.
  void SetBrokenSockets(const std::vector<int>& sockets);
  // The state a pallet arrives in, which is the state the machine starts in: the axes at the zero, the
  // spindles stopped, the coolant off, the spindle empty and the magazine at socket 1 (docs/predict.md
  // judgement call 4). The segments that take the machine there from where it stands, none when it is
  // there; the receiver runs them before a new run's first segment, outside the run's cycle time.
  std::vector<Segment> ToArrival() const;

  // Cutting time since ResetCutting(), per tool that was in the spindle: machine seconds of feed moves
  // (linear, arc, thread) with the spindle turning. The station charges it to the tools' life.
  struct ToolCut {
    std::string tool;
    int socket = 0;
    double cutting_s = 0;
  };
  const std::vector<ToolCut>& Cutting() const { return cutting_; }
  void ResetCutting();

  // ---- Observation.
  // Events since the last call (started, completed with probe results, flushed, alarms), in order.
  std::vector<Event> TakeEvents();
  // The same into `into` (cleared first), whose buffer the machine keeps for the next events: a loop that
  // takes events every few periods allocates nothing (the by-value form allocates a new buffer each call).
  void TakeEvents(std::vector<Event>& into);
  bool HasEvents() const { return !events_.empty(); }
  AxisState State() const;
  Execution execution() const;
  const Alarm& alarm() const { return alarm_; }
  const AxisVector& commanded() const { return filter_.Output(); }  // machine units (X radius)
  const AxisVector& interpolated() const { return planner_.Position(); }
  AxisVector actual() const;
  AxisVector following_error() const;
  const Planner& planner() const { return planner_; }
  int filter_length() const { return filter_.length(); }

 private:
  struct Entry {
    Segment seg;           // in machine units (lathe X as a radius)
    bool planned = false;  // handed to the planner or to the device sequencer
  };
  enum class OpPhase { kNone, kTimer, kMotion, kIndexUnclamp, kIndexMove, kIndexClamp, kIndexRest };
  struct Op {
    OpPhase phase = OpPhase::kNone;
    std::uint64_t seg = 0;
    double until = 0;  // machine time when the timer phase ends
    Segment s;
    double t0 = 0;            // machine time when the operation started
    double index_target = 0;  // B index move, shortest way (may lie outside [min, max] until clamped)
  };
  struct PendingCompletion {
    std::uint64_t seg;
    std::uint64_t release_tick;
    bool wait_in_position;
  };

  void FeedPlanner();
  bool StartBarrier(Entry& e);
  void StepOp();
  void Complete(std::uint64_t seg, const ProbeResult* probe = nullptr);
  void RaiseAlarm(AlarmCode code, const std::string& text, std::uint64_t seg);
  void FlushAll();
  bool InPosition(const AxisVector& target, double tol = 0) const;
  bool SoftLimitCheck(const Segment& s, const AxisVector& start, std::string& why) const;
  AxisVector EndOf(const Segment& s, const AxisVector& start) const;
  Feed FeedOf(const Segment& s, double length) const;
  double FeedNow(const Segment& s, double length) const;  // units/s at today's spindle speed
  bool PlanThread(const Segment& s, const AxisVector& start, const AxisVector& end, std::string& why);
  bool StartSpindle(const Segment& s);
  int MagazineSteps(int socket) const;
  bool StartLiveTool(const Segment& s);
  // A lathe's C-axis joint (M110) or its release (M109): false after an alarm; `t` the seconds it takes.
  bool StartJoint(const Segment& s, double& t);
  double XDiameter() const { return 2.0 * std::abs(filter_.Output()[kX]); }  // constant surface speed
  void Emit(EventKind kind, std::uint64_t seg, const Alarm* alarm = nullptr,
            const ProbeResult* probe = nullptr);
  AxisVector ToSegmentUnits(AxisVector v) const;
  void ProbeCheck();
  void ChargeCutting(double seconds);
  bool SpindleToolBroken() const;
  const partmodel::PartModel* PartOnTable() const;
  // The stylus ball's centre in the part model's frame: the machine position less the probe's length (to the
  // ball's tip), plus the ball's radius in Z.
  partmodel::Pose PoseOf(const AxisVector& v) const;

  machine::MachineConfig cfg_;
  ClockKind clock_kind_;
  PlannerLimits limits_;
  Planner planner_;
  JerkFilter filter_;
  std::array<AxisServo, kNumAxes> servos_{};
  std::array<bool, kNumAxes> present_{};
  // The present axes' indices in axis order, for the per-tick loops (no branch per absent axis).
  std::array<int, kNumAxes> axes_{};
  int num_axes_ = 0;
  bool co_axes_ = false;  // the machine has U, V or W: the per-period vector arithmetic is nine wide

  std::deque<Entry> queue_;
  std::size_t next_ = 0;  // first queue entry not yet planned
  std::deque<PendingCompletion> pending_;
  Op op_;
  std::vector<Event> events_;

  std::uint64_t ticks_ = 0, overruns_ = 0;
  std::chrono::steady_clock::time_point wall_start_{};
  bool wall_started_ = false;
  AxisVector prev_cmd_ = AxisVector::Zero(), prev_vel_ = AxisVector::Zero();
  bool alarm_pending_ = false;
  Alarm pending_alarm_;
  Alarm alarm_;
  std::uint64_t alarm_seg_ = 0;
  bool aborting_ = false;
  double feed_ovr_ = 1.0, rapid_ovr_ = 1.0;

  // Devices
  Spindle spindle_;
  Spindle live_tool_;  // a lathe's live-tool (M-tool) spindle, when the machine has one
  bool spindle_oriented_ = false;
  // A lathe whose C axis is its work spindle in position control: C moves only while joined (M110), and
  // the spindle cannot turn while it is. Kept through Reset(), as M110 is through the NC's reset (ln 2059).
  bool c_is_spindle_ = false;
  bool c_joined_ = false;
  CoolantMode coolant_ = CoolantMode::kOff;
  std::map<int, std::string> magazine_;  // socket -> tool
  std::string spindle_tool_;
  int spindle_tool_socket_ = 0;
  std::vector<int> broken_commanded_;  // SetBrokenSockets
  std::vector<ToolCut> cutting_;
  int cut_index_ = -1;  // cutting_'s entry of the spindle tool, once it has cut
  int magazine_at_ = 1;
  int pallet_table_ = 0, pallet_shuttle_ = 0;
  bool b_clamped_ = true;
  std::map<int, partmodel::PartModel> parts_;
  std::optional<partmodel::PartModel> run_part_;

  // Probe
  bool probing_ = false, probe_tripped_ = false, probe_break_ = false;
  double probe_length_ = 0;
  std::uint64_t probe_seg_ = 0;
  AxisVector probe_prev_ = AxisVector::Zero(), probe_trip_ = AxisVector::Zero();
};

const char* ExecutionName(Execution e);
const char* SegmentKindName(SegmentKind k);

}  // namespace cell::servo
