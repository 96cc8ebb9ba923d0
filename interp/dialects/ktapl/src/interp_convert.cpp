// KT-APL Type I blocks (manual ch. 2, 3, 5, 8): the block's G codes (modal state, cycles, probing), parameter
// passing to defined cycles (letters A-Z -> L801-L826), T, S and M codes, the feed, and the order in which a
// block acts: immediate M codes, the motion, then the after-type M code.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "interp_internal.h"

namespace cell::interp::ktapl {

Word KtRun::EvalWord(const RawWord& w, bool dwell, bool passing, bool drop_undefined, bool& dropped) {
  Word r;
  r.letter = w.letter;
  r.col = w.col;
  dropped = false;
  try {
    switch (w.kind) {
      case WordKind::kNumber:
        r.literal = true;
        r.num = w.num;
        r.v = ScaleLiteral(w.letter, w.num, metric_, dwell, passing);
        r.neg_zero = w.num.neg && w.num.as_written == 0;
        return r;
      case WordKind::kParam:
        r.v = Param(w.param);
        break;
      case WordKind::kNegParam:
        r.v = -Param(w.param);
        break;
      case WordKind::kExpr:
        r.v = EvalValue(w.expr, *this);
        break;
    }
  } catch (const ExprError& e) {
    // G78: words that refer to undefined parameters are dropped silently.
    if (drop_undefined && e.text.rfind("Error L number NOT in table", 0) == 0) {
      dropped = true;
      return r;
    }
    Fail(w.kind == WordKind::kExpr ? ExprCol(w.expr, e.offset, w.col) : w.col, e.text);
  }
  if (IntegerLetter(w.letter)) r.v = std::floor(r.v + 0.5);
  return r;
}

// The G codes that only set a mode (or do nothing here); false for the others.
bool KtRun::ModeGCode(int g) {
  switch (g) {
    case 0:
      mode_.contouring = false;
      break;
    case 1:
      mode_.contouring = true;
      break;
    case 28:
      mode_.obstruction_detection = true;
      break;
    case 29:
      mode_.obstruction_detection = false;
      break;
    case 36:
      mode_.inspection_recording = true;
      break;
    case 39:
      mode_.calculated_offsets = false;
      break;
    case 47:
      if (!mode_.calculated_offsets) calc_b_ = pos_[kB];  // calculated for where the table stands
      mode_.calculated_offsets = true;
      break;
    case 48:
      mode_.explicit_fixtures = true;
      break;
    case 49:
      mode_.explicit_fixtures = false;
      break;
    case 50:  // adaptive control off: the state the cell is always in (judgement call 80)
      mode_.adaptive = Adaptive::kOff;
      break;
    case 90:
      mode_.incremental = false;
      break;
    case 91:
      mode_.incremental = true;
      break;
    case 93:
      mode_.inverse_time = true;
      break;
    case 94:
      mode_.inverse_time = false;
      break;
    case 4:   // the block's dwell (BlockCodes::dwell)
    case 70:  // units: before the block's words are read
    case 71:
    case 79:
      break;
    default:
      return false;
  }
  return true;
}

// Codes the manual defines that the cell cannot honour: refused rather than accepted without their effect
// (docs/dialects/ktapl.md, "Refused codes"; judgement calls 79-80).
void KtRun::RefusedGCode(int g, int col) {
  switch (g) {
    case 44:  // ln 1654
      Fail(col,
           "G44 IS NOT AVAILABLE: FEEDRATE AT THE TOOL CENTERLINE ON COMPENSATED ARCS IS NOT "
           "IMPLEMENTED");
    case 52:  // ln 1740
      Fail(col, "G52 IS NOT AVAILABLE: THE CELL CANNOT MEASURE SPINDLE HORSEPOWER FOR CALIBRATION");
    default:  // G51, G53: ln 1728-1774
      Fail(col, fmt::format("G{} IS NOT AVAILABLE: ADAPTIVE CONTROL NEEDS SPINDLE HORSEPOWER, WHICH THE "
                            "CELL CANNOT MEASURE",
                            g));
  }
}

// G40-G46: the compensation codes of the block (acted on by CompPrepare).
void KtRun::CompGCode(int g, int col) {
  switch (g) {
    case 40:
    case 41:
    case 42:
      if (comp_codes_.g && comp_codes_.g != g) Fail(col, "G40, G41 AND G42 CANNOT BE IN THE SAME BLOCK");
      comp_codes_.any = true;
      comp_codes_.g = g;
      comp_codes_.g_col = col;
      break;
    case 43:
      comp_codes_.any = comp_codes_.g43 = true;
      break;
    case 46:
      comp_codes_.any = comp_codes_.g46 = true;
      comp_codes_.g46_col = col;
      break;
    default:
      break;
  }
}

void KtRun::ConvertGCodes(const GWords& gs, bool pass800, BlockCodes& k) {
  bool plane_set = false, b20 = false, b21 = false;
  for (auto [g, col] : gs) {
    if (pass800 && !(g == 77 || g == 78 || g == 70 || g == 71 || g == 80 || g == 800 ||
                     (g >= 801 && g <= 899) || (g >= 81 && g <= 89) || (g >= 24 && g <= 27))) {
      k.passed.push_back({g, col});
      continue;
    }
    if (ModeGCode(g)) continue;
    switch (g) {
      case 2:
      case 3:
        k.arc = g;
        k.arc_col = col;
        break;
      case 17:
        mode_.plane = geom::Plane::kXY;
        plane_set = true;
        break;
      case 18:
        mode_.plane = geom::Plane::kZX;
        plane_set = true;
        break;
      case 19:
        mode_.plane = geom::Plane::kYZ;
        plane_set = true;
        break;
      case 20:
        b20 = true;
        break;
      case 21:
        b21 = true;
        break;
      case 22:
      case 23:
        k.probe = true;
        k.probe_g = g;
        break;
      case 24:
      case 25:
      case 26:
      case 27:
        k.probe_cycle = g;
        break;
      case 37:
        CloseOpenFile(col, true);
        mode_.inspection_recording = false;
        break;
      case 33:
        k.g33_col = col;
        break;
      case 38:
        k.g38_col = col;
        break;
      case 40:
      case 41:
      case 42:
      case 43:
      case 46:
        CompGCode(g, col);
        break;
      case 60:
      case 61:
      case 62:
        mode_.probe_count =
            g == 60 ? ProbeCount::kOff : (g == 61 ? ProbeCount::kContacts : ProbeCount::kBreaks);
        if (g != 60) machine_[1022] = 0;
        break;
      case 77:
        k.inhibit_cycle = true;
        break;
      case 78:
        k.drop_undefined = true;
        break;
      case 80:
      case 800:
        k.cancel = true;
        mode_.cycle = 0;
        for (auto it = program_.lower_bound(800); it != program_.end() && it->first <= 899;) {
          it = program_.erase(it);
        }
        break;
      case 92:
        k.g92 = true;
        break;
      case 98:
        k.g98 = true;
        break;
      case 99:
        k.g99 = true;
        break;
      case 44:
      case 51:
      case 52:
      case 53:
        RefusedGCode(g, col);
      default:
        if ((g >= 81 && g <= 89) || (g >= 801 && g <= 899)) {
          if (RunningCycle()) Fail(col, "A RUNNING DEFINED CYCLE CANNOT CALL ANOTHER CYCLE");
          if (mode_.plane != geom::Plane::kXY && g <= 89) Fail(col, "FIXED CYCLES WORK ONLY IN G17");
          mode_.cycle = g;
          break;
        }
        Fail(col, fmt::format("ILLEGAL G CODE G{}", g));
    }
  }
  // G20/G21 go with a plane code; without one they add to the co-axis substitution in force.
  if (plane_set) {
    mode_.coaxis_first = b20;
    mode_.coaxis_second = b21;
  } else {
    if (b20) mode_.coaxis_first = true;
    if (b21) mode_.coaxis_second = true;
  }
}

bool KtRun::PassCycleParameters(const RawWords& raw, const BlockCodes& k, const ParsedBlock* pb,
                                bool drop_undefined, uint32_t axis_mask, Words& words) {
  const bool series800 = mode_.cycle >= 801;
  for (const auto& rw : raw) {
    char l = rw.letter;
    if (l == 'G') continue;
    if (!series800 && !(l == 'A' || l == 'B' || l == 'C' || l == 'E' || l == 'F' || l == 'R' || l == 'X' ||
                        l == 'Y' || l == 'Z')) {
      continue;
    }
    bool dropped;
    Word w = EvalWord(rw, false, true, drop_undefined, dropped);
    if (dropped) continue;
    if (w.literal && w.neg_zero && (l == 'A' || l == 'B' || l == 'C')) w.v = -360.0;
    SetParam(800 + (l - 'A') + 1, w.v, rw.col);
  }
  if (series800 && !k.passed.empty()) SetParam(807, k.passed.back().code, k.passed.back().col);
  if (series800 && pb && pb->has_n) SetParam(814, ScaleLiteral('N', pb->n, metric_, false, true), 1);
  const uint32_t cycle_axes = (1u << kX) | (1u << kY) | (1u << kZ) | (1u << kA) | (1u << kB) | (1u << kC);
  const bool trigger = (axis_mask & cycle_axes) != 0;
  if (series800 && !trigger) {
    // A block without X Y Z A B C only passes its letters; its M, S, T and F still act (so that, for
    // example, M30 ends the program while a G800-series cycle is pending). Axis words do not move.
    words.erase(
        std::remove_if(words.begin(), words.end(), [](const Word& w) { return AxisOfLetter(w.letter) >= 0; }),
        words.end());
  }
  return trigger;
}

BlockMCodes KtRun::ReadMCodes(const Words& words, bool trigger) {
  BlockMCodes mc;
  for (const auto& m : words) {
    if (m.letter != 'M') continue;
    int code = static_cast<int>(m.v);
    switch (code) {
      case 0:
      case 1:
      case 2:
      case 5:
      case 6:
      case 9:
      case 23:
      case 24:
      case 30:
      case 60:
        if (mc.after >= 0) Fail(m.col, "ONLY ONE AFTER-TYPE M CODE IS ALLOWED PER BLOCK");
        mc.after = code;
        mc.after_col = m.col;
        if (code == 6) mc.m06 = true;
        break;
      case 19:
        mc.m19 = true;
        break;
      case 25:
        mc.m25 = true;
        break;
      case 99:
        mc.m99 = true;
        break;
      case 3:
      case 4:
      case 7:
      case 8:
      case 20:
      case 21:
      case 26:
      case 27:
      case 28:
      case 29:
      case 40:
      case 48:
      case 49:
      case 51:
      case 52:
      case 57:
      case 58:
      case 59:
        break;
      default:
        Fail(m.col, fmt::format("ILLEGAL M CODE M{}", code));
    }
  }
  if (trigger && mc.after >= 0) Fail(mc.after_col, "AFTER-TYPE M CODES ARE NOT ALLOWED IN A CYCLE BLOCK");
  return mc;
}

namespace {

const Word* Find(const Words& words, char l) {
  const Word* r = nullptr;
  for (const auto& w : words) {
    if (w.letter == l) r = &w;
  }
  return r;
}

// ln 5037, 5045: M30 and M60 "must be programmed in a block by itself" (an N number, a label and a comment
// aside). An M30 that is an IFT action is the action's only item.
void CheckAloneInBlock(const ParsedBlock& pb, const BlockMCodes& mc) {
  const bool own = std::any_of(pb.words.begin(), pb.words.end(),
                               [&](const RawWord& w) { return w.letter == 'M' && w.col == mc.after_col; });
  if (!own) return;
  const bool others =
      pb.words.size() > 1 ||
      std::any_of(pb.stmts.begin(), pb.stmts.end(), [](const Statement& st) { return st.mnemonic != "LBL"; });
  if (others) Fail(mc.after_col, fmt::format("M{} MUST BE PROGRAMMED IN A BLOCK BY ITSELF", mc.after));
}

}  // namespace

void KtRun::ToolAndSpeed(const Words& words, const BlockMCodes& mc, bool s_is_flutes) {
  if (const Word* t = Find(words, 'T')) {
    if (t->v < 0 || t->v > 9999999) Fail(t->col, "T WORD OUT OF RANGE 1-9999999");
    selected_tool_ = ToolName(t->v);
    Out<ToolSelectOp>().tool = selected_tool_;
  }
  bool speed_changed = false;
  const Word* s = s_is_flutes ? nullptr : Find(words, 'S');
  if (s && !mc.m19) {
    if (s->v < 0 || s->v > 99999) Fail(s->col, "S WORD OUT OF RANGE 0-99999");
    speed_changed = s->v != speed_;
    speed_ = s->v;
    mode_.tapping_range = false;
  }
  ImmediateMCodes(words, speed_changed, s, mc.after == 0);
}

void KtRun::ImmediateMCodes(const Words& words, bool speed_changed, const Word* s, bool m00) {
  const bool running = mode_.spindle == SpindleDir::kCw || mode_.spindle == SpindleDir::kCcw;
  bool dir_given = false;
  for (const auto& m : words) {
    if (m.letter != 'M') continue;
    int code = static_cast<int>(m.v);
    switch (code) {
      case 3:
      case 4: {
        mode_.spindle = code == 3 ? SpindleDir::kCw : SpindleDir::kCcw;
        dir_given = true;
        SpindleOp& c = Out<SpindleOp>();
        c.dir = mode_.spindle;
        c.rpm = speed_;
        break;
      }
      case 19: {
        mode_.spindle = SpindleDir::kOrient;
        SpindleOp& c = Out<SpindleOp>();
        c.dir = SpindleDir::kOrient;
        c.rpm = speed_;
        c.angle = s ? s->v : 0;  // M19 S: the keylock angle
        break;
      }
      case 7:
      case 8:
      case 51:
      case 52:
      case 57:
      case 58:
      case 59: {
        static const std::map<int, CoolantMode> kModes = {
            {7, CoolantMode::kMist},     {8, CoolantMode::kFlood},    {51, CoolantMode::kWashFlood},
            {52, CoolantMode::kWashAir}, {57, CoolantMode::kAuxMist}, {58, CoolantMode::kAuxFlood},
            {59, CoolantMode::kAuxPulse}};
        CoolantMode mode = kModes.at(code);
        if (code == 7 || code == 8) mode_.coolant = mode, mode_.aux_coolant = CoolantMode::kOff;
        if (code >= 57) mode_.aux_coolant = mode;  // ln 2987-3057: one optional coolant at a time
        if (code == 51) mode_.wash_flood = true, mode_.wash_air = false;
        if (code == 52) mode_.wash_air = true, mode_.wash_flood = false;
        CoolantOp& c = Out<CoolantOp>();
        c.m = code;
        c.mode = mode;
        break;
      }
      case 20:
      case 21:
      case 26:
      case 27:
      case 28:
      case 29:
      case 40:
      case 48:
      case 49:
        if (code == 20 || code == 21) mode_.secondary_probe = code == 21;
        if (code == 26 || code == 27) mode_.b_clamp_off = code == 27;
        if (code == 28 || code == 29) mode_.c_clamp_off = code == 29;
        if (code == 40) mode_.tapping_range = true;
        if (code == 48 || code == 49) mode_.overrides_locked = code == 49;
        Out<AuxOp>().m = code;
        // M49 forces feed and spindle speed to 100 %, M48 gives the selectors back (ln 2896-2937): the
        // control's own effect, after the machine-logic signal (call 83).
        if (code == 48 || code == 49) Out<OverridesOp>().fixed = code == 49;
        break;
      case 99: {
        // With M00 in the block and an operator at the machine the program stops with the block's comment
        // shown (E20, ln 3078-3094): the comment is the alarm's message.
        std::string text = "M99 alarm - see MAIN display";
        if (operator_ && m00 && !block_comment_.empty()) text += ": " + block_comment_;
        Out<AlarmOp>().text = text;
        break;
      }
      default:
        break;
    }
  }
  if (speed_changed && running && !dir_given) {
    SpindleOp& c = Out<SpindleOp>();
    c.dir = mode_.spindle;
    c.rpm = speed_;
  }
}

namespace {

// Does the block run in G800-series passing mode? A probe cycle (G24-G27) takes the block's other G codes
// as L807 and its letters as L801-L826, as the G800-series cycles do (App. E checks that there are none:
// "NO OTHER M OR G CODES ALLOWED").
bool PassesLetters(const GWords& gs, int cycle, bool running_cycle, bool g77) {
  int new_cycle = cycle;
  for (auto [g, col] : gs) {
    (void)col;
    if (g == 80 || g == 800) new_cycle = 0;
    if ((g >= 81 && g <= 89) || (g >= 801 && g <= 899)) new_cycle = g;
  }
  const bool probe_block =
      std::any_of(gs.begin(), gs.end(), [](GWord g) { return g.code >= 24 && g.code <= 27; });
  return (!running_cycle && !g77 && new_cycle >= 801) || probe_block;
}

// Column of the block's first axis word (1 without one).
int MotionCol(const Words& words) {
  for (const auto& w : words) {
    if (AxisOfLetter(w.letter) >= 0) return w.col;
  }
  return 1;
}

}  // namespace

// G codes first: they decide the units and the cycle mode of the block.
void KtRun::ReadGWords(const RawWords& raw, bool drop_undefined, GWords& gs) {
  for (const auto& w : raw) {
    if (w.letter != 'G') continue;
    if (w.kind == WordKind::kNumber && !w.num.point && !w.num.neg && w.num.digits <= 2) {
      // G0-G99 as written (most G words): what EvalWord and the format check give it, without them.
      gs.push_back({static_cast<int>(w.num.as_written), w.col});
      continue;
    }
    bool dropped;
    Word g = EvalWord(w, false, false, drop_undefined, dropped);
    if (dropped) continue;
    CheckWordFormat(g, metric_);
    if (g.v < 0 || g.v > 999) Fail(w.col, "ILLEGAL G CODE");
    gs.push_back({static_cast<int>(g.v), w.col});
  }
  bool has70 = false, has71 = false;
  for (const GWord& g : gs) {
    has70 = has70 || g.code == 70;
    has71 = has71 || g.code == 71;
  }
  if (has70 && has71) Fail(gs.front().col, "G70 AND G71 CANNOT BE IN THE SAME BLOCK");
  if (has70) SetUnits(false);
  if (has71) SetUnits(true);
  // The run's unit mode at start: the basic state, or the G70/G71 of the first Type I block.
  EmitUnitsOnce();
}

// The axis words of the block as a mask; E I J K P Q R H D stay as the letters' values.
uint32_t KtRun::KeepLetters(const Words& words) {
  uint32_t axis_mask = 0;
  block_d_ = false;
  for (const auto& w : words) {
    int a = AxisOfLetter(w.letter);
    if (a >= 0) axis_mask |= 1u << a;
    if (w.letter == 'E' || w.letter == 'I' || w.letter == 'J' || w.letter == 'K' || w.letter == 'P' ||
        w.letter == 'Q' || w.letter == 'R' || w.letter == 'H' || w.letter == 'D') {
      letters_[w.letter - 'A'] = w.v;
      if (w.letter == 'D') block_d_ = true;
    }
  }
  return axis_mask;
}

// A probe cycle block: its letters to L801-L826, its other G code to L807, then the cycle.
void KtRun::ProbeCycleBlock(const RawWords& raw, const BlockCodes& k, const ParsedBlock* pb,
                            bool drop_undefined, bool running_cycle) {
  if (running_cycle) Fail(1, "PROBE CYCLES CANNOT BE CALLED FROM A CYCLE");
  for (const auto& rw : raw) {
    if (rw.letter == 'G') continue;
    bool dropped;
    Word w = EvalWord(rw, false, true, drop_undefined, dropped);
    if (!dropped) SetParam(800 + (rw.letter - 'A') + 1, w.v, rw.col);
  }
  if (!k.passed.empty()) SetParam(807, k.passed.back().code, k.passed.back().col);
  // The block's N number, passed as X.4: the cycles write it back as N<L814*10000> (App. E).
  if (pb && pb->has_n) SetParam(814, ScaleLiteral('N', pb->n, metric_, false, true), 1);
  CallCycle(k.probe_cycle);
}

// The F word: G94's feed (its linear or rotary format is decided with the move), or G93's for this block.
std::optional<double> KtRun::BlockFeed(const Word* f, const BlockCodes& k, const BlockMCodes& mc) {
  if (!f || k.dwell || mc.m06 || mc.m25) return std::nullopt;
  if (f->v < 0) Fail(f->col, "FEEDRATE MAY NOT BE NEGATIVE");
  if (!mode_.inverse_time) {
    feed_ = f->v;
    return std::nullopt;
  }
  // Table 1-B: G93 is 3.1 in inch and 5.1 in metric, so a metric F without a point has one decimal.
  Word fw = *f;
  if (fw.literal && !fw.num.point && metric_) fw.v = fw.num.as_written / 10;
  CheckFeedFormat(fw, FeedFormat::kInverseTime, metric_);
  return fw.v;
}

// H word: fixture offsets.
void KtRun::FixtureWord(const Words& words) {
  const Word* h = Find(words, 'H');
  if (!h) return;
  int hv = static_cast<int>(h->v);
  if (hv < 0 || hv > 32) Fail(h->col, "H WORD OUT OF RANGE 0-32");
  if (hv != 0 && !mode_.explicit_fixtures)
    Fail(h->col, "H WORD NOT ALLOWED IN G49 (IMPLICIT FIXTURE OFFSET) MODE");
  active_h_ = hv;
  calc_b_ = pos_[kB];  // G47: the line is calculated for where the table stands
}

// ln 1183-1185: P0 leaves the tool length compensation out of the block's targets (M25, the preferred
// form, leaves out every offset). The manual defines no other P in a Type I block (judgement call 78).
bool KtRun::LengthBypass(const Words& words, bool arc) {
  const Word* p = Find(words, 'P');
  if (!p) return false;
  if (p->v != 0) Fail(p->col, "ONLY P0 (LENGTH COMPENSATION BYPASS) IS DEFINED FOR THE P WORD");
  if (arc) Fail(p->col, "P0 IS NOT ALLOWED IN A CIRCULAR BLOCK");
  return true;
}

// G33 (ln 7247-7322): modal until a feedrate is programmed ("F COMMAND CANCELS G33" in its own block); E the
// lead per spindle revolution, required in the G33 block and modal after it; D the change of the lead per
// revolution, in G33 only, for its own block (judgement call 89); only Z and U may move.
void KtRun::ThreadWords(const Words& words, const BlockCodes& k, const Word* f, uint32_t axis_mask,
                        bool passes) {
  thread_block_ = false;
  thread_change_ = 0;
  if (passes) return;  // the letters of a cycle call are the cycle's values
  const Word* e = Find(words, 'E');
  const Word* d = Find(words, 'D');
  if (k.g33_col) {
    if (f) Fail(f->col, "F COMMAND CANCELS G33");
    if (!e) Fail(k.g33_col, "LEAD SPECIFICATION REQUIRED");
    if (!mode_.threading) thread_angle_ = 0;
    mode_.threading = true;
  } else if (f && mode_.threading) {
    mode_.threading = false;  // ln 7251: "cleared ... thru programming a feedrate"
  }
  if (d) {
    if (!mode_.threading) Fail(d->col, "D COMMAND ALLOWED IN G33 ONLY");
    if (d->v < 0) Fail(d->col, "FEEDRATE IS 0 BEFORE END POINT IS REACHED");
    thread_change_ = ToMm(d->v);
  }
  if (!mode_.threading) return;
  if (e) {
    if (e->v <= 0) Fail(e->col, "LEAD SPECIFICATION REQUIRED");
    thread_lead_ = ToMm(e->v);
  }
  for (const auto& w : words) {
    int a = AxisOfLetter(w.letter);
    if (a >= 0 && a != kZ && a != kU) Fail(w.col, "ILLEGAL THREADING AXIS");
  }
  if (k.arc) Fail(k.arc_col, "CIRCULAR MOVES ARE NOT ALLOWED IN G33");
  if (k.probe || k.dwell) Fail(k.g33_col ? k.g33_col : 1, "G33 ALLOWS ONLY Z AND U MOVES");
  if (axis_mask && mode_.obstruction_detection) Fail(MotionCol(words), "G33 MOVES ARE NOT ALLOWED IN G28");
  thread_block_ = axis_mask != 0;
}

void KtRun::ExecTypeI(BlockCtx& bc, const ParsedBlock* pb) {
  const auto& raw = bc.words;
  if (raw.empty()) return;
  const bool drop_undefined = std::any_of(raw.begin(), raw.end(), [](const RawWord& w) {
    return w.letter == 'G' && w.kind == WordKind::kNumber && !w.num.point && w.num.as_written == 78;
  });
  GWords gs;  // fits: one per raw word
  ReadGWords(raw, drop_undefined, gs);
  const bool running_cycle = RunningCycle();
  bool g77 = false, g04 = false;
  for (const GWord& g : gs) {
    g77 = g77 || g.code == 77;
    g04 = g04 || g.code == 4;
  }
  const bool pass800 = PassesLetters(gs, mode_.cycle, running_cycle, g77);

  BlockCodes k;
  k.dwell = g04;
  Words words;
  // The letters of `words` (bit 0 A): the work for M, S, T, F, H, P only in blocks with them.
  uint32_t letters = 0;
  for (const auto& w : raw) {
    if (w.letter == 'G') continue;
    bool dropped;
    Word r = EvalWord(w, k.dwell, false, drop_undefined, dropped);
    if (dropped) continue;
    // Letters passed to a G800-series or probe cycle are parameters in the passing formats (ln 8945-8983).
    if (!pass800) CheckWordFormat(r, metric_);
    words.push_back(r);
    letters |= 1u << (r.letter - 'A');
  }
  auto has = [letters](char l) { return (letters & (1u << (l - 'A'))) != 0; };
  ConvertGCodes(gs, pass800, k);

  uint32_t axis_mask = KeepLetters(words);
  const int motion_col = MotionCol(words);
  if (comp_codes_.any || comp_.engaged()) [[unlikely]] {
    CompPrepare(words, motion_col, running_cycle, k.probe || k.probe_cycle != 0, k.g92);
  }

  if (k.probe_cycle) {
    ProbeCycleBlock(raw, k, pb, drop_undefined, running_cycle);
    return;
  }

  // Cycle parameter passing (manual ch. 8: letters A-Z -> L801-L826). M25 / M06 blocks move in machine
  // coordinates and never run a pending cycle.
  bool trigger = false;
  const bool machine_block = has('M') && std::any_of(words.begin(), words.end(), [](const Word& w) {
                               return w.letter == 'M' && (w.v == 25 || w.v == 6);
                             });
  const bool passes_letters = mode_.cycle >= 801 && !running_cycle && !g77 && !machine_block;
  if (mode_.cycle != 0 && !running_cycle && !g77 && !machine_block) {
    trigger = PassCycleParameters(raw, k, pb, drop_undefined, axis_mask, words);
    if (mode_.cycle >= 801) {
      if (trigger) {
        CallCycle(mode_.cycle);
        return;  // nothing of a triggering G800-series block is executed by the control
      }
      axis_mask = 0;  // its axis words were removed: they only pass values
    }
  }

  const BlockMCodes mc = has('M') ? ReadMCodes(words, trigger) : BlockMCodes{};
  if ((mc.after == 30 || mc.after == 60) && pb) CheckAloneInBlock(*pb, mc);
  // ln 7082: "G38 S16", S the flutes of the cutter.
  if (has('T') || has('S') || has('M')) ToolAndSpeed(words, mc, k.g38_col != 0);

  const Word* f = has('F') ? Find(words, 'F') : nullptr;
  if (k.g33_col || mode_.threading || block_d_) [[unlikely]]
    ThreadWords(words, k, f, axis_mask, trigger || passes_letters);
  const std::optional<double> block_feed = BlockFeed(f, k, mc);

  if (trigger) {
    // P0 would have to reach into the cycle body's moves (ln 1185): refused, never ignored (call 78).
    if (const Word* p = Find(words, 'P')) Fail(p->col, "P0 IS NOT ALLOWED IN A FIXED CYCLE BLOCK");
    // G80-series: everything but the passed letters has been executed; run the cycle body.
    CallCycle(mode_.cycle);
    return;
  }
  if (has('H')) FixtureWord(words);
  if (k.g38_col) CheckTool(Find(words, 'S'));  // where the block before left the tool (ln 7061-7090)
  length_bypass_ = !passes_letters && has('P') && LengthBypass(words, k.arc != 0);
  Motion(words, k, mc, axis_mask, motion_col, f, block_feed);
  length_bypass_ = false;
  thread_block_ = false;
  AfterMCode(mc);
  if (mc.m99 && mc.after == 0 && !operator_) {
    // In cycle and library code the operator cannot see the block: its comment is the message (App. E
    // puts each error's text there: "! ERROR: PROBE DID NOT MAKE CONTACT WITH SURFACE").
    std::string text = "M99 alarm - see MAIN display (program stopped by M99 M00)";
    if (!cur_own_ && !block_comment_.empty()) text += ": " + block_comment_;
    Fail(1, text, "M99");
  }
  // A cycle body that cancels the cycle has finished: App. E's probe cycles leave each branch with
  // GL843G800 ("restoring G90/G91 and cancelling the cycle") and the next branch follows in the text.
  if (k.cancel && running_cycle) bc.cycle_return = true;
}

void KtRun::AfterMCode(const BlockMCodes& mc) {
  switch (mc.after) {
    case 0:
    case 1: {
      if (mc.after == 1 && !optional_stop_) break;
      StopOp& c = Out<StopOp>();
      c.m = mc.after;
      c.optional = mc.after == 1;
      if (mode_.spindle == SpindleDir::kCw || mode_.spindle == SpindleDir::kCcw)
        mode_.spindle = SpindleDir::kStop;
      mode_.coolant = CoolantMode::kOff;
      mode_.aux_coolant = CoolantMode::kOff;
      break;
    }
    case 5: {
      mode_.spindle = SpindleDir::kStop;
      SpindleOp& c = Out<SpindleOp>();
      c.dir = SpindleDir::kStop;
      c.rpm = speed_;
      break;
    }
    case 6:
      ChangeTool(mc.after_col);
      if (mode_.spindle == SpindleDir::kCw || mode_.spindle == SpindleDir::kCcw)
        mode_.spindle = SpindleDir::kStop;
      if (mode_.overrides_locked) Out<OverridesOp>().fixed = false;  // "M49 is canceled by M06" (ln 2937)
      mode_.overrides_locked = false;
      break;
    case 9: {
      mode_.coolant = CoolantMode::kOff;
      mode_.aux_coolant = CoolantMode::kOff;
      mode_.wash_flood = mode_.wash_air = false;
      CoolantOp& c = Out<CoolantOp>();
      c.m = 9;
      c.mode = CoolantMode::kOff;
      break;
    }
    case 23:
    case 24:
      mode_.z_prime_retracted = mc.after == 24;
      Out<AuxOp>().m = mc.after;
      break;
    case 60:
      Out<PalletOp>().m = 60;
      mode_.contouring = false;
      u88_x_ = 0.254;
      u88_y_ = 0;
      break;
    case 2:
    case 30: {
      EndOp& c = Out<EndOp>();
      c.m = mc.after;
      c.shuttle = mc.after == 30;
      ResetAtEnd();
      Finish(Step::kEnd);
      break;
    }
    default:
      break;
  }
}

}  // namespace cell::interp::ktapl
