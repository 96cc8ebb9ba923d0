// The EMCOTRONIC TM02 executor's internals, shared by its files (split by concern as LinuxCNC splits its
// interpreter; the manual is ../shared/seeds/emcotronic-tm02-turning.txt, "ln N" below):
//   interp_read.cpp      the tape format: blocks, words, number formats, indexed P/D parameters
//   interp_flow.cpp      the run's life cycle: program structure, G25/M17 subroutines, G27 jumps, M30, what
//                        carries into the next program, the operator monitor parameters
//   interp_convert.cpp   one block: G and M groups, F S T, zero shifts G53-G59/G92, scaling G51/G50, the
//                        radius compensation rules
//   interp_motion.cpp    positions (diameter X, radius U and I, absolute and incremental), G00-G03, G33,
//                        chamfer/radius requests, the move pipeline and the output
//   interp_cycles.cpp    G84 turning, G86 grooving, G87/G88 drilling
//   interp_thread.cpp    G85 threading
//   contour.cpp          the look-ahead stages: chamfer/radius insertion (DC 5.10) and tool-nose radius
//                        compensation G41/G42 (on the core's offset-path geometry)
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "cell/interp/call_stack.h"
#include "cell/interp/canon.h"
#include "cell/interp/emco.h"
#include "cell/interp/geometry/offset_path.h"
#include "cell/interp/parse_cache.h"
#include "cell/interp/run_base.h"
#include "cell/interp/run_error.h"

namespace cell::interp::emco {

using geom::Vec2;

constexpr double kInch = 25.4;
constexpr double kPi = 3.14159265358979323846;
constexpr int kMaxNesting = 10;  // G25 levels (ALARM 300)

// ---------------------------------------------------------------------------------------------------------
// Errors: the manual's alarm (3 digits, "version 6.00" numbering; the 2-digit numbers in older pages map to
// them: 51 -> 510) with its title, or a text of our own where the manual has no alarm (RunError and Fail:
// cell/interp/run_error.h).

// The alarm list's title for `code` ("OFFSET CHANGED, GO WITH G00"); empty for codes we do not raise.
std::string_view AlarmTitle(int code);
[[noreturn]] void Alarm(int code, int col, std::string_view detail = {});

// ---------------------------------------------------------------------------------------------------------
// The tape format (interp_read.cpp)

// One word as written: the address, the P/D index, and the number with or without a decimal point.
struct Word {
  char letter = 0;     // upper case
  int8_t index = -1;   // P0-P7 / D0-D7; -1 for other letters
  bool point = false;  // written with a decimal point
  bool sign = false;   // written with a + or - sign
  double value = 0;    // signed, as written (digits with the point where it was written)
  uint16_t col = 1;    // 1-based column of the address letter
};

constexpr int kMaxWords = 40;

// One line of program text. A block holds at most about 4 screen lines (ln 860): longer blocks, and more
// than kMaxWords words, are ALARM 650.
struct Block {
  bool header = false;  // program start: "%", "%nn" or "Onnnn" (ln 5633-5636)
  int program = -1;     // the header's program number (-1: "%" alone)
  bool skip = false;    // "/" right after the block number (ln 1004-1025)
  bool has_n = false;
  int n = 0;
  uint8_t count = 0;
  std::array<Word, kMaxWords> w{};
};
constexpr std::size_t kMaxBlockChars = 128;  // 4 lines of 32 characters, comments not counted

// Parses one line (a trailing '\r' is ignored). Throws RunError.
void ParseBlock(std::string_view text, Block& out);
// True when the line is a program header ("%..." or "O<digits>"), without parsing the rest.
bool IsHeaderLine(std::string_view text);

// ---------------------------------------------------------------------------------------------------------
// A block's words as they act: duplicates resolved (the last one wins, ln 878-883), values in mm.

struct Val {
  bool set = false;
  bool point = false;
  bool sign = false;
  double raw = 0;  // as written
  double v = 0;    // converted (mm for lengths; the raw number for the others)
  int col = 0;
  int order = 0;  // index of the word in the block (X/Z order selects cycle variants)
};

struct Code {
  int code = 0;
  int col = 1;
};

struct BlockWords {
  Val x, z, i, k, f, s, t, l;  // x/z: X or U (z: Z or W) whichever came last
  bool x_inc = false, z_inc = false;
  std::array<Val, 8> p, d;
  std::array<Code, 12> g{}, m{};
  int ng = 0, nm = 0;
  int first_col = 1;  // column of the first word after N (diagnostics of the block as a whole)
  bool has_pos() const { return x.set || z.set; }
  int pos_col() const { return x.set && (!z.set || x.col < z.col) ? x.col : (z.set ? z.col : first_col); }
  bool any_p() const;
  bool any_d() const;
  // Value n: 0-7 x z i k f s t l, 8-15 P0-P7, 16-23 D0-D7.
  Val& Slot(int n);
  uint32_t set_mask = 0;  // the values set (bit n: Slot(n))
  // Back to an empty block: only the values set are cleared (the executor reuses one BlockWords, and zeroing
  // all of it for every block cost more than reading the block).
  void Clear();
};

// ---------------------------------------------------------------------------------------------------------
// Moves between the executor, the look-ahead stages and the output. Positions are in the work plane of the
// core's geometry (Vec2 x = Z, y = X as a radius, mm), after scaling and the zero shifts, before the tool
// offset; the output writes X as a diameter with the tool offset added.

struct Move {
  enum Kind : uint8_t { kRapid, kLinear, kArc, kThread } kind = kRapid;
  Vec2 end;
  Vec2 center;  // arcs
  bool cw = false;
  double sweep = 0;  // arcs: degrees
  Feed feed;         // linear and arc
  double lead = 0;   // thread: mm per revolution along the major axis
  uint32_t used = 0;
  int line = 0;
  int col = 1;
};

// What goes through the stages: a move or any other command, in program order.
struct Item {
  bool is_move = true;
  Move m;
  Canon c;
};
using Sink = std::function<void(Item&&)>;

// Chamfer and radius insertion between two G01 lines (DC 5.10, ln 55-116, alarms 381-391): the first line
// is held until the next move is known.
class CornerInsert {
 public:
  explicit CornerInsert(Sink out) : out_(std::move(out)) {}
  bool engaged() const { return held_; }
  // The G01 line from `start` with P0 (radius, chamfer=false) or P1 (chamfer) at its end corner.
  void Hold(Move&& m, Vec2 start, double size, bool chamfer);
  void Take(Item&& it);

