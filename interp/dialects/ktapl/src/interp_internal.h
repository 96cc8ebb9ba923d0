// The KT-APL executor's internals, shared by its files (split by concern as LinuxCNC splits its interpreter):
//   interp_read.cpp        the tape format: blocks, words, number formats
//   interp_flow.cpp        block stepping, definitions, calls, jumps, the run's life cycle
//   interp_params.cpp      L parameters, letters, G/M state for IFT, expressions
//   interp_statements.cpp  Type II statements (a mnemonic table)
//   interp_files.cpp       files a program writes (OIF, OPF, FWR, CLF, MSG into a file, file operations)
//   interp_tools.cpp       tool table (TLD, ZTB, UAT) and fixture offsets (FXC, UFX)
//   interp_convert.cpp     Type I blocks: G codes, cycle calls, M, T, S, F, the block's motion
//   interp_motion.cpp      linear, rotary and index moves, probe moves, regrid, floating zero
//   interp_arc.cpp         circular interpolation (on the core's arc geometry)
//   interp_comp.cpp        the executor's side of cutter compensation (cutter_comp.h is the look-ahead)
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cell/interp/axis_letters.h"
#include "cell/interp/call_stack.h"
#include "cell/interp/canon.h"
#include "cell/interp/geometry/arc.h"
#include "cell/interp/ktapl.h"
#include "cell/interp/ktapl_statements.h"
#include "cell/interp/parse_cache.h"
#include "cell/interp/run_base.h"
#include "cell/interp/run_error.h"
#include "cell/interp/scan.h"
#include "cutter_comp.h"
#include "expr.h"
#include "tld.h"
#include "util.h"

