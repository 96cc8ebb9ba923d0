// Canonical commands: the seam between a dialect front-end and the rest of the cell (RS274NGC-style canon).
// Every op has its own payload type; no field changes its meaning from one op to another. Every op and its
// JSON form are documented in docs/canonical-commands.md.
//
//   Canon c;                                // a command: the program line and one payload
//   auto& m = c.Set<LinearOp>();            // choose the op (fields at their defaults)
//   m.to.pos[kX] = 10; m.feed.rate = 500;
//   if (auto* arc = c.If<ArcOp>()) ...      // read by type
//   switch (c.op()) ...                     // or by op
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <type_traits>
#include <variant>

#include "cell/tooltable/tooltable.h"

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

using AxisArray = std::array<double, kAxisCount>;

// The ops, in the order of the payload alternatives in Canon::Payload.
enum class Op : std::uint8_t {
  kUnits,       // first op of every run, and again whenever the unit mode changes
  kRapid,       // move at rapid rate
  kLinear,      // straight feed move
  kArc,         // circular or helical feed move
  kThread,      // spindle-synchronised straight move (lathe threading)
  kDwell,       // pause
  kSpindle,     // spindle on cw/ccw, stop, orient, speed change, constant surface speed
  kCoolant,     // coolant mode change
  kToolSelect,  // magazine pre-selection (the change follows with tool_change)
  kToolChange,  // tool into the spindle / turret station into the cutting position
  kStop,        // program stop / optional stop
  kEnd,         // program end
  kPallet,      // mid-program pallet shuttle
  kMessage,     // operator message
  kAlarm,       // audible / operator alarm that does not stop the run
  kAux,         // any other M function (clamps, overrides, probe select, chuck, tailstock, ...)
  kRegrid,      // the absolute position registers are reloaded, no motion
  kProbe,       // probe move; the result comes from the Environment
  kOutput,      // discrete outputs
  kWaitInput,   // wait for discrete inputs
  kFileOpen,    // a file the program writes is opened
  kFileWrite,   // a line written to it
  kFileClose,   // it is closed
  kFileOp,      // copy, delete, print, remote copy, save/load of tables
  kEvent,       // an event record
  kToolData,    // the program changed the tool table
  kOverrides,   // the operator's feed and spindle speed overrides are fixed at 100 % or enabled again
};
inline constexpr int kOpCount = static_cast<int>(Op::kOverrides) + 1;

// Stable JSON name of an op ("rapid", "tool_change", ...).
const char* OpName(Op op);

enum class FeedMode : std::uint8_t { kPerMinute, kInverseTime, kPerRev, kDegPerMinute };
enum class XMode : std::uint8_t { kRadius, kDiameter };  // lathes program X as a diameter
// kAxis: the spindle is position-controlled as the rotary axis C (a lathe's C-axis joint, Okuma M110); it
// does not rotate as a spindle until a stop (M109) returns it to speed control.
enum class SpindleDir : std::uint8_t { kStop, kCw, kCcw, kOrient, kAxis };
// Which spindle a spindle op drives: the work (main) spindle, or a turn-mill's live (rotary) tool on the
// turret (Okuma M12-M14 with SB=).
enum class SpindleId : std::uint8_t { kMain, kLiveTool };
enum class CoolantMode : std::uint8_t {
  kOff,
  kMist,
  kFlood,
  kWashFlood,  // KT-APL M51 pallet wash
  kWashAir,    // M52
  kAuxMist,    // M57
  kAuxFlood,   // M58
  kAuxPulse,   // M59
};
enum class ProbeOutcome : std::uint8_t { kContact, kBreak, kNone, kAlready, kToolOk, kToolBroken };

const char* SpindleDirName(SpindleDir d);
const char* SpindleIdName(SpindleId s);
const char* CoolantModeName(CoolantMode m);
const char* ProbeOutcomeName(ProbeOutcome r);

// Where a move ends: the absolute position (mm / deg) after all offsets. `used` says which axes the run has
// used so far (bit i = Axis i); only those are written. Rotary axes that turned in this block carry their
// signed travel in degrees (bit i of `travel_mask`).
struct Target {
  AxisArray pos{};
  std::uint32_t used = 0;
  AxisArray travel{};
  std::uint32_t travel_mask = 0;
};