 private:
  // Writes the held line up to its insertion and the insertion; returns how far it lies back on `it`.
  double Close(const Item& it);

  Sink out_;
  bool held_ = false;
  Move line_;
  Vec2 start_;             // the held line's programmed start (its direction and length)
  double trim_start_ = 0;  // what the insertion before it took off its start (a chain of corners)
  double size_ = 0;
  bool chamfer_ = false;
  std::deque<Item> after_;  // other commands between the two lines
};

// Tool-nose radius compensation (G40/G41/G42, ln 2357-3118): the one-block look-ahead. The executor enforces
// the syntax rules (alarms 350/360/500-530/580); this class does the geometry (its alarms 570, and 540/560
// through the arcs it is given) and writes the nose centre path shifted by the tip offset (S + (P - S)), so
// the theoretical tip P the tool data are measured to moves as the compensated contour demands.
class NoseComp {
 public:
  explicit NoseComp(Sink out) : out_(std::move(out)) {}
  bool engaged() const { return state_ != kOff; }
  bool on() const { return state_ == kOn || state_ == kCancelPending; }
  // Compensation selected: the next move (from `from`, the programmed tip position) is the approach.
  void Select(int side, double radius, Vec2 tip_offset, Vec2 from, bool suppress_570);
  // G40: the next move is the departure (the tip goes to its programmed end).
  void Cancel() {
    if (state_ == kOn) state_ = kCancelPending;
  }
  void Take(Item&& it);
  // End of the program while on (the held move ends at its own normal offset).
  void Finish();

 private:
  enum State { kOff, kSelectPending, kOn, kCancelPending };
  struct Held {
    geom::Path path;
    Move m;
    bool approach = false;
    double trim_start = 0;  // mm (lines) or degrees (arcs) cut off its start by the corner before it
  };
  geom::Path PathOf(const Move& m, Vec2 start) const;
  void Release(Vec2 end, double trim_end);
  void Emit(const Move& m, Vec2 end, const Vec2* center, double sweep);
  void FillArc(const geom::Corner& k, const Move& like);
  void Check570(bool ok);
  void Put(Item&& it) { staged_.push_back(std::move(it)); }
  void PutAfter();
  void Settle();

