// The LinuxCNC differential (issue 33 item 1): random programs in a dialect's own syntax and the same
// toolpath as RS-274/NGC, run through cell-interp and LinuxCNC's rs274, compared move by move
// (docs/testing.md).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace cell::oracle {

using Vec3 = std::array<double, 3>;  // x y z

// The modes a generated motion block runs in (the generator picks them; each module writes them its way).
struct Modes {
  bool inch = false;         // program unit
  bool incremental = false;  // G91-like distances
  int plane = 17;            // 17 XY, 18 ZX, 19 YZ
  bool swapped = false;      // the plane's two axes in the other order (Balt-System (DPI,X,Z) is ZX swapped)
  bool per_rev = false;      // feed per revolution
  bool inverse = false;      // inverse time feed (G93): F is 1/min of the move
  int offset = 0;            // work offset 0 (none) .. kOffsets-1
};

// kSet: the position is `end` (G92), no motion; kThread: a lathe thread pass (parts only, `feed` its lead)
enum class MoveKind { kRapid, kLine, kArc, kCycle, kSet, kThread };

// One generated motion block. Positions are program coordinates in the program unit, x as a radius (a lathe
// module writes diameters); every coordinate lies on the unit's grid, so both programs state it exactly.
struct Block {
  Modes m;
  MoveKind kind = MoveKind::kLine;
  Vec3 start{};  // where the block starts (program coordinates of this block's offset)
  Vec3 end{};
  Vec3 center{};                // arcs: the centre (the plane's two axes; the third is the start's)
  Vec3 rot_start{}, rot_end{};  // a b c in degrees (a rotary-only move: end == start)
  bool cw = false;
  bool radius_form = false;
  double radius = 0;   // radius form: the radius (negative beyond 180 degrees)
  int turns = 0;       // helix: extra full turns
  double pitch = 0;    // helix: travel of the third axis per turn (Balt K), 0 without turns
  double feed = 0;     // unit/min or unit/rev
  int cycle = 0;       // kCycle: the dialect's code at each of `holes` (x y), from the R plane to `bottom`
  double r_level = 0;  // kCycle: the R plane; the tool returns there after each hole (G99)
  double bottom = 0;
  std::vector<std::array<double, 2>> holes;
  // kCycle, a peck cycle (Caps::pecks): the peck (Balt-System I, KT-APL E), its reduction factor K (0: none)
  // and least peck J (0: none), and whether the tool goes back to R between pecks (Balt-System with K, KT-APL
  // G87) or feeds on (Balt-System I alone, KT-APL G83).
  double peck = 0, peck_k = 0, peck_j = 0;
  bool discharge = false;
  double backoff = 0;  // kCycle: the feeding-on variant's back-off between pecks (Caps::Peck), program units
  bool tap_pitch = false;  // kCycle G84: the dialect states the pitch, F / S (Balt-System K, S1000), not F
  unsigned omit =
      0;  // words a module may leave out where they change nothing: bits 0-2 axis x y z, 3-5 centre
  // The block's B positioning selected its offset (Caps::implicit_offsets) or turned it (calculated_offsets).
  bool offset_by_b = false;
  Vec3 offset_mm{};  // the work offset in force (mm; turned with B under Caps::calculated_offsets)
};

// The work offsets every program may select (mm; x a radius). Offset 0 is the machine zero. Whole thousandths
// of an inch (0.0254 mm): on both units' grids, so rs274's four inch decimals print them exactly.
inline constexpr int kOffsets = 3;
inline constexpr std::array<Vec3, kOffsets> kOffsetTable{
    {{0, 0, 0}, {12.7, -20.32, 5.08}, {-35.052, 14.478, -7.747}}};
// Caps::implicit_offsets: the B position (degrees) that selects each offset (KT-APL's FXC I); 0 none.
inline constexpr std::array<double, kOffsets> kOffsetB{0, 90, 270};
// The offset an absolute B positioning to `b` (degrees, any turn) selects under implicit offsets.
int OffsetAtB(double b);

