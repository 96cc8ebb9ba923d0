// Okuma OSP-E100L lathes (docs/dialects/okuma.md): the unit system of the program (UNIT_SYSTEM, ln 1033-1093:
// 1 mm, 10 um, 1 um, inch, 1/10000 inch; in the counting systems a word counts units, F too), G90/G91 with X
// a diameter either way, G02/G03 with I (a radius) and K from the start in G90 and G91 (ln 1232-1240) or the
// radius L with CALRG beyond 180 degrees (ln 1263-1289), G94/G95.
#include <cmath>

#include "cell/oracle/oracle.h"
#include "modules.h"

namespace cell::oracle {
namespace {

struct UnitSystem {
  const char* name;
  bool inch;
  int decimals;    // the grid of a position
  double count;    // units per mm (inch) a word counts; 0: a decimal number
  double per_min;  // F in G94: units per mm/min (inch/min), the table's own row (ln 1048-1059)
};

const std::array<UnitSystem, 5> kSystems{{{"1MM", false, 3, 0, 1},
                                          {"10UM", false, 2, 100, 1},
                                          {"1UM", false, 3, 1000, 10},
                                          {"INCH", true, 4, 0, 1},
                                          {"0.0001INCH", true, 4, 10000, 100}}};

const UnitSystem& SystemOf(std::uint64_t seed) {
  return kSystems[seed % kSystems.size()];
}

class Okuma final : public Module {
 public:
  std::string Name() const override { return "okuma"; }
  std::string Extension() const override { return "okuma"; }
  Caps Capabilities(std::uint64_t seed) const override {
    const UnitSystem& u = SystemOf(seed);
    Caps c;
    c.lathe = true;
    c.planes = {18};
    c.helix = false;
    c.offsets = false;  // the zero offset is one per run (ZERO_OFFSET_X/Z): not generated yet
    c.inch = u.inch;
    c.inch_only = u.inch;
    c.unit_switch = false;
    c.position_set = "G50";  // G50 X Z: zero shift by the present position (ln 1663-1705)
    c.mm_decimals = u.decimals;
    c.inch_decimals = u.decimals;
    // G74 on the centre line (ln 3954-4004, E-48): from the start, pecks of D each followed by a rapid back
    // DA= (0.5 mm by default, PECK_RETRACT), to Z, back to the start: LinuxCNC's G73 with Q = D where DA= is
    // its 0.254 mm (0.010 in; not on the 10 um grid), else its moves. No I K L (shift, approach, full
    // retract).
    c.cycles = c.cycles_per_rev = {74};
    Caps::Peck g74;
    g74.code = 74;
    g74.feeding_on = g74.backoff_word = true;
    g74.native = 73;
    c.pecks = {g74};
    return c;
  }
  // CALL O name runs a subprogram of the same file up to its RTS (ln 7962-8229).
  std::optional<SubprogramForm> Subprogram() const override {
    return SubprogramForm{"CALL O1001", "O1001\n", "RTS\n", false};
  }
  Program Write(const std::vector<Block>& blocks, std::uint64_t seed) const override {
    return WriteIn(blocks, SystemOf(seed));
  }
  std::vector<std::string> Forms() const override {
    std::vector<std::string> names;
    for (const auto& u : kSystems) names.push_back(u.name);
    return names;
  }
  Program WriteForm(const std::vector<Block>& blocks, std::uint64_t seed,
                    const std::string& form) const override {
    for (const auto& u : kSystems)
      if (form == u.name) return WriteIn(blocks, u);
    return Write(blocks, seed);
  }

 private:
  static Program WriteIn(const std::vector<Block>& blocks, const UnitSystem& u);
};

std::string Word(const UnitSystem& u, double v) {
  if (u.count > 0) return Num(std::round(v * u.count), 0);
  return Num(v, u.decimals);
}

// Per revolution F counts the length unit; per minute the table's feed row (1 um: 0.1 mm/min, 1/10000 inch:
// 0.01 inch/min).
std::string Feed(const UnitSystem& u, const Block& b) {
  if (b.m.per_rev) return Num(u.count > 0 ? b.feed * u.count : b.feed, 6);
  return Num(b.feed * u.per_min, 6);
}

std::string Motion(const UnitSystem& u, const Block& b) {
  if (b.kind == MoveKind::kSet) return "G50 X" + Word(u, 2 * b.end[0]) + " Z" + Word(u, b.end[2]);
  if (b.kind == MoveKind::kCycle)  // from X0 at the present Z
    return "G00 X0\nG74 X0 Z" + Word(u, b.bottom) + " D" + Word(u, b.peck) + " DA=" + Word(u, b.backoff) +
           " F" + Feed(u, b);
  std::string s = b.kind == MoveKind::kRapid  ? "G00"
                  : b.kind == MoveKind::kLine ? "G01"
                  : b.cw                      ? "G02"
                                              : "G03";
  if (b.kind == MoveKind::kArc && b.radius_form && b.radius < 0) s += " CALRG";
  double x = 2 * (b.m.incremental ? b.end[0] - b.start[0] : b.end[0]);
  double z = b.m.incremental ? b.end[2] - b.start[2] : b.end[2];
  // A line may leave out an axis that stays; an arc keeps both (one quadrant only without, ln 1296).
  bool line = b.kind != MoveKind::kArc;
  if (!(line && OmitAxis(b, 0))) s += " X" + Word(u, x);
  if (!(line && OmitAxis(b, 2))) s += " Z" + Word(u, z);
  if (b.kind == MoveKind::kArc) {
    if (b.radius_form)
      s += " L" + Word(u, std::fabs(b.radius));
    else
      for (int a : {0, 2})  // I or K left out is 0 (ln 1293)
        if (!OmitCentre(b, a)) s += (a == 0 ? " I" : " K") + Word(u, b.center[a] - b.start[a]);
  }
  if (b.kind != MoveKind::kRapid) s += " F" + Feed(u, b);
  return s;
}

Program Okuma::WriteIn(const std::vector<Block>& blocks, const UnitSystem& u) {
  Program p;
  p.params = std::string("UNIT_SYSTEM=") + u.name + "\n";
  p.inch_anywhere = u.inch;
  p.dialect_text = std::string("(generated by cell-oracle-gen, tests/oracle; UNIT_SYSTEM=") + u.name +
                   ")\nG94 S1000 M03\n";
  Modes m;
  m.inch = u.inch;
  m.plane = 18;
  for (const Block& b : blocks) {
    std::string pre;
    if (b.m.incremental != m.incremental) pre += b.m.incremental ? "G91 " : "G90 ";
    if (b.m.per_rev != m.per_rev) pre += b.m.per_rev ? "G95 " : "G94 ";
    m = b.m;
    std::string line = pre + Motion(u, b);
    p.blocks_dialect.push_back(line);
    p.dialect_text += line + "\n";
  }
  p.dialect_text += "M02\n";
  return p;
}

}  // namespace

const Module& OkumaModule() {
  static const Okuma m;
  return m;
}

}  // namespace cell::oracle