namespace cell::interp::ktapl {

constexpr double kInch = 25.4;
constexpr double kPi = 3.14159265358979323846;
constexpr int kMaxLevels = 4;  // main + 3 nested calls
constexpr int kMaxDefinitions = 20;

// Program errors: RunError and Fail (cell/interp/run_error.h), the alarm the manual's number where it has
// one.

using scan::IsDigit;
inline bool IsAlpha(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z');
}
// AxisOfLetter: cell/interp/axis_letters.h.

// ---------------------------------------------------------------------------------------------------------
// The tape format (interp_read.cpp)

// A number as written in a Type I word.
struct RawNum {
  bool neg = false;
  bool point = false;
  double as_written = 0;  // with the point where written, or the integer digits when there is none
  int digits = 0;         // digits written (format checks)
  int frac_digits = 0;    // digits after the point up to the last non-zero one (the resolution used)
};

enum class WordKind { kNumber, kParam, kNegParam, kExpr };

struct RawWord {
  char letter = 0;
  WordKind kind = WordKind::kNumber;
  RawNum num;
  int param = 0;
  std::string_view expr;  // into the block text, which outlives the block's execution
  int col = 1;
};

// At most 40 words fit in an 80-character block; 48 leaves room for IFT action words.
constexpr size_t kMaxWords = 48;
using RawWords = InlineVec<RawWord, kMaxWords>;

// A word with its value: numbers scaled by the letter's format, parameters and expressions evaluated.
struct Word {
  char letter = 0;
  double v = 0;
  bool literal = false;  // written as a number (format scaling applied)
  bool neg_zero = false;
  int col = 1;
  RawNum num;  // as written, when literal (the F word's format depends on the block)
};
using Words = InlineVec<Word, kMaxWords>;

// A G code of the block and its column.
struct GWord {
  int code = 0;
  int col = 1;
};
using GWords = InlineVec<GWord, kMaxWords>;

struct ParsedBlock {
  bool deleted = false;
  bool has_n = false;
  RawNum n;  // the sequence number as written (passed to G800-series cycles as L814)
  RawWords words;
  std::vector<Statement> stmts;
  std::string comment;
  void Clear() {
    deleted = has_n = false;
    n = {};
    words.clear();
    stmts.clear();
    comment.clear();
  }
};

// Implied decimals of a letter written without a point (metric / inch, dwell F, cycle parameter passing).
int ImpliedDecimals(char letter, bool metric, bool dwell, bool passing);
// G H M P S T take whole numbers.
bool IntegerLetter(char c);
double ScaleLiteral(char letter, const RawNum& n, bool metric, bool dwell, bool passing);
void AddWord(RawWords& words, const RawWord& w);

// The format tables (manual ln 893-1237, 4401-4409, 5976): a word's digit count, its resolution (literal
// words) and its range (every value, substituted ones too), in program units. Letters without a table
// (D O P Q) keep only the tape reader's limit. Throws through Fail.
void CheckWordFormat(const Word& w, bool metric);
// The F word of a feed (Tables 1-A, 1-B; ln 5976): which format it is read in.
enum class FeedFormat { kLinear, kRotary, kInverseTime };
void CheckFeedFormat(const Word& f, FeedFormat fmt, bool metric);
// G02/G03 radius limits (ln 5501), in mm: .001 in / .01 mm up to 1690.9320 in / 42949.672 mm.
double MinArcRadiusMm(bool metric);
double MaxArcRadiusMm(bool metric);
// Parses one block (or an IFT action fragment) into words and statements, into `pb` (cleared first: a reused
// block keeps its storage). Expression words view `s`.
void ParseBlock(std::string_view s, bool fragment, ParsedBlock& pb);

// ---------------------------------------------------------------------------------------------------------
// Definitions and the call stack (interp_flow.cpp)

// A subroutine (DFS) or defined cycle (DFC): where its body is.
struct Def {
  TextSpan span;
  bool report_own = true;  // a local definition reports its own lines; library code the calling block's
  bool is_cycle = false;
  std::string name;
};

// What KT-APL keeps per frame besides the text position.
struct FrameData {
  bool is_cycle = false;
  std::map<int, double> locals;  // L0-L99 (L0: the remaining run count of a CLS)
  JumpTargets<int> labels;       // LBL numbers found by GTO
};
using Frames = CallStack<FrameData>;

struct FixtureLine {
  bool set = false;
  bool has_i = false;
  double i = 0;
  AxisArray v{};
};
constexpr int kFixtureLines = 32;  // H1-H32

// A fixture-table line's value as the station keeps it between runs: "H<n>.<X|Y|Z|A|B|C>" (mm, degrees,
// what the line adds to the axis) and "H<n>.I" (the B position G49 selects it at). axis -1 is I.
struct FixtureField {
  int h;
  int axis;
};
std::string FixtureKey(int h, int axis);
std::optional<FixtureField> ParseFixtureKey(std::string_view key);

// A CLS the block makes (its definition, L0-L99 and column). Outside BlockCtx: clang cannot construct a
// nested class with default member initializers in an optional until the enclosing class is complete.
struct BlockCall {
  Def def;
  std::map<int, double> locals;
  int col = 1;
};

// What a block's statements leave for the end of the block.
struct BlockCtx {
  RawWords words;
  std::optional<int> jump;
  int jump_col = 1;
  bool end = false;
  int end_col = 1;
  using Call = BlockCall;
  std::optional<Call> call;  // a CLS: made only then (most blocks call nothing)
  int gto_count = 0;
  int items = 0;
  int own_words = 0;          // Type I words of the block itself (not of its IFT actions)
  bool cycle_return = false;  // G80/G800 in a running defined cycle: the cycle ends with the block
};

// ---------------------------------------------------------------------------------------------------------
// Modal state, by meaning (the G and M codes that set each are in the comments; ActiveCode maps them back
// for IFT).

enum class Adaptive { kOff, kOn, kWithoutAirGap };   // G50 / G51 / G53
enum class ProbeCount { kOff, kContacts, kBreaks };  // G60 / G61 / G62 (L1022 counts)
enum class CutterComp { kOff, kLeft, kRight };       // G40 / G41 / G42 as programmed

struct Modal {
  bool contouring = false;                      // G01; G00 is the decelerating feed mode
  geom::Plane plane = geom::Plane::kXY;         // G17 / G18 / G19
  bool coaxis_first = false;                    // G20: the plane's first axis is its co-axis (U V W)
  bool coaxis_second = false;                   // G21: the second axis
  bool incremental = false;                     // G91 (G90)
  bool inverse_time = false;                    // G93 (G94)
  int cycle = 0;                                // defined cycle in force (81-89, 801-899); 0 = G80
  bool obstruction_detection = false;           // G28 (G29)
  bool inspection_recording = false;            // G36 (G37)
  bool fill_in_bypass = false;                  // G46
  bool threading = false;                       // G33 (cleared by an F word, ln 7251)
  bool calculated_offsets = false;              // G47 (G39)
  bool explicit_fixtures = false;               // G48: H selects the fixture line (G49: implicit)
  Adaptive adaptive = Adaptive::kOff;           // G50 / G51 / G53
  ProbeCount probe_count = ProbeCount::kOff;    // G60 / G61 / G62
  CutterComp cutter_comp = CutterComp::kOff;    // G40 / G41 / G42
  SpindleDir spindle = SpindleDir::kStop;       // M03 / M04 / M05 / M19
  CoolantMode coolant = CoolantMode::kOff;      // M07 / M08 / M09
  CoolantMode aux_coolant = CoolantMode::kOff;  // M57 / M58 / M59
  bool secondary_probe = false;                 // M21 (M20)
  bool z_prime_retracted = true;                // M24 (M23)
  bool b_clamp_off = false;                     // M27 (M26)
  bool c_clamp_off = false;                     // M29 (M28)
  bool tapping_range = false;                   // M40
  bool overrides_locked = false;                // M49 (M48)
  bool wash_flood = false, wash_air = false;    // M51, M52
};

// The G codes of a Type I block as they act (ConvertGCodes -> the rest of ExecTypeI).
struct BlockCodes {
  int arc = 0, arc_col = 1;  // G02 / G03
  bool dwell = false;        // G04
  bool g92 = false, g98 = false, g99 = false;
  bool cancel = false;  // G80 / G800
  bool probe = false;   // G22 / G23
  int probe_g = 0;
  int g38_col = 0;              // G38 in the block (its column): S is the number of flutes
  int g33_col = 0;              // G33 in the block (its column)
  int probe_cycle = 0;          // G24-G27
  bool inhibit_cycle = false;   // G77
  bool drop_undefined = false;  // G78
  GWords passed;                // G codes handed to a G800-series cycle (L807)
};

// The M codes of a block that act after its motion (one per block), and the immediate ones that matter
// to the rest of the block.
struct BlockMCodes {
  int after = -1, after_col = 1;
  bool m06 = false, m25 = false, m19 = false, m99 = false;
};

// ---------------------------------------------------------------------------------------------------------

class KtRun final : public RunBase, public ExprContext {
 public:
  explicit KtRun(const RunOptions& o);

