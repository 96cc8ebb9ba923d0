// The Okuma OSP-E100L executor's internals, shared by its files (split by concern as LinuxCNC splits its
// interpreter):
//   interp_read.cpp      the tape format: blocks, sequence names, words, assignments, statements (block.h)
//   expr.cpp             User Task expressions (expr.h)
//   interp_flow.cpp      block stepping, continuation lines, program and sequence search, GOTO, IF, CALL/RTS,
//                        MODIN/MODOUT, the run's life cycle
//   interp_vars.cpp      common, local, system and I/O variables, user alarms, READ/WRITE/GET/PUT
//   interp_convert.cpp   NC blocks: G/M/S/T/F, modal state, the order of a block's actions
//   interp_motion.cpp    coordinates and offsets, G00/G01 with taper angles, G50, C axis, G04
//   interp_arc.cpp       G02/G03 with I/K or the radius L (CALRG), on the core's arc geometry
//   contour_stage.cpp    automatic chamfering and rounding G75/G76 and angle-only lines (one-move look-ahead)
//   nose_comp.cpp        tool-nose radius compensation G40/G41/G42 on the core's offset geometry
//   interp_thread.cpp    thread cutting G31-G35 and the compound thread cycles G71/G72
//   interp_cycles.cpp    grooving G73/G74, tapping G77/G78
//   interp_mtool.cpp     the M-tool compound fixed cycles G178-G190 (drilling, boring, tapping, synchronized
//                        tapping, threads, key ways)
//   interp_ccontour.cpp  contour generation G101-G103 (face), G132/G133 (side) as pieces, coordinate
//                        conversion G137/G136
//   lap.cpp              LAP tool paths (AP modes I-V) from a captured contour
//   interp_lap.cpp       the executor's side of LAP: contour capture, G84-G88 calls, modal restore
//   tool_data.cpp        Okuma tool data (tool offsets, nose radius) in the manual's variables
#pragma once

#include <array>
#include <bitset>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "block.h"
#include "cell/interp/call_stack.h"
#include "cell/interp/canon.h"
#include "cell/interp/geometry/arc.h"
#include "cell/interp/geometry/offset_path.h"
#include "cell/interp/okuma.h"
#include "cell/interp/parse_cache.h"
#include "cell/interp/run_base.h"
#include "expr.h"
#include "lap.h"
#include "staged.h"
#include "tool_data.h"

namespace cell::interp::okuma {

constexpr double kPi = 3.14159265358979323846;

// The unit systems of numeric input (ln 1033-1093): what the number "1" means.
enum class UnitSystem { k1mm, k10um, k1um, kInch, k10000thInch };

// What Okuma keeps per frame besides the text position.
struct FrameData {
  enum Kind : uint8_t { kMain, kSub, kModin, kLap } kind = kMain;
  int modin_limit = 0;       // MODIN subprograms [0, limit) follow this frame's motion blocks
  size_t program_begin = 0;  // where this program's text starts (sequence search)
  int program_begin_line = 1;
  bool tape_started = false;  // a "%" or a block other than a comment: a "$" line is no longer a tape header
  JumpTargets<std::string> labels;  // sequence names found by GOTO / IF / LAP
  int runs_left = 0;                // CALL ... Q n: runs still to come after this one
  TextPos first{};                  // where a repeated run starts again
};
using Frames = CallStack<FrameData>;

// A program found by name: its text and where its first block is.
struct ProgramRef {
  std::shared_ptr<const ProgramText> text;
  size_t begin = 0;
  int line = 1;
  bool own = true;  // reports its own lines (in PROGRAM itself) or the calling block's
};

// A MODIN in force (ln 8048-8073).
struct Modin {
  std::string name;
  ProgramRef program;
};

// Values of a block's words by address, evaluated and scaled to mm / deg / s.
struct BlockWords {
  std::array<double, 26> v{};
  std::array<int, 26> col{};
  uint32_t has = 0;
  // Extended addresses (SA SB QA DA DB FA FB XA XB ZA ZB PZ PW).
  std::array<double, 13> ext{};
  std::array<int, 13> ext_col{};
  uint16_t ext_has = 0;
  struct Code {
    int code = 0;
    int col = 1;
  };
  std::vector<Code> g, m;
  // A G code other than a motion code (G00-G03, G31-G35, G101-G103, G132/G133): most blocks have none, and
  // then FindG/HasG, which look only for such codes, answer without a search.
  bool other_g = false;
  int t_digits = 0;       // digits written in the T word (4 or 6)
  bool absolute = false;  // X, Z, C are absolute whatever G90/G91 (G137 converted them)