struct Feed {
  double rate = 0;  // mm/min, deg/min, 1/min (inverse time) or mm/rev, per `mode`
  FeedMode mode = FeedMode::kPerMinute;
  bool exact_stop = false;  // decelerate to a stop at the end of the block
};

// The two axes of a circular plane: first and second (G17 X,Y; G18 Z,X; G19 Y,Z; co-axis pairs such as
// Z,U). The arc direction is seen from the positive end of the plane normal.
struct PlaneAxes {
  std::int8_t first = kX, second = kY;
};

struct UnitsOp {
  static constexpr Op kOp = Op::kUnits;
  bool metric = false;
  XMode x_mode = XMode::kRadius;
};
struct RapidOp {
  static constexpr Op kOp = Op::kRapid;
  Target to;
};
struct LinearOp {
  static constexpr Op kOp = Op::kLinear;
  Target to;
  Feed feed;
};
struct ArcOp {
  static constexpr Op kOp = Op::kArc;
  Target to;
  Feed feed;
  std::array<double, 3> center{};  // absolute x y z (a co-axis in the slot of its parallel axis)
  bool cw = true;
  PlaneAxes plane;
  double angle = 0;  // degrees swept (positive; 360 for a full circle)
};
// A thread cut: a straight move whose travel along the major axis (the axis with the larger travel) is
// `lead` mm per spindle revolution, starting at spindle angle `start_angle` (deg from the index mark).
struct ThreadOp {
  static constexpr Op kOp = Op::kThread;
  Target to;
  double lead = 0;          // mm per revolution
  double lead_change = 0;   // mm per revolution, per revolution (variable lead); 0 normally
  double start_angle = 0;   // degrees
  bool exact_stop = false;  // stop in position at the end: never chained into the next thread (Okuma G65)
};
struct DwellOp {
  static constexpr Op kOp = Op::kDwell;
  double seconds = 0;
};
struct SpindleOp {
  static constexpr Op kOp = Op::kSpindle;
  SpindleId spindle = SpindleId::kMain;  // which spindle: its state below is that spindle's alone
  SpindleDir dir = SpindleDir::kStop;
  double rpm = 0;      // programmed speed (constant rpm mode; the last speed for stop / orient)
  double angle = 0;    // orient: keylock angle, degrees
  double css = 0;      // constant surface speed, m/min; 0 = off (rpm applies)
  double max_rpm = 0;  // programmed spindle limit (lathes: Okuma G50 S, EMCO G92 S); 0 = none
};
struct CoolantOp {
  static constexpr Op kOp = Op::kCoolant;
  int m = 0;  // the M code as programmed
  CoolantMode mode = CoolantMode::kOff;
};
struct ToolSelectOp {
  static constexpr Op kOp = Op::kToolSelect;
  std::string tool;
};
struct ToolChangeOp {
  static constexpr Op kOp = Op::kToolChange;
  std::string tool;  // tool number (KT-APL "1001" or "33412.5"; a lathe's turret tool "3")
  int offset = 0;    // lathes: the tool offset number the T word selects; 0 = none / the tool's own
  int tip = -1;      // lathes: tool-nose tip position code 0-9 in force; -1 = not a lathe tool
  int socket = 0;    // the magazine socket of the data set the control chose (an alternate); 0 = not chosen
};
struct StopOp {
  static constexpr Op kOp = Op::kStop;
  int m = 0;
  bool optional = false;
  std::string why;  // a stop the control makes itself (KT-APL G38: "TOOL BROKEN"); "" for M00/M01
};
struct EndOp {
  static constexpr Op kOp = Op::kEnd;
  int m = 0;
  bool shuttle = false;  // KT-APL M30: the pallet leaves
};
struct PalletOp {
  static constexpr Op kOp = Op::kPallet;
  int m = 60;
};
struct MessageOp {
  static constexpr Op kOp = Op::kMessage;
  std::string text;
};
struct AlarmOp {
  static constexpr Op kOp = Op::kAlarm;
  std::string text;
};
struct AuxOp {
  static constexpr Op kOp = Op::kAux;
  int m = 0;
};
struct RegridOp {
  static constexpr Op kOp = Op::kRegrid;
  Target to;
};
struct ProbeOp {
  static constexpr Op kOp = Op::kProbe;
  int g = 0;  // the dialect's probe code (KT-APL 22, 23, 38)
  Target to;  // where the probe stopped
  Feed feed;
  ProbeOutcome result = ProbeOutcome::kNone;
};
struct OutputOp {
  static constexpr Op kOp = Op::kOutput;
  std::string spec;
};
struct WaitInputOp {
  static constexpr Op kOp = Op::kWaitInput;
  std::string spec;
};
struct FileOpenOp {
  static constexpr Op kOp = Op::kFileOpen;
  std::string name;
  std::string type;  // KT-APL "AS" / "NC"
  bool append = false;
  bool inspection = false;
};
struct FileWriteOp {
  static constexpr Op kOp = Op::kFileWrite;
  std::string text;
};
struct FileCloseOp {
  static constexpr Op kOp = Op::kFileClose;
};
struct FileOpOp {
  static constexpr Op kOp = Op::kFileOp;
  std::string what;  // CPY, DLF, PRT, RCP, USF, ULF
  std::string args;
  std::string text;  // USF: the file's content (the fixture offset table as FXC lines)
};
struct EventOp {
  static constexpr Op kOp = Op::kEvent;
  std::string text;
};
// A tool-table change made by the program: the data set as it now stands (every field of the dialect's
// form), a process compensation for one pallet (KT-APL TLD with W: `pallet` set, the entry's length and
// diameter are the compensation's), or the whole table cleared.
struct ToolDataOp {
  static constexpr Op kOp = Op::kToolData;
  bool cleared = false;
  int pallet = 0;
  tooltable::ToolEntry entry;
};