  std::map<std::string, double> Variables() const override;
  tooltable::ToolTable Tools() const override { return tools_; }

  // ExprContext
  double Param(int n) override;
  bool ParamDefined(int n) override;
  double Letter(char c) override;
  bool ActiveCode(char gm, int code) override;

 private:
  // Life cycle and output (interp_flow.cpp)
  void StepOnce() override;
  void Finish(Step::Kind kind);
  void EmitUnitsOnce();
  void EmitUnits();
  // The next output command with payload T, filled in place (the motion hot path: no Canon copies).
  template <class T>
  T& Out();
  int ReportLine() const { return cur_line_; }

  // Blocks (interp_flow.cpp)
  void ExecBlock(std::string_view text, size_t start);
  void Define(const Statement& st, size_t level_idx);
  void DoCall(const Def& d, std::map<int, double> locals, bool is_cycle);
  void DoEnd(int col);
  void ReturnFromCycle();
  void DoJump(int label, int col);
  std::optional<Def> FindDef(const std::string& name);
  std::optional<Def> LoadLibrary(const std::string& name, const std::string& text);
  bool RunningCycle() const;
  void CallCycle(int g);

  // Parameters (interp_params.cpp)
  void SetParam(int n, double v, int col);
  void DeleteParam(int n);
  void SetFlag(int n);
  int EvalParamRef(std::string_view text, int col);
  double Eval(std::string_view text, int col);
  // 1-based column in the current block of `offset` within `text`, or `col` when `text` is not found.
  int ExprCol(std::string_view text, size_t offset, int col) const;
  bool EvalCond(const std::string& text, int col);
  std::string ExpandName(std::string_view name, int col);