  bool Has(char a) const { return (has >> (a - 'A')) & 1u; }
  double Get(char a) const { return v[static_cast<size_t>(a - 'A')]; }
  int Col(char a) const { return col[static_cast<size_t>(a - 'A')]; }
  bool HasExt(int i) const { return (ext_has >> i) & 1u; }
  // For codes other than the motion codes (those are read by ReadNcGCodes).
  bool HasG(int code) const { return FindG(code) != nullptr; }
  const Code* FindG(int code) const {
    if (!other_g) return nullptr;
    for (const auto& c : g) {
      if (c.code == code) return &c;
    }
    return nullptr;
  }
  bool HasM(int code) const;
  void Clear() {
    has = 0;
    ext_has = 0;
    g.clear();
    m.clear();
    other_g = false;
    t_digits = 0;
    absolute = false;
  }
};
int ExtIndex(Addr a);  // index into BlockWords::ext, -1 if not an extended address
// G178-G190 but G180: the M-tool compound fixed cycles (ln 4073-4098).
inline bool IsMToolCycle(int g) {
  return g == 178 || g == 179 || (g >= 181 && g <= 190);
}

// Modal state by meaning (the codes that set it in the comments).
struct Modal {
  int motion = 0;              // G00 G01 G02 G03 G31-G35 G101-G103 (their numbers); -1 none (G137)
  bool incremental = false;    // G91 (G90 at reset)
  bool per_rev = true;         // G95 (power-on and reset) / G94
  bool css = false;            // G96 / G97
  bool turret_b = false;       // G14 / G13 (reset)
  bool droop = false;          // G65 / G64
  bool chuck_barrier = false;  // M25 / M24 (off at power-on and reset, ln 9108)
  bool tail_barrier = false;   // M21 / M20
  int comp = 40;               // G40 / G41 / G42 as programmed
  SpindleDir spindle = SpindleDir::kStop;  // M03 M04 M05 M19 (as the spindle turns, after G14's mirror)
  bool coolant = false;                    // M08 / M09
  bool c_joined = false;                   // M110 / M109
  bool c_clamped = false;                  // M147 / M146 (power-on)
  bool c_negative = false;                 // M16 / M15 (reset)
  bool thread_chamfer = false;             // M23 / M22
  int thread_mode = 32;                    // M32 M33 M34
  int infeed = 73;                         // M73 M74 M75
  bool mtool_release = false;              // M153 / M152
  SpindleDir mtool = SpindleDir::kStop;    // M13 M14 / M12: the live (M-tool) spindle
  bool feed_fixed = false;                 // M161 / M160: the feedrate override fixed at 100 %
};

// The thread chain in progress (repeated G31/G32/G33 blocks, G34/G35 chains).
struct ThreadChain {
  bool active = false;
  int g = 0;
  double start_angle = 0;  // C of the first block
  AxisArray start{};       // G31-G33: the cycle start point (machine)
  bool cycle = false;      // G31-G33: a pass ran; the next blocks repeat it with new X (Z)
  double last_x = 0, last_z = 0, taper = 0, shift = 0, lead_change = 0;
};

// The M-tool compound fixed cycle in force (G181-G190 until G180, ln 4073-4937): its words are modal within
// the mode (a block gives only what changes, ln 4797-4799).
struct MToolCycle {
  int g = 0;                  // 178, 179, 181-190; 0 = none
  AxisArray start{};          // the cycle start point (X0, Z0: where the mode began), machine
  BlockWords words;           // the words in force
  bool need_g180 = false;     // a Q block ran: only G180 may follow (ln 4651-4657)
  bool chained = false;       // G187/G188: a thread ran; the next block continues from its end (ln 4400-4433)
  bool after_cancel = false;  // G180 ran: the next block needs both X and Z (ln 4527)
  bool zigzag = false;        // G190: M212 (M211, one direction, by default: ln 4505)
  bool equal = false;         // G190: M214 (M213, the designated infeed D, by default)
  long budget = 0;            // moves one block may still make (a guard, judgement 38)
  int col = 1;                // the block's cycle column (for the guard's alarm)
};

struct FacePath;  // a face contour in Cartesian program coordinates (interp_ccontour.cpp)

class OkRun final : public RunBase, public VarReader {
 public:
  explicit OkRun(const RunOptions& o);

