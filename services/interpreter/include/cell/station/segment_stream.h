// The motion segment stream from the station to its axis servo (docs/axis-servo.md, "Credits" and
// "Re-sends"): segments of a run carry seq 1, 2, ...; segment n leaves only when n <= the servo's credit_seq
// (4 before the servo has spoken for the run); every segment is kept until the servo reports it completed
// and is sent again, in order, from the servo's received_seq when the servo matches again or has been silent
// for a second with segments missing. A servo alarm, a restarted servo (new boot_id), a servo that vanished
// or takes nothing for 10 s end the run with an error.
//
// Thread-safe: the run's thread sends and waits; progress and probe results arrive from any thread. No DDS:
// the ServoLink writes the segments, the Clock times every wait.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "cell/idl/motion.h"
#include "cell/station/clock.h"
#include "cell/tooltable/tooltable.h"

namespace cell::station {

// The servo side of the stream (the service: a bus writer on cell/station/<ID>/segments).
class ServoLink {
 public:
  virtual ~ServoLink() = default;
  virtual void Write(const cell::MotionSegment& segment) = 0;  // never called under the stream's lock
  virtual std::size_t Matched() = 0;                           // servos matched now
  virtual std::uint64_t TotalMatched() = 0;                    // matches since creation (a re-match counts)
  // True when a servo is there in both directions (segments out, progress in) within `timeout`.
  virtual bool WaitForServo(Clock::Duration timeout) = 0;
  // The run's part model (cell/station/<ID>/part, a state topic).
  virtual void WritePart(const cell::PartModel& part) = 0;
  // Joins the bus anew (a new DDS participant, a stranger to every peer): discovery with the servo starts
  // clean, both ways. Never called under the stream's lock.
  virtual void Rejoin() = 0;
};

class SegmentStream {
 public:
  static constexpr std::uint64_t kInitialCredit = 4;  // segments sent before the servo has spoken for a run
  static constexpr auto kServoGone = std::chrono::seconds(10);
  static constexpr auto kResendAfter = std::chrono::seconds(1);
  static constexpr auto kPoll = std::chrono::milliseconds(200);
  static constexpr auto kProbeTimeout = std::chrono::seconds(120);

  SegmentStream(std::string station, Clock& clock, ServoLink& link);

  // A new run: counting restarts. `checkpoint` runs in every wait of the run and throws to end it (a
  // cancel, the station stopping).
  void Begin(std::int32_t run_id, std::function<void()> checkpoint);
  // True when a servo is on the bus (both directions) within `timeout`, or within `timeout` more after this
  // process joined the bus anew.
  bool WaitForServo(Clock::Duration timeout);
  // Sends the next segment of the run (station, run id and seq are filled in), waiting for a credit.
  // Throws cell::Error when the run cannot go on.
  void Send(cell::MotionSegment segment);
  // Gives the servo the run's workpiece (its pallet map named a part model; station, run id filled in) and
  // waits until the servo reports holding it, before the run's first segment. Throws cell::Error when the
  // servo does not take it within kServoGone.
  void SendPart(cell::PartModel part);
  // Sends a probe move and waits for its result.
  cell::ProbeResult Probe(cell::MotionSegment segment);
  // Waits until the servo has completed every segment sent.
  void WaitDrained();
  // Waits, with every check of the run (cancel, stop, servo alarm, lost servo), until `ready()` holds:
  // KT-APL WAI. `ready` runs without the stream's lock; whoever changes its answer calls Wake().
  void WaitUntil(const std::function<bool()>& ready);

  // From the servo. OnProgress returns true when the servo's report of the operator's feed hold changed.
  bool OnProgress(const cell::SegmentProgress& p);
  void OnProbe(const cell::ProbeResult& r);
  // Wakes the waits (after a cancel or a stop request) so that their checkpoint runs now.
  void Wake();

  // The tools' cutting time the servo reported since the last call (per tool and socket, from its cumulative
  // counts of this run): charged to their life by the run (at M06) or by the commit after it.
  std::vector<tooltable::ToolWear> TakeWear();

  double RunMachineSeconds() const;
  bool ServoHeld() const;
  std::uint64_t SentSeq() const;
  std::size_t Unacknowledged() const;  // sent, not yet completed

 private:
  void WaitCredit(std::unique_lock<std::mutex>& lk, std::uint64_t seq);
  void Check(std::unique_lock<std::mutex>& lk);
  bool RejoinOnce(std::unique_lock<std::mutex>& lk, const char* why);
  void ResendMissing(std::unique_lock<std::mutex>& lk);

  const std::string station_;
  Clock& clock_;
  ServoLink& link_;
  mutable std::mutex mu_;
  std::condition_variable cv_;
  std::function<void()> checkpoint_;
  std::int32_t run_id_ = 0;
  std::uint64_t sent_seq_ = 0, completed_seq_ = 0, credit_seq_ = 0;
  std::uint64_t received_seq_ = 0;  // the servo holds 1..received_seq_ of this run (its last report)
  double run_machine_s_ = 0;
  bool alarm_ = false;
  std::string alarm_code_, alarm_text_;
  std::int32_t servo_part_run_ = 0;                  // the run whose part model the servo reports holding
  std::uint64_t run_boot_ = 0;                       // the servo process this run started on
  bool servo_restarted_ = false;                     // progress came from another servo process mid-run
  bool servo_held_ = false;                          // the servo reports the operator's feed hold in effect
  bool rejoined_ = false;                            // this run has joined the bus anew for a deaf servo
  std::optional<Clock::TimePoint> unmatched_since_;  // the segment writer matches no servo since then
  std::deque<cell::MotionSegment> unacked_;          // written, not yet completed
  std::uint64_t matches_ = 0;                        // link_.TotalMatched() at the last check
  Clock::TimePoint last_progress_{}, last_report_{}, last_resend_{};
  std::map<std::uint64_t, cell::ProbeResult> probes_;  // results of this run by seq
  struct Cut {
    double reported_s = 0;  // the servo's cumulative count for this run
    double taken_s = 0;     // what TakeWear has handed out
  };
  std::map<std::pair<std::string, int>, Cut> cut_;  // this run's cutting time by (tool, socket)
};

}  // namespace cell::station