  // Statements (interp_statements.cpp, interp_files.cpp, interp_tools.cpp)
  using StatementFn = void (KtRun::*)(const Statement& st, BlockCtx& bc, bool in_ift);
  static const std::vector<std::pair<uint32_t, StatementFn>>& StatementTable();
  void ExecStatement(const Statement& st, BlockCtx& bc, bool in_ift);
  void StPar(const Statement& st, BlockCtx& bc, bool in_ift);
  void StIft(const Statement& st, BlockCtx& bc, bool in_ift);
  void StGto(const Statement& st, BlockCtx& bc, bool in_ift);
  void StLbl(const Statement& st, BlockCtx& bc, bool in_ift);
  void StEnd(const Statement& st, BlockCtx& bc, bool in_ift);
  void StCls(const Statement& st, BlockCtx& bc, bool in_ift);
  void StDlp(const Statement& st, BlockCtx& bc, bool in_ift);
  void StHeading(const Statement& st, BlockCtx& bc, bool in_ift);
  void StRefused(const Statement& st, BlockCtx& bc, bool in_ift);
  void StSsa(const Statement& st, BlockCtx& bc, bool in_ift);
  void StMsg(const Statement& st, BlockCtx& bc, bool in_ift);
  void StOif(const Statement& st, BlockCtx& bc, bool in_ift);
  void StOpf(const Statement& st, BlockCtx& bc, bool in_ift);
  void StClf(const Statement& st, BlockCtx& bc, bool in_ift);
  void StFwr(const Statement& st, BlockCtx& bc, bool in_ift);
  void StDat(const Statement& st, BlockCtx& bc, bool in_ift);
  void StFileOp(const Statement& st, BlockCtx& bc, bool in_ift);
  void StErrorMode(const Statement& st, BlockCtx& bc, bool in_ift);
  void StSetWai(const Statement& st, BlockCtx& bc, bool in_ift);
  void StTld(const Statement& st, BlockCtx& bc, bool in_ift);
  void StFxc(const Statement& st, BlockCtx& bc, bool in_ift);
  void StZtb(const Statement& st, BlockCtx& bc, bool in_ift);
  void StMir(const Statement& st, BlockCtx& bc, bool in_ift);
  void StU88(const Statement& st, BlockCtx& bc, bool in_ift);
  void StUat(const Statement& st, BlockCtx& bc, bool in_ift);
  void StEvt(const Statement& st, BlockCtx& bc, bool in_ift);
  void Par(const Statement& st);
  void OpenFile(const std::string& name, const std::string& type, bool append, int col);
  // Closes the open file (CLF, G37, or before another is opened); `flag`: CLF/G37 set L1050 when done.
  void CloseOpenFile(int col, bool flag);
  void OpenInspectionFile(std::string name, int col);
  void EmitFileWrite(std::string text, int col);
  // Asks the environment to do a file effect; false when it did not finish (a CER-covered error warns).
  bool FileDevice(const Canon& op, int device, int col);
  void ApplyTool();
  void LoadFixtureFile(const std::string& name, int col);
  void ChangeTool(int col);
  void CheckTool(const Word* flutes);

  // Type I blocks (interp_convert.cpp)
  void ExecTypeI(BlockCtx& bc, const ParsedBlock* pb);
  void ReadGWords(const RawWords& raw, bool drop_undefined, GWords& gs);
  uint32_t KeepLetters(const Words& words);
  void ProbeCycleBlock(const RawWords& raw, const BlockCodes& k, const ParsedBlock* pb, bool drop_undefined,
                       bool running_cycle);
  std::optional<double> BlockFeed(const Word* f, const BlockCodes& k, const BlockMCodes& mc);
  void FixtureWord(const Words& words);
  bool LengthBypass(const Words& words, bool arc);
  Word EvalWord(const RawWord& w, bool dwell, bool passing, bool drop_undefined, bool& dropped);
  void ConvertGCodes(const GWords& gs, bool pass800, BlockCodes& k);
  bool ModeGCode(int g);
  [[noreturn]] void RefusedGCode(int g, int col);
  void CompGCode(int g, int col);
  bool PassCycleParameters(const RawWords& raw, const BlockCodes& k, const ParsedBlock* pb,
                           bool drop_undefined, uint32_t axis_mask, Words& words);
  BlockMCodes ReadMCodes(const Words& words, bool trigger);
  void ToolAndSpeed(const Words& words, const BlockMCodes& mc, bool s_is_flutes);
  void ImmediateMCodes(const Words& words, bool speed_changed, const Word* s, bool m00);
  void AfterMCode(const BlockMCodes& mc);