  std::map<std::string, double> Variables() const override;
  tooltable::ToolTable Tools() const override { return tools_.table(); }

  // VarReader
  double Common(int n, int col) override;
  double Local(uint64_t name, int col) override;
  Value System(uint64_t name, const Value* index, int col) override;
  bool MicronUnits() const override { return units_ == UnitSystem::k1um; }
  double SettingUnit() const override { return inch_ ? 0.0001 : 0.001; }

 private:
  // Life cycle and output (interp_flow.cpp)
  void StepOnce() override;
  void Finish();
  void ReportError(const RunError& e, int first_line);
  template <class T>
  T& Out();
  void Commit();
  void Sink(Staged&& s);
  void EndBlockStages(bool xz);
  bool StagesEngaged() const;
  void EmitUnitsOnce();

  // Blocks and control flow (interp_flow.cpp)
  const Block* ReadBlock(int* first_line);
  void ExecBlock(const Block& b);
  void ExecStatement(const Block& b);
  bool ProgramEnds(const Block& b);
  std::optional<ProgramRef> FindProgram(const std::string& name);
  std::optional<ProgramRef> ProgramIn(const std::shared_ptr<const ProgramText>& text, const std::string& name,
                                      bool own);
  void CallProgram(const ProgramRef& p, const std::string& name, FrameData::Kind kind, int modin_limit,
                   const Block* args);
  void Return(int col);
  std::optional<TextPos> FindSequence(const std::string& name, bool from_start);
  void Jump(const std::string& label, int col);
  void SkipContourDefinition(const Block& b);
  void TriggerModin();
  void ResetProgramState();

  // Chuck and tailstock barriers (barrier.cpp)
  void BarrierCode(int m, int col);
  bool CheckBarriers();
  void BarrierOffAfterBlock();
  double BarrierDatum(const char* name) const;

  // Variables (interp_vars.cpp)
  void Assignment(const Assign& a, const Block& b, bool call_arg);
  void SetLocal(uint64_t name, double v, bool new_entry, int col);
  void SetSystem(uint64_t name, const Value* index, double v, int col);
  double ScaleSystemInput(const Value& v) const;
  void RaiseUserAlarm(int which, double code, int col);
  void PopLocals(int level);
  std::optional<double> EnvValue(const std::string& name);
  void ExecIo(const Block& b);

  // NC blocks (interp_convert.cpp)
  void ExecNc(const Block& b);
  void RefuseUnsupported(const BlockWords& w);
  void RefuseTorqueAndTurretB(const BlockWords& w);
  static const char* RefusedControlM(int m);
  // The G codes of an NC block as they act (ReadNcGCodes -> the rest of ExecNc).
  struct NcGCodes {
    int motion_g = -1, motion_col = 1, comp_g = 0;
    bool dwell = false, g50 = false, g90 = false, g91 = false, g13 = false, g14 = false, g80 = false;
    bool g180 = false, mtool_fresh = false;  // G180; a G181-G190 code in this block
    bool g136 = false, g137 = false;         // coordinate conversion off / on
    int chamfer = 0, cycle = 0, lap = 0, cycle_col = 1;
  };
  void ReadNcGCodes(const BlockWords& w, NcGCodes& k);
  // The addresses the block's function reads, and the G code that function is named by in a refusal.
  uint32_t UsedAddresses(const NcGCodes& k, int* g) const;
  void RefuseUnusedAddresses(const BlockWords& w, const NcGCodes& k) const;
  void MotionGCode(int motion_g, int motion_col);
  void NcAction(const BlockWords& w, const Block& b, const NcGCodes& k, bool xz);
  double WordValue(const Block& b, const Word& w);
  void CollectWords(const Block& b, BlockWords& w);
  void ApplyModalG(const BlockWords& w, bool* motion_code, int* motion_col);
  void ToolWord(const BlockWords& w);
  void SpindleAndM(const BlockWords& w, bool before_motion);
  void MToolSpindle(const BlockWords& w);
  void EmitMTool(SpindleDir d);
  void FixFeedOverride(bool fixed, int m);
  void CycleFeedFixed(bool fixed);
  void CAxisJoint(const BlockWords& w, const BlockWords::Code& m);
  void StopAndEnd(const BlockWords& w);
  double Scale(char addr, double v, bool feed_per_rev) const;
  double ScaleLength(double v) const;