  Sink out_;
  State state_ = kOff;
  int side_ = geom::kLeft;
  double r_ = 0;
  Vec2 tip_;
  bool suppress_570_ = false;
  int col_ = 1;  // the column alarms point at: the first position word of the block being taken
  Vec2 prog_;    // programmed position at the end of the moves taken so far
  bool has_held_ = false;
  Held held_;
  std::deque<Item> after_;   // other commands after the held move
  std::deque<Item> staged_;  // written, final once the next move has passed its checks (Settle)
};

// ---------------------------------------------------------------------------------------------------------
// Modal state (groups of ln 1938-1954 and 4922-4941), by meaning.

enum class Motion : uint8_t { kNone, kRapid, kLinear, kCw, kCcw, kThread, kG84, kG85, kG86, kG87, kG88 };

// "" when a station keeps `name` (what EmRun::Variables() reports) with this value; else a one-line reason.
std::string CheckKeptVariable(std::string_view name, double value);

struct Modal {
  Motion motion = Motion::kNone;  // group 0 (no start-up state: ln 1304)
  bool css = false;               // G96 (G97)
  bool per_min = false;           // G94 (G95)
  int shift_a = 0;                // group 3: 0 (G53), 1 (G54), 2 (G55)
  int shift_b = 0;                // group 5: 0 (G56), 3 (G57), 4 (G58), 5 (G59)
  bool metric = true;             // G71 (G70)
  int comp = 40;                  // group 8: 40, 41, 42
  int spindle = 5;                // M group 0: 3, 4, 5, 19
  bool exact_stop = false;        // M38 (M39)
  bool coolant = false;           // M08 (M09)
  int chuck = 25, tailstock = 20, catcher = 23, turret_logic = 51, door = 52;  // M groups 5-9
};

// The operator monitor parameters that change interpretation (ln 5300-5990), from RunOptions::params.
struct Monitor {
  int o11 = 9;        // bit 0: X as a diameter, bit 1: G70 at start-up, bit 2: collet, bit 3: M51, bit 4: M53
  int o22 = 80;       // lowest subroutine number
  int o40 = 0;        // bit 4: part counter, bit 5: work presetting, bit 6: no ALARM 570
  int s00 = 100;      // minimum infeed / drill depth, um
  int s01 = 1;        // G85 idle passes
  int s02 = 500;      // G86/G87 retract per cut, um
  double m08 = 0;     // M19 angle without S
  int d02 = 0;        // work presetting: parts per start
  bool skip = false;  // the SKIP key: skip blocks are not run
  std::optional<double> limit_x_plus, limit_x_minus, limit_z_plus, limit_z_minus;  // R03 R06 R05 R08
  long max_idle = 1000000;
};

// What EMCO keeps per frame besides the text position.
struct FrameData {
  int number = -1;             // the program's O number (-1 when it has none)
  int runs_left = 1;           // G25 runs still to go, this one included
  JumpTargets<int> blocks;     // N numbers found by G27
  std::size_t body_begin = 0;  // where the program's blocks start (after its header)
  int body_line = 1;
};
using Frames = CallStack<FrameData>;

// ---------------------------------------------------------------------------------------------------------

class EmRun final : public RunBase {
 public:
  explicit EmRun(const RunOptions& o);

  std::map<std::string, double> Variables() const override;
  tooltable::ToolTable Tools() const override { return tools_; }

 private:
  // Life cycle and program structure (interp_flow.cpp)
  void ReadParams(const RunOptions& o);
  void RestoreVariables(const std::map<std::string, double>& vars);
  void StepOnce() override;
  void ExecLine(const Line& line);
  void FindMainProgram();
  bool LastBlock() const;
  struct Subroutine {
    TextSpan span;
    bool own = false;  // in the program's own file: it reports its own lines
  };
  const Subroutine* FindSubroutine(int number);
  void CallSubroutine(const BlockWords& bw, int col);
  void ReturnFromSubroutine(int col);
  void EndOfSubroutine();
  void Jump(const BlockWords& bw, int col);
  void EndOfProgram(int col);
  void FinishRun();
  void EmitUnits();

  // One block (interp_convert.cpp)
  void Execute(const Block& b);
  void Collect(const Block& b, BlockWords& bw) const;
  void ConvertValues(BlockWords& bw) const;
  void CheckWords(const BlockWords& bw, Motion motion, bool g04, bool g92, bool g51, bool flow) const;
  void ToolWord(const BlockWords& bw);
  void SpindleWords(const BlockWords& bw, int spindle_m, bool g96, bool g97, bool g92);
  void SpindleOp(int line);
  void AuxBefore(int m, int col);
  void Coolant(bool on);
  bool ZeroShifts(const BlockWords& bw, int g3, int g5, bool g92, int col3, int col5);
  void Scaling(const BlockWords& bw, int g, int col);
  void CompCode(int g, int col);
  void CompBlock(const BlockWords& bw, Motion motion, bool moves);

