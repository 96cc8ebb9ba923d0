// Okuma M-tool compound fixed cycles (manual SECTION 7 §8, ln 4073-4937) for turn-mills with a C axis and a
// live tool: G181 drilling, G182 boring, G183 deep-hole drilling, G184 tapping, G189 reaming, G190 key ways,
// G178/G179 synchronized tapping (face with K, side with I; repeated at each C or Q times around), G185/G186
// thread cutting with C turning at SA= and the straight chained threads G187/G188; G180 cancels. The cycle
// starts the live tool and clamps and unclamps C itself (ln 4522-4526); its words are modal within the mode.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "interp_internal.h"

namespace cell::interp::okuma {
namespace {

double Sign(double v) {
  return v < 0 ? -1.0 : (v > 0 ? 1.0 : 0.0);
}

uint32_t Bits(std::string_view s) {
  uint32_t m = 0;
  for (char c : s) m |= 1u << (c - 'A');
  return m;
}

constexpr int kSa = 0;  // BlockWords::ext index of SA=

}  // namespace

// What a block in M-tool cycle mode may hold (ln 4746, 4801-4803, 4523, 4095-4098): no incremental data, no
// S, M or T (the cycle's own M136, M141, M211-M214 in its G block; M140 is refused before), C joined and
// unclamped at the start, G94 for the drilling family and G95 for the threads, and after a Q block only G180.
void OkRun::MToolChecks(const BlockWords& w, int g, bool fresh, int col) {
  if (mc_.need_g180) Fail(col, "a block with Q (the repeat count) must be followed by G180");
  if (modal_.incremental) Fail(col, "no incremental data (G91) in an M-tool compound fixed cycle");
  if (!modal_.c_joined) Fail(col, "the M-tool compound fixed cycles need the C axis joined (M110)");
  if (lap_.active || lap_.finish) Fail(col, "an M-tool compound fixed cycle cannot be part of a LAP contour");
  if (modal_.comp != 40)
    Fail(col, "M-tool compound fixed cycles are not allowed in nose radius compensation mode");
  if (open_line_)
    Fail(col, "after a line given by an angle only, the next block must be a line with X, Z and A");
  if (fresh && mc_.g == 0 && modal_.c_clamped) {
    Fail(col, "the C axis must be unclamped (M146) before an M-tool compound fixed cycle");
  }
  for (char a : {'S', 'T'}) {
    if (w.Has(a)) Fail(w.Col(a), fmt::format("no {} code in M-tool compound fixed cycle mode", a));
  }
  if (w.HasExt(ExtIndex(MakeAddr('S', 'B')))) {
    Fail(w.ext_col[static_cast<size_t>(ExtIndex(MakeAddr('S', 'B')))],
         "no SB= in M-tool compound fixed cycle mode");
  }
  for (const auto& m : w.m) {
    const bool own = m.code == 136 || m.code == 141 || (m.code >= 211 && m.code <= 214);
    if (!own || !fresh)
      Fail(m.col, fmt::format("no M code (M{}) in M-tool compound fixed cycle mode", m.code));
  }
  for (const auto& c : w.g) {
    if (!(IsMToolCycle(c.code) || c.code == 94 || c.code == 95)) {
      Fail(c.col, fmt::format("G{} in M-tool compound fixed cycle mode: cancel it with G180 first", c.code));
    }
  }
  const bool thread = g >= 185 && g <= 188;
  if (g == 178 || g == 179) return;  // F per minute or per M-tool revolution (ln 4569-4577)
  if (thread && !modal_.per_rev)
    Fail(col, fmt::format("G{} takes its feed only in G95 (mm per C revolution)", g));
  if (!thread && modal_.per_rev) Fail(col, fmt::format("G{} takes its feed only in G94 (mm/min)", g));
}

// A block's words join those in force; I and K, R and the bottom word replace each other.
void OkRun::MToolMerge(const BlockWords& w) {
  BlockWords& m = mc_.words;
  if (w.Has('I') && w.Has('K')) Fail(w.Col('K'), "I and K in one M-tool cycle block: give one of them");
  if (w.Has('C') && std::fabs(w.Get('C')) > 359.999 + 1e-9) Fail(w.Col('C'), "C is 0 to +-359.999 degrees");
  const uint32_t keep = Bits("XZCRIKDELUWJ");
  if (w.Has('I')) m.has &= ~Bits("K");
  if (w.Has('K')) m.has &= ~Bits("I");
  for (int i = 0; i < 26; ++i) {
    if (!((keep >> i) & 1u) || !((w.has >> i) & 1u)) continue;
    m.v[static_cast<size_t>(i)] = w.v[static_cast<size_t>(i)];
    m.col[static_cast<size_t>(i)] = w.col[static_cast<size_t>(i)];
    m.has |= 1u << i;
  }
  if (w.HasExt(kSa)) {
    m.ext[kSa] = w.ext[kSa];
    m.ext_col[kSa] = w.ext_col[kSa];
    m.ext_has = static_cast<uint16_t>(m.ext_has | 1u);
  }
  // R (a depth from the cutting start) and the bottom level (Z for face, X for side work) replace each other.
  const char bottom = m.Has('I') ? 'X' : 'Z';
  if (w.Has('R') && w.Has(bottom) && mc_.g != 190) {
    Fail(w.Col('R'), fmt::format("R and the hole bottom {} cannot both be given", bottom));
  }
  if (w.Has('R')) m.has &= ~Bits(bottom == 'X' ? "X" : "Z");
  if (w.Has(bottom)) m.has &= ~Bits("R");
}

void OkRun::MToolBlock(const BlockWords& w, int g, bool fresh, int col) {
  if (mc_.g == 0) {
    mc_ = MToolCycle();
    mc_.start = pos_;
  }
  if (fresh && g != mc_.g) mc_.chained = false;
  mc_.g = g;
  mc_.budget = 200000;
  mc_.col = col;
  if (w.HasM(211) || w.HasM(212)) mc_.zigzag = w.HasM(212);
  if (w.HasM(213) || w.HasM(214)) mc_.equal = w.HasM(214);
  MToolMerge(w);
  // Q3/Q4 run again for each block with C, Q or another position (ln 4132, 4797-4799); F alone changes F.
  if (!(w.has & Bits("XZCRIKQDELUWJ")) && !w.HasExt(kSa)) return;
  if (g >= 185 && g <= 188) {
    if (w.Has('Q')) Fail(w.Col('Q'), "the thread cutting cycles G185-G188 have no repeat function");
    MToolThread(mc_.words, g, col);
  } else {
    MToolDrill(w, g, col);
  }
}

// One rapid to `target` (the axes in `moved`) with C indexed to the program angle c_prog (ln 4116, 4137).
void OkRun::MToolIndex(AxisArray target, uint32_t moved, double c_prog) {
  double t = std::fmod(c_prog + Offset(kC), 360.0);
  if (t < 0) t += 360.0;
  AxisArray travel{};
  uint32_t tmask = 0;
  const double tr = CTravelTo(t);
  target[kC] = t;
  if (std::fabs(tr) > 1e-9) {
    travel[kC] = tr;
    tmask = 1u << kC;
  }
  EmitMove(target, moved | (1u << kC), true, 0, FeedMode::kPerMinute, travel, tmask, nullptr);
}

void OkRun::MToolMove(int axis, double v, bool rapid, double feed) {
  if (--mc_.budget < 0) {
    Fail(mc_.col, "more than 200000 moves in one M-tool cycle block: D is too small or Q too large");
  }
  AxisArray t = pos_;
  t[static_cast<size_t>(axis)] = v;
  EmitMove(t, 1u << axis, rapid, feed, FeedMode::kPerMinute, {}, 0, nullptr);
}

// The live tool starts forward after Q1 (ln 4255, 4277, 4299): once, while it does not already turn so.
void OkRun::MToolStart() {
  if (modal_.mtool != SpindleDir::kCw) EmitMTool(SpindleDir::kCw);
}

// The clamps the cycle generates (ln 4523-4526) go out as the program's M147/M146 would.
void OkRun::MToolClamp(bool clamp) {
  if (modal_.c_clamped == clamp) return;
  modal_.c_clamped = clamp;
  Out<AuxOp>().m = clamp ? 147 : 146;
}

// The drilling family and G190: one hole (key way) at C, or Q of them 360/Q apart from C (ln 4636-4657).
void OkRun::MToolDrill(const BlockWords& w, int g, int col) {
  const BlockWords& m = mc_.words;
  if (!m.Has('I') && !m.Has('K')) Fail(col, fmt::format("G{} needs K (face) or I (side work)", g));
  const char shift = m.Has('K') ? 'K' : 'I';
  if (m.Get(shift) < 0) Fail(m.Col(shift), fmt::format("{} must not be negative (ln 4125)", shift));
  if (f_ <= 0) Fail(col, fmt::format("G{} needs a cutting feedrate F", g));
  int n = 1;
  if (w.Has('Q')) {
    const double q = w.Get('Q');
    if (q < 0 || q > 9999 || q != std::floor(q)) Fail(w.Col('Q'), "Q (the number of holes) is 0-9999");
    n = std::max(1, static_cast<int>(q));
    mc_.need_g180 = true;
  }
  const double c0 = m.Has('C') ? m.Get('C') : ToProgram(kC, pos_[kC]);
  for (int i = 0; i < n; ++i) {
    const double c = c0 + 360.0 * i / n;
    if (g == 190) {
      MToolKeyway(m, c, col);
    } else if (g == 178 || g == 179) {
      MToolSyncTap(m, g, c, col);
    } else {
      MToolHole(m, g, c, col);
    }
  }
}

// A hole's axes (ln 4116-4123): face work (K) feeds along Z at the X given, side work (I) along X at the Z
// given; the cutting start is K (I) from the cycle start toward the bottom, or by R's sign; I and R along X
// are diameters.
OkRun::HolePath OkRun::MToolHolePath(const BlockWords& m, int g, int col) {
  HolePath h;
  const bool face = m.Has('K');
  h.da = face ? kZ : kX;
  h.pa = face ? kX : kZ;
  const char dl = face ? 'Z' : 'X';
  h.d0 = mc_.start[static_cast<size_t>(h.da)];
  const double shift = m.Get(face ? 'K' : 'I');
  const double unit = ToMachine(h.da, 1) - ToMachine(h.da, 0);  // +1, or -1 for X on turret B
  if (m.Has('R')) {
    h.dir = Sign(m.Get('R')) * unit;
    h.ds = h.d0 + h.dir * shift;
    h.bottom = h.ds + m.Get('R') * unit;
  } else {
    if (!m.Has(dl)) Fail(col, fmt::format("G{} needs the hole bottom {} or the depth R", g, dl));
    h.bottom = ToMachine(h.da, m.Get(dl));
    h.dir = Sign(h.bottom - h.d0);
    h.ds = h.d0 + h.dir * shift;
  }
  if (h.dir == 0 || (h.bottom - h.ds) * h.dir < -1e-9) {
    Fail(col, fmt::format("G{}: the hole bottom lies before the cutting start point", g));
  }
  return h;
}

// Q1 of a hole: its position (X for face work, Z for side work) and C at rapid.
void OkRun::MToolHoleIndex(const BlockWords& m, const HolePath& h, double c) {
  const char pl = h.pa == kX ? 'X' : 'Z';
  AxisArray t = pos_;
  t[static_cast<size_t>(h.pa)] = m.Has(pl) ? ToMachine(h.pa, m.Get(pl)) : pos_[static_cast<size_t>(h.pa)];
  MToolIndex(t, 1u << h.pa, c);
}

// Q1-Q4 of one hole (ln 4116-4123, 4249-4339, 4435-4453).
void OkRun::MToolHole(const BlockWords& m, int g, double c, int col) {
  const HolePath h = MToolHolePath(m, g, col);
  const int da = h.da;
  const double ds = h.ds, bottom = h.bottom;
  // Q1: the hole's position and C at rapid, then the live tool forward.
  MToolHoleIndex(m, h, c);
  MToolStart();
  // Q2: the cutting start at rapid, then C clamps (not with M141, ln 4168-4171).
  MToolMove(da, ds, true, 0);
  if (!words_.HasM(141)) MToolClamp(true);
  // Q3: the cut (pecks for G183), the dwell E, the live tool's stop (G182) or reversal (G184).
  if (g == 183) {
    MToolPecks(da, ds, bottom, h.dir, col);
  } else {
    MToolMove(da, bottom, false, f_);
  }
  if (m.Has('E') && m.Get('E') > 0) Out<DwellOp>().seconds = Scale('T', m.Get('E'), false);
  if (g == 182 || g == 184) EmitMTool(SpindleDir::kStop);
  if (g == 184) EmitMTool(SpindleDir::kCcw);
  // Q4: back to the cutting start (at feed for G184/G189), to the cycle start with M136 or the parameter,
  // C unclamps; the live tool turns forward again.
  MToolMove(da, ds, !(g == 184 || g == 189), f_);
  if (words_.HasM(136) || multi_return_start_) MToolMove(da, h.d0, true, 0);
  MToolClamp(false);
  if (g == 184) EmitMTool(SpindleDir::kStop);
  if (g == 182 || g == 184) EmitMTool(SpindleDir::kCw);
}

// G178/G179 synchronized tapping (ln 4530-4627; judgement 63): Q1 the hole's X (Z) and C at rapid, the live
// tool stopped; Q2 the cutting start at rapid (D, the live tool's start angle, is not kept: OK01's live tool
// has no one-point clutch, ln 4585); Q3 C clamps, feed and live-tool overrides at 100 % (ln 4615), the live
// tool forward (G179: reverse) at SB=, the tap fed to the bottom at P x SB mm/min and in position there
// (ln 4610); Q4 the live tool reversed, back to the cutting start at the same feed, the overrides given back,
// C unclamps (the text's "clamped", as G184's, judgement 53), then the cycle start with M136, the live tool
// stops (ln 4623). P is F per M-tool revolution in G95 (ln 4573), F / SB in G94 (ln 4571); with J, F / J.
void OkRun::MToolSyncTap(const BlockWords& m, int g, double c, int col) {
  if (sb_ <= 0) Fail(col, fmt::format("G{} needs the M-tool spindle speed SB= > 0", g));
  if (f_ <= 0) Fail(col, fmt::format("G{} needs a cutting feedrate F", g));
  if (m.Has('D') && std::fabs(m.Get('D')) > 359.999 + 1e-9) Fail(m.Col('D'), "D is 0 to 359.999 degrees");
  const double j = m.Has('J') ? m.Get('J') : 1;
  if (j < 1 || j != std::floor(j)) Fail(m.Col('J'), "J (threads within F) must be a whole number >= 1");
  const double feed = (modal_.per_rev ? f_ * sb_ : f_) / j;  // mm/min
  const HolePath h = MToolHolePath(m, g, col);
  const SpindleDir fwd = g == 178 ? SpindleDir::kCw : SpindleDir::kCcw;
  const SpindleDir rev = g == 178 ? SpindleDir::kCcw : SpindleDir::kCw;
  MToolHoleIndex(m, h, c);
  if (modal_.mtool != SpindleDir::kStop) EmitMTool(SpindleDir::kStop);
  MToolMove(h.da, h.ds, true, 0);
  if (!words_.HasM(141)) MToolClamp(true);
  CycleFeedFixed(true);
  EmitMTool(fwd);
  const bool droop = modal_.droop;
  modal_.droop = true;  // each synchronized move ends in position (ln 4610)
  MToolMove(h.da, h.bottom, false, feed);
  EmitMTool(rev);
  MToolMove(h.da, h.ds, false, feed);
  modal_.droop = droop;
  CycleFeedFixed(false);
  MToolClamp(false);
  if (words_.HasM(136) || multi_return_start_) MToolMove(h.da, h.d0, true, 0);
  EmitMTool(SpindleDir::kStop);
}

// G183's step feed (ln 4305-4316, 4659-4673): D per step, back alpha at rapid after each; with L, once the
// infeed since the last return reaches L, back to the cutting start and down again to alpha before the depth
// reached. D, L and alpha along X are diameters.
void OkRun::MToolPecks(int axis, double from, double bottom, double dir, int col) {
  const BlockWords& m = mc_.words;
  if (!m.Has('D') || m.Get('D') <= 0) Fail(col, "G183 needs the peck feed D > 0");
  const double d = m.Get('D');
  const double l = m.Has('L') ? std::fabs(m.Get('L')) : 0;
  if (std::fabs(bottom - from) / d > 200000) Fail(col, "more than 200000 pecks in the cycle: D is too small");
  double reached = from, since_return = 0;
  while ((bottom - reached) * dir > 1e-9) {
    const double next = (bottom - (reached + dir * d)) * dir > 0 ? reached + dir * d : bottom;
    MToolMove(axis, next, false, f_);
    since_return += std::fabs(next - reached);
    reached = next;
    if ((bottom - reached) * dir <= 1e-9) break;
    if (l > 0 && since_return >= l - 1e-9) {
      MToolMove(axis, from, true, 0);
      since_return = 0;
    }
    MToolMove(axis, reached - dir * multi_peck_, true, 0);
  }
}

// G190 (ln 4455-4528): Q1 C at rapid, Q2 the depth axis to K (I) from the cycle start, Q3 passes along the
// key way from the cycle start's X (Z) to the X (Z) given, each entered at the infeed feed E: D deep each
// (M213, the rest last) or equal passes of at most D (M214), one direction (M211: out and back at rapid) or
// zigzag (M212), leaving W (U) for a finish pass at the bottom; Q4 back to the start at rapid.
void OkRun::MToolKeyway(const BlockWords& m, double c, int col) {
  const bool face = m.Has('K');
  const int da = face ? kZ : kX, la = face ? kX : kZ;
  const char dl = face ? 'Z' : 'X', ll = face ? 'X' : 'Z', al = face ? 'W' : 'U';
  if (!m.Has(dl) || !m.Has(ll))
    Fail(col, fmt::format("G190 needs {} (the key way bottom) and {} (its end)", dl, ll));
  if (!m.Has('D') || m.Get('D') <= 0) Fail(col, "G190 needs the depth of cut D > 0");
  const double d0 = mc_.start[static_cast<size_t>(da)], l0 = mc_.start[static_cast<size_t>(la)];
  const double bottom = ToMachine(da, m.Get(dl)), lend = ToMachine(la, m.Get(ll));
  const double dir = Sign(bottom - d0);
  const double ds = d0 + dir * m.Get(face ? 'K' : 'I');
  const double allow = m.Has(al) ? m.Get(al) : 0;
  const double rough = bottom - dir * allow;
  if (dir == 0 || (rough - ds) * dir <= 1e-9 || allow < 0) {
    Fail(col, "G190: the key way bottom (less its finish allowance) lies before the cutting start point");
  }
  const double e = m.Has('E') && m.Get('E') > 0 ? Scale('F', m.Get('E'), false) : f_;
  std::vector<double> levels;
  const double total = std::fabs(rough - ds), d = m.Get('D');
  if (total / d > 10000) Fail(col, "more than 10000 key way passes: D is too small");
  const int n = static_cast<int>(std::ceil(total / d - 1e-9));
  if (n > 10000) Fail(col, "more than 10000 key way passes: D is too small");
  for (int i = 1; i <= n; ++i)
    levels.push_back(mc_.equal ? ds + dir * total * i / n : ds + dir * std::min(total, d * i));
  if (allow > 0) levels.push_back(bottom);
  MToolIndex(pos_, 0, c);
  MToolStart();
  MToolMove(da, ds, true, 0);
  if (!words_.HasM(141)) MToolClamp(true);
  bool far = false;  // the tool is at the key way's end
  for (double level : levels) {
    if (!mc_.zigzag && far) {
      MToolMove(da, ds, true, 0);
      MToolMove(la, l0, true, 0);
      far = false;
    }
    MToolMove(da, level, false, e);
    MToolMove(la, far ? l0 : lend, false, f_);
    far = !far;
  }
  MToolMove(da, ds, true, 0);
  MToolMove(la, l0, true, 0);
  if (words_.HasM(136) || multi_return_start_) MToolMove(da, d0, true, 0);
  MToolClamp(false);
}

// G185-G188 (ln 4341-4433, 4858-4907): Q1 at rapid to the thread's start with C indexed, Q2 the cut while C
// turns at SA= rpm, the tool advancing F per C revolution (one inverse-time move: revolutions = length / F,
// time = revolutions / SA), Q3/Q4 back at rapid (G185: X then Z, G186: Z then X). G187/G188 stop after Q2;
// the next block continues from there and G180 returns. I (G185/G187) and the transverse start I are
// diameters.
void OkRun::MToolThread(const BlockWords& m, int g, int col) {
  const bool along_z = g == 185 || g == 187;
  if (!m.Has('X') || !m.Has('Z')) Fail(col, fmt::format("G{} needs X and Z", g));
  if (!m.HasExt(kSa) || m.ext[kSa] <= 0) Fail(col, fmt::format("G{} needs SA= (the C speed, rpm) > 0", g));
  if (f_ <= 0) Fail(col, fmt::format("G{} needs F (the lead per C revolution)", g));
  const double x0 = mc_.start[kX], z0 = mc_.start[kZ];
  const double x1 = ToMachine(kX, m.Get('X')), z1 = ToMachine(kZ, m.Get('Z'));
  const double i = m.Has('I') ? m.Get('I') : 0, k = m.Has('K') ? m.Get('K') : 0;
  AxisArray from = pos_, to = pos_;
  if (along_z) {
    from[kX] = x1;
    from[kZ] = z0 + Sign(z1 - z0) * k;
    to[kX] = ToMachine(kX, m.Get('X') + i);
    to[kZ] = z1;
  } else {
    from[kX] = x0 + Sign(x1 - x0) * i;
    from[kZ] = z1;
    to[kX] = x1;
    to[kZ] = ToMachine(kZ, m.Get('Z') + k);
  }
  if (!mc_.chained) {
    MToolIndex(from, (1u << kX) | (1u << kZ), m.Has('C') ? m.Get('C') : ToProgram(kC, pos_[kC]));
    MToolStart();
  }
  const double length = along_z ? std::fabs(to[kZ] - pos_[kZ]) : std::fabs(to[kX] - pos_[kX]) / 2;
  const double revs = length / f_;
  if (revs < 1e-9) Fail(col, fmt::format("G{}: the thread has no length", g));
  if (revs > 100000) Fail(col, fmt::format("G{}: more than 100000 C revolutions", g));
  AxisArray travel{};
  travel[kC] = (modal_.c_negative ? -360.0 : 360.0) * revs;
  to[kC] = std::fmod(pos_[kC] + travel[kC], 360.0);
  if (to[kC] < 0) to[kC] += 360.0;
  EmitMove(to, (1u << kX) | (1u << kZ) | (1u << kC), false, m.ext[kSa] / revs, FeedMode::kInverseTime, travel,
           1u << kC, nullptr);
  if (g == 187 || g == 188) {
    mc_.chained = true;
    return;
  }
  MToolMove(along_z ? kX : kZ, along_z ? x0 : z0, true, 0);
  MToolMove(along_z ? kZ : kX, along_z ? z0 : x0, true, 0);
}

// G180 (ln 4091, 4400-4433, 4527): the mode ends; a chained G187/G188 thread returns to the cycle start at
// rapid first. The live tool goes on turning and C stays unclamped (M13 and M146, ln 4526).
void OkRun::MToolCancel(int col) {
  (void)col;
  if (mc_.g == 0) return;
  if (mc_.chained) {
    const bool along_z = mc_.g == 187;
    MToolMove(along_z ? kX : kZ, mc_.start[along_z ? kX : kZ], true, 0);
    MToolMove(along_z ? kZ : kX, mc_.start[along_z ? kZ : kX], true, 0);
  }
  mc_ = MToolCycle();
  mc_.after_cancel = true;
}

}  // namespace cell::interp::okuma