  // Motion (interp_motion.cpp, interp_arc.cpp)
  double Offset(int axis) const;
  double ToMachine(int axis, double prog) const;
  double ToProgram(int axis, double machine) const;
  void Motion(const BlockWords& w, const Block& b, int motion_col);
  void LineMotion(const BlockWords& w, const Block& b, bool rapid, int motion_col);
  bool TargetOf(const BlockWords& w, AxisArray& target, uint32_t* moved, int motion_col);
  void CTarget(const BlockWords& w, AxisArray& target, AxisArray& travel, uint32_t* travel_mask);
  void EmitMove(const AxisArray& target, uint32_t moved, bool rapid, double feed, FeedMode fm,
                const AxisArray& travel, uint32_t travel_mask, const CornerSpec* spec);
  void Arc(const BlockWords& w, const Block& b, bool cw, int col);
  void Dwell(const BlockWords& w, int col);
  void ZeroShift(const BlockWords& w, int col);
  void CheckLimits(AxisArray& target, int col);
  double Feed() const { return f_; }
  FeedMode FeedModeNow() const { return modal_.per_rev ? FeedMode::kPerRev : FeedMode::kPerMinute; }

  // Nose radius compensation (interp_convert.cpp side)
  void CompCodes(const BlockWords& w, int motion_col, bool has_xz);
  geom::Vec2 TipVector(int tip) const;

  // Threads (interp_thread.cpp)
  void ThreadBlock(const BlockWords& w, int g, int col);
  void RunThreadPass(const AxisArray& cycle_start, const AxisArray& pass_start, const AxisArray& pass_end,
                     double lead, double lead_change, double start_angle, bool face, double chamfer);
  void EmitThread(const AxisArray& to, double lead, double lead_change, double start_angle,
                  bool lead_along_x);
  void ThreadCycle(const BlockWords& w, int g, int col);
  void CompoundThread(const BlockWords& w, int g, int col);
  std::vector<double> InfeedDepths(double d, double h, double u, int pattern, int mode, bool has_u, int col);

  // Cycles (interp_cycles.cpp)
  void Grooving(const BlockWords& w, int g, int col);
  void Tapping(const BlockWords& w, int g, int col);

  // M-tool compound fixed cycles (interp_mtool.cpp)
  void MToolBlock(const BlockWords& w, int g, bool fresh, int col);
  bool MToolMode(const BlockWords& w, NcGCodes& k);
  void MToolMerge(const BlockWords& w);
  void MToolChecks(const BlockWords& w, int g, bool fresh, int col);
  void MToolDrill(const BlockWords& w, int g, int col);
  struct HolePath {
    int da = 0, pa = 0;  // the depth axis and the position axis
    double d0 = 0, ds = 0, bottom = 0,
           dir = 0;  // cycle start, cutting start, bottom along da; the feed's sign
  };
  HolePath MToolHolePath(const BlockWords& m, int g, int col);
  void MToolHoleIndex(const BlockWords& m, const HolePath& h, double c);
  void MToolHole(const BlockWords& w, int g, double c, int col);
  void MToolSyncTap(const BlockWords& m, int g, double c, int col);
  void MToolPecks(int axis, double from, double bottom, double dir, int col);
  void MToolKeyway(const BlockWords& w, double c, int col);
  void MToolThread(const BlockWords& w, int g, int col);
  void MToolCancel(int col);
  void MToolIndex(AxisArray target, uint32_t moved, double c_prog);
  void MToolMove(int axis, double v, bool rapid, double feed);
  void MToolClamp(bool clamp);
  void MToolStart();
  double CTravelTo(double t) const;

