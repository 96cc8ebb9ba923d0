// One EMCO block (manual ln 1160-1331, 1370-1897, 1938-1954, 4909-5221): its words with the last one
// winning, the G and M groups and what each does before, during and after the block's motion, F S T, the
// zero shifts G53-G59 with G92 writing PSO 5, scaling G51/G50 (DC 5.00), and the syntax rules of the radius
// compensation G40/G41/G42.
#include <fmt/format.h>

#include <bit>
#include <cmath>

#include "cell/interp/geometry/tool_nose.h"
#include "interp_internal.h"

namespace cell::interp::emco {

namespace {

// G code groups (ln 1938-1954); -1: not a G code of this control (ALARM 410). Scaling G50/G51 (DC 5.00)
// is kept apart as group 9.
int GroupOfG(int g) {
  switch (g) {
    case 0:
    case 1:
    case 2:
    case 3:
    case 4:
    case 33:
    case 84:
    case 85:
    case 86:
    case 87:
    case 88:
      return 0;
    case 96:
    case 97:
      return 1;
    case 94:
    case 95:
      return 2;
    case 53:
    case 54:
    case 55:
      return 3;
    case 92:
      return 4;
    case 56:
    case 57:
    case 58:
    case 59:
      return 5;
    case 25:
    case 26:
    case 27:
      return 6;
    case 70:
    case 71:
      return 7;
    case 40:
    case 41:
    case 42:
      return 8;
    case 50:
    case 51:
      return 9;
    default:
      return -1;
  }
}

// M code groups (ln 4922-4941); 10: M65 (DC 5.00, turning); -1: ALARM 420 (M27 is the milling variant's).
int GroupOfM(int m) {
  switch (m) {
    case 3:
    case 4:
    case 5:
    case 19:
      return 0;
    case 38:
    case 39:
      return 1;
    case 0:
    case 17:
    case 30:
      return 2;
    case 8:
    case 9:
      return 3;
    case 25:
    case 26:
      return 5;
    case 20:
    case 21:
      return 6;
    case 23:
    case 24:
      return 7;
    case 50:
    case 51:
      return 8;
    case 52:
    case 53:
      return 9;
    case 65:
      return 10;
    default:
      return -1;
  }
}

Motion MotionOf(int g) {
  switch (g) {
    case 0:
      return Motion::kRapid;
    case 1:
      return Motion::kLinear;
    case 2:
      return Motion::kCw;
    case 3:
      return Motion::kCcw;
    case 33:
      return Motion::kThread;
    case 84:
      return Motion::kG84;
    case 85:
      return Motion::kG85;
    case 86:
      return Motion::kG86;
    case 87:
      return Motion::kG87;
    default:
      return Motion::kG88;
  }
}

bool Threading(Motion m) {
  return m == Motion::kThread || m == Motion::kG85;
}

// Value `slot` of the block (BlockWords::Slot) as word `w`, the order-th of its block.
void Set(BlockWords& bw, int slot, const Word& w, int order) {
  bw.set_mask |= 1u << slot;
  Val& v = bw.Slot(slot);
  v.set = true;
  v.point = w.point;
  v.sign = w.sign;
  v.raw = w.value;
  v.v = w.value;
  v.col = w.col;
  v.order = order;
}

}  // namespace

bool BlockWords::any_p() const {
  for (const Val& v : p) {
    if (v.set) return true;
  }
  return false;
}

bool BlockWords::any_d() const {
  for (const Val& v : d) {
    if (v.set) return true;
  }
  return false;
}

Val& BlockWords::Slot(int n) {
  switch (n) {
    case 0:
      return x;
    case 1:
      return z;
    case 2:
      return i;
    case 3:
      return k;
    case 4:
      return f;
    case 5:
      return s;
    case 6:
      return t;
    case 7:
      return l;
    default:
      return n < 16 ? p[static_cast<size_t>(n - 8)] : d[static_cast<size_t>(n - 16)];
  }
}

void BlockWords::Clear() {
  for (uint32_t m = set_mask; m != 0; m &= m - 1) Slot(std::countr_zero(m)) = Val{};
  set_mask = 0;
  x_inc = z_inc = false;
  ng = nm = 0;
  first_col = 1;
}

void EmRun::Collect(const Block& b, BlockWords& bw) const {
  bw.first_col = b.count > 0 ? b.w[0].col : 1;
  for (int i = 0; i < b.count; ++i) {
    const Word& w = b.w[i];
    switch (w.letter) {
      case 'X':
      case 'U':
        Set(bw, 0, w, i);
        bw.x_inc = w.letter == 'U';
        break;
      case 'Z':
      case 'W':
        Set(bw, 1, w, i);
        bw.z_inc = w.letter == 'W';
        break;
      case 'I':
        Set(bw, 2, w, i);
        break;
      case 'K':
        Set(bw, 3, w, i);
        break;
      case 'F':
        Set(bw, 4, w, i);
        break;
      case 'S':
        Set(bw, 5, w, i);
        break;
      case 'T':
        Set(bw, 6, w, i);
        break;
      case 'L':
        Set(bw, 7, w, i);
        break;
      case 'P':
        Set(bw, 8 + w.index, w, i);
        break;
      case 'D':
        Set(bw, 16 + w.index, w, i);
        break;
      case 'G':
      case 'M': {
        // G2/M2: two digits, no point and no sign (ln 1102-1110): G+01 is outside the format like G1.5.
        if (w.point || w.sign || w.value < 0 || w.value > 99 || w.value != std::floor(w.value)) {
          Alarm(w.letter == 'G' ? 410 : 420, w.col, fmt::format("{}{}", w.letter, w.value));
        }
        auto& list = w.letter == 'G' ? bw.g : bw.m;
        int& n = w.letter == 'G' ? bw.ng : bw.nm;
        if (n >= static_cast<int>(list.size())) Alarm(650, w.col, "too many G or M words");
        list[n++] = {static_cast<int>(w.value), w.col};
        break;
      }
      default:
        break;
    }
  }
}

// Lengths without a decimal point are um (G71) or 1/10000 inch (G70) (ln 884-887); every value has the
// range of its format (ln 1102-1158; ALARM 620 beyond it).
void EmRun::ConvertValues(BlockWords& bw) const {
  auto length = [&](Val& v) {
    if (!v.set) return;
    if (std::fabs(v.raw) > (v.point ? 9999.999 : 9999999.0))
      Alarm(620, v.col, "lengths are at most +-9999.999");
    double unit = v.point ? 1.0 : (mode_.metric ? 0.001 : 0.0001);
    v.v = v.raw * unit * (mode_.metric ? 1.0 : kInch);
  };
  auto whole = [&](Val& v, double hi, const char* what) {
    if (!v.set) return;
    if (v.raw < 0 || v.raw > hi) Alarm(620, v.col, what);
  };
  length(bw.x);
  length(bw.z);
  length(bw.i);
  length(bw.k);
  length(bw.p[0]);
  length(bw.p[1]);
  length(bw.p[2]);
  // F4 and S4 are digits without a decimal point (ln 1146, 4985): F0.15 is outside the format, not 0.15 um.
  if (bw.f.set && bw.f.point) Alarm(620, bw.f.col, "F is F4, without a decimal point");
  if (bw.s.set && bw.s.point) Alarm(620, bw.s.col, "S is S4, without a decimal point");
  // F4, S4, D45 (and T, L) are "digits without decimal point and sign" (ln 1146, 1154-1156): a sign is
  // outside the format (judgement 29).
  if (bw.set_mask & 0xf0u) {  // any of F, S, T, L (slots 4-7)
    for (const Val* v : {&bw.f, &bw.s, &bw.t, &bw.l}) {
      if (v->set && v->sign) Alarm(620, v->col, "F, S, T and L are written without a sign");
    }
  }
  whole(bw.f, 9999, "F is 0-9999 (F4)");
  whole(bw.s, 9999, "S is 0-9999 (S4)");
  whole(bw.t, 9999, "T is 0000-9999 (TTCC)");
  whole(bw.l, 25599, "L is at most 25599 (subroutine O0255, 99 runs)");
  // Most blocks have no D word: the loop only when one is set (set_mask bits 16-23).
  for (Val& d : bw.d) {
    if ((bw.set_mask & 0xff0000u) == 0) break;
    if (!d.set) continue;
    // D45 has no point (ln 1154-1156); the printed "D3 = 2.000" is 2000 um with a thousands separator (the
    // listing importer reads it so), and on tape 2.000 would be 2 um: refused (judgement 29).
    if (d.point) Alarm(620, d.col, "D is D45, without a decimal point: D3=2000 is 2 mm");
    if (d.sign) Alarm(620, d.col, "D is D45, without a sign");
    if (d.raw < 0 || d.raw > 32767) Alarm(620, d.col, "D parameters are 0-32767");
    if (d.raw != std::floor(d.raw)) Alarm(200, d.col, "D parameters are whole numbers");
  }
}

// A word with no G code to use it (ALARM 400), a parameter its group-0 code does not take (ALARM 480).
void EmRun::CheckWords(const BlockWords& bw, Motion motion, bool g04, bool g92, bool g51, bool flow) const {
  (void)flow;
  if (bw.has_pos()) {
    if (g04) Alarm(400, bw.pos_col(), "a position word in a G04 block");
    if (!g92 && !g51 && motion == Motion::kNone)
      Alarm(400, bw.pos_col(), "no G00-G03, G33 or cycle is active");
  }
  if ((bw.i.set || bw.k.set) && motion != Motion::kCw && motion != Motion::kCcw) {
    Alarm(480, bw.i.set ? bw.i.col : bw.k.col, "I/K without G02/G03");
  }
  // Which P and D each group-0 code takes (P/D words belong to their block, ln 1289).
  unsigned p_ok = 0, d_ok = 0;
  if (g04) {
    d_ok = 1u << 4;
  } else if (g51) {
    p_ok = 1u << 7;
  } else {
    switch (motion) {
      case Motion::kLinear:
        p_ok = 0b11;  // P0 radius, P1 chamfer (DC 5.10)
        break;
      case Motion::kG84:
        p_ok = 0b101;
        d_ok = 0b1101;
        break;
      case Motion::kG85:
        p_ok = 0b101;
        d_ok = 0b11111000;
        break;
      case Motion::kG86:
        d_ok = 0b111000;
        break;
      case Motion::kG87:
      case Motion::kG88:
        d_ok = 0b1111000;
        break;
      default:
        break;
    }
  }
  // Only when the block has a P or D word (set_mask bits 8-23): most have none.
  for (int i = 0; i < 8 && (bw.set_mask & 0xffff00u) != 0; ++i) {
    if (bw.p[i].set && !(p_ok & (1u << i)))
      Alarm(g51 ? 374 : 480, bw.p[i].col, fmt::format("P{} not used here", i));
    if (bw.d[i].set && !(d_ok & (1u << i)))
      Alarm(g51 ? 374 : 480, bw.d[i].col, fmt::format("D{} not used here", i));
  }
}

void EmRun::Execute(const Block& b) {
  BlockWords& bw = words_;
  bw.Clear();
  Collect(b, bw);

  // G codes: the last of a group wins (ln 878-883).
  // Group slots start empty (-1, column 1); copied from constants, not filled element by element.
  static constexpr std::array<int, 10> kNoG = {-1, -1, -1, -1, -1, -1, -1, -1, -1, -1};
  static constexpr std::array<int, 11> kNoM = {-1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1};
  static constexpr std::array<int, 10> kGCol1 = {1, 1, 1, 1, 1, 1, 1, 1, 1, 1};
  static constexpr std::array<int, 11> kMCol1 = {1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1};
  std::array<int, 10> g = kNoG;
  std::array<int, 10> gcol = kGCol1;
  bool g04 = false;
  int g04col = 1;
  for (int n = 0; n < bw.ng; ++n) {
    int code = bw.g[n].code;
    if (code == 4) {
      g04 = true;
      g04col = bw.g[n].col;
      continue;
    }
    int grp = GroupOfG(code);
    if (grp < 0) Alarm(410, bw.g[n].col, fmt::format("G{:02d}", code));
    g[grp] = code;
    gcol[grp] = bw.g[n].col;
  }
  std::array<int, 11> m = kNoM;
  std::array<int, 11> mcol = kMCol1;
  for (int n = 0; n < bw.nm; ++n) {
    int grp = GroupOfM(bw.m[n].code);
    if (grp < 0) Alarm(420, bw.m[n].col, fmt::format("M{:02d}", bw.m[n].code));
    m[grp] = bw.m[n].code;
    mcol[grp] = bw.m[n].col;
  }

  // G70/G71 only in the first block (ALARM 390); it sets how this block's values read.
  if (g[7] >= 0 && (g[7] == 71) != mode_.metric) {
    if (!first_block_) Alarm(390, gcol[7]);
    mode_.metric = g[7] == 71;
    if (units_emitted_) {
      Canon c;
      c.line = cur_line_;
      auto& u = c.Set<UnitsOp>();
      u.metric = mode_.metric;
      u.x_mode = XMode::kDiameter;
      EmitOther(std::move(c));
    }
  }
  first_block_ = false;
  ConvertValues(bw);

  Motion motion = g[0] >= 0 ? MotionOf(g[0]) : mode_.motion;
  bool g92 = g[4] == 92;
  bool g51 = g[9] == 51;
  bool flow = g[6] >= 0;
  CheckWords(bw, motion, g04, g92, g51, flow);
  if (bw.l.set && !flow) Alarm(400, bw.l.col, "L without G25/G26/G27");
  bool moves = bw.has_pos() && !g04 && !g92 && !g51;

  // After a chamfer/radius block the next block must be a G01 with a position (ALARM 381/382).
  bool corner_block = motion == Motion::kLinear && moves && (bw.p[0].set || bw.p[1].set);
  if (corner_next_) {
    if (!moves) Alarm(382, bw.first_col);
    if (motion != Motion::kLinear) Alarm(381, g[0] >= 0 ? gcol[0] : bw.pos_col());
    corner_block = true;
    corner_next_ = false;
  }
  if (corner_block && g[9] >= 0) Alarm(386, gcol[9]);

  // M30 with compensation on: the M30 block cancels it with its own G00/G01 move (ln 2901-2911).
  if (m[2] == 30 && mode_.comp != 40 && g[8] < 0) {
    if (!moves || (motion != Motion::kRapid && motion != Motion::kLinear))
      Alarm(510, mcol[2], "M30 with G41/G42 active");
    g[8] = 40;
    gcol[8] = mcol[2];
  }
  // Before the motion: tool (before G41/G42 of the same block, which take its nose radius), feed mode,
  // spindle, coolant and the other switching functions.
  if (bw.t.set) {
    if (corner_block && static_cast<int>(bw.t.raw) != t_) Alarm(387, bw.t.col);
    ToolWord(bw);
  }
  if (g[8] >= 0) CompCode(g[8], gcol[8]);
  if (g[2] >= 0) mode_.per_min = g[2] == 94;
  if (bw.f.set) {
    if (Threading(motion) && !g04) {
      pitch_ = bw.f.raw;
    } else {
      feed_ = bw.f.raw;
    }
  }
  SpindleWords(bw, m[0], g[1] == 96, g[1] == 97, g92);
  if (m[1] >= 0) mode_.exact_stop = m[1] == 38;
  if (m[3] == 8) Coolant(true);
  for (int grp = 5; grp <= 10 && bw.nm > 0; ++grp) {  // without M words every group is empty
    if (m[grp] >= 0) AuxBefore(m[grp], mcol[grp]);
  }
  if (ZeroShifts(bw, g[3], g[5], g92, gcol[3], gcol[5]) && corner_block) {
    Alarm(385, g[3] >= 0 ? gcol[3] : gcol[5]);
  }
  if (g[9] >= 0) Scaling(bw, g[9], gcol[9]);
  if (g51 && g[0] >= 0 && g[0] >= 84) Alarm(370, gcol[9]);
  if (g[0] >= 0) mode_.motion = motion;
  if (g04 && !bw.d[4].set) Alarm(480, g04col, "G04 needs D4");

  CompBlock(bw, motion, moves);
  if (moves) {
    MotionBlock(bw, motion);
  }

  // After the motion: spindle stop, coolant off, dwell at the end of the block (ln 2167), program stop.
  if (m[0] == 5 && mode_.spindle != 5) {
    mode_.spindle = 5;
    SpindleOp(cur_line_);
  } else if (m[0] == 5) {
    mode_.spindle = 5;
  }
  if (m[3] == 9) Coolant(false);
  if (g04) {
    int tenths = static_cast<int>(bw.d[4].raw);
    if (tenths < 1 || tenths > 10000) Alarm(200, bw.d[4].col, "G04 D4 is 1-10000 (0.1-1000 s)");
    Canon c;
    c.line = cur_line_;
    c.Set<DwellOp>().seconds = tenths / 10.0;
    EmitOther(std::move(c));
    idle_ = 0;
  }
  if (m[2] == 0) {
    Canon c;
    c.line = cur_line_;
    c.Set<StopOp>().m = 0;
    EmitOther(std::move(c));
    idle_ = 0;
  }
  if (corner_block && !corner_next_ && corner_.engaged()) corner_next_ = true;

  // Program flow.
  if (g[6] == 25) {
    CallSubroutine(bw, gcol[6]);
  } else if (g[6] == 27) {
    Jump(bw, gcol[6]);
  } else if (g[6] == 26) {
    // G26 calls a polygon program of the graphic simulation (ln 2275-2284). The cell has no graphic
    // simulation and keeps no polygon programs: ALARM 750, as a control without that program (judgement 30).
    const double l = bw.l.set ? bw.l.raw : 0;
    if (!bw.l.set || l < 7000 || l > 9999 || (l >= 8001 && l <= 8899))
      Alarm(751, bw.l.set ? bw.l.col : gcol[6], "G26 takes L7000-L9999, not the tool profiles 8001-8899");
    Alarm(750, gcol[6], fmt::format("O{:04d}: the cell keeps no polygon programs", static_cast<int>(l)));
  }
  if (m[2] == 17) ReturnFromSubroutine(mcol[2]);
  if (m[2] == 30) EndOfProgram(mcol[2]);
}

// T TTCC (ln 1372-1559): the turret position and the tool correction number. A new T moves the turret and
// changes the offset; the next move must be G00 (ALARM 490).
void EmRun::ToolWord(const BlockWords& bw) {
  if (bw.t.point) Alarm(430, bw.t.col, "T is TTCC without a decimal point");
  int t = static_cast<int>(bw.t.raw);
  int tt = t / 100, cc = t % 100;
  if (tt == 0 && cc != 0) Alarm(430, bw.t.col, fmt::format("T{:04d}: a correction needs its tool number", t));
  if (t == t_) return;  // the active T written again (ln 1197-1210)
  if (mode_.comp != 40) Alarm(360, bw.t.col);
  t_ = t;
  Correction c = LookUp(tools_, cc);
  tool_off_ = cc == 0 ? Vec2{} : Vec2{c.z, c.x};
  offset_changed_ = true;
  if (tt == 0) return;  // T0000: no tool, the turret stays
  Canon op;
  op.line = cur_line_;
  auto& k = op.Set<ToolChangeOp>();
  // The tool in turret position TT: the table's entry at that socket (its own number when a correction
  // carries it, as T0303; else the correction filed there), so the servo's turret finds it; TT itself when
  // the table has none (offline without tool data).
  k.tool = std::to_string(tt);
  const tooltable::ToolEntry* at = nullptr;
  for (const auto& e : tools_.entries()) {
    if (e.socket != tt) continue;
    if (at == nullptr || e.tool == k.tool) at = &e;
  }
  if (at != nullptr) k.tool = at->tool;
  k.offset = cc;
  k.tip = c.tip;
  EmitOther(std::move(op));
}

// S is rpm (G97), m/min (G96), the G92 speed limit, or the M19 angle (ln 924-933); M03/M04 start the spindle
// before the block's motion, an S or G96/G97 change while it turns changes it.
void EmRun::SpindleWords(const BlockWords& bw, int spindle_m, bool g96, bool g97, bool g92) {
  bool changed = false;
  if (g96 != g97 && mode_.css != g96) {
    mode_.css = g96;
    changed = true;
  }
  if (bw.s.set) {
    if (spindle_m == 19) {
      // the orientation angle, below
    } else if (g92) {
      if (speed_limit_ != bw.s.raw) changed = true;
      speed_limit_ = bw.s.raw;
    } else {
      if (speed_ != bw.s.raw) changed = true;
      speed_ = bw.s.raw;
    }
  }
  bool running = mode_.spindle == 3 || mode_.spindle == 4;
  if (spindle_m == 3 || spindle_m == 4) {
    if (mode_.spindle != spindle_m || changed) {
      mode_.spindle = spindle_m;
      SpindleOp(cur_line_);
    }
    return;
  }
  if (spindle_m == 19) {
    if (bw.s.set && (bw.s.raw < 0 || bw.s.raw > 360)) Alarm(620, bw.s.col, "M19 S is 0-360 degrees");
    mode_.spindle = 19;
    Canon c;
    c.line = cur_line_;
    auto& k = c.Set<cell::interp::SpindleOp>();
    k.dir = SpindleDir::kOrient;
    k.rpm = speed_;
    k.angle = bw.s.set ? bw.s.raw : mon_.m08;
    EmitOther(std::move(c));
    return;
  }
  if (running && changed) SpindleOp(cur_line_);
}

void EmRun::SpindleOp(int line) {
  Canon c;
  c.line = line;
  auto& k = c.Set<cell::interp::SpindleOp>();
  k.dir = mode_.spindle == 3 ? SpindleDir::kCw : mode_.spindle == 4 ? SpindleDir::kCcw : SpindleDir::kStop;
  if (mode_.css) {
    // G96: S is m/min (ft/min in inch), V = D*S*pi/1000 (ln 4859-4872); the servo keeps the rpm.
    k.css = mode_.metric ? speed_ : speed_ * 0.3048;
    if (k.dir == SpindleDir::kStop) k.css = 0;
  } else {
    k.rpm = speed_;
  }
  k.max_rpm = speed_limit_;
  EmitOther(std::move(c));
}

// M08 (before the motion) / M09 (after it, and at M30): flood coolant on or off when it changes.
void EmRun::Coolant(bool on) {
  if (mode_.coolant == on) return;
  mode_.coolant = on;
  Canon c;
  c.line = cur_line_;
  auto& k = c.Set<CoolantOp>();
  k.m = on ? 8 : 9;
  k.mode = on ? CoolantMode::kFlood : CoolantMode::kOff;
  EmitOther(std::move(c));
}

// Switching functions before the motion (ln 4992-5221, DC 5.00 M65).
void EmRun::AuxBefore(int m, int col) {
  bool turning = mode_.spindle == 3 || mode_.spindle == 4;
  int* state = nullptr;
  switch (m) {
    case 20:
    case 21:
      if (turning) Alarm(940, col);
      state = &mode_.tailstock;
      break;
    case 25:
      if (turning) Alarm(940, col);
      state = &mode_.chuck;
      break;
    case 26:
      state = &mode_.chuck;
      break;
    case 23:
    case 24:
      state = &mode_.catcher;
      break;
    case 50:
    case 51:
      state = &mode_.turret_logic;
      break;
    case 52:
    case 53:
      state = &mode_.door;
      break;
    case 65: {
      // Wait for the bar loading magazine (a queue buster: the station answers it).
      if (mode_.comp != 40) Alarm(361, col);
      Canon c;
      c.line = cur_line_;
      c.Set<WaitInputOp>().spec = "M65";
      EmitOther(std::move(c));
      env_->WaitInputs("M65");
      idle_ = 0;
      return;
    }
    default:
      return;
  }
  *state = m;  // every programmed switching function goes to the machine, changed or not
  Canon c;
  c.line = cur_line_;
  c.Set<AuxOp>().m = m;
  EmitOther(std::move(c));
}

// PSO 1/2 (group 3, G53 cancels) and PSO 3/4/5 (group 5, G56 cancels) add up (ln 1605-1734); G92 X/Z
// replace PSO 5, U/W add to it, a diameter X is stored as a radius (ln 1736-1847).
bool EmRun::ZeroShifts(const BlockWords& bw, int g3, int g5, bool g92, int col3, int col5) {
  if (g92 && bw.has_pos()) {
    if (mode_.shift_b == 5 || g5 == 59) Alarm(700, bw.pos_col(), "G92 while G59 is active");
    Vec2& r = pso_[5];
    if (bw.x.set) r.y = bw.x_inc ? r.y + bw.x.v : ((mon_.o11 & 1) ? bw.x.v / 2 : bw.x.v);
    if (bw.z.set) r.x = bw.z_inc ? r.x + bw.z.v : bw.z.v;
  }
  int a = g3 < 0 ? mode_.shift_a : g3 - 53;
  int b = g5 < 0 ? mode_.shift_b : (g5 == 56 ? 0 : g5 - 54);
  if (a == mode_.shift_a && b == mode_.shift_b) return false;
  if (scaling_) Alarm(371, g3 >= 0 ? col3 : col5);
  mode_.shift_a = a;
  mode_.shift_b = b;
  offset_changed_ = true;
  return true;
}

// G51 X/U Z/W P7: scale about the reference point by P7 until G50 (DC 5.00, ln 157-201).
void EmRun::Scaling(const BlockWords& bw, int g, int col) {
  if (g == 50) {
    scaling_ = false;
    scale_first_move_ = false;
    return;
  }
  if (!bw.p[7].set) Alarm(374, col, "G51 needs P7");
  double f = bw.p[7].raw;
  if (f < 0) Alarm(373, bw.p[7].col);
  if (f == 0) Alarm(374, bw.p[7].col, "P7 = 0");
  Vec2 ref = prog_;
  if (bw.x.set) ref.y = bw.x_inc ? prog_.y + bw.x.v : ((mon_.o11 & 1) ? bw.x.v / 2 : bw.x.v);
  if (bw.z.set) ref.x = bw.z_inc ? prog_.x + bw.z.v : bw.z.v;
  scaling_ = true;
  scale_ = f;
  scale_ref_ = ref;
  scale_first_move_ = true;
}

// G40/G41/G42 (ln 2892-3000): a change of side needs G40 and a move first (ALARM 530); the tool needs a
// nose radius (ALARM 350); at least two XZ moves before G40 (ALARM 510).
void EmRun::CompCode(int g, int col) {
  if (g == 40) {
    if (mode_.comp == 40) return;
    mode_.comp = 40;
    if (comp_request_ == 41 || comp_request_ == 42) {  // selected, never moved: nothing to undo
      comp_request_ = 0;
      return;
    }
    if (comp_moves_ < 2) Alarm(510, col);
    comp_request_ = 40;
    comp_idle_ = -1;
    comp_.Cancel();
    return;
  }
  if (mode_.comp == g && comp_request_ != 40) return;
  if (mode_.comp != 40 || comp_request_ == 40) Alarm(530, col);
  Correction c = LookUp(tools_, t_ % 100);
  if (t_ % 100 == 0 || c.r <= 0) Alarm(350, col, t_ % 100 == 0 ? "no tool correction active" : "R = 0");
  mode_.comp = g;
  comp_request_ = g;
  comp_idle_ = -1;  // the requesting block itself does not count toward the 5 blocks
}

// The blocks around a compensation request and while it is on (ln 2892-2917).
void EmRun::CompBlock(const BlockWords& bw, Motion motion, bool moves) {
  if (comp_request_ == 0 && !comp_.on()) return;
  bool xz_change = false;
  if (moves) {
    Vec2 to = Target(bw);
    xz_change = std::fabs(to.x - prog_.x) > 1e-9 || std::fabs(to.y - prog_.y) > 1e-9;
  }
  if (comp_request_ != 0) {
    if (!moves) {
      if (++comp_idle_ > 5) Alarm(500, bw.first_col);
      return;
    }
    if (motion != Motion::kRapid && motion != Motion::kLinear)
      Alarm(520, bw.pos_col(), "the move must be G00 or G01");
    if (!xz_change) Alarm(520, bw.pos_col(), "X or Z must change");
    if (comp_request_ != 40) {
      Correction c = LookUp(tools_, t_ % 100);
      comp_.Select(comp_request_ == 41 ? geom::kLeft : geom::kRight, c.r, geom::NoseTipOffset(c.tip, c.r),
                   ToWork(prog_), (mon_.o40 & 64) != 0);
      comp_moves_ = 1;
    } else {
      comp_moves_ = 0;
    }
    comp_request_ = 0;
    comp_idle_ = 0;
    return;
  }
  if (xz_change) {
    comp_idle_ = 0;
    ++comp_moves_;
  } else if (++comp_idle_ > 5) {
    Alarm(500, bw.first_col);
  }
}

}  // namespace cell::interp::emco