  // Motion (interp_motion.cpp)
  double FeedRate(const BlockWords& bw, int col, Feed& out) const;
  Vec2 Target(const BlockWords& bw) const;  // programmed end (Z, X radius), unscaled
  Vec2 ToWork(Vec2 prog) const;             // scaling and zero shifts
  Vec2 Shift() const;                       // active zero shift (Z, X radius)
  void MotionBlock(const BlockWords& bw, Motion motion);
  void Arc(const BlockWords& bw, bool cw, Vec2 to, const Feed& feed);
  void Thread33(const BlockWords& bw, Vec2 to);
  double Lead(const BlockWords& bw, int col);
  void EmitMove(Move&& m);
  void EmitOther(Canon&& c);
  void Route(Item&& it, int stage);
  void Write(Item&& it);
  void WriteMove(const Move& m);
  Vec2 ToolOffset() const;  // (Z, X diameter) of the active correction
  void CheckLimits(double x, double z, int line, int col) const;

  // Cycles (interp_cycles.cpp, interp_thread.cpp)
  void CycleMove(Move::Kind kind, Vec2 prog, const Feed* feed, double lead = 0);
  void G84(const BlockWords& bw, Vec2 k, const Feed& feed);
  void G85(const BlockWords& bw, Vec2 k);
  void G86(const BlockWords& bw, Vec2 k, const Feed& feed);
  void G87(const BlockWords& bw, Vec2 k, const Feed& feed, bool redraw);
  int D(const BlockWords& bw, int i, int def) const;
  double DLen(const BlockWords& bw, int i, double def) const;  // a D length in mm (um or 1/10000 in)

  // Options and environment.
  Monitor mon_;

  // Stepping.
  std::unique_ptr<Frames> frames_;
  ParseCache<Block> cache_;
  std::map<int, Subroutine> subs_;  // subroutines found so far, by number
  bool own_indexed_ = false;
  Block scratch_;
  BlockWords words_;  // the block being executed (Execute)
  int cur_line_ = 1;
  bool cur_own_ = true;
  bool first_block_ = true;  // group 7 may change only here (ALARM 390)
  bool main_started_ = false;
  bool units_emitted_ = false;
  bool ended_ = false;
  long idle_ = 0;
  int parts_this_start_ = 0;

  // Modal state, positions, offsets.
  Modal mode_;
  double feed_ = 0;   // F as programmed (G94 mm/min or 1/100 in/min; G95 um/rev or 1/10000 in/rev)
  double pitch_ = 0;  // F of G33/G85 blocks (um or 1/10000 in): "the last effective feed is cancelled as long
                      // as G85 is active" (ln 3796), and comes back after it
  double speed_ = 0;  // S (rpm, or m/min under G96)
  double speed_limit_ = 0;  // G92 S, rpm
  int t_ = 0;               // T as TTCC
  Vec2 tool_off_;           // the active correction's offsets (Z, X diameter)
  Vec2 prog_;               // programmed position (Z, X radius), unscaled
  uint32_t used_ = 0;
  std::array<Vec2, 6> pso_{};    // PSO 1-5 (Z, X radius); [0] unused
  bool offset_changed_ = false;  // a T or shift change waits for its G00 (ALARM 490)
  bool scaling_ = false;
  bool scale_first_move_ = false;  // the first move after G51 must be absolute (ALARM 372)
  Vec2 scale_ref_;
  double scale_ = 1;
  int parts_ = 0;  // D03

  // Output state.
  double out_x_ = 0, out_z_ = 0;  // last written position (X diameter, Z) after all offsets
  bool out_known_ = true;         // machine state starts at zero (DESIGN §4)

  // Look-ahead stages.
  CornerInsert corner_;
  NoseComp comp_;
  bool corner_next_ = false;  // the block after a chamfer/radius block must be a G01 with a position
  int comp_request_ = 0;      // 41/42 selected, 40 cancelled: waits for its G00/G01 move
  int comp_idle_ = 0;         // blocks without XZ change since the request / while on (ALARM 500)
  int comp_moves_ = 0;        // moves with an XZ change while on (ALARM 510)

  // Tools.
  tooltable::ToolTable tools_;
};

// Tool data of correction `corr` (1-99): offsets (Z, X diameter), nose radius, tip code; zeros when the
// table has no such entry.
struct Correction {
  double x = 0, z = 0, r = 0;
  int tip = 0;
};
Correction LookUp(const tooltable::ToolTable& tools, int corr);

}  // namespace cell::interp::emco