  // Contour generation and coordinate conversion (interp_ccontour.cpp)
  bool CoordConversion(BlockWords& w, const NcGCodes& k);
  void ConvertXY(BlockWords& w, int motion, int col);
  void ContourMove(const BlockWords& w, int g, int col);
  void SideContour(const BlockWords& w, int g, int col);
  void ContourChecks(const BlockWords& w, int col);
  void ContourLine(double r0, double c0, double r1, double c1, double z0, double z1, int col);
  void ContourCentre(double r0, double c0, double r1, double c1, double z0, double z1, int col);
  void ContourChords(const FacePath& path, double c1, double z0, double z1, int col);
  void ContourPiece(double x_prog, double z_prog, double c_prog, double c_travel, double feed, FeedMode fm,
                    int col);

  // LAP (interp_lap.cpp)
  void LapCall(const BlockWords& w, const Block& b, int g, int col);
  void LapBlock(const Block& b, const BlockWords& w);
  void LapEndCapture(int col);
  void LapRestore();
  void LapCapture(Staged& s);

  // The program text (options and environment: RunBase).
  std::unique_ptr<Frames> frames_;
  ParseCache<Block> cache_;
  Block fresh_;
  std::string joined_;
  std::map<std::string, std::shared_ptr<const ProgramText>> files_;  // library texts by file name
  std::map<std::string, ProgramRef> programs_;                       // programs by O name
  std::vector<Modin> modins_;
  int cur_line_ = 1;
  bool cur_own_ = true;
  const Block* cur_block_ = nullptr;
  const Block* parsing_ = nullptr;  // the block being read or run (diagnostic lines of continuation lines)
  std::vector<Segment> segments_;
  bool main_started_ = false;  // the main program's name block has been read
  BlockWords words_;
  bool units_emitted_ = false;
  long idle_ = 0;
  long max_idle_ = 1000000;
  bool ended_ = false;

  // Settings.
  UnitSystem units_ = UnitSystem::k1mm;
  bool inch_ = false;
  bool block_delete_ = false;
  bool optional_stop_ = false;
  double arc_tolerance_ = 0.01;      // OTHER FUNCTION 1 No. 6, mm
  double peck_retract_ = 0.5;        // long word No. 7, mm
  double multi_peck_ = 0.5;          // MULTIPLE MACHINING pecking amount alpha of G183 (mm; X a diameter)
  bool multi_return_start_ = false;  // MULTIPLE MACHINING multi cycle return point: the cycle start point
  bool g184_sync_ = false;           // MULTIPLE MACHINING G184 tapping mode 1: G184 is G178 (ln 4539)
  double lap_relief_ = 0.1;          // LAP bar turning relief, mm
  double lap_clearance_ = 2.0;       // LAP4 clearance Lc, mm
  double thread_chamfer_feed_ = 0;   // OTHER FUNCTION 1, unused offline
  int m75_pattern_ = 3;

