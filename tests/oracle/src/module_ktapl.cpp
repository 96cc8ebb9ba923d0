// KT-APL (docs/dialects/ktapl.md): G70/G71 units, G90/G91, G17-G19 (G18 is (Z, X), App. H), I J K the centre
// by axis letter, absolute in G90 and incremental in G91, R only in G90 G17 (negative beyond 180 degrees),
// helices by the normal axis's word, rapids as F0 (DESIGN §4), every number with its decimal point (implied
// decimals otherwise, judgement call 64), feeds with one decimal (call 63), blocks under 80 characters (call
// 2). Fixture offsets: the work offsets as fixture lines H1, H2 (I the B position, G49), set by FXC or by UFX
// at the machine zero (ln 3476-3536, 4156-4211), selected by G48 H or by B positioning under G49 (ln 1682,
// 1700, 7018-7026), turned with B under G47 or not (G39); B an index table (B_AXIS=index, the default) or a
// full rotary axis: each of these per program, by its seed. G92 regrids the machine's absolute
// position (ln 1579): its word is the NGC twin's plus the fixture offset in force (ktapl.md call 90).
#include <cmath>

#include "cell/oracle/oracle.h"
#include "modules.h"

namespace cell::oracle {
namespace {

// The program's fixture form by its seed: B an index table or rotary; the line selected by H or by B.
bool IndexB(std::uint64_t seed) {
  return seed % 2 == 0;
}
bool Implicit(std::uint64_t seed) {
  return (seed / 2) % 2 == 1;
}
bool Calculated(std::uint64_t seed) {  // G47
  return (seed / 4) % 2 == 1;
}
bool Ufx(std::uint64_t seed) {  // the lines by UFX: offset = where the axes are (0) - the word
  return (seed / 8) % 2 == 1;
}

class Ktapl final : public Module {
 public:
  std::string Name() const override { return "ktapl"; }
  std::string Extension() const override { return "ktapl"; }
  Caps Capabilities(std::uint64_t seed) const override {
    Caps c;
    c.radius_form_g17_absolute = true;
    c.full_circle = true;
    // App. D's G82 (ln 11596) feeds to 0.01 in (0.254 mm) above the bottom, then at F.5 (F12.7) with S100
    // to it, dwells 2 s: not LinuxCNC's G82, stated as its moves.
    c.cycles = {81, 82, 83, 84, 85, 86, 87, 89};
    // G83 (App. D, ln 1947-1996) feeds on by E, dwelling between (LinuxCNC's G73 backs off 0.254 mm); G87
    // (ln 2099-2150) goes back to R after each E, feeds at 100 in/min (2540 mm/min) to 0.1 in (2.54 mm) above
    // the last bottom and E below it (LinuxCNC's G83 rapids to 0.254 mm above). G84 (ln 1998-2051) is
    // LinuxCNC's, its feed at most 32 in/min (812.8 mm/min).
    Caps::Peck g82, g83, g87;
    g82.code = 82;
    g82.feeding_on = true;
    g82.slow_end = 0.254, g82.slow_end_in = 0.01, g82.slow_feed = 12.7;
    g83.feeding_on = true;
    g87.code = 87;
    g87.discharging = true;
    g87.clearance = 2.54;
    g87.approach_feed = 2540;
    c.pecks = {g82, g83, g87};
    c.tap_max_feed = 812.8;
    c.per_rev = false;  // G93 inverse time and G94 only
    c.inverse_time = true;
    c.position_set = "G92";  // regrid (ln 1579)
    c.position_set_machine = true;
    c.implicit_offsets = Implicit(seed);  // G49: the line whose I is where B goes (ln 7018-7026)
    c.offsets = !c.implicit_offsets;      // G48 H (ln 6935)
    // G47 (ln 1678-1680, 6286-6308): the line's X/Z offset turns with B. Metric only: a turned offset is off
    // the inch grid, and rs274 prints it and the points in it to four inch decimals.
    c.calculated_offsets = Calculated(seed);
    c.inch = !c.calculated_offsets;
    c.index_b = IndexB(seed);  // index moves: whole degrees at F0, Z after B (ln 4491-4546)
    // B as a full rotary axis (B_AXIS=rotary) or index table, alone or with X Y Z in a G00/G01 block (ln
    // 5964-5983; not in an arc, ln 947). Alone F is whole deg/min (F3.0, ln 5976); with linear axes F is
    // theirs and B follows (ln 5983), LinuxCNC's rule. A G90 word is the position mod 360, its sign the sense
    // (ln 4481-4546). A and C (with B, F on B alone, ln 5978) are not generated.
    c.rotary = true;
    c.rotary_linear = true;
    c.rotary_axes = 2;
    c.rotary_wrap = true;
    c.rotary_whole_feed = true;
    return c;
  }
  // (DFS,NAME) ... (END) defines, (CLS,NAME) runs it once (ln 3262-3287, 3329-3379).
  std::optional<SubprogramForm> Subprogram() const override {
    return SubprogramForm{"(CLS,SUB1)", "(DFS,SUB1)\n", "(END)\n", true};
  }
  Program Write(const std::vector<Block>& blocks, std::uint64_t seed) const override;
};

std::string Coord(const Block& b, double v) {
  return Num(v, b.m.inch ? 4 : 3, true);
}

// G81-G89 (App. D, ln 1916-1922): the cycle block drills its own X Y, each later X Y block drills again,
// G80 ends it; E the peck of G83 and G87 (ln 5175).
std::string Cycle(const Block& b) {
  std::string s = "G" + std::to_string(b.cycle);
  for (std::size_t h = 0; h < b.holes.size(); ++h) {
    s += (h ? "\nX" : "X") + Coord(b, b.holes[h][0]) + "Y" + Coord(b, b.holes[h][1]);
    if (h == 0) {
      s += "Z" + Coord(b, b.bottom) + "R" + Coord(b, b.r_level);
      if (b.peck > 0) s += "E" + Coord(b, b.peck);  // inch 4.4, metric 5.3 (ln 1029-1047)
      s += "F" + Num(b.feed, 1, true);
    }
  }
  return s + "\nG80";
}

std::string Motion(const Block& b) {
  if (b.kind == MoveKind::kSet) {  // the machine's absolute position: the program's plus the fixture offset
    const Vec3& f = b.offset_mm;
    const double unit = b.m.inch ? 25.4 : 1.0;
    return "G92X" + Coord(b, b.end[0] + f[0] / unit) + "Y" + Coord(b, b.end[1] + f[1] / unit) + "Z" +
           Coord(b, b.end[2] + f[2] / unit);
  }
  if (b.kind == MoveKind::kCycle) return Cycle(b);
  static const std::array<std::array<int, 3>, 3> axes{{{0, 1, 2}, {2, 0, 1}, {1, 2, 0}}};
  const auto& ax = axes[static_cast<std::size_t>(b.m.plane - 17)];
  const char* letters = "XYZ";
  const char* centre = "IJK";
  std::string s = b.kind == MoveKind::kRapid  ? "G00"
                  : b.kind == MoveKind::kLine ? "G01"
                  : b.cw                      ? "G02"
                                              : "G03";
  for (int i = 0; i < 3; ++i) {
    bool moves = b.end[i] != b.start[i];
    if (b.kind == MoveKind::kArc && i == ax[2] && !moves) continue;
    if (OmitAxis(b, i)) continue;
    if (b.offset_by_b && !moves)
      continue;  // off the inch grid in the new line: KT-APL keeps an axis not named
    s += std::string(1, letters[i]) + Coord(b, b.m.incremental ? b.end[i] - b.start[i] : b.end[i]);
  }
  for (int i = 0; i < 3; ++i) {
    double travel = b.rot_end[i] - b.rot_start[i];
    if (travel == 0) continue;
    s += "ABC"[i];
    if (b.m.incremental) {
      s += Num(travel, 3, true);
    } else {  // the position in [0, 360), "-" turning the negative way (B-0. too)
      long to = ((std::lround(b.rot_end[i] * 1000) % 360000) + 360000) % 360000;
      s += (travel < 0 ? "-" : "") + Num(to / 1000.0, 3, true);
    }
  }
  if (b.kind == MoveKind::kArc) {
    if (b.radius_form) {
      s += "R" + Coord(b, b.radius);
    } else {
      for (int k = 0; k < 2; ++k)
        if (!OmitCentre(b, ax[k]))  // a missing centre word is the start's coordinate (judgement call 8)
          s += std::string(1, centre[ax[k]]) +
               Coord(b, b.center[ax[k]] - (b.m.incremental ? b.start[ax[k]] : 0));
    }
  }
  s += b.kind == MoveKind::kRapid ? "F0" : "F" + Num(b.feed, 1, true);
  return s;
}

Program Ktapl::Write(const std::vector<Block>& blocks, std::uint64_t seed) const {
  Program p;
  p.params = IndexB(seed) ? "B_AXIS=index\n" : "B_AXIS=rotary\n";
  p.dialect_text = "%\n! generated by cell-oracle-gen (tests/oracle)\nG71G90G94G17S1000M03\n";
  for (int k = 1; k < kOffsets; ++k) {  // the work offsets as fixture lines, mm (G71)
    const Vec3& o = kOffsetTable[static_cast<std::size_t>(k)];
    const double sign = Ufx(seed) ? -1 : 1;  // UFX at the machine zero, before any move
    p.dialect_text += (Ufx(seed) ? "(UFX,H" : "(FXC,H") + std::to_string(k) + "X" +
                      Num(sign * o[0], 3, true) + "Y" + Num(sign * o[1], 3, true) + "Z" +
                      Num(sign * o[2], 3, true) + "I" + Num(kOffsetB[static_cast<std::size_t>(k)], 3, true) +
                      ")\n";
  }
  p.dialect_text += Implicit(seed) ? "G49\n" : "G48\n";
  if (Calculated(seed)) p.dialect_text += "G47\n";
  Modes m;
  for (const Block& b : blocks) {
    std::string pre;
    // G48: the line by H on its own block; G49: the block's B positioning selects it.
    if (b.m.offset != m.offset && !b.offset_by_b) pre += "H" + std::to_string(b.m.offset);
    if (b.m.inch != m.inch) pre += b.m.inch ? "G70" : "G71";
    if (b.m.inverse != m.inverse) pre += b.m.inverse ? "G93" : "G94";
    if (b.m.incremental != m.incremental) pre += b.m.incremental ? "G91" : "G90";
    if (b.m.plane != m.plane) pre += "G" + std::to_string(b.m.plane);
    if (!pre.empty()) pre += "\n";
    p.inch_anywhere = p.inch_anywhere || b.m.inch;
    m = b.m;
    std::string line = Motion(b);
    p.blocks_dialect.push_back(pre + line);
    p.dialect_text += pre + line + "\n";
  }
  p.dialect_text += "M30\n";
  return p;
}

}  // namespace

const Module& KtaplModule() {
  static const Ktapl m;
  return m;
}

}  // namespace cell::oracle