  // Motion (interp_motion.cpp, interp_arc.cpp)
  double Offset(int axis) const;
  double FixtureOffset(int axis) const;
  void RebaseFixtures(const Words& words, const BlockMCodes& mc, uint32_t axis_mask, bool positioning,
                      AxisArray& target);
  double ToMm(double v) const { return metric_ ? v : v * kInch; }
  double FromMm(double v) const { return metric_ ? v : v / kInch; }
  void ResetAtEnd();
  void Motion(const Words& words, const BlockCodes& k, const BlockMCodes& mc, uint32_t axis_mask,
              int motion_col, const Word* f, std::optional<double> block_feed);
  // G33 threading with the U-head (ln 7247-7322): the block's E, D and F words and its axes.
  void ThreadWords(const Words& words, const BlockCodes& k, const Word* f, uint32_t axis_mask, bool passes);
  void LinearMotion(const Words& words, const BlockCodes& k, const BlockMCodes& mc, uint32_t axis_mask,
                    int motion_col, std::optional<double> eff, const Word* fw);
  void GuardedMove(uint32_t axis_mask, const AxisArray& target, bool rapid, double feed, FeedMode fm,
                   bool exact, const AxisArray& travel, uint32_t travel_mask, int col);
  void ProbeMove(const BlockCodes& k, uint32_t axis_mask, const AxisArray& target, bool rapid, double feed,
                 FeedMode fm);
  void Regrid(const Words& words);
  void FloatingZero(const Words& words, const BlockCodes& k);
  void EmitMove(const AxisArray& target, uint32_t moved, bool rapid, double feed, FeedMode fm, bool exact,
                const AxisArray& travel, uint32_t travel_mask);
  void Arc(const Words& words, bool cw, int col, double feed, FeedMode fm);
  geom::PlaneAxesN PlaneAxes() const;
  void SetUnits(bool metric);

  // Cutter diameter compensation (interp_comp.cpp): while comp_ is engaged, commands are staged in
  // comp_stage_ and handed to it (its finished commands then go to out_).
  struct CompCodes {   // G40-G46 of the block being executed (comp_codes_; reset by CompPrepare)
    bool any = false;  // one of them is in the block
    bool g43 = false, g46 = false;
    int g = 0;  // G40/G41/G42
    int g_col = 1, g46_col = 1;
  };
  void CompPrepare(const Words& words, int motion_col, bool running_cycle, bool probe, bool g92);
  template <class T>
  T& CompSlot();
  void CompCommit();
  void CompEndBlock(bool counts);
  void CompFinish();
  void CompDrain();
  [[noreturn]] void CompFail(const cc::CompError& e);

  // Stepping.
  std::unique_ptr<Frames> frames_;
  cc::Compensator comp_;
  Canon comp_stage_;
  bool comp_staged_ = false;
  CompCodes comp_codes_;  // written only by blocks that have the codes: nothing to set up per block
  int comp_col_ = 1, comp_g_col_ = 1;
  bool units_emitted_ = false;
  int cur_line_ = 1;
  bool cur_own_ = true;
  long idle_ = 0;
  long max_idle_ = 1000000;