  // Modal state and positions (machine coordinates, X a diameter).
  Modal modal_;
  AxisArray pos_{};
  int barrier_off_ = 0;       // M24 (1) / M20 (2) in this block: off once its moves are checked
  AxisArray barrier_from_{};  // where the last command the barrier check passed ends (machine)
  uint32_t used_ = 0;
  bool open_line_ = false;  // the last line was given by an angle only: its end comes with the next block
  std::array<double, kAxisCount> zero_offset_{};  // VZOF*
  std::array<double, kAxisCount> zero_shift_{};   // VZSH* (G50; cleared by reset)
  double f_ = 0;                                  // F (mm/rev or mm/min)
  double e_ = 0;                                  // E: LAP roughing feed along the contour
  // The spindle phase at the end of the last thread when nothing has gone out after it (G65 starts a thread
  // that follows it at this phase: it no longer continues the chain).
  struct ThreadPhase {
    bool valid = false;
    AxisArray at{};
    double angle = 0;
  } thread_phase_;
  double s_ = 0;        // S as last programmed (rpm)
  double sb_ = 0;       // SB= as last programmed (M-tool rpm; kept through reset, ln 1877)
  double css_ = 0;      // G96 S (m/min)
  double max_rpm_ = 0;  // G50 S
  ThreadChain chain_;
  MToolCycle mc_;
  // G137 coordinate conversion (ln 6803-6918): the Cartesian face system at angle theta (program C) and the
  // last X, Y commanded in it (radius values).
  struct CoordConv {
    bool on = false;
    bool need_xy = false;  // the first block after G137 gives both X and Y, absolute (ln 6884-6918)
    double theta = 0, x = 0, y = 0;
  } conv_;
  bool contour_mode_ = false;   // the last motion block was G101-G103 (X > 0 is checked when the mode begins)
  double contour_tol_ = 0.001;  // CONTOUR_TOLERANCE: chord error of a contour generation path, mm
  double centre_override_ = 1;  // MULTIPLE MACHINING C-axis center override (1-1000 %, ln 6680-6686)
  bool side_inner_ = false;     // SIDE_CONTOUR_PLANE=INNER: G132/G133 on the inner development plane
  double c_net_ = 0;            // C degrees turned since M110 (the 5965-turn bound of G132/G133)
  std::array<double, kAxisCount> pos_limit_{}, neg_limit_{};  // VPVL*, VNVL* (machine); set flags below
  uint32_t pos_limit_set_ = 0, neg_limit_set_ = 0;

  // Tools.
  ToolData tools_;
  int tool_ = 0, offset_no_ = 0, nose_no_ = 0;
  double nose_r_ = 0;
  int tip_ = 0;

  // Variables.
  std::array<double, 201> common_{};
  std::bitset<201> common_set_;
  struct LocalVar {
    uint64_t name;
    double v;
    int level;
  };
  std::vector<LocalVar> locals_;
  std::map<std::pair<uint64_t, int>, double> system_;  // other system variables by (name, index)
  std::array<char, 17> vuacm_{};
  std::map<int, double> vdout_;
  std::string read_area_, write_area_;
  size_t rrp_ = 0;

  // Stages: G75/G76 and angle-only lines, then nose radius compensation; the last one's output goes to the
  // command queue or, while a LAP contour is captured, to the capture.
  ContourStage corner_;
  NoseComp comp_;
  Staged stage_;
  bool staged_ = false;
  bool force_stage_ = false;  // the next command goes through the stages (it starts a look-ahead)
  double tip_at_comp_ = 0;

  // LAP.
  struct LapState {
    bool active = false;  // a rough cycle is capturing its contour
    bool finish = false;  // G87: the contour runs as written
    int g = 0;
    int call_line = 0;
    size_t depth = 0;    // the capture frame's depth
    bool blank = false;  // between G83 and G81/G82
    bool have_contour = false;
    bool transverse = false;
    bool first_block_seen = false;  // a motion block of the current shape ran
    bool first_rapid = true;        // the finish contour's first block is G00
    bool capture_started = false;   // the current shape's start point is known
    geom::Vec2 capture_at;
    LapParams params;
    std::vector<LapElement> contour, blank_shape;
    AxisArray start{};  // the AP start point (machine)
    Modal modal;
    double f = 0, e = 0, s = 0;
    uint32_t used = 0;
  } lap_;
};

template <class T>
T& OkRun::Out() {
  EmitUnitsOnce();
  idle_ = 0;
  if constexpr (!std::is_same_v<T, ThreadOp>) thread_phase_.valid = false;
  if (!StagesEngaged()) [[likely]]
    return out_.Emplace<T>(cur_line_);
  if (staged_) Commit();
  stage_.kind = Staged::kOp;
  stage_.c.line = cur_line_;
  stage_.corner = CornerSpec();
  stage_.efeed = e_;
  staged_ = true;
  return stage_.c.Set<T>();
}

}  // namespace cell::interp::okuma