// What a dialect has: the generator draws only from these.
struct Caps {
  bool lathe = false;               // X is a diameter, XZ plane only (G18), no Y
  bool inch = true;                 // has an inch unit form
  bool unit_switch = true;          // the unit may change mid-program (else one per program, by the seed)
  bool inch_only = false;           // with unit_switch off: every program in inch (Okuma's inch systems)
  bool rapid_after_offset = false;  // a work offset change needs a G00 next (EMCO ALARM 490)
  bool incremental = true;          // G91 (or U/W) distances
  std::vector<int> planes{17, 18, 19};
  bool swapped_planes = false;     // planes with their axes in either order
  bool full_circle = false;        // a centre-form arc may end where it starts
  std::string position_set;        // the code that sets the present position (Okuma G50, KT-APL G92 regrid)
  bool rotary = false;             // A B C moves alone (degrees; F in deg/min)
  bool rotary_linear = false;      // rotary axes moving with X Y Z in one G00/G01 block
  unsigned rotary_axes = 7;        // which of A B C (bits 0-2) the dialect turns
  int max_axes = 0;                // axis words a linear block may hold (0: no limit)
  bool rotary_wrap = false;        // an absolute rotary word is the position mod 360, its sign the sense
  bool rotary_whole_feed = false;  // a rotary-only F is whole deg/min (KT-APL F3.0)
  // G94 F of a rotary+linear move is the rate along the vector of the travels in mm and degrees; the NGC
  // twin states the rate along X Y Z that follows from it (Balt-System ln 3961-3976).
  bool rotary_vector_feed = false;
  // Drilling cycles against LinuxCNC's G81-G89 (G17, G90, G99 retract); on a lathe one hole on the spindle
  // axis from where the tool is, after a rapid to X0 (LinuxCNC: G17 for the cycle, R there).
  std::vector<int> cycles;
  std::vector<int> cycles_per_rev;  // those allowed in feed per revolution
  // A drilling cycle whose moves no LinuxCNC cycle makes from the same words, a peck cycle above all (its G83
  // comes back down by rapid to 0.254 mm above the last bottom, its G73 backs off 0.254 mm): the NGC twin
  // states its moves as G0/G1 (PeckBottoms), or `native` where that cycle makes them.
  struct Peck {
    int code = 83;
    bool feeding_on = false;   // the variant that feeds peck after peck (a dwell between, not compared)
    bool discharging = false;  // the variant that goes back to R after each peck, then down to `clearance`
    double clearance = 0;      // mm above the last bottom the re-approach ends
    double approach_feed = 0;  // mm/min of the re-approach (0: a rapid)
    // The peck after a re-approach feeds `peck` from there (Balt-System "R1 = R1 + I - 1": I - 1 of new
    // depth); else it goes `peck` below the last bottom.
    bool from_clearance = false;
    bool reduce = false;      // K and J: the peck shrinks by K each time down to J
    double clearance_in = 0;  // inch programs: the clearance in inch (0: `clearance` / 25.4)
    // The feeding-on variant backs off by rapid between pecks (Block::backoff; LinuxCNC's G73 by 0.254 mm,
    // 0.010 in): by this much (mm, inch; EMCO G87's S02) or by a word of the block (Okuma G74 DA=).
    double backoff = 0, backoff_in = 0;
    bool backoff_word = false;
    // Pecks of equal depth, the fewest of at most `peck` (EMCO G87/G88 D3 without D5, ln 4724-4761).
    bool equal = false;
    int native = 0;  // the LinuxCNC cycle that makes the same moves where the back-off is its own (G73)
    // No pecks: a feed to this far (mm, inch) above the bottom, the rest at `slow_feed` mm/min (KT-APL G82).
    double slow_end = 0, slow_end_in = 0, slow_feed = 0;
  };
  std::vector<Peck> pecks;
  bool tap_pitch = false;                 // G84 may state the pitch instead of F (F = pitch x S)
  double tap_max_feed = 0;                // mm/min: G84's highest feed (0: none)
  bool radius_form = true;                // arcs by R
  bool radius_form_g17_absolute = false;  // R only in G90 G17 (KT-APL)
  bool helix = true;                      // the plane's third axis may move along an arc
  bool helix_turns = false;               // multi-turn helices (and how the dialect writes them)
  bool per_rev = true;
  bool inverse_time = false;  // G93
  bool offsets = true;
  // The offset follows B (KT-APL G49, ln 1700, 7018-7026): an absolute positioning (rapid) of B to
  // kOffsetB[k] selects offset k, to any other position none; `offsets` (drawn by mode changes) is off then.
  bool implicit_offsets = false;
  // The offset in force turns with B (KT-APL G47, ln 1678-1680, 6286-6308, ktapl.md call 77): X' = X cos d -
  // Z sin d, Z' = X sin d + Z cos d, d the B of the last positioning of B (or where B stood when the offset
  // was selected) less the offset's kOffsetB. The NGC twin sets the turned offset by G10 L2 before the block.
  bool calculated_offsets = false;
  // B is an index table (KT-APL B_AXIS=index, ln 4491-4546): whole degrees, every B move a rapid (F0), the
  // block's X Y with B and then its Z (the NGC twin states the two moves).
  bool index_b = false;
  // The position set names the machine's absolute position (KT-APL G92, ln 1579): the dialect's word is the
  // NGC twin's G92 word plus the work offset in force (a module adds it).
  bool position_set_machine = false;
  int mm_decimals = 3;  // the grid of a coordinate word
  int inch_decimals = 4;
  int feed_decimals = 1;  // per minute feeds
};

