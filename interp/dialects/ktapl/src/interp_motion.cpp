// KT-APL motion (manual ch. 2, 5, 6): offsets (floating zero G98, fixture lines, tool length on Z), dwell,
// regrid G92, linear moves with rotary and index-table axes, implicit fixture offsets (G49), probe moves
// G22/G23 (queue busters), and the reset at program end.
#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>

#include "interp_internal.h"

namespace cell::interp::ktapl {

double KtRun::Offset(int axis) const {
  double o = g98_[axis] + FixtureOffset(axis);
  if (axis == kZ) o += tool_len_;
  return o;
}

// The active fixture line's offset on an axis. G47: the line's X/Z offset turns with the table from its
// initial B (the line's I) to the B of the last positioning; ln 6296: X-.5 Z-.75 at B20, B to 110 gives
// X.75 Z-.5 (judgement call 77).
double KtRun::FixtureOffset(int axis) const {
  if (active_h_ <= 0) return 0;
  const FixtureLine& f = fixtures_[active_h_];
  if (!mode_.calculated_offsets || (axis != kX && axis != kZ)) [[likely]]
    return f.v[axis];
  const double d = (calc_b_ - (f.has_i ? f.i : 0)) * kPi / 180;
  const double c = std::cos(d), s = std::sin(d);
  return axis == kX ? f.v[kX] * c - f.v[kZ] * s : f.v[kX] * s + f.v[kZ] * c;
}

// The fixture line of a block that moves B, before the block's linear targets are final. G49: a G90 G00
// move of B to a listed I position selects that line. G47: a positioning move of B recalculates the line
// in force for the new B (ln 6288-6290; "not applied dynamically during machining", ln 6278), and a B
// position no line lists keeps it. The block's linear targets are re-based on the new offsets.
void KtRun::RebaseFixtures(const Words& words, const BlockMCodes& mc, uint32_t axis_mask, bool positioning,
                           AxisArray& target) {
  const bool calc = mode_.calculated_offsets && positioning;
  if (calc && active_h_ > 0) {
    for (const auto& w : words) {
      // The manual gives the calculation for B only (ln 6296); A/C would turn other axes (call 77).
      if (w.letter == 'A' || w.letter == 'C')
        Fail(w.col, "G47 CALCULATED FIXTURE OFFSETS ARE DEFINED FOR THE B AXIS ONLY");
    }
  }
  if (!(axis_mask & (1u << kB))) return;
  int h = active_h_;
  if (!mode_.explicit_fixtures && !mode_.incremental && !mode_.contouring && !mc.m25) {
    int hit = 0;
    for (int n = 1; n <= kFixtureLines; ++n) {
      if (fixtures_[n].set && fixtures_[n].has_i && std::fabs(fixtures_[n].i - target[kB]) < 1e-6) hit = n;
    }
    if (hit != 0 || !mode_.calculated_offsets) h = hit;
  }
  if (h == active_h_ && !calc) return;
  AxisArray prog{};
  for (int a : {kX, kY, kZ}) prog[a] = target[a] - Offset(a);
  active_h_ = h;
  if (calc) calc_b_ = target[kB];
  if (mc.m25) return;  // the block's linear targets are machine positions
  for (int a : {kX, kY, kZ}) {
    if (axis_mask & (1u << a)) target[a] = prog[a] + Offset(a);
  }
}

void KtRun::ResetAtEnd() {
  mode_.contouring = false;
  mode_.plane = geom::Plane::kXY;
  mode_.coaxis_first = mode_.coaxis_second = false;
  mode_.incremental = false;
  mode_.inverse_time = false;
  mode_.fill_in_bypass = mode_.calculated_offsets = false;
  mode_.cutter_comp = CutterComp::kOff;
  mode_.secondary_probe = mode_.b_clamp_off = mode_.c_clamp_off = mode_.wash_flood = mode_.wash_air = false;
  mode_.coolant = CoolantMode::kOff;
  mode_.aux_coolant = CoolantMode::kOff;
  mode_.spindle = SpindleDir::kStop;
  u88_x_ = 0.254;
  u88_y_ = 0;
  mode_.cycle = 0;
  program_.clear();
  for (auto& f : *frames_) f.data.locals.clear();
}

void KtRun::EmitMove(const AxisArray& target, uint32_t moved, bool rapid, double feed, FeedMode fm,
                     bool exact, const AxisArray& travel, uint32_t travel_mask) {
  used_ |= moved;
  // Only the moved axes (two or three of nine in most blocks), lowest first.
  moved &= (1u << kAxisCount) - 1;
  bool change = travel_mask != 0;
  for (uint32_t m = moved; m != 0 && !change; m &= m - 1) {
    const int a = std::countr_zero(m);
    if (std::fabs(target[a] - pos_[a]) > 1e-9) change = true;
  }
  if (!change) return;  // ln 2264: a block that commands the current position does not move
  for (uint32_t m = moved; m != 0; m &= m - 1) {
    const int a = std::countr_zero(m);
    pos_[a] = target[a];
  }
  Target* to;
  if (rapid) {
    to = &Out<RapidOp>().to;
  } else if (thread_block_) [[unlikely]] {
    // ln 7263-7265: "G33E.1D.01Z-2.000" moves .11 in the first revolution, .12 in the second: the lead at
    // the start is E + D/2 for a lead that grows by D per revolution (judgement call 89).
    ThreadOp& t = Out<ThreadOp>();
    t.lead = thread_lead_ + thread_change_ / 2;
    t.lead_change = thread_change_;
    t.start_angle = thread_angle_;
    t.exact_stop = exact;
    to = &t.to;
  } else {
    LinearOp& l = Out<LinearOp>();
    l.feed = {feed, fm, exact};
    to = &l.to;
  }
  to->pos = pos_;
  to->used = used_;
  to->travel = travel;
  to->travel_mask = travel_mask;
}

void KtRun::Regrid(const Words& words) {
  for (const auto& w : words) {
    int a = AxisOfLetter(w.letter);
    if (a < 0) continue;
    pos_[a] = IsRotaryAxis(a) ? w.v : ToMm(w.v);
    used_ |= 1u << a;
  }
  RegridOp& c = Out<RegridOp>();
  c.to.pos = pos_;
  c.to.used = used_;
}

void KtRun::FloatingZero(const Words& words, const BlockCodes& k) {
  if (k.g99) g98_ = {};
  if (!k.g98) return;
  for (const auto& w : words) {
    int a = AxisOfLetter(w.letter);
    if (a < 0) Fail(w.col, "G98 BLOCK MAY CONTAIN ONLY AXIS WORDS");
    double v = IsRotaryAxis(a) ? w.v : ToMm(w.v);
    if (a == kX && mir_x_) v = -v;
    if (a == kY && mir_y_) v = -v;
    g98_[a] = 0;
    g98_[a] = pos_[a] - Offset(a) - v;
    used_ |= 1u << a;
  }
}

void KtRun::Motion(const Words& words, const BlockCodes& k, const BlockMCodes& mc, uint32_t axis_mask,
                   int motion_col, const Word* f, std::optional<double> block_feed) {
  const uint32_t rotary_mask = (1u << kA) | (1u << kB) | (1u << kC);
  // A G94 feed word of this block: its format (Table 1-A or the rotary F3.0) depends on the move.
  const Word* fw = (f && !k.dwell && !mc.m06 && !mc.m25 && !mode_.inverse_time) ? f : nullptr;
  if (fw && (k.g92 || k.g98 || k.g99 || !(axis_mask || k.arc)))
    CheckFeedFormat(*fw, FeedFormat::kLinear, metric_);
  if (k.dwell) {
    if (axis_mask) Fail(motion_col, "NO AXIS WORDS ALLOWED IN A G04 BLOCK");
    if (!f) Fail(1, "G04 NEEDS F (DWELL SECONDS)");
    // Table 1-C: 5.1 (the tenths are truncated below, judgement call 13).
    if (f->literal && f->num.digits > 6) Fail(f->col, "F WORD HAS MORE THAN 6 DIGITS (G04 DWELL FORMAT 5.1)");
    double secs = std::floor(f->v * 10 + 1e-6) / 10;  // F format 5.1
    if (secs < 0.1 || secs > 99999.9) Fail(f->col, "G04 DWELL MUST BE F.1-F99999.9 SECONDS");
    Out<DwellOp>().seconds = secs;
  } else if (k.g92) {
    Regrid(words);
  } else if (k.g98 || k.g99) {
    FloatingZero(words, k);
  } else if (mc.m06) {
    if (selected_tool_.empty()) Fail(mc.after_col, "M06 NEEDS A SELECTED TOOL (T WORD)");
    // Axis words of the M06 block are ignored (the slides go to the tool change position).
  } else if (axis_mask || k.arc) {
    std::optional<double> eff = mode_.inverse_time ? block_feed : feed_;
    if (mode_.inverse_time && !block_feed && !mc.m25) {
      Fail(k.arc ? k.arc_col : motion_col, "F MUST BE PROGRAMMED IN EVERY G93 MOTION BLOCK");
    }
    if (k.arc) {
      if (axis_mask & rotary_mask) Fail(k.arc_col, "ROTARY AXIS WORDS ARE NOT ALLOWED IN A CIRCULAR BLOCK");
      if (mc.m25) Fail(k.arc_col, "M25 IS NOT ALLOWED IN A CIRCULAR BLOCK");
      // The machine's guarded move is straight (judgement call 81).
      if (mode_.obstruction_detection)
        Fail(k.arc_col, "CIRCULAR MOVES ARE NOT ALLOWED IN G28 (OBSTRUCTION DETECTION)");
      if (!eff) Fail(k.arc_col, "NO FEEDRATE PROGRAMMED");
      if (*eff == 0) Fail(f ? f->col : k.arc_col, "F0 IS NOT ALLOWED IN A CIRCULAR BLOCK");
      if (fw) CheckFeedFormat(*fw, FeedFormat::kLinear, metric_);
      bool cw = k.arc == 2;
      if (mir_x_ != mir_y_) cw = !cw;
      double feed = mode_.inverse_time ? *eff : ToMm(*eff);
      Arc(words, cw, k.arc_col, feed, mode_.inverse_time ? FeedMode::kInverseTime : FeedMode::kPerMinute);
    } else {
      LinearMotion(words, k, mc, axis_mask, motion_col, eff, fw);
    }
  }
}

void KtRun::LinearMotion(const Words& words, const BlockCodes& k, const BlockMCodes& mc, uint32_t axis_mask,
                         int motion_col, std::optional<double> eff, const Word* fw) {
  const uint32_t rotary_mask = (1u << kA) | (1u << kB) | (1u << kC);
  AxisArray target = pos_;
  AxisArray travel{};
  uint32_t travel_mask = 0;
  bool b_moves = false;
  const Word* b_word = nullptr;
  for (const auto& w : words) {
    int a = AxisOfLetter(w.letter);
    if (a < 0) continue;
    if (IsRotaryAxis(a)) {
      if (a == kB) b_word = &w;
      if (a == kB && b_index_ && std::fabs(w.v - std::round(w.v)) > 1e-9) {
        Fail(w.col, "INDEX TABLE POSITIONS ARE WHOLE DEGREES");
      }
      double cur = pos_[a];
      double t, tr;
      if (mode_.incremental && !mc.m25) {
        tr = w.v;
        t = std::fmod(cur + tr, 360.0);
        if (t < 0) t += 360.0;
      } else {
        t = std::fmod(std::fabs(w.v), 360.0);
        bool ccw = w.v < 0 || w.neg_zero;
        tr = ccw ? -std::fmod(cur - t + 360.0, 360.0) : std::fmod(t - cur + 360.0, 360.0);
        if (std::fabs(tr) < 1e-9 || std::fabs(std::fabs(tr) - 360.0) < 1e-9) tr = 0;
      }
      target[a] = t;
      if (std::fabs(tr) > 1e-9) {
        travel[a] = tr;
        travel_mask |= 1u << a;
        if (a == kB) b_moves = true;
      }
      continue;
    }
    double v = ToMm(w.v);
    if (mc.m25) {
      target[a] = v;  // M25: machine coordinates, every offset bypassed for the block
      continue;
    }
    if ((a == kX && mir_x_) || (a == kY && mir_y_)) v = -v;
    double off = Offset(a);
    double prog = pos_[a] - off;
    target[a] = (mode_.incremental ? prog + v : v) + off;
    if (a == kZ && length_bypass_) target[a] -= tool_len_;  // P0 (ln 1185)
  }
  const bool positioning =
      mc.m25 || !mode_.contouring || (eff && *eff == 0) || (b_index_ && (axis_mask & (1u << kB)));
  RebaseFixtures(words, mc, axis_mask, positioning, target);
  bool linear_moves = false;
  for (uint32_t m = axis_mask & ~rotary_mask & ((1u << kAxisCount) - 1); m != 0 && !linear_moves;
       m &= m - 1) {
    const int a = std::countr_zero(m);
    if (std::fabs(target[a] - pos_[a]) > 1e-9) linear_moves = true;
  }
  // ln 5976-5978: rotary departures only (one or two rotary axes): F is degrees per minute in F3.0, so a
  // number without a point is whole degrees (F17 = 17 DPM, where a linear block reads 1.7 IPM). An index
  // table move runs at F0 (ln 4491); its F is the modal feed of the blocks after it.
  const bool rotary_only = !linear_moves && travel_mask && !(b_index_ && b_moves);
  if (fw && fw->v != 0)
    CheckFeedFormat(*fw, rotary_only ? FeedFormat::kRotary : FeedFormat::kLinear, metric_);
  // A G33 thread runs at the spindle's pace, whatever the modal feed (F0 included).
  if (thread_block_ && mc.m25) Fail(motion_col, "M25 IS NOT ALLOWED IN A G33 BLOCK");
  bool rapid = !thread_block_ && (mc.m25 || (eff && *eff == 0));
  const uint32_t linear_mask = axis_mask & ~rotary_mask;
  if (b_index_ && (axis_mask & (1u << kB)) && !rapid) {
    if (linear_mask || (axis_mask & ((1u << kA) | (1u << kC)))) {
      Fail(b_word->col, "INDEX TABLE MOVES WITH OTHER AXES REQUIRE F0");
    }
    rapid = true;  // an index-only block is forced to F0 for the block
  }
  if (!rapid && !eff && !thread_block_) Fail(motion_col, "NO FEEDRATE PROGRAMMED");
  double feed = 0;
  FeedMode fm = FeedMode::kPerMinute;
  if (!rapid && eff) {
    if (mode_.inverse_time) {
      fm = FeedMode::kInverseTime;
      feed = *eff;
    } else if (!linear_moves && travel_mask) {
      fm = FeedMode::kDegPerMinute;
      feed = fw && fw->literal && !fw->num.point ? fw->num.as_written : *eff;
    } else {
      feed = ToMm(*eff);
    }
  }
  const bool exact = !mode_.contouring;
  if (k.probe) {
    ProbeMove(k, axis_mask, target, rapid, feed, fm);
    return;
  }
  // Under G28 every straight move is the guarded probe move (obstruction detection), else a plain move.
  auto move = [&](uint32_t mask, const AxisArray& to, const AxisArray& tr, uint32_t tr_mask) {
    if (mode_.obstruction_detection) [[unlikely]]
      GuardedMove(mask, to, rapid, feed, fm, exact, tr, tr_mask, motion_col);
    else
      EmitMove(to, mask, rapid, feed, fm, exact, tr, tr_mask);
  };
  if (b_moves && b_index_ && (axis_mask & (1u << kZ)) && std::fabs(target[kZ] - pos_[kZ]) > 1e-9) {
    // Index B (with X, Y) first, then Z; in G28 too.
    AxisArray first = target;
    first[kZ] = pos_[kZ];
    move(axis_mask & ~(1u << kZ), first, travel, travel_mask);
    move(1u << kZ, target, {}, 0);
  } else {
    move(axis_mask, target, travel, travel_mask);
  }
}

// G28 obstruction detection (ln 1539-1541; ln 9416: "E-stop and message upon any probe contact"): the
// block's linear move is the machine's probe move that must not touch (on a station the servo's guarded
// probe segment). A rotary turn of the block comes first as a plain move (judgement call 81).
void KtRun::GuardedMove(uint32_t axis_mask, const AxisArray& target, bool rapid, double feed, FeedMode fm,
                        bool exact, const AxisArray& travel, uint32_t travel_mask, int col) {
  const uint32_t rotary_mask = (1u << kA) | (1u << kB) | (1u << kC);
  if (comp_.engaged()) Fail(col, "G28 MOVES ARE NOT ALLOWED WITH G41/G42 IN EFFECT");
  if (travel_mask) {
    AxisArray turned = pos_;
    for (int a : {kA, kB, kC}) turned[a] = target[a];
    EmitMove(turned, axis_mask & rotary_mask, rapid, feed, fm, exact, travel, travel_mask);
  }
  bool moves = false;
  for (int a = 0; a < kAxisCount; ++a) {
    if (!IsRotaryAxis(a) && (axis_mask & (1u << a)) && std::fabs(target[a] - pos_[a]) > 1e-9) moves = true;
  }
  used_ |= axis_mask;
  if (!moves) return;
  interp::ProbeMove mv;
  mv.make = true;
  mv.from = pos_;
  mv.to = pos_;
  for (int a = 0; a < kAxisCount; ++a) {
    if (!IsRotaryAxis(a) && (axis_mask & (1u << a))) mv.to[a] = target[a];
  }
  mv.feed = rapid || fm != FeedMode::kPerMinute ? 0 : feed;
  mv.length = tool_len_;
  const ProbeResult pr = env_->Probe(mv);
  if (pr.already) {
    // The stylus is deflected at the start (after a G22 touch; offline, a run starting in the model): the
    // probe cannot signal a new contact until it breaks, and the guarded move cannot start. The block runs
    // as programmed (judgement call 81; 9-16 MULTIBORES probes with G27 under G28).
    EmitMove(mv.to, axis_mask & ~rotary_mask, rapid, feed, fm, exact, {}, 0);
    return;
  }
  ProbeOutcome result = ProbeOutcome::kNone;
  if (pr.event) {
    result = ProbeOutcome::kContact;
    for (int a = 0; a < kAxisCount; ++a) {
      if (!IsRotaryAxis(a) && (axis_mask & (1u << a))) pos_[a] = pr.at[a];
    }
  } else {
    pos_ = mv.to;
  }
  ProbeOp& c = Out<ProbeOp>();
  c.g = 28;
  c.feed = {rapid ? 0 : feed, fm, false};
  c.result = result;
  c.to.pos = pos_;
  c.to.used = used_;
  if (result == ProbeOutcome::kContact) {
    Fail(col, "OBSTRUCTION DETECTED: PROBE CONTACT IN G28 (OBSTRUCTION DETECTION)", "E-STOP");
  }
}

void KtRun::ProbeMove(const BlockCodes& k, uint32_t axis_mask, const AxisArray& target, bool rapid,
                      double feed, FeedMode fm) {
  // G22 (stop on contact) / G23 (stop on break): a queue buster, answered by the Environment.
  interp::ProbeMove mv;
  mv.make = k.probe_g == 22;
  mv.from = pos_;
  mv.to = target;
  mv.feed = rapid || fm != FeedMode::kPerMinute ? 0 : feed;
  mv.length = tool_len_;
  ProbeResult pr = env_->Probe(mv);
  ProbeOutcome result;
  if (pr.already) {
    machine_[1021] = 1;
    result = ProbeOutcome::kAlready;
  } else if (pr.event) {
    machine_[1021] = 8;
    result = k.probe_g == 22 ? ProbeOutcome::kContact : ProbeOutcome::kBreak;
    // L3042-L3049 hold the latch as the display shows it: relative to the offsets in effect (the probe
    // cycles move back to it in G90 with those offsets, App. E; G25's note: "relative to offsets").
    static const int kOrder[8] = {kX, kY, kZ, kB, kA, kC, kU, kV};
    for (int i = 0; i < 8; ++i) {
      const int a = kOrder[i];
      probe_latch_[i] = IsRotaryAxis(a) ? pr.at[a] : pr.at[a] - Offset(a);
    }
    for (int a = 0; a < kAxisCount; ++a) {
      if (axis_mask & (1u << a)) pos_[a] = pr.at[a];
    }
    if (mode_.probe_count == ProbeCount::kContacts && k.probe_g == 22) machine_[1022] += 1;
    if (mode_.probe_count == ProbeCount::kBreaks && k.probe_g == 23) machine_[1022] += 1;
  } else {
    machine_[1021] = 2;
    result = ProbeOutcome::kNone;
    for (int a = 0; a < kAxisCount; ++a) {
      if (axis_mask & (1u << a)) pos_[a] = target[a];
    }
  }
  machine_[1020] = 1;
  used_ |= axis_mask;
  ProbeOp& c = Out<ProbeOp>();
  c.g = k.probe_g;
  c.feed = {rapid ? 0 : feed, fm, false};
  c.result = result;
  c.to.pos = pos_;
  c.to.used = used_;
}

}  // namespace cell::interp::ktapl
