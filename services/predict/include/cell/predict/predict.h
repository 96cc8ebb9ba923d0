// Predicted cycle times (issue 40, DESIGN §6b): a program run offline through its dialect and one station's
// servo model (cell/servo/machine.h) on the virtual clock, as the station would run it: the canonical ops
// become motion segments through the station's own mapping (ToSegment, then the servo's FromWire), the
// machine takes them on credit with its look-ahead, and waits where the station waits for the machine
// (outputs, M00, Balt-System '#', probes). The result is machine seconds from the first segment's start to
// the last one's completion: the interval of a job's cycle_s (docs/axis-servo.md "Cycle time").
//
//   cell::predict::Input in;
//   in.program = "PUMP"; in.text = text; in.program_dialect = "ktapl";
//   in.station = cell::interp::LoadStation("KT01");
//   cell::predict::Prediction p = cell::predict::Predict(in);  // p.seconds or p.why
//
// What only a run knows (an input wait, a probe without a part model) gives no number but a reason.
#pragma once

#include <functional>
#include <map>
#include <optional>
#include <stop_token>
#include <string>

#include "cell/config/config.h"
#include "cell/machine/machine_config.h"
#include "cell/tooltable/tooltable.h"

namespace cell::predict {

struct Input {
  std::string program;          // the name, for diagnostics and the run's PROGRAM
  std::string text;             // the program's text
  std::string program_dialect;  // what the store recorded; "" = the station's
  config::StationConfig station;
  // The station's machine model; nullopt: read from the station file (station.file).
  std::optional<machine::MachineConfig> machine;
  // Subprograms and cycles by name, as the station finds them (its namespace, then HOST); nullptr: none.
  std::function<std::optional<std::string>(const std::string&)> library;
  // The station's published tool table and kept variables; nullopt/empty: the station file's tools.
  std::optional<tooltable::ToolTable> tools;
  std::map<std::string, double> variables;
  int pallet = 0;  // the pallet the run is for (KT-APL L3020, the part model probed); 0: not known
  // Bounds on a program that never ends offline (a loop on a variable only a run changes).
  double max_machine_s = 24 * 3600.0;
  long max_ops = 20'000'000;
  double max_wall_s = 10.0;  // a prediction is not worth more of the machine than this
  std::stop_token stop;      // a caller that stops (the scheduler's PredictionQueue) ends the run early
};

struct Prediction {
  std::optional<double> seconds;  // machine seconds, first segment to end; nullopt: see why
  std::string why;                // why there is no number ("" when there is one)
  // No number this time only: the wall-clock bound passed or the caller stopped (another try may finish).
  bool transient = false;
  long segments = 0;  // motion and device segments the servo ran
};

Prediction Predict(const Input& in);

// Why a station cannot run a program of `program_dialect` at all ("" when it can): the same rule as the
// scheduler's (docs/scheduler.md §1: a station runs programs of its own dialect only; aliases compare equal).
std::string DialectMismatch(const std::string& program_dialect, const config::StationConfig& station);

}  // namespace cell::predict
