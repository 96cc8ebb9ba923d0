// Canonical commands: the seam between a dialect front-end and the rest of the cell (RS274NGC-style canon).
// Every op is documented in docs/canonical-commands.md.
#pragma once

#include <array>
#include <cstdint>
#include <string>

namespace cell::interp {

// Axis indices, in the order the JSON keys are written.
enum Axis : int { kX = 0, kY, kZ, kA, kB, kC, kU, kV, kW, kAxisCount };

// Lower-case JSON key of an axis ("x" .. "w").
inline const char* AxisName(int axis) {
  static constexpr const char* kNames[kAxisCount] = {"x", "y", "z", "a", "b", "c", "u", "v", "w"};
  return (axis >= 0 && axis < kAxisCount) ? kNames[axis] : "?";
}
// True for the rotary axes A, B, C (degrees); the others are linear (millimetres).
inline bool IsRotaryAxis(int axis) {
  return axis == kA || axis == kB || axis == kC;
}

enum class Op {
  kUnits,       // first op of every run, and again whenever the unit mode changes
  kRapid,       // move at rapid rate
  kLinear,      // straight feed move
  kArc,         // circular or helical feed move
  kDwell,       // G04
  kSpindle,     // spindle on cw/ccw, stop, orient, speed change
  kCoolant,     // coolant mode change
  kToolSelect,  // T word: magazine pre-selection
  kToolChange,  // M06
  kStop,        // M00 / M01
  kEnd,         // M02 / M30
  kPallet,      // M60 mid-program pallet shuttle (M30's shuttle is a field of kEnd)
  kMessage,     // (MSG,...) operator message
  kAlarm,       // M99 audible alarm
  kAux,         // any other M function (clamps, overrides, probe select, ...)
  kRegrid,      // G92: the absolute position registers are reloaded, no motion
  kProbe,       // G22/G23 probe move; the result is reported by the Environment
  kOutput,      // (SET,...) discrete outputs
  kWaitInput,   // (WAI,...) wait for discrete inputs
  kFileOpen,    // OIF / OPF / (MSG,NAM,...)
  kFileWrite,   // FWR / MSG into an open file
  kFileClose,   // CLF / G37
  kFileOp,      // CPY, DLF, PRT, RCP, USF, ULF
  kEvent,       // (EVT,...)
  kToolData,    // TLD / ZTB,T changes to the tool table
};

const char* OpName(Op op);

enum class FeedMode { kPerMinute, kInverseTime, kPerRev, kDegPerMinute };

enum class Plane { kXY, kZX, kYZ };

struct Canon {
  Op op = Op::kRapid;
  int line = 0;  // 1-based line of the block in PROGRAM that caused it (calling block for library code)

  // Motion: absolute end position (mm / deg) after all offsets; `used` says which axes the run has used so
  // far (bit i = Axis i); only those are written.
  std::array<double, kAxisCount> pos{};
  uint32_t used = 0;
  // Signed rotary travel of this block in degrees (rotary axes only, bit i of `travel_mask`).
  std::array<double, kAxisCount> travel{};
  uint32_t travel_mask = 0;

  double feed = 0;  // mm/min, deg/min, 1/min (inverse time)
  FeedMode f_mode = FeedMode::kPerMinute;
  bool exact_stop = false;  // KT-APL G00 (decelerate at block end)

  // Arcs.
  std::array<double, 3> center{};  // absolute x y z (mm)
  bool cw = true;
  std::string plane;  // "xy", "zx", "yz", or co-axis pairs such as "zu"
  double turns = 0;   // angle swept, degrees (positive)

  // Units op.
  bool metric = false;

  // Generic fields used by the other ops (see docs/canonical-commands.md).
  double value = 0;   // dwell seconds, spindle speed, M number, ...
  double value2 = 0;  // spindle orientation angle, ...
  std::string text;   // message / alarm / file name / tool / mode word
  std::string text2;  // file type / second name / ...
  int code = 0;       // M code, probe G code, ...
  bool flag = false;  // optional stop, shuttle at M30, append, ...

  // Back to the defaults above, keeping the strings' buffers (a reused command slot). Keep in step with
  // the member list (canon_test checks Reset against a fresh Canon).
  void Reset() {
    op = Op::kRapid;
    line = 0;
    pos = {};
    used = 0;
    travel = {};
    travel_mask = 0;
    feed = 0;
    f_mode = FeedMode::kPerMinute;
    exact_stop = false;
    center = {};
    cw = true;
    plane.clear();
    turns = 0;
    metric = false;
    value = value2 = 0;
    text.clear();
    text2.clear();
    code = 0;
    flag = false;
  }
};

// One JSON object on a single line, without the trailing newline (DESIGN §4).
std::string ToJsonLine(const Canon& c);
// The same, appended to `out` (no allocation once `out` has grown: the CLI's hot path).
void AppendJsonLine(std::string& out, const Canon& c);

}  // namespace cell::interp
