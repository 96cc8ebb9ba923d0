// Okuma NC blocks (manual SECTIONS 3-6, seed ln 1625-2175, 9246-9880): G codes and their modal groups, the
// T word (nose-R number, turret station, offset number), S with G96/G97/G50, M codes, F and E, and the order
// in which a block acts: T and S first, spindle and other M codes before the axes (ln 1854, 1918, 9114),
// then the motion or cycle, then M00/M01/M02/M30, then the MODIN subprograms.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "interp_internal.h"

namespace cell::interp::okuma {
namespace {

constexpr Addr kExt[13] = {MakeAddr('S', 'A'), MakeAddr('S', 'B'), MakeAddr('Q', 'A'), MakeAddr('D', 'A'),
                           MakeAddr('D', 'B'), MakeAddr('F', 'A'), MakeAddr('F', 'B'), MakeAddr('X', 'A'),
                           MakeAddr('X', 'B'), MakeAddr('Z', 'A'), MakeAddr('Z', 'B'), MakeAddr('P', 'Z'),
                           MakeAddr('P', 'W')};

bool IsLengthAddress(char a) {
  return a == 'X' || a == 'Z' || a == 'I' || a == 'K' || a == 'D' || a == 'H' || a == 'L' || a == 'U' ||
         a == 'W' || a == 'R' || a == 'Y';
}
bool IsAngleAddress(char a) {
  return a == 'A' || a == 'B' || a == 'C';
}

// What the G codes the cell does not run are, for the alarm text (appendix ln 9246-9482).
const char* UnsupportedG(int g) {
  switch (g) {
    case 17:
    case 19:
    case 119:
      return "cutter radius compensation plane for C-axis contour milling";
    case 20:
    case 21:
      return "home position return";
    case 22:
      return "torque skip";
    case 30:
      return "skip cycle";
    case 36:
    case 37:
      return "M-tool synchronized feed";
    case 62:
      return "mirror image designation";
    case 100:
      return "turret priority designation";
    case 107:
    case 108:
      return "spindle-synchronized tapping";
    case 112:
    case 113:
      return "circular thread cutting: an option whose format the manual does not give (ln 5603, 9374-9375), "
             "and the servo's thread is a straight move";
    case 122:
    case 123:
      return "W-axis command for the sub spindle";
    case 138:
      return "Y-axis mode: the appendix names it at ln 9400 without a format, and OK01 has no Y axis";
    case 140:
    case 141:
    case 142:
    case 143:
      return "machining mode selection";
    case 152:
      return "programmable tailstock positioning";
    default:
      if (g >= 161 && g <= 171) return "G code macro";
      if (g >= 205 && g <= 214) return "G code macro";
      if (g == 191) return "longitudinal key-way cutting cycle: listed in the appendix only, no format";
      return nullptr;
  }
}

bool KnownG(int g) {
  static constexpr int kKnown[] = {0,   1,   2,   3,   4,   13,  14,  18,  28,  29,  31,  32,  33,  34,
                                   35,  40,  41,  42,  50,  64,  65,  71,  72,  73,  74,  75,  76,  77,
                                   78,  80,  81,  82,  83,  84,  85,  86,  87,  88,  90,  91,  94,  95,
                                   96,  97,  101, 102, 103, 110, 111, 132, 133, 136, 137, 178, 179, 180,
                                   181, 182, 183, 184, 185, 186, 187, 188, 189, 190};
  return std::find(std::begin(kKnown), std::end(kKnown), g) != std::end(kKnown);
}

bool IsMotionG(int g) {
  return g == 0 || g == 1 || g == 2 || g == 3 || (g >= 31 && g <= 35) || (g >= 101 && g <= 103) || g == 132 ||
         g == 133;
}

}  // namespace

int ExtIndex(Addr a) {
  for (int i = 0; i < 13; ++i) {
    if (kExt[i] == a) return i;
  }
  return -1;
}

bool BlockWords::HasM(int code) const {
  return std::any_of(m.begin(), m.end(), [code](const Code& c) { return c.code == code; });
}

double OkRun::ScaleLength(double v) const {
  switch (units_) {
    case UnitSystem::k10um:
      return v * 0.01;
    case UnitSystem::k1um:
      return v * 0.001;
    case UnitSystem::kInch:
      return v * 25.4;
    case UnitSystem::k10000thInch:
      return v * 0.00254;
    default:
      return v;
  }
}

// F and E (ln 1048-1059): feed per revolution like a length, feed per minute and time by their own rows.
double OkRun::Scale(char addr, double v, bool feed_per_rev) const {
  if (addr == 'T') {  // time (G04 F, dwell E)
    switch (units_) {
      case UnitSystem::k10um:
        return v * 0.1;
      case UnitSystem::k1um:
      case UnitSystem::k10000thInch:
        return v * 0.01;
      default:
        return v;
    }
  }
  if (feed_per_rev) return ScaleLength(v);
  switch (units_) {
    case UnitSystem::k1um:
      return v * 0.1;
    case UnitSystem::kInch:
      return v * 25.4;
    case UnitSystem::k10000thInch:
      return v * 0.254;
    default:
      return v;
  }
}

void OkRun::CollectWords(const Block& b, BlockWords& w) {
  const double angle_unit = units_ == UnitSystem::k1um || units_ == UnitSystem::k10000thInch ? 0.001
                            : units_ == UnitSystem::k10um                                    ? 0.01
                                                                                             : 1.0;
  for (const Item& it : b.items) {
    if (it.assign) {
      Assignment(b.assigns[it.i], b, false);
      continue;
    }
    const Word& wd = b.words[it.i];
    double v = wd.expr ? Evaluate(b.pool, wd.node, *this).v : wd.num;
    const char a = static_cast<char>(wd.addr & 0xff);
    if (wd.addr >> 8) {
      int i = ExtIndex(wd.addr);
      if (w.HasExt(i)) Fail(wd.col, fmt::format("address {} given twice in one block", AddrName(wd.addr)));
      const char a2 = static_cast<char>(wd.addr >> 8);
      const bool length = (a == 'D' || a == 'X' || a == 'Z') && (a2 == 'A' || a2 == 'B');
      w.ext[static_cast<size_t>(i)] = length ? ScaleLength(v) : v;
      w.ext_col[static_cast<size_t>(i)] = wd.col;
      w.ext_has = static_cast<uint16_t>(w.ext_has | (1u << i));
      continue;
    }
    if (a == 'G' || a == 'M') {
      const int hi = a == 'G' ? 999 : 511;
      // A literal written without a point is a whole number already (no floor call for most codes).
      const bool whole = (!wd.expr && !wd.point) || v == std::floor(v);
      if (!whole || v < 0 || v > hi) Fail(wd.col, fmt::format("{}{}: not a {} code", a, v, a));
      auto& list = a == 'G' ? w.g : w.m;
      if (a == 'M' && w.m.size() >= 8) Fail(wd.col, "more than 8 M codes in one block");
      list.push_back({static_cast<int>(v), wd.col});
      if (a == 'G' && !IsMotionG(static_cast<int>(v))) w.other_g = true;
      continue;
    }
    if (w.Has(a)) Fail(wd.col, fmt::format("address {} given twice in one block", a));
    if (IsLengthAddress(a)) v = ScaleLength(v);
    if (IsAngleAddress(a)) v *= angle_unit;
    const size_t k = static_cast<size_t>(a - 'A');
    w.v[k] = v;
    w.col[k] = wd.col;
    w.has |= 1u << k;
    if (a == 'T') w.t_digits = wd.digits;
  }
}

// The block's G codes: modal groups, one-shots, and the codes the cell does not run.
void OkRun::ReadNcGCodes(const BlockWords& w, NcGCodes& k) {
  for (const auto& g : w.g) {
    if (g.code == 312 || g.code == 313) {
      // The side contour generation programming mode (parameter No. 56 bit 4 with G119, ln 6785-6801) is not
      // the cell's: G312/G313 outside it are the manual's alarm.
      Fail(g.col,
           fmt::format("Alarm B UNUSABLE contour generation command: G{} outside the side contour generation "
                       "programming mode (ln 6799-6801)",
                       g.code),
           "2224");
    }
    // Motion codes (all known) first: most blocks' only G code needs no search of the known codes.
    if (IsMotionG(g.code)) {
      if (k.motion_g >= 0 && k.motion_g != g.code) Fail(g.col, "two motion G codes in one block");
      k.motion_g = g.code;
      k.motion_col = g.col;
      continue;
    }
    if (!KnownG(g.code)) {
      if (const char* what = UnsupportedG(g.code)) {
        Fail(g.col, fmt::format("G{} ({}) is not supported by the cell's OSP-E100L dialect", g.code, what));
      }
      Fail(g.col, fmt::format("G{} is not an OSP-E100L G code", g.code));
    }
    switch (g.code) {
      case 4:
        k.dwell = true;
        break;
      case 13:
        k.g13 = true;
        break;
      case 14:
        k.g14 = true;
        break;
      case 18:
      case 28:
        break;  // the turning plane; torque limit cancel: the cell's only states (G17/G19/G119, G29 refused)
      case 136:
        k.g136 = true;
        break;
      case 137:
        k.g137 = true;
        break;
      case 40:
      case 41:
      case 42:
        if (k.comp_g && k.comp_g != g.code) Fail(g.col, "two of G40/G41/G42 in one block");
        k.comp_g = g.code;
        break;
      case 50:
        k.g50 = true;
        break;
      case 64:
      case 65:
        modal_.droop = g.code == 65;
        break;
      case 71:
      case 72:
      case 73:
      case 74:
      case 77:
      case 78:
        if (k.cycle) Fail(g.col, "two cycle G codes in one block");
        k.cycle = g.code;
        k.cycle_col = g.col;
        break;
      case 75:
      case 76:
        k.chamfer = g.code;
        break;
      case 80:
        k.g80 = true;
        break;
      case 84:
        break;  // change of rough turning conditions: read by G85
      case 85:
      case 86:
      case 87:
      case 88:
        k.lap = g.code;
        k.cycle_col = g.col;
        break;
      case 90:
        k.g90 = true;
        break;
      case 91:
        k.g91 = true;
        break;
      case 94:
      case 95:
        if (lap_.active || lap_.finish) Fail(g.col, "G94/G95 cannot change inside a LAP contour");
        modal_.per_rev = g.code == 95;
        break;
      case 96:
      case 97:
        if (lap_.active || lap_.finish) Fail(g.col, "G96/G97 cannot change inside a LAP contour");
        if (!w.Has('S')) Fail(g.col, fmt::format("a G{} block must contain S", g.code));
        break;
      case 110:
        break;  // constant surface speed on turret A: the cell's only state (G111 refused)
      case 180:
        k.g180 = true;
        break;
      case 178:
      case 179:
      case 181:
      case 182:
      case 183:
      case 184:
      case 185:
      case 186:
      case 187:
      case 188:
      case 189:
      case 190:
        if (k.cycle) Fail(g.col, "two cycle G codes in one block");
        // G184 calls the synchronized tapping cycle G178 when the "G184 tapping mode" parameter is 1
        // (ln 4539, judgement 66).
        k.cycle = g.code == 184 && g184_sync_ ? 178 : g.code;
        k.cycle_col = g.col;
        k.mtool_fresh = true;
        break;
      default:
        break;
    }
  }
}

// The block's motion G code, checked against a LAP contour being defined.
void OkRun::MotionGCode(int motion_g, int motion_col) {
  if (motion_g == 0 && (lap_.active || lap_.finish) && lap_.first_block_seen && !lap_.blank) {
    Fail(motion_col, "G00 is allowed only in the first block of a LAP contour");
  }
  if (lap_.active && lap_.blank &&
      (motion_g == 0 || (!lap_.first_block_seen && (motion_g == 2 || motion_g == 3)))) {
    Fail(motion_col, motion_g == 0 ? "G00 cannot define a blank shape (G83)"
                                   : "the first block of a blank shape (G83) cannot be G02/G03");
  }
  modal_.motion = motion_g;
  if (!(motion_g >= 31 && motion_g <= 35)) chain_.active = false;
  if (motion_g < 101 || motion_g > 103) contour_mode_ = false;
}

// What the block does after its codes: a dwell, a zero shift, a cycle, or its move.
void OkRun::NcAction(const BlockWords& w, const Block& b, const NcGCodes& k, bool xz) {
  if (k.dwell) {
    Dwell(w, w.FindG(4)->col);
  } else if (k.g50) {
    ZeroShift(w, w.FindG(50)->col);
  } else if (k.lap) {
    LapCall(w, b, k.lap, k.cycle_col);
  } else if (k.cycle == 71 || k.cycle == 72) {
    CompoundThread(w, k.cycle, k.cycle_col);
  } else if (k.cycle == 73 || k.cycle == 74) {
    Grooving(w, k.cycle, k.cycle_col);
  } else if (k.cycle == 77 || k.cycle == 78) {
    Tapping(w, k.cycle, k.cycle_col);
  } else if (IsMToolCycle(k.cycle)) {
    MToolBlock(w, k.cycle, k.mtool_fresh, k.cycle_col);
  } else {
    if (k.chamfer && modal_.motion != 1) {
      Fail(w.FindG(k.chamfer)->col, fmt::format("G{} is effective only in G01 mode", k.chamfer));
    }
    Motion(w, b, k.motion_col);
    if ((lap_.active || lap_.finish) && xz) lap_.first_block_seen = true;
  }
}

void OkRun::ExecNc(const Block& b) {
  BlockWords& w = words_;
  w.Clear();
  CollectWords(b, w);
  const bool xz = w.Has('X') || w.Has('Z');
  const bool contour_start = w.HasG(81) || w.HasG(82) || w.HasG(83);
  if (contour_start && !b.seq.empty()) {
    if (lap_.active || lap_.finish) {
      LapBlock(b, w);
    } else {
      SkipContourDefinition(b);
    }
    return;
  }
  if (contour_start)
    Fail(w.FindG(81) ? w.FindG(81)->col : 1, "G81/G82/G83 must carry the contour's sequence name");
  if (w.has == 0 && w.ext_has == 0 && w.g.empty() && w.m.empty() && b.label.empty() && !b.calrg) {
    EndBlockStages(false);
    return;
  }

  NcGCodes k;
  if (!w.g.empty()) ReadNcGCodes(w, k);
  // P, G29/G111 (G codes other than motion codes), PZ=/PW=, M codes: what RefuseUnsupported looks at.
  if (w.Has('P') || w.other_g || w.ext_has != 0 || !w.m.empty()) RefuseUnsupported(w);
  if (k.g90 && k.g91) Fail(w.FindG(91)->col, "G90 and G91 in one block");
  if (k.g90) modal_.incremental = false;
  if (k.g91) modal_.incremental = true;
  if ((k.g137 || conv_.on) && CoordConversion(w, k)) {  // G137 and its mode (G136 ends it)
    EndBlockStages(false);
    return;
  }
  // The M-tool cycle mode's side: nothing to do without G180, a cycle code or mode, or an M code (most
  // blocks).
  const bool mtool = k.g180 || k.cycle != 0 || mc_.g != 0 || mc_.after_cancel || !w.m.empty();
  if (mtool && MToolMode(w, k)) {
    EndBlockStages(false);
    return;
  }
  if (k.g13 || k.g14) {
    // Turret selection (ln 7156-7361): alone in its block; refused during G41/G42, G91, LAP and G96.
    const bool b_turret = k.g14;
    if (b_turret != modal_.turret_b) {
      const int col = w.FindG(k.g14 ? 14 : 13)->col;
      if (modal_.comp != 40 || modal_.incremental || lap_.active || lap_.finish || modal_.css) {
        Fail(col, "ALARM-B change timing G13/G14 (turret selection during G41/G42, G91, LAP or G96)");
      }
      modal_.turret_b = b_turret;
    }
    EndBlockStages(false);
    return;
  }
  RefuseUnusedAddresses(w, k);
  if (!b.label.empty() && !k.lap) Fail(b.label_col, "a sequence name argument is taken only by G85-G88");
  if (k.lap && b.label.empty())
    Fail(k.cycle_col, fmt::format("G{} needs the contour's sequence name", k.lap));
  if (k.motion_g >= 0) MotionGCode(k.motion_g, k.motion_col);
  if (k.cycle && modal_.comp != 40 && (k.cycle == 71 || k.cycle == 72)) {
    Fail(k.cycle_col, "thread cycles are not allowed in nose radius compensation mode");
  }

  // T, then S and the M codes that act before the axes.
  // T: in G73/G74 the offset number of the last groove (read by the cycle), else the turret and offsets.
  if (w.Has('T') && k.cycle != 73 && k.cycle != 74) ToolWord(w);
  // S, SB=, M codes, G96/G97 (G codes other than motion codes): most blocks have none.
  if (w.Has('S') || w.ext_has != 0 || !w.m.empty() || w.other_g) SpindleAndM(w, true);
  if (w.Has('F') && !k.dwell) {
    double f = Scale('F', w.Get('F'), modal_.per_rev);
    if (f < 0) Fail(w.Col('F'), "F must not be negative");
    f_ = f;
  }
  const bool thread_block =
      k.cycle == 71 || k.cycle == 72 || (modal_.motion >= 31 && modal_.motion <= 35 && xz);
  if (w.Has('E') && !thread_block && !k.dwell && k.cycle == 0) {
    e_ = Scale('F', w.Get('E'), modal_.per_rev);
  }

  // Nose radius compensation codes act on this block's move.
  if (w.other_g) CompCodes(w, k.motion_col, xz);  // G40-G42

  NcAction(w, b, k, xz);
  if (k.g80) {
    if (!lap_.active && !lap_.finish) Fail(w.FindG(80)->col, "G80 without a LAP contour definition");
    EndBlockStages(xz);
    LapEndCapture(w.FindG(80)->col);
    StopAndEnd(w);
    return;
  }
  const bool motion_block = xz && IsMotionG(modal_.motion) && !k.dwell && !k.g50 && !k.lap && k.cycle == 0;
  EndBlockStages(xz);
  if (!w.m.empty()) StopAndEnd(w);  // M00/M01/M02/M30
  if (!ended_ && motion_block && !modins_.empty()) TriggerModin();
}

// The M-tool cycle mode's side of a block (ln 4073-4130, 4521-4528): G180 alone ends it (true: the block is
// done), the block after G180 needs X and Z, and a block without a G code of its own runs the cycle in force.
bool OkRun::MToolMode(const BlockWords& w, NcGCodes& k) {
  if (k.g180) {
    const int col = w.FindG(180)->col;
    if (w.has != 0 || w.ext_has != 0 || !w.m.empty() || w.g.size() > 1) {
      Fail(col, "G180 must be alone in its block");
    }
    MToolCancel(col);
    return true;
  }
  // The column refusals point at; found only when needed (two scans of the 26 letters, for every block).
  auto block_col = [&w] {
    int col = !w.g.empty() ? w.g.front().col : (!w.m.empty() ? w.m.front().col : 0);
    for (int i = 0; i < 26 && col == 0; ++i) {  // no G or M: the block's first word
      if ((w.has >> i) & 1u) col = w.col[static_cast<size_t>(i)];
    }
    for (int i = 0; i < 26 && w.g.empty() && w.m.empty(); ++i) {
      if ((w.has >> i) & 1u) col = std::min(col, w.col[static_cast<size_t>(i)]);
    }
    return col == 0 ? 1 : col;
  };
  if (mc_.after_cancel) {
    const int col = block_col();
    if (!w.Has('X') || !w.Has('Z')) {
      Fail(col, "the block after G180 must contain both X and Z");
    }
    mc_.after_cancel = false;
  }
  if (k.cycle == 0 && mc_.g != 0) {
    const int col = block_col();
    if (k.motion_g >= 0 || k.lap || k.dwell || k.g50) {
      Fail(col, "cancel the M-tool compound fixed cycle with G180 first");
    }
    k.cycle = mc_.g;
    k.cycle_col = col;
  }
  if (IsMToolCycle(k.cycle)) MToolChecks(w, k.cycle, k.mtool_fresh, k.cycle_col);
  if (!k.mtool_fresh) {
    for (const auto& m : w.m) {
      if (m.code == 136 || m.code == 141 || (m.code >= 211 && m.code <= 214)) {
        Fail(m.col,
             fmt::format("M{} acts only in the block of an M-tool compound fixed cycle (G178-G190)", m.code));
      }
    }
  }
  return false;
}

namespace {

// The mask of single-letter addresses (bit 0: A) of `letters`, made at compile time: the address check runs
// for every block.
consteval uint32_t LetterBits(std::string_view letters) {
  uint32_t m = 0;
  for (char c : letters) m |= 1u << (c - 'A');
  return m;
}

}  // namespace

// The single-letter addresses the block's function reads (each function's programming format: ln 1147-1300,
// 1642-1707, 3239-3414, 3640-4071, 5124-5252, 2235-2447 for I/K with G40-G42); F, S and T belong to any
// block. `what` names the function for the alarm.
uint32_t OkRun::UsedAddresses(const NcGCodes& k, int* g) const {
  const uint32_t any =
      LetterBits("FST") | ((lap_.active || lap_.finish) ? LetterBits("E") : 0);  // E: a contour's feed
  auto named = [&](int code, uint32_t letters) {
    *g = code;  // the text is made only for a refusal: this runs for every block
    return any | letters;
  };
  if (k.dwell) return named(4, LetterBits(""));
  if (k.g50) return named(50, LetterBits("XZC"));
  if (k.lap) return named(k.lap, k.lap == 88 ? LetterBits("DUWEHB") : LetterBits("DUWE"));
  switch (k.cycle) {
    case 71:
      return named(71, LetterBits("XZAIBDUHLEJQ"));
    case 72:
      return named(72, LetterBits("XZAKBDWHLEJQ"));
    case 73:
    case 74:
      return named(k.cycle, LetterBits("XZIKDLE"));
    case 77:
    case 78:
      return named(k.cycle, LetterBits("XZK"));
    case 178:
    case 179:
      return named(k.cycle, LetterBits("XZCRIKQDJ"));
    case 183:
      return named(183, LetterBits("XZCRIKQDEL"));
    case 185:
    case 186:
    case 187:
    case 188:
      return named(k.cycle, LetterBits("XZCIK"));
    case 190:
      return named(190, LetterBits("XZCIKQDUWE"));
    default:
      if (k.cycle >= 181 && k.cycle <= 189) return named(k.cycle, LetterBits("XZCRIKQE"));
      break;
  }
  const int motion = k.motion_g >= 0 ? k.motion_g : modal_.motion;
  uint32_t used = named(motion, LetterBits("XZY"));  // Y: Motion names the missing axis itself
  if (k.comp_g) used |= LetterBits("IK");            // the entry or exit vector of G40/G41/G42
  switch (motion) {
    case 0:
    case 1:
      used |= LetterBits("CA") | (k.chamfer ? LetterBits("L") : 0);
      break;
    case 2:
    case 3:
      used |= LetterBits("IKL");
      break;
    case 31:
    case 32:
    case 33:
      used |= LetterBits("CIKAELJ");
      break;
    case 101:
      used |= LetterBits("C");
      break;
    case 102:
    case 103:
    case 132:
    case 133:
      used |= LetterBits("CL");
      break;
    case -1:
      break;
    default:  // G34/G35
      used |= LetterBits("CAEJ");
      break;
  }
  return used;
}

// A word the block's function does not read (a stray Q5 on a G01 block, K on a G00) is refused, not ignored
// (judgement 51); the manual prints no alarm number for it.
void OkRun::RefuseUnusedAddresses(const BlockWords& w, const NcGCodes& k) const {
  // Every block but G04 and G85-G88 reads X, Z, F, S and T (UsedAddresses): a block of only those (most
  // blocks) has nothing to refuse.
  if (!k.dwell && !k.lap && w.ext_has == 0 && (w.has & ~LetterBits("XZFST")) == 0) return;
  int g = 0;
  const uint32_t unused = w.has & ~UsedAddresses(k, &g);
  if (unused == 0 && w.ext_has == 0) return;  // nearly every block: nothing to refuse
  // Extended addresses: QA= with a C word (ln 2075), DA= in G73/G74 (ln 3933), the G84 change points of a
  // G85/G86 call (ln 5145-5173), SA= in G185-G188, SB= anywhere; PZ=, PW= are refused before.
  uint32_t ext_used = 0;
  if (k.lap == 85 || k.lap == 86) ext_used |= 0xFFu << 3;  // DA DB FA FB XA XB ZA ZB
  if (k.cycle == 73 || k.cycle == 74) ext_used |= 1u << 3;
  if (w.Has('C')) ext_used |= 1u << 2;
  ext_used |= 1u << 1;                                   // SB=, like S, in any block (ln 1863-1871)
  if (k.cycle >= 185 && k.cycle <= 188) ext_used |= 1u;  // SA=, the C speed of G185-G188 (ln 4234)
  for (int i = 0; i < 13; ++i) {
    if (!w.HasExt(i) || ((ext_used >> i) & 1u)) continue;
    const int col = w.ext_col[static_cast<size_t>(i)];
    if (i == 2) Fail(col, "QA= (C-axis revolutions, ln 2075) needs a C word in its block");
    Fail(col, fmt::format("address {}= is not used by a G{:02} block", AddrName(kExt[i]), g));
  }
  if (unused == 0) return;
  // No motion code in force: only after G137 (coordinate conversion cancels the mode, judgement 58).
  std::string what = g < 0 ? std::string("a block after G137") : fmt::format("a G{:02} block", g);
  char a = 'A';
  while (!((unused >> (a - 'A')) & 1u)) ++a;
  if (k.chamfer == 0 && a == 'L' && (modal_.motion == 0 || modal_.motion == 1) && k.cycle == 0 && !k.lap) {
    what += " without G75/G76";
  }
  Fail(w.Col(a), fmt::format("address {} is not used by {}", a, what));
}

// Torque limits (G29 with PZ=/PW=, ln 1504-1531) have no torque model in the servo; G111 (constant surface
// speed on turret B, ln 1827, 7075) belongs to the two-saddle model (judgement 45). G28 (torque limit cancel)
// and G110 are the cell's only states and run.
void OkRun::RefuseTorqueAndTurretB(const BlockWords& w) {
  if (const auto* g29 = w.FindG(29)) {
    Fail(g29->col,
         "G29 (torque limit, ln 1504-1519) is not supported by the cell's OSP-E100L dialect: no torque "
         "model");
  }
  if (const auto* g111 = w.FindG(111)) {
    Fail(g111->col,
         "G111 (constant surface speed on turret B of the two-saddle model, ln 1827, 7075) is not supported: "
         "one "
         "saddle");
  }
  for (const char* name : {"PZ", "PW"}) {
    if (w.ext_has == 0) break;  // no extended address in the block (nearly every block)
    const int i = ExtIndex(MakeAddr(name[0], name[1]));
    if (w.HasExt(i)) {
      Fail(w.ext_col[static_cast<size_t>(i)],
           fmt::format(
               "{}= (torque, ln 1504-1519, 1594-1614) is not supported by the cell's OSP-E100L dialect: "
               "no torque model",
               name));
    }
  }
}

// M codes that switch a function of the control the cell does not have (judgement 49): their OFF/cancel
// partner is the cell's only state and goes out as `aux`.
const char* OkRun::RefusedControlM(int m) {
  switch (m) {
    case 29:
      return "tool interference check ON, ln 9520";
    case 124:
      return "STM time-over check ON, ln 1985-1986, 2142-2175";
    case 165:
      return "slide hold and single block ignored, ln 2006-2007";
    case 194:
      return "thread phase matching ON, ln 2025-2026";
    case 196:
      return "store of the manual phase-matching move, ln 2027-2029";
    case 197:
      return "clear of the phase-matching amount, ln 2030-2031";
    case 203:
      return "turret unclamp during G00, ln 9144-9167";
    default:
      if ((m >= 321 && m <= 325) || (m >= 341 && m <= 360)) {
        return "M code macro: CALL of a fixed subprogram, ln 9836-9878, whose format the manual does not "
               "give";
      }
      return nullptr;
  }
}

// Codes and words the manual defines that the cell cannot do, refused before the block does anything.
void OkRun::RefuseUnsupported(const BlockWords& w) {
  // P is the 2S synchronisation code (ln 6960-6990): the cell runs one program on one saddle (judgement 45).
  if (w.Has('P')) {
    Fail(w.Col('P'),
         "P (two-turret synchronisation, ln 6960-6990) is not supported: one program, one saddle");
  }
  if (w.other_g || w.ext_has != 0) RefuseTorqueAndTurretB(w);  // G29, G111, PZ=, PW=
  for (const auto& m : w.m) {
    if (const char* what = RefusedControlM(m.code)) {
      Fail(m.col, fmt::format("M{} ({}) is not supported by the cell's OSP-E100L dialect", m.code, what));
    }
    switch (m.code) {
      case 140:
        // Ignoring the live tool's speed answer in tapping (ln 1989-1990, 4172-4173) asks for the overlap
        // M61/M63 ask for (judgement 44).
        Fail(m.col,
             "M140 (tapping cycle M-tool speed answer ignore) is not supported by the cell's OSP-E100L "
             "dialect: "
             "the axes always wait for the spindle");
      case 61:
      case 63:
        // The servo's spindle segment completes at speed and the move waits for it: the overlap these codes
        // ask for (ln 1971-1974, 9112-9142) cannot be given (judgement 44).
        Fail(m.col,
             fmt::format("M{} ({}) is not supported by the cell's OSP-E100L dialect: the axes always wait "
                         "for the spindle",
                         m.code,
                         m.code == 61 ? "surface speed arrival ignore" : "spindle rotation answer ignore"));
      case 100:
        Fail(m.col,
             "M100 (waiting synchronisation of two turrets, ln 6992-7005) is not supported: one program, "
             "one saddle");
      default:
        break;
    }
  }
}

// T nntt oo / tt oo (ln 1885-1922, 2249-2274): nose-R number, turret station, offset number, right-aligned.
void OkRun::ToolWord(const BlockWords& w) {
  const double v = w.Get('T');
  const int col = w.Col('T');
  if (v < 0 || v > 999999 || v != std::floor(v))
    Fail(col, "T is up to 6 digits: nose-R number, tool, offset");
  const int t = static_cast<int>(v);
  const int nose = t / 10000, tool = (t / 100) % 100, offset = t % 100;
  if (nose > 96 || offset > 96) Fail(col, "tool offset and nose radius numbers are 00-96");
  if (lap_.active || lap_.finish) Fail(col, "turret change inside a LAP contour");
  if (tool != 0 && tool != tool_ && modal_.comp != 40) {
    Fail(col, "turret change during nose radius compensation (G41/G42): cancel with G40 first");
  }
  if (tool != 0) tool_ = tool;
  offset_no_ = offset;
  nose_no_ = nose;
  nose_r_ = tools_.NoseRadius(nose);
  tip_ = tools_.Tip(nose);
  if (tool != 0) {
    ToolChangeOp& c = Out<ToolChangeOp>();
    c.tool = std::to_string(tool);
    c.offset = offset;
    c.tip = tip_;
  }
  if (modal_.comp != 40) {
    // A new nose-R set while compensating (T110111, ln 2261-2274); an offset number alone cancels the radius.
    if (staged_) Commit();
    Staged m;
    m.kind = Staged::kCompOn;
    m.side = (modal_.comp == 41) != modal_.turret_b ? geom::kLeft : geom::kRight;
    m.radius = nose_r_;
    m.tip = TipVector(tip_);
    m.from = pos_;
    Sink(std::move(m));
  }
}

void OkRun::SpindleAndM(const BlockWords& w, bool before_motion) {
  (void)before_motion;
  const auto* g96 = w.FindG(96);
  const auto* g97 = w.FindG(97);
  // Without S, an extended address (SB=), an M code, G96 or G97 the block leaves both spindles as they are.
  if (!w.Has('S') && w.ext_has == 0 && w.m.empty() && !g96 && !g97) return;
  const bool g50 = w.HasG(50);
  bool speed_change = false;
  if (w.Has('S')) {
    double s = w.Get('S');
    if (s < 0 || s > 65535) Fail(w.Col('S'), "S is 0-65535");
    if (g50) {
      max_rpm_ = s;  // G50 S: the spindle speed limit (ln 1708-1722)
    } else if (g96 || (modal_.css && !g97)) {
      css_ = inch_ ? s * 0.3048 : s;
    } else {
      s_ = s;
    }
    speed_change = true;
  }
  if (g96) modal_.css = true;
  if (g97) modal_.css = false;
  // M codes: spindle first, then the others (M00/M01/M02/M30 wait for the motion).
  bool spindle_m = false;
  for (const auto& m : w.m) {
    // Joined as C (M110) the spindle is an axis: it turns or orients only after M109 (ln 1983-1984); M05
    // finds it stopped and leaves it joined (judgement 65).
    if (modal_.c_joined && (m.code == 3 || m.code == 4 || m.code == 19)) {
      Fail(m.col, fmt::format("M{:02d}: the spindle is joined as the C axis (M110); M109 returns it to "
                              "spindle control",
                              m.code));
    }
    if (modal_.c_joined && m.code == 5) continue;
    switch (m.code) {
      case 3:
      case 4: {
        bool cw = m.code == 3;
        if (modal_.turret_b) cw = !cw;  // turret B runs the spindle mirrored (ln 7193-7212)
        modal_.spindle = cw ? SpindleDir::kCw : SpindleDir::kCcw;
        spindle_m = true;
        break;
      }
      case 5:
        modal_.spindle = SpindleDir::kStop;
        spindle_m = true;
        break;
      case 19:
        modal_.spindle = SpindleDir::kOrient;
        spindle_m = true;
        break;
      default:
        break;
    }
  }
  const bool running = modal_.spindle == SpindleDir::kCw || modal_.spindle == SpindleDir::kCcw;
  if (spindle_m || ((speed_change || g96 || g97) && running)) {
    SpindleOp& sp = Out<SpindleOp>();
    sp.dir = modal_.spindle;
    sp.rpm = s_;
    sp.css = modal_.css ? css_ : 0;
    sp.max_rpm = max_rpm_;
  }
  MToolSpindle(w);
  for (const auto& m : w.m) {
    const int c = m.code;
    switch (c) {
      case 0:
      case 1:
      case 2:
      case 30:
      case 3:
      case 4:
      case 5:
      case 19:
        break;
      case 8:
      case 9: {
        modal_.coolant = c == 8;
        CoolantOp& co = Out<CoolantOp>();
        co.m = c;
        co.mode = c == 8 ? CoolantMode::kFlood : CoolantMode::kOff;
        break;
      }
      case 15:
      case 16:
        modal_.c_negative = c == 16;
        break;
      case 22:
      case 23:
        modal_.thread_chamfer = c == 23;
        break;
      case 26:
      case 27:
      case 85:
      case 60:
      case 136:
      case 141:
      case 211:
      case 212:
      case 213:
      case 214:
        break;  // read by the blocks that use them; M60 (wait for the surface speed) is what the servo does
      case 32:
      case 33:
      case 34:
        modal_.thread_mode = c;
        break;
      case 73:
      case 74:
      case 75:
        modal_.infeed = c;
        break;
      case 20:
      case 21:
      case 24:
      case 25:
        BarrierCode(c, m.col);
        break;
      case 109:
      case 110:
        CAxisJoint(w, m);
        break;
      case 12:
      case 13:
      case 14:
        break;  // the M-tool spindle (MToolSpindle, with the main spindle)
      case 146:
      case 147:
        modal_.c_clamped = c == 147;
        Out<AuxOp>().m = c;
        break;
      case 152:
      case 153:
        modal_.mtool_release = c == 153;
        break;
      case 160:
      case 161:
        FixFeedOverride(c == 161, c);
        break;
      case 193:
      case 195:
      case 196:
        if (w.has != 0 || w.g.size() + w.m.size() > 1)
          Fail(m.col, fmt::format("M{} must be alone in its block", c));
        Out<AuxOp>().m = c;
        break;
      default:
        Out<AuxOp>().m = c;
        break;
    }
  }
}

// M161 / M160 (ln 2002-2003): the feedrate override dial ignored (100 %) / valid again, as the `overrides`
// op after the code's `aux` (judgement 62). M49/M48 and M163/M162 fix spindle overrides the cell's spindles
// do not have: they go out as `aux` only.
void OkRun::FixFeedOverride(bool fixed, int m) {
  Out<AuxOp>().m = m;
  modal_.feed_fixed = fixed;
  Out<OverridesOp>().fixed = fixed;
}

// A cycle that fixes the feed override for its own moves (G77/G78 ln 4069, G178/G179 ln 4615): the
// `overrides` op at its start and its end, unless M161 fixed it already.
void OkRun::CycleFeedFixed(bool fixed) {
  if (!modal_.feed_fixed) Out<OverridesOp>().fixed = fixed;
}

// The M-tool (live tool) spindle (ln 1863-1871, 1945-1946, 2036-2060, 4732-4744): SB= its speed (kept through
// reset), M13 CW, M14 CCW, M12 stop. Rotating it needs the C axis joined (M110) unless the interlock is
// released (M153); the manual gives that alarm no number. A new SB= while it turns changes its speed.
void OkRun::MToolSpindle(const BlockWords& w) {
  const int sb = ExtIndex(MakeAddr('S', 'B'));
  bool speed_change = false;
  if (w.HasExt(sb)) {
    const double v = w.ext[static_cast<size_t>(sb)];
    if (v < 0 || v > 65535 || v != std::floor(v))
      Fail(w.ext_col[static_cast<size_t>(sb)], "SB is 0-65535 (M-tool spindle rpm)");
    speed_change = v != sb_;
    sb_ = v;
  }
  const BlockWords::Code* code = nullptr;
  for (const auto& m : w.m) {
    if (m.code != 12 && m.code != 13 && m.code != 14) continue;
    if (code) Fail(m.col, "two of M12/M13/M14 in one block");
    code = &m;
  }
  const bool released = (modal_.mtool_release || w.HasM(153)) && !w.HasM(152);
  if (code && code->code != 12 && !modal_.c_joined && !released) {
    Fail(code->col,
         fmt::format("M{}: the M-tool spindle cannot rotate while the C axis is not joined (M110); "
                     "M153 releases the interlock",
                     code->code));
  }
  const SpindleDir d = !code              ? modal_.mtool
                       : code->code == 12 ? SpindleDir::kStop
                       : code->code == 13 ? SpindleDir::kCw
                                          : SpindleDir::kCcw;
  const bool running = d == SpindleDir::kCw || d == SpindleDir::kCcw;
  if (code || (speed_change && running)) EmitMTool(d);
}

void OkRun::EmitMTool(SpindleDir d) {
  modal_.mtool = d;
  SpindleOp& sp = Out<SpindleOp>();
  sp.spindle = SpindleId::kLiveTool;
  sp.dir = d;
  sp.rpm = sb_;
}

// M110 joins the spindle as the C axis (alone in its block, not cleared by reset); M109 returns it to spindle
// control, stopped (ln 1983-1984, 2057-2069). Both are the main spindle's state: `spindle` ops.
void OkRun::CAxisJoint(const BlockWords& w, const BlockWords::Code& m) {
  if (m.code == 110 && (w.has != 0 || w.ext_has != 0 || w.g.size() + w.m.size() > 1)) {
    Fail(m.col, "M110 must be alone in its block");
  }
  modal_.c_joined = m.code == 110;
  if (modal_.c_joined) c_net_ = 0;
  modal_.spindle = m.code == 110 ? SpindleDir::kAxis : SpindleDir::kStop;
  SpindleOp& sp = Out<SpindleOp>();
  sp.dir = modal_.spindle;
  sp.rpm = s_;
  sp.css = modal_.css ? css_ : 0;
  sp.max_rpm = max_rpm_;
}

void OkRun::StopAndEnd(const BlockWords& w) {
  for (const auto& m : w.m) {
    if (m.code == 0 || (m.code == 1 && optional_stop_)) {
      StopOp& s = Out<StopOp>();
      s.m = m.code;
      s.optional = m.code == 1;
    }
  }
  for (const auto& m : w.m) {
    if (m.code == 2 || m.code == 30) {
      if (lap_.active || lap_.finish) Fail(m.col, fmt::format("M{} inside a LAP contour", m.code));
      EndOp& e = Out<EndOp>();
      e.m = m.code;
      e.shuttle = false;
      ResetProgramState();
      Finish();
      return;
    }
  }
}

void OkRun::CompCodes(const BlockWords& w, int motion_col, bool has_xz) {
  (void)motion_col;
  (void)has_xz;
  int code = 0, col = 1;
  for (const auto& g : w.g) {
    if (g.code >= 40 && g.code <= 42) {
      code = g.code;
      col = g.col;
    }
  }
  if (!code) return;
  if (modal_.motion != 0 && modal_.motion != 1) {
    Fail(col, fmt::format("G{} must be given in G00 or G01 mode", code));
  }
  if (code != 40 && lap_.active && lap_.blank)
    Fail(col, "nose radius compensation cannot start in a blank shape");
  if (code == 40 && modal_.comp == 40) return;
  if (staged_) Commit();
  Staged m;
  m.from = pos_;
  m.has_ik = w.Has('I') || w.Has('K');
  if (m.has_ik) {
    double i = w.Has('I') ? w.Get('I') : 0;
    if (modal_.turret_b) i = -i;
    m.ik = {w.Has('K') ? w.Get('K') : 0, i};
  }
  if (code == 40) {
    m.kind = Staged::kCompOff;
  } else {
    m.kind = Staged::kCompOn;
    m.side = (code == 41) != modal_.turret_b ? geom::kLeft : geom::kRight;
    m.radius = nose_r_;
    m.tip = TipVector(tip_);
  }
  modal_.comp = code;
  Sink(std::move(m));
}

// The cell's numbering of the nose R pattern (the manual keeps the pattern in the tool data without numbering
// it, ln 3167): the direction from the nose-R centre to the imaginary tool tip, +Z to the right, +X up.
geom::Vec2 OkRun::TipVector(int tip) const {
  static constexpr double kDir[10][2] = {{0, 0}, {1, 1}, {-1, 1}, {-1, -1}, {1, -1},
                                         {1, 0}, {0, 1}, {-1, 0}, {0, -1},  {0, 0}};
  const int t = (tip >= 0 && tip <= 9) ? tip : 0;
  double dx = kDir[t][1];
  if (modal_.turret_b) dx = -dx;
  return {kDir[t][0] * nose_r_, dx * nose_r_};
}

}  // namespace cell::interp::okuma