// KT-APL M49 / M48 (ln 2896-2937): while `fixed`, feed and spindle speed run at 100 % of their programmed
// values whatever the operator's override selectors say (a feed override of 0 % still stops the axes); M48,
// and M06, enable the selectors again. The station applies it to what it publishes to the servo.
struct OverridesOp {
  static constexpr Op kOp = Op::kOverrides;
  bool fixed = false;
};

struct Canon {
  using Payload = std::variant<UnitsOp, RapidOp, LinearOp, ArcOp, ThreadOp, DwellOp, SpindleOp, CoolantOp,
                               ToolSelectOp, ToolChangeOp, StopOp, EndOp, PalletOp, MessageOp, AlarmOp, AuxOp,
                               RegridOp, ProbeOp, OutputOp, WaitInputOp, FileOpenOp, FileWriteOp, FileCloseOp,
                               FileOpOp, EventOp, ToolDataOp, OverridesOp>;

  int line = 0;  // 1-based line of the block in PROGRAM that caused it (calling block for library code)
  Payload p;

  Op op() const { return static_cast<Op>(p.index()); }
  template <class T>
  T& Set() {
    return p.emplace<T>();
  }
  template <class T>
  T& As() {
    return std::get<T>(p);
  }
  template <class T>
  const T& As() const {
    return std::get<T>(p);
  }
  template <class T>
  T* If() {
    return std::get_if<T>(&p);
  }
  template <class T>
  const T* If() const {
    return std::get_if<T>(&p);
  }
  // The end position of the ops that have one (rapid, linear, arc, thread, regrid, probe); nullptr else.
  Target* target();
  const Target* target() const { return const_cast<Canon*>(this)->target(); }
  // The feed of the ops that have one (linear, arc, probe); nullptr else.
  Feed* feed();
  const Feed* feed() const { return const_cast<Canon*>(this)->feed(); }
};

// Each payload sits at the index of its op.
template <class T>
inline constexpr bool kPayloadAtItsOp =
    std::is_same_v<std::variant_alternative_t<static_cast<std::size_t>(T::kOp), Canon::Payload>, T>;
static_assert(std::variant_size_v<Canon::Payload> == static_cast<std::size_t>(kOpCount));
static_assert(kPayloadAtItsOp<UnitsOp> && kPayloadAtItsOp<ArcOp> && kPayloadAtItsOp<ThreadOp> &&
              kPayloadAtItsOp<ToolChangeOp> && kPayloadAtItsOp<ProbeOp> && kPayloadAtItsOp<FileOpOp> &&
              kPayloadAtItsOp<ToolDataOp>);

// One JSON object on a single line, without the trailing newline (DESIGN §4).
std::string ToJsonLine(const Canon& c);
// The same, appended to `out` (no allocation once `out` has grown: the CLI's hot path).
void AppendJsonLine(std::string& out, const Canon& c);

}  // namespace cell::interp
