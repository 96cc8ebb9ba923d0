// What the station shows and what its operator presses.
//
// StatusBoard: the station's state (StationStatus, MTConnect vocabulary) with the one rule for the displayed
// execution: while the servo reports the operator's feed hold in effect it shows FEED_HOLD, otherwise what
// the run state says (READY, ACTIVE, WAIT, PROGRAM_COMPLETED, STOPPED).
//
// Panel: feed hold, cycle start and overrides (persisted: a held machine stays held when its interpreter
// restarts) and the abort of a cancelled run (not persisted), published to the servo as ServoControl.
//
// Each publishes under its own lock, so samples of one topic never overtake each other.
#pragma once

#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <string>

#include "cell/idl/motion.h"
#include "cell/idl/station.h"
#include "cell/station/clock.h"
#include "cell/station/station_db.h"

namespace cell::station {

class StatusBoard {
 public:
  StatusBoard(const std::string& station, const std::string& dialect, Clock& clock,
              std::function<void(const cell::StationStatus&)> publish);

  void Queued(int n);  // runs accepted and not yet started
  void RunStarted(std::int32_t pallet, std::int32_t dispatch_id);
  void RunEnded(bool completed, int queued);
  // Where the run is (published with the next Publish: the caller throttles).
  void Position(const std::string& program, int line, const std::string* tool);
  // The run waits: for inputs (KT-APL WAI, execution WAIT, "waiting for I04D.1=1") or for the operator's
  // cycle start after M00 / M01 (PROGRAM_STOPPED / OPTIONAL_STOP); `text` is the status text; "" when the
  // wait is over (ACTIVE again).
  void Waiting(const std::string& text, cell::Execution execution = cell::EXECUTION_WAIT);
  // The program's operator message (KT-APL MSG outside an inspection file, Okuma/EMCO messages): the status
  // text while nothing is awaited, until the next message or the run's end.
  void Message(const std::string& text);
  std::string LastMessage() const;
  void Warning(const std::string& code, const std::string& text);  // a program error: condition WARNING
  void Reset();                                                    // condition NORMAL, alarm cleared
  void ServoHeld(bool held);                                       // publishes when it changes the display
  void Publish();
  // The run loop's periodic sample: published only when something changed since the last one (a block of
  // a long move is one line for many periods; 32 running stations at 10 Hz were the scheduler's largest
  // inflow, issue 43).
  void PublishChanged();
  cell::StationStatus Get() const;

 private:
  void Show();  // the displayed execution (caller holds mu_)
  void Send();  // stamps, keeps and publishes status_ (caller holds mu_)

  Clock& clock_;
  std::function<void(const cell::StationStatus&)> publish_;
  mutable std::mutex mu_;
  cell::StationStatus status_;
  cell::StationStatus sent_;                      // the last sample published (its updated_ns aside)
  cell::Execution base_ = cell::EXECUTION_READY;  // what the run state alone says
  bool held_ = false;
  std::string message_;  // the run's last operator message
};

class Panel {
 public:
  Panel(const std::string& station, StationDb& db, std::function<void(const cell::ServoControl&)> publish);

  // STATION_FEED_HOLD, STATION_CYCLE_START or STATION_OVERRIDE: recorded, persisted, published; returns
  // the control's revision. Throws cell::Error(kInvalidArgument) for an override out of range.
  std::uint32_t Press(const cell::StationRequest& r);
  // The [ENABLE OPTION STOP] switch as the operator last set it (persisted); unset: never touched, the
  // station file's [params] OPTIONAL_STOP decides.
  std::optional<bool> OptionalStop() const;
  // Cycle starts pressed since the process started: a run stopped at M00 goes on at the next one.
  std::uint64_t CycleStarts() const;
  // The scheduler cancelled the running dispatch: the servo stops it too.
  void AbortRun(std::int32_t run_id);
  // The program fixes feed and spindle speed at 100 % (KT-APL M49, Okuma M161: an `overrides` op) or gives
  // the selectors back (M48, M06, the program's end). While fixed the servo gets a feed override of 100 % (0
  // % stays 0 %: "axis motion is inhibited", ln 2917); the operator's setting is kept, changes to it are
  // recorded, and it is published again when the program releases the selectors. The servo's spindle has no
  // override, so the spindle is always at 100 %. Not persisted: a restarted interpreter starts no program.
  void FixOverrides(bool fixed);
  void Publish();
  cell::ServoControl Get() const;  // what the servo is sent

 private:
  cell::ServoControl Sent() const;  // control_ as the servo gets it (caller holds mu_)

  StationDb& db_;
  std::function<void(const cell::ServoControl&)> publish_;
  mutable std::mutex mu_;
  cell::ServoControl control_;
  std::uint64_t cycle_starts_ = 0;
  std::optional<bool> optional_stop_;
  bool overrides_fixed_ = false;
};

}  // namespace cell::station