struct Program {
  std::string dialect_text;                 // the program in the dialect's syntax
  std::string ngc_text;                     // the same toolpath as NGC
  std::string params;                       // cell-interp --params file text (empty: none)
  std::vector<std::string> blocks_dialect;  // per motion block, its text in each form (for reports)
  std::vector<std::string> blocks_ngc;
  bool inch_anywhere = false;  // the 2e-3 tolerance applies
};

// How a dialect calls blocks as a subprogram (the subprogram property): `call` replaces the blocks in the
// main program; `head` + the blocks + `tail` define them, just before the call (`in_place`, e.g. KT-APL's
// DFS) or after the main program's end.
struct SubprogramForm {
  std::string call, head, tail;
  bool in_place = false;
};

// A dialect module: writes a generated block list as a program of its own.
class Module {
 public:
  virtual ~Module() = default;
  virtual std::string Name() const = 0;       // cell-interp --dialect
  virtual std::string Extension() const = 0;  // program file extension
  virtual Caps Capabilities(std::uint64_t seed) const = 0;
  virtual Program Write(const std::vector<Block>& blocks, std::uint64_t seed) const = 0;
  // The named forms Write can state one block list in (the units property: Okuma's unit systems, EMCO's
  // micrometre and decimal words); empty: the blocks' own unit is the only form.
  virtual std::vector<std::string> Forms() const { return {}; }
  // Write in `form` (one of Forms(); "" is Write's own choice by the seed).
  virtual Program WriteForm(const std::vector<Block>& blocks, std::uint64_t seed,
                            const std::string& form) const {
    (void)form;
    return Write(blocks, seed);
  }
  // The dialect's subprogram (called once); none: the property does not apply.
  virtual std::optional<SubprogramForm> Subprogram() const { return std::nullopt; }
};

// The (first, second, normal) axis indices of a block's plane: G17 X Y Z, G18 Z X Y, G19 Y Z X, the first two
// exchanged when swapped.
std::array<int, 3> AxesOf(const Modes& m);
// Whether a module may leave out axis word `axis` (absolute: the value is the start's; incremental: 0) or the
// centre word of `axis` (its offset from the start is 0), as the block's omit bits allow.
bool OmitAxis(const Block& b, int axis);
// A move of rotary axes alone (F in deg/min in either unit), not one with X Y Z.
bool RotaryAlone(const Block& b);
bool OmitCentre(const Block& b, int axis);

const Module* FindModule(const std::string& name);
std::vector<std::string> ModuleNames();  // in priority order: balt ktapl emco okuma

// A cycle block's peck rule (none: not a peck cycle), and the bottoms its pecks feed to at one hole, from
// its R plane down to its bottom (program units): a peck that would reach the bottom or pass it ends there.
const Caps::Peck* PeckOf(const Block& b, const Caps& caps);
std::vector<double> PeckBottoms(const Block& b, const Caps::Peck& p);

// The random block list for a dialect's capabilities (deterministic for a seed).
std::vector<Block> Generate(const Caps& caps, std::uint64_t seed, int count);

// The NGC form of a block list (lathe: G7 G18, diameters).
struct NgcText {
  std::string text;
  std::vector<std::string> blocks;
};
NgcText WriteNgc(const std::vector<Block>& blocks, const Caps& caps);

// Number formatting shared by the modules: fixed decimals with trailing zeros dropped; `point` keeps a
// trailing decimal point on whole numbers ("10.").
std::string Num(double v, int decimals, bool point = false);

// One move as both interpreters report it, machine coordinates in mm, x a radius.
struct Move {
  MoveKind kind = MoveKind::kLine;
  Vec3 end{};
  Vec3 center{};
  Vec3 rot{};       // a b c, degrees
  Vec3 travel{};    // a b c signed degrees of this move (cell-interp states positions in [0, 360))
  int plane = 17;   // the NGC plane the arc is in
  bool cw = false;  // seen from the plane's normal (G17 +Z, G18 +Y, G19 +X)
  int turns = 0;
  double feed = 0;  // mm/min or mm/rev
  bool per_rev = false;
  bool inverse = false;  // cell-interp: f is 1/min (InverseToPerMinute makes it mm/min as rs274 states it)
  bool was_inverse = false;  // cell-interp: the feed was inverse time
  double floor = 0;          // rs274: the least rate it gives an inverse-time move, 0.1 unit/min (in mm/min)
  int line = 0;
};

// Drops the lines that go nowhere (a cycle's rapid to the R plane it is already on: rs274 states it, a
// dialect may not).
void DropStill(std::vector<Move>& moves);
// Inverse-time feeds as mm/min: F x the move's length (LinuxCNC's reading of G93).
void InverseToPerMinute(std::vector<Move>& moves);

