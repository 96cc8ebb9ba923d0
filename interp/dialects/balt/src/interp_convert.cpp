// Balt-System ISO blocks (manual §5.7-5.8): the G codes of Table 5.2 in the modal groups a-m of Table 5.4
// and their compatibility (Table 5.5), F, S, T, H and the M functions of Table 5.3, then the block's motion,
// fixed cycle, probing cycle or GTL profile step.
#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>

#include "interp_internal.h"

namespace cell::interp::balt {
namespace {

// Column of Table 5.5 for a G code; -1 for codes without one (G93-G97).
int CompatColumn(int g) {
  switch (g) {
    case 0:
      return 0;
    case 1:
      return 1;
    case 2:
    case 3:
      return 2;
    case 33:
      return 3;
    case 80:
      return 5;
    case 72:
    case 73:
    case 74:
      return 6;
    case 21:
      return 7;
    case 20:
      return 8;
    case 41:
    case 42:
      return 9;
    case 40:
      return 10;
    case 27:
    case 28:
      return 11;
    case 29:
      return 12;
    case 4:
      return 13;
    case 9:
      return 14;
    case 90:
    case 91:
      return 15;
    case 79:
      return 16;
    case 70:
    case 71:
      return 17;
    case 17:
    case 18:
    case 19:
      return 18;
    default:
      return (g >= 81 && g <= 89) ? 4 : -1;
  }
}

// Row of Table 5.5 (ln 2620-2663; 1 = not compatible in one block). The G42 row is printed shifted by the
// scan: it is the G41 row (a judgement call).
const char* CompatRow(int g) {
  switch (g) {
    case 0:
    case 1:
      return "1111010110000000001";
    case 2:
    case 3:
      return "1111111110000000001";
    case 4:
    case 9:
      return "0001101000010110001";
    case 17:
    case 18:
    case 19:
      return "1111111111111111111";
    case 20:
      return "1111111111000000101";
    case 21:
      return "1111111110000000101";
    case 27:
      return "0000101000011100001";
    case 28:
      return "0001101000011100001";
    case 29:
      return "0000101000011000001";
    case 33:
      return "1111111111100000001";
    case 40:
      return "0001111001100000101";
    case 41:
    case 42:
      return "0001111010100000101";
    case 70:
    case 71:
      return "0000000000000000011";
    case 72:
    case 73:
    case 74:
      return "0111111111111000101";
    case 79:
      return "0000111111100001101";
    case 80:
      return "1111111111100000101";
    case 90:
    case 91:
      return "0000000000000001101";
    default:
      if (g >= 81 && g <= 89) return "0011111111111000101";
      return "0000000000000000001";  // G93-G97
  }
}

// Modal group of a code (Table 5.4), for two codes of one group in a block.
char GroupOf(int g) {
  switch (g) {
    case 0:
    case 1:
    case 2:
    case 3:
    case 33:
      return 'a';
    case 17:
    case 18:
    case 19:
      return 'b';
    case 27:
    case 28:
    case 29:
      return 'c';
    case 20:
    case 21:
      return 'd';
    case 40:
    case 41:
    case 42:
      return 'e';
    case 70:
    case 71:
      return 'f';
    case 90:
    case 91:
      return 'h';
    case 79:
      return 'i';
    case 4:
    case 9:
      return 'j';
    case 72:
    case 73:
    case 74:
      return 'k';
    case 93:
    case 94:
    case 95:
      return 'l';
    case 96:
    case 97:
      return 'm';
    default:
      return (g >= 80 && g <= 89) ? 'g' : 0;
  }
}

bool Exists(int g) {
  switch (g) {
    case 0:
    case 1:
    case 2:
    case 3:
    case 4:
    case 9:
    case 17:
    case 18:
    case 19:
    case 20:
    case 21:
    case 27:
    case 28:
    case 29:
    case 33:
    case 40:
    case 41:
    case 42:
    case 70:
    case 71:
    case 72:
    case 73:
    case 74:
    case 79:
    case 80:
    case 81:
    case 82:
    case 83:
    case 84:
    case 85:
    case 86:
    case 89:
    case 90:
    case 91:
    case 93:
    case 94:
    case 95:
    case 96:
    case 97:
      return true;
    default:
      return false;
  }
}

bool MotionStart(int m) {
  switch (m) {
    case 3:
    case 4:
    case 7:
    case 8:
    case 10:
    case 11:
    case 12:
    case 13:
    case 14:
    case 19:
    case 41:
    case 42:
    case 43:
    case 44:
    case 45:
      return true;
    default:
      return false;
  }
}

}  // namespace

BlockG BaltRun::ReadGCodes(const ParsedBlock& pb) {
  BlockG g;
  if (!(pb.letters & LetterBit('G'))) return g;
  InlineVec<GCode, 16> codes;
  for (const Word& w : pb.words) {
    if (w.letter != 'G') continue;
    double v = ValueOf(w.v, w.col);
    // A whole code 0-99 (every valid one) passes without std::floor, a libm call.
    if (!(v >= 0 && v <= 99 && v == static_cast<double>(static_cast<int>(v)))) [[unlikely]] {
      if (v != std::floor(v) || v < 0) Fail(w.col, 13, fmt::format("G{:g}", v));
      if (v > 99) Fail(w.col, 18, fmt::format("G{:g} (G codes are G00-G99)", v));
    }
    int code = static_cast<int>(v);
    if (!Exists(code)) Fail(w.col, 17, fmt::format("G{:02} does not exist on this control", code));
    if (codes.size() >= 8) Fail(w.col, 21, "more than 8 G functions in the block");
    codes.push_back({code, w.col});
  }
  if (codes.empty()) return g;
  g.first_col = codes[0].col;
  g.count = static_cast<int>(codes.size());
  CheckCompatibility(pb, codes);
  for (const GCode& gc : codes) {
    const int code = gc.code;
    switch (GroupOf(code)) {
      case 'a':
        g.any_motion = true;
        g.motion = code == 0   ? Motion::kRapid
                   : code == 1 ? Motion::kLinear
                   : code == 2 ? Motion::kCw
                   : code == 3 ? Motion::kCcw
                               : Motion::kThread;
        break;
      case 'b':
        g.plane = code;
        break;
      case 'c':
        g.dyn = code;
        break;
      case 'd':
        g.gtl = code;
        break;
      case 'e':
        g.comp = code;
        break;
      case 'f':
        g.unit = code;
        break;
      case 'g':
        g.cycle = code;
        break;
      case 'h':
        g.absinc = code;
        break;
      case 'i':
        g.g79 = true;
        break;
      case 'j':
        (code == 4 ? g.dwell : g.decel) = true;
        break;
      case 'k':
        g.probe = code;
        break;
      case 'l':
        g.feed = code;
        break;
      case 'm':
        g.speed = code;
        break;
      default:
        break;
    }
  }
  return g;
}

void BaltRun::CheckCompatibility(const ParsedBlock& pb, const InlineVec<GCode, 16>& codes) {
  for (std::size_t i = 0; i < codes.size(); ++i) {
    for (std::size_t j = i + 1; j < codes.size(); ++j) {
      int a = codes[i].code, b = codes[j].code;
      int ca = CompatColumn(a), cb = CompatColumn(b);
      bool clash = GroupOf(a) != 0 && GroupOf(a) == GroupOf(b);
      if (cb >= 0 && CompatRow(a)[cb] == '1') clash = true;
      if (ca >= 0 && CompatRow(b)[ca] == '1') clash = true;
      if (clash) Fail(codes[j].col, 25, fmt::format("G{:02} and G{:02} in one block (Table 5.5)", a, b));
    }
  }
  // G17-G19 stand alone (ln 2956).
  for (const GCode& gc : codes) {
    const int code = gc.code, col = gc.col;
    if (code >= 17 && code <= 19 &&
        (pb.words.size() > 1 || pb.elem.kind || pb.result_e >= 0 || !pb.commands.empty())) {
      Fail(col, 25, fmt::format("G{} must be alone in its block", code));
    }
  }
}

void BaltRun::ApplyModal(const BlockG& g, const ParsedBlock& pb) {
  (void)pb;
  if (g.unit) {
    bool metric = g.unit == 71;
    if (metric != mode_.metric) {
      mode_.metric = metric;
      FrameChanged();
      if (units_emitted_) Out<UnitsOp>().metric = metric;
    }
  }
  if (g.absinc) mode_.incremental = g.absinc == 91;
  if (g.plane) {
    if (contour_.engaged() || gtl_profile_)
      Fail(g.first_col, 25, "the plane cannot change with compensation or in a GTL profile");
    static constexpr int kAxes[3][2] = {{kX, kY}, {kZ, kX}, {kY, kZ}};
    mode_.p1 = kAxes[g.plane - 17][0];
    mode_.p2 = kAxes[g.plane - 17][1];
    mode_.plane_g = g.plane;
    contour_.SetPlane(mode_.p1, mode_.p2);
    FrameChanged();
  }
  if (g.dyn) mode_.dynamic = g.dyn == 27 ? Dynamic::kG27 : (g.dyn == 28 ? Dynamic::kG28 : Dynamic::kG29);
  if (g.feed) {
    if (g.feed == 95 && !transducer_) Fail(g.first_col, 97, "G95 needs a spindle transducer");
    mode_.feed = g.feed == 93 ? FeedCode::kG93 : (g.feed == 94 ? FeedCode::kG94 : FeedCode::kG95);
  }
  if (g.speed) {
    if (g.speed == 96 && !transducer_) Fail(g.first_col, 97, "G96 needs a spindle transducer");
    bool css = g.speed == 96;
    if (css != mode_.css) {
      mode_.css = css;
      spindle_changed_ = true;  // told after the block's S word
    }
  }
  if (g.any_motion) {
    if (g.motion == Motion::kThread && !transducer_) Fail(g.first_col, 97, "G33 needs a spindle transducer");
    mode_.motion = g.motion;
  }
}

void BaltRun::EmitSpindle(SpindleDir dir) {
  spindle_ = dir;
  SpindleOp& s = Out<SpindleOp>();
  s.dir = dir;
  s.rpm = mode_.css ? 0 : speed_;
  if (mode_.css) s.css = speed_ * (mode_.metric ? 1.0 : 0.3048);  // ft/min in G70
}

void BaltRun::SpeedWord(const Word& w) {
  double s = ValueOf(w.v, w.col);
  if (s < 0.01 || s > 99999.99) Fail(w.col, 13, "S is 0.01-99999.99");
  if (!speed_set_ || s != speed_) spindle_changed_ = true;
  speed_ = s;
  speed_set_ = true;
}

// M functions active at the start of the motion (Table 5.3): spindle, coolant, orientation, axis locks,
// gear ranges; H functions (machine logic) go out with them.
void BaltRun::AuxBefore(const ParsedBlock& pb, bool moves) {
  (void)moves;
  for (const Word& w : pb.words) {
    if (w.letter == 'H') {
      double h = ValueOf(w.v, w.col);
      if (h < 0 || h > 99 || h != std::floor(h))
        Fail(w.col, 18, fmt::format("H{:g} (H codes are H00-H99)", h));
      if (!logic_h_.test(static_cast<std::size_t>(h)))
        Fail(w.col, 51,
             fmt::format("H{:02} is not a function of this machine (H_CODES)", static_cast<int>(h)));
      Out<OutputOp>().spec = fmt::format("H{:02}", static_cast<int>(h));
      continue;
    }
    if (w.letter != 'M') continue;
    int m = static_cast<int>(ValueOf(w.v, w.col));
    if (!MotionStart(m)) continue;
    switch (m) {
      case 3:
      case 4:
      case 13:
      case 14: {
        if (!speed_set_) Fail(w.col, 48, fmt::format("M{:02} without S", m));
        SpindleDir dir = (m == 3 || m == 13) ? SpindleDir::kCw : SpindleDir::kCcw;
        if (dir != spindle_) EmitSpindle(dir);
        if (m >= 13) {
          flood_with_spindle_ = true;
          if (coolant_ != CoolantMode::kFlood) {
            coolant_ = CoolantMode::kFlood;
            CoolantOp& c = Out<CoolantOp>();
            c.m = m;
            c.mode = CoolantMode::kFlood;
          }
        }
        break;
      }
      case 7:
      case 8: {
        CoolantMode mode = m == 7 ? CoolantMode::kMist : CoolantMode::kFlood;
        coolant_ = mode;
        CoolantOp& c = Out<CoolantOp>();
        c.m = m;
        c.mode = mode;
        break;
      }
      case 19: {
        // Always before the other motion of its block (ln 3735).
        spindle_ = SpindleDir::kOrient;
        SpindleOp& s = Out<SpindleOp>();
        s.dir = SpindleDir::kOrient;
        s.rpm = speed_;
        break;
      }
      default:
        MachineLogicM(m, w.col);  // M10-M12 axis locks, M41-M45 gear ranges
        break;
    }
  }
}

// M functions active at the end of the motion, in the order of the block; M02 / M30 end the program.
void BaltRun::AuxAfter(const ParsedBlock& pb) {
  int end_m = 0;
  for (const Word& w : pb.words) {
    if (w.letter != 'M') continue;
    int m = static_cast<int>(ValueOf(w.v, w.col));
    if (MotionStart(m)) continue;
    switch (m) {
      case 0:
        Out<StopOp>().m = 0;
        break;
      case 1:
        // USO=1 makes M01 a stop (Tables 4.3, 5.3; Table 2.1 says the opposite: a judgement call).
        if (optional_stop_) {
          StopOp& s = Out<StopOp>();
          s.m = 1;
          s.optional = true;
        }
        break;
      case 2:
      case 30:
        end_m = m;
        break;
      case 5:
        if (spindle_ != SpindleDir::kStop) EmitSpindle(SpindleDir::kStop);
        if (flood_with_spindle_ && coolant_ != CoolantMode::kOff) {
          coolant_ = CoolantMode::kOff;
          CoolantOp& c = Out<CoolantOp>();
          c.m = 5;
          c.mode = CoolantMode::kOff;
        }
        flood_with_spindle_ = false;
        break;
      case 6:
        ToolChange(w.col);
        break;
      case 9: {
        coolant_ = CoolantMode::kOff;
        flood_with_spindle_ = false;
        CoolantOp& c = Out<CoolantOp>();
        c.m = 9;
        c.mode = CoolantMode::kOff;
        break;
      }
      case 60:
        Out<PalletOp>().m = 60;
        break;
      default:
        MachineLogicM(m, w.col);
        break;
    }
  }
  if (end_m) FinishProgram(end_m);
}

// An M code the canon has no op of its own for goes to the machine logic as an `aux` op when the machine
// builder assigned it (Table 5.3, ln 2555-2589: "normally assigned by the machine builder", ln 2500); any
// other is FILMS4 51 UNKNOWN M OR H CODES (ln 10065).
void BaltRun::MachineLogicM(int m, int col) {
  if (!logic_m_.test(static_cast<std::size_t>(m)))
    Fail(col, 51, fmt::format("M{:02} is not a function of this machine (M_CODES)", m));
  Out<AuxOp>().m = m;
}

void BaltRun::ExecIso(const ParsedBlock& pb) {
  BlockG g = ReadGCodes(pb);
  // Word counts (ln 2699, 2706, L9992): 3 axes, 4 M, 4 H, one S, one T, one F.
  int ms = 0, hs = 0;
  std::uint32_t axes = 0;
  const Word* f = nullptr;
  const Word* s = nullptr;
  const Word* t = nullptr;
  const Word* corner = nullptr;
  int ij = 0;
  int n_axes = 0;  // std::popcount(axes) without a libgcc call per word (no -mpopcnt)
  for (const Word& w : pb.words) {
    int a = AxisOfLetter(w.letter);
    if (a >= 0) {
      if (axes & (1u << a)) Fail(w.col, 24, fmt::format("axis {} twice", w.letter));
      axes |= 1u << a;
      if (++n_axes > 3) Fail(w.col, 23, "more than 3 axes in a block");  // no axis twice: the bits set
      continue;
    }
    switch (w.letter) {
      case 'M': {
        if (++ms > 4) Fail(w.col, 23, "more than 4 M functions in a block");
        double m = ValueOf(w.v, w.col);
        if (m < 0 || m != std::floor(m)) Fail(w.col, 13, fmt::format("M{:g}", m));
        if (m > 99) Fail(w.col, 18, fmt::format("M{:g} (M codes are M00-M99)", m));
        break;
      }
      case 'H':
        if (++hs > 4) Fail(w.col, 23, "more than 4 H functions in a block");
        break;
      case 'F':
        if (f) Fail(w.col, 24, "F twice");
        f = &w;
        break;
      case 'S':
        if (s) Fail(w.col, 24, "S twice");
        s = &w;
        break;
      case 'T':
        if (t) Fail(w.col, 24, "T twice");
        t = &w;
        break;
      case 'I':
      case 'J':
        ++ij;
        break;
      case 'r':
      case 'b':
        if (corner) Fail(w.col, 24, "one corner word per block");
        corner = &w;
        break;
      case 'P':
      case 'Q':
      case 'D':
        Fail(w.col, 24, fmt::format("axis {} is not configured on this machine", w.letter));
      default:
        break;
    }
  }
  if (g.count) ApplyModal(g, pb);  // without G codes it changes nothing
  if (g.comp || contour_.on() || g.gtl || gtl_profile_) CompCodes(g, pb);
  if (f) {
    double v = ValueOf(f->v, f->col);
    if (v < 0.01 || v > 99999.99) Fail(f->col, 13, "F is 0.01-99999.99");
    if (mode_.feed == FeedCode::kG93) {
      block_feed_ = v;
    } else {
      feed_ = v * UnitFactor();
    }
  }
  if (s) SpeedWord(*s);
  if (spindle_changed_) {
    // A new speed or speed mode while the spindle turns (docs/canonical-commands.md: spindle).
    spindle_changed_ = false;
    if (spindle_ == SpindleDir::kCw || spindle_ == SpindleDir::kCcw) EmitSpindle(spindle_);
  }
  if (t) ToolWord(*t);
  const bool motion_words = axes != 0 || pb.elem.kind || ij > 0 || pb.s2;
  if (ms || hs) AuxBefore(pb, motion_words);

  if (g.probe) {
    Probe(pb, g, ReadTargets(pb, mode_.incremental, false));
  } else if (gtl_profile_ || g.gtl) {
    gtl_block_ = true;
    Targets tg = ReadTargets(pb, mode_.incremental, false);
    gtl_block_ = false;
    GtlBlock(pb, g, tg);
  } else if (g.cycle >= 81) {
    DeclareCycle(pb, g);
  } else if (mode_.cycle != 80 && g.cycle != 80) {
    CycleBlock(pb, g, ReadTargets(pb, mode_.incremental, true));
  } else if (corner && axes == 0 && !pb.elem.kind) {
    if (corner->letter == 'r' && ij == 0) {
      if (!contour_.engaged()) Fail(corner->col, 77, "a radius word needs the move before it");
      const double r = ValueOf(corner->v, corner->col) * UnitFactor() * PlaneScale();
      try {
        contour_.Corner('r', r, cur_line_);
      } catch (const ContourError& e) {
        Fail(corner->col, e.code, e.text);  // "two corner words in a row", a radius after a virtual point
      }
    } else {
      if (!contour_.engaged()) Fail(corner->col, 77, "a bevel word needs the move before it");
      double v = ValueOf(corner->v, corner->col);
      if (corner->v.neg) Fail(corner->col, 13, "a bevel is written without a sign");
      try {
        contour_.Corner('b', v * UnitFactor() * PlaneScale(), cur_line_);
      } catch (const ContourError& e) {
        Fail(corner->col, e.code, e.text);
      }
    }
  } else {
    if (g.cycle == 80) {
      mode_.cycle = 80;
      cycle_ = Cycle();
    }
    Targets tg = ReadTargets(pb, mode_.incremental, true);
    bool arc = mode_.motion == Motion::kCw || mode_.motion == Motion::kCcw;
    if (tg.mask || (arc && ij > 0)) Move(pb, g, tg);
  }
  if (g.dwell) EmitDwell(tmr_);  // G04: TMR seconds at the end of the block (ln 3635)
  if (ms) AuxAfter(pb);
  hold_next_ = false;
}

}  // namespace cell::interp::balt