  // Modal state and positions.
  bool metric_ = false;
  bool basic_metric_ = false;
  Modal mode_;
  std::optional<double> feed_;  // program units
  double speed_ = 0;
  AxisArray pos_{};
  uint32_t used_ = 0;
  AxisArray g98_{};  // floating zero (G98)
  std::array<FixtureLine, kFixtureLines + 1> fixtures_{};
  int active_h_ = 0;
  double calc_b_ = 0;           // G47: the B position the active line's offsets are calculated for
  bool length_bypass_ = false;  // P0 in the block being executed: no tool length compensation (ln 1185)
  bool mir_x_ = false, mir_y_ = false;
  double u88_x_ = 0.254, u88_y_ = 0;  // mm
  // G33: the modal lead E (mm/rev), this block's lead change D (mm/rev per rev), the SSA start angle (deg),
  // and whether this block's move is the thread.
  double thread_lead_ = 0, thread_change_ = 0, thread_angle_ = 0;
  bool thread_block_ = false;
  bool block_d_ = false;  // the block has a D word (KeepLetters)
  std::array<double, 26> letters_{};

  // Tools.
  tooltable::ToolTable tools_;
  std::string selected_tool_, active_tool_;
  int active_socket_ = 0;  // the data set M06 chose among the tool number's alternates (0: by number)
  int uat_ = 0;
  double tool_len_ = 0, tool_dia_ = 0;
  int pallet_ = 0;
  bool block_delete_ = false, optional_stop_ = false, b_index_ = true;
  bool operator_ = false;  // OPERATOR=1 (a station): M99 M00 is the alarm and a program stop, not an error
  int max_pallet_ = 255;

  // Files and system parameters.
  int cer_ = 0;              // device classes whose errors only warn (CER): kDeviceMas | kDeviceSeq | ...
  std::string part_number_;  // the inspection header's PALLET CODE/PART NUMBER (PART_NUMBER; else L3020)
  std::string fwr_pending_;
  std::array<double, 8> probe_latch_{};
  std::array<double, 6> dat_{};
  std::map<int, double> program_;  // L100-L999
  std::map<int, double> machine_;  // L1000-L2999
  // Files written by this run (OPF/OIF + FWR/MSG): an NC file written and closed can be called with CLS
  // (manual Fig 7.28). The program store keeps the real files; this is the run's own view of them.
  struct MemFile {
    std::string type;
    std::string text;
  };
  std::map<std::string, MemFile> files_;
  std::string open_file_;  // upper-case name of the file open for writing; empty: none

  // Definitions.
  std::map<std::string, Def> defs_;
  std::map<std::string, Def> lib_cache_;
  ParseCache<ParsedBlock> cache_;
  ParsedBlock fresh_;          // the block being run when it is not cached (its storage reused)
  std::string_view block_;     // the block being executed (diagnostic columns)
  std::string block_comment_;  // its comment (the operator's message of an M99 M00 in cycle code)
  int local_defs_ = 0;
};

template <class T>
T& KtRun::Out() {
  EmitUnitsOnce();
  idle_ = 0;
  if (comp_.engaged()) [[unlikely]]
    return CompSlot<T>();
  return out_.Emplace<T>(cur_line_);
}

template <class T>
T& KtRun::CompSlot() {
  if (comp_staged_) CompCommit();
  comp_stage_.line = cur_line_;
  comp_staged_ = true;
  return comp_stage_.Set<T>();
}

// Device classes of CER/SER (ln 8358-8395): mass storage, sequential (printer), remote (FMS host).
constexpr int kDeviceMas = 1, kDeviceSeq = 2, kDeviceRem = 4;
// The inspection header's delimiter line (ch. 7 ln 7908: "the dashed line"; its length is lost in the scan).
inline constexpr const char* kInspectionDelimiter = "------------------------------";  // judgement call 54
// The header OIF (and MSG,NAM) writes when it opens a file (ch. 7 ln 7898-7908), lines ending in "\n":
// serial number, pallet code/part number, the YY:MM:DD HH:MM stamp of `now` (year, month, day, hour,
// minute, second), the delimiter.
std::string InspectionHeader(const std::string& serial, const std::string& part_number,
                             const std::array<int, 6>& now);

// A tool number as the control writes it from a value: 33412.5 -> "33412.5", 1001 -> "1001".
std::string ToolName(double v);

}  // namespace cell::interp::ktapl