// Properties every program keeps (issue 33 item 2, docs/testing.md "Properties"): rewrites of a generated
// block list that state the same motion another way.
// Every block absolute.
std::vector<Block> Absolute(std::vector<Block> blocks);
// Every block incremental where the dialect writes it so and its start is on its unit's grid (the unit and
// offset of the block before; not a cycle, not a position set, not KT-APL's R form: G90 only).
std::vector<Block> Incremental(std::vector<Block> blocks, const Caps& caps);
// Per-minute inch feeds on a step whose mm value lies on the dialect's feed grid (5 x 10^-feed_decimals
// in/min: 0.5 in/min is 12.7 mm/min), so a unit conversion states the feed exactly.
std::vector<Block> ConvertibleFeeds(std::vector<Block> blocks, const Caps& caps);
// Arcs whose start and end lie at different distances from the centre on a grid of `decimals` (the
// generator's snapping on a coarse grid) become lines to their end: an interpreter may mend such an arc.
std::vector<Block> ExactArcs(std::vector<Block> blocks, int decimals);
// Inch blocks in mm where `convert(index)`: positions x 25.4 rounded to the caps' mm grid (at most 5e-4 mm
// off), feeds x 25.4 (inverse time unchanged).
std::vector<Block> InchToMm(std::vector<Block> blocks, const Caps& caps, bool (*convert)(std::size_t));

// Moves as a transform of the program makes them (about the machine zero, which is the program zero without
// offsets): mirrored in the axes of `axes` (bits x y z; an arc's sense flips when one of its plane's axes
// is), turned by `degrees` counterclockwise in the XY plane, scaled by `factor` in x y z.
void MirrorMoves(std::vector<Move>& moves, unsigned axes);
void RotateMoves(std::vector<Move>& moves, double degrees);
void ScaleMoves(std::vector<Move>& moves, double factor);

// `threads`: thread ops become kThread moves (the parts' comparer); without, they are skipped.
std::vector<Move> ParseCellInterp(const std::string& json_lines, bool lathe, std::string* error,
                                  bool threads = false);
std::vector<Move> ParseRs274(const std::string& canon, bool lathe, std::string* error);

// Compare the two lists; empty when they agree, else the first disagreement in words.
struct Disagreement {
  std::size_t index = 0;  // move index
  std::string field;
  std::string detail;
};
std::optional<Disagreement> Compare(const std::vector<Move>& cell, const std::vector<Move>& ngc, double tol);
std::string Describe(const Move& m);

// One part in every dialect of its kind (issue 33 item 3, docs/testing.md "Parts"): a part's programs and
// which of their lines cut the finished contour, read from tests/oracle/parts/<part>/part.txt.
struct LineRange {
  int first = 0, last = 0;  // 1-based program lines, inclusive
};
struct PartProgram {
  std::string file, dialect, params, tools;  // file names in the part's folder ("" none)
  std::vector<LineRange> finish;             // lines whose feed moves cut the finished contour
  std::vector<LineRange> thread;             // lines whose last thread pass is the finished thread
  // Lines of a plunge cycle (a groove): the feed moves that end deepest (the least x) are the groove's floor,
  // compared as points; the pecks on the way down are each manual's own.
  std::vector<LineRange> bottoms;
  Vec3 origin{};  // the part zero in the machine frame, mm (x a radius)
  // Compensation that goes round an outside corner on an arc of this radius about it (EMCO, ln 2753) is
  // compared as the intersection of the two offset elements (Okuma, ln 2298-2324): the same corner is cut.
  // Every arc of that radius between two lines is taken for such a corner (a concave fillet of twice the
  // radius makes one too): a part that programs one must not use this.
  double corner_arcs = 0;
  // The finish lines run more than once (a loop, a subprogram called twice, Balt-System's RPT with a stock
  // allowance): only the last pass counts, the moves since the program last went back to an earlier line.
  bool last_pass = false;
};
struct Part {
  std::string name;
  std::vector<PartProgram> programs;
};
// Reads part.txt (its syntax: docs/testing.md); a line range may name N-words ("N101-N120": the program
// lines that begin with them).
bool ReadPart(const std::string& dir, Part* part, std::string* error);

// The finished contour of a run's moves: where it starts and its elements (lines, arcs, the finished thread)
// in the part's frame; collinear lines are joined and lines that go nowhere dropped, so two programs that
// cut one contour in different blocks still agree.
struct Contour {
  std::vector<Vec3> starts;  // where each element starts (drilled holes: a gap of rapids before each)
  std::vector<Move> elements;
};
Contour FinishedContour(const std::vector<Move>& moves, const PartProgram& p, double tol);
// The first element where two contours differ (start and end point, arc centre in its plane, plane, sense,
// thread lead), or none; element i is index i + 1.
std::optional<Disagreement> CompareContours(const Contour& a, const Contour& b, double tol);

}  // namespace cell::oracle
