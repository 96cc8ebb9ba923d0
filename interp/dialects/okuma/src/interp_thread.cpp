// Okuma thread cutting (manual SECTION 7, seed ln 3228-3905): the fixed thread cycles G31/G33 (longitudinal)
// and G32 (end face) with their repeated pass blocks, the single-path threads G34/G35 with variable lead
// (M26/M27 lead axis), thread chamfering M23/M22, multi-start phases C, and the compound cycles G71/G72 with
// the infeed modes M32/M33/M34 and patterns M73/M74/M75. Threads reach the servo as spindle-synchronised
// `thread` commands whose lead is along the move's major axis.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "interp_internal.h"

namespace cell::interp::okuma {
namespace {

double Sign(double v) {
  return v < 0 ? -1.0 : 1.0;
}

// Spindle revolutions of a thread `travel` long along its major axis: lead x rho + change x rho^2 / 2 =
// travel.
double Revolutions(double travel, double lead, double change) {
  if (std::fabs(change) < 1e-12) return travel / lead;
  return (-lead + std::sqrt(std::max(0.0, lead * lead + 2 * change * travel))) / change;
}

}  // namespace

// One thread move from the current position to `to` with `lead` mm per revolution along Z (or X when
// lead_along_x), written with the lead along the move's major axis (ThreadOp, docs/canonical-commands.md).
void OkRun::EmitThread(const AxisArray& to, double lead, double lead_change, double start_angle,
                       bool lead_along_x) {
  const double dz = std::fabs(to[kZ] - pos_[kZ]);
  const double dx = std::fabs(to[kX] - pos_[kX]) / 2;  // radial travel
  if (dz < 1e-9 && dx < 1e-9) return;
  const double along = lead_along_x ? dx : dz;
  const double major = std::max(dz, dx);
  if (along < 1e-9)
    Fail(1, fmt::format("thread without travel along its lead axis ({})", lead_along_x ? "X" : "Z"));
  const double k = major / along;
  used_ |= (1u << kX) | (1u << kZ);
  const AxisArray from = pos_;
  // Under G65 (droop control, ln 1741-1746) a thread after a thread stops between them, so it starts at the
  // phase the spindle reached at the end of the first: the same groove (judgement 44).
  const bool continues = modal_.droop && thread_phase_.valid && thread_phase_.at[kX] == from[kX] &&
                         thread_phase_.at[kZ] == from[kZ];
  if (continues) start_angle = thread_phase_.angle;
  pos_[kX] = to[kX];
  pos_[kZ] = to[kZ];
  ThreadOp& t = Out<ThreadOp>();
  t.to.pos = pos_;
  t.to.used = used_;
  t.lead = lead * k;
  t.lead_change = lead_change * k;
  t.start_angle = std::fmod(std::fmod(start_angle, 360.0) + 360.0, 360.0);
  t.exact_stop = modal_.droop;
  if (staged_) stage_.from = from;
  thread_phase_ = {true, pos_,
                   std::fmod(t.start_angle + 360.0 * Revolutions(major, t.lead, t.lead_change), 360.0)};
}

void OkRun::ThreadCycle(const BlockWords& w, int g, int col) {
  if (modal_.css) Fail(col, "thread cutting is not allowed in G96 (constant surface speed) mode");
  if (modal_.comp != 40) Fail(col, "G31/G32/G33 are not allowed in nose radius compensation mode");
  const bool face = g == 32;
  if (!chain_.active || chain_.g != g) {
    chain_ = ThreadChain();
    chain_.active = true;
    chain_.g = g;
    chain_.start = pos_;
    chain_.start_angle = w.Has('C') ? w.Get('C') : 0;  // later C words are ignored (ln 3629-3636)
  }
  if (w.Has('C') && (w.Get('C') < 0 || w.Get('C') > 359.999))
    Fail(w.Col('C'), "C (thread phase) is 0-359.999");
  const double j = w.Has('J') ? w.Get('J') : 1;
  if (j < 1 || j != std::floor(j)) Fail(w.Col('J'), "J (threads within F) must be a whole number >= 1");
  if (f_ <= 0) Fail(col, "thread cutting needs the lead F");
  const double lead = f_ / j;
  if (lead < 0.001 || lead > 1000) Fail(col, "the thread lead is 0.001-1000 mm");
  // E (lead variation) of the first block holds for the repeated passes, like its lead.
  const double e = w.Has('E') ? Scale('F', w.Get('E'), true) : (chain_.cycle ? chain_.lead_change : 0);
  chain_.lead_change = e;
  const AxisArray s = chain_.start;
  auto prog = [&](int axis, char a) {
    const double cur = ToProgram(axis, s[static_cast<size_t>(axis)]);
    return ToMachine(axis, modal_.incremental ? cur + w.Get(a) : w.Get(a));
  };
  AxisArray p1 = s, p2 = s;
  const double sgn = modal_.turret_b ? -1.0 : 1.0;
  if (!face) {
    // G33/G31 X Z {I|A} E F K L J C (ln 3239-3296): X the pass diameter at the end, Z the end, I the radius
    // difference start - end of a taper (+ increasing), K the Z shift of the start point.
    if (!w.Has('X') && !w.Has('Z')) return;
    p2[kX] = w.Has('X') ? prog(kX, 'X') : (chain_.cycle ? chain_.last_x : s[kX]);
    p2[kZ] = w.Has('Z') ? prog(kZ, 'Z') : (chain_.cycle ? chain_.last_z : s[kZ]);
    const double zs = s[kZ] + (w.Has('K') ? w.Get('K') : (chain_.cycle ? chain_.shift : 0));
    double taper = 0;  // radius
    if (w.Has('I') && w.Has('A')) Fail(w.Col('A'), "give the taper with I or A, not both");
    if (w.Has('I'))
      taper = w.Get('I');
    else if (w.Has('A'))
      taper = (zs - p2[kZ]) * std::tan(w.Get('A') * kPi / 180.0);
    else if (chain_.cycle)
      taper = chain_.taper;
    p1[kZ] = zs;
    p1[kX] = p2[kX] - sgn * 2 * taper;
    chain_.taper = taper;
    chain_.shift = zs - s[kZ];
  } else {
    // G32 X Z {K|A} E I L J F C (ln 3298-3344): X the end, Z this pass, K the Z difference start - end, I the
    // X shift of the start point; the lead is along X.
    if (!w.Has('X') && !w.Has('Z')) return;
    p2[kX] = w.Has('X') ? prog(kX, 'X') : (chain_.cycle ? chain_.last_x : s[kX]);
    p2[kZ] = w.Has('Z') ? prog(kZ, 'Z') : (chain_.cycle ? chain_.last_z : s[kZ]);
    const double xs = s[kX] + sgn * (w.Has('I') ? w.Get('I') : (chain_.cycle ? chain_.shift : 0));
    double taper = 0;
    if (w.Has('K') && w.Has('A')) Fail(w.Col('A'), "give the taper with K or A, not both");
    if (w.Has('K'))
      taper = w.Get('K');
    else if (w.Has('A'))
      taper = (xs - p2[kX]) / 2 * std::tan(w.Get('A') * kPi / 180.0);
    else if (chain_.cycle)
      taper = chain_.taper;
    p1[kX] = xs;
    p1[kZ] = p2[kZ] - taper;
    chain_.taper = taper;
    chain_.shift = (xs - s[kX]) * sgn;
  }
  chain_.cycle = true;
  chain_.last_x = p2[kX];
  chain_.last_z = p2[kZ];
  const bool chamfer = modal_.thread_chamfer;
  const double l = w.Has('L') ? w.Get('L') : lead;
  RunThreadPass(s, p1, p2, lead, e, chain_.start_angle, face, chamfer ? l : 0);
}

void OkRun::RunThreadPass(const AxisArray& s, const AxisArray& p1, const AxisArray& p2, double lead,
                          double lead_change, double start_angle, bool face, double chamfer) {
  // a: rapid infeed to the pass start.
  {
    AxisArray t = pos_;
    t[kX] = p1[kX];
    t[kZ] = p1[kZ];
    EmitMove(t, (1u << kX) | (1u << kZ), true, 0, FeedModeNow(), {}, 0, nullptr);
  }
  // b: the thread; with M23 the tool pulls out over the last `chamfer` of the lead axis (ln 3439-3452), at 45
  // degrees (the pull-out feed is a machine parameter).
  const int lead_axis = face ? kX : kZ;
  const int infeed_axis = face ? kZ : kX;
  if (chamfer > 1e-9) {
    const double lead_dist = std::fabs(p2[lead_axis] - p1[lead_axis]) / (face ? 2 : 1);
    const double c = std::min(chamfer, lead_dist);
    const double frac = lead_dist > 1e-9 ? (lead_dist - c) / lead_dist : 0;
    AxisArray q = p1;
    q[kX] = p1[kX] + (p2[kX] - p1[kX]) * frac;
    q[kZ] = p1[kZ] + (p2[kZ] - p1[kZ]) * frac;
    EmitThread(q, lead, lead_change, start_angle, face);
    AxisArray out = p2;
    const double away = Sign(s[infeed_axis] - p2[infeed_axis]);
    out[infeed_axis] = p2[infeed_axis] + away * c * (infeed_axis == kX ? 2 : 1);
    EmitThread(out, lead, lead_change, start_angle, face);
  } else {
    EmitThread(p2, lead, lead_change, start_angle, face);
  }
  // c: the infeed axis back to the cycle start; d: the lead axis back to it (both at rapid; the retract rate
  // is a machine parameter).
  AxisArray t = pos_;
  t[infeed_axis] = s[infeed_axis];
  EmitMove(t, 1u << infeed_axis, true, 0, FeedModeNow(), {}, 0, nullptr);
  t[lead_axis] = s[lead_axis];
  EmitMove(t, 1u << lead_axis, true, 0, FeedModeNow(), {}, 0, nullptr);
}

void OkRun::ThreadBlock(const BlockWords& w, int g, int col) {
  // G34 / G35 X Z (A) E F C J (ln 3385-3414): a thread from the current position, its lead growing (G34) or
  // shrinking (G35) by E per revolution; the lead is along Z unless the block has M27.
  if (modal_.css) Fail(col, "thread cutting is not allowed in G96 (constant surface speed) mode");
  const bool first = !chain_.active || (chain_.g != 34 && chain_.g != 35) || chain_.cycle;
  if (w.Has('C')) {
    if (!first) Fail(w.Col('C'), "C (thread phase) is accepted only in the first G34/G35 block");
    if (w.Get('C') < 0 || w.Get('C') > 359.999) Fail(w.Col('C'), "C (thread phase) is 0-359.999");
  }
  if (first) {
    chain_ = ThreadChain();
    chain_.active = true;
    chain_.start_angle = w.Has('C') ? w.Get('C') : 0;
  }
  chain_.g = g;
  const double j = w.Has('J') ? w.Get('J') : 1;
  if (j < 1 || j != std::floor(j)) Fail(w.Col('J'), "J (threads within F) must be a whole number >= 1");
  if (f_ <= 0) Fail(col, "thread cutting needs the lead F");
  const double lead = f_ / j;
  if (lead < 0.001 || lead > 1000) Fail(col, "the thread lead is 0.001-1000 mm");
  double e = w.Has('E') ? Scale('F', w.Get('E'), true) : 0;
  if (g == 35) e = -e;
  AxisArray target = pos_;
  uint32_t moved = 0;
  const bool was_open = open_line_;
  TargetOf(w, target, &moved, col);
  CornerSpec spec;
  if (was_open) {
    spec.end_angle = true;
    const double r = w.Get('A') * kPi / 180.0;
    spec.end_dir = {std::cos(r), modal_.turret_b ? -std::sin(r) : std::sin(r)};
    open_line_ = false;
  } else if (w.Has('A') && !w.Has('X') && !w.Has('Z')) {
    spec.open_end = true;
    const double r = w.Get('A') * kPi / 180.0;
    spec.dir = {std::cos(r), modal_.turret_b ? -std::sin(r) : std::sin(r)};
    open_line_ = true;
  }
  const bool along_x = w.HasM(27);
  if (spec.any()) {
    // The end comes with the next block: the thread op is held with the corner stage.
    force_stage_ = true;
    const AxisArray from = pos_;
    used_ |= moved;
    ThreadOp& t = Out<ThreadOp>();
    force_stage_ = false;
    pos_ = target;
    t.to.pos = pos_;
    t.to.used = used_;
    t.lead = lead;  // along Z or X: the axes' share is known only at the corner; Z lead kept as given
    t.lead_change = e;
    t.start_angle = chain_.start_angle;
    t.exact_stop = modal_.droop;
    thread_phase_.valid = false;  // the lead along the axes is known only at the corner
    if (staged_) {
      stage_.from = from;
      stage_.corner = spec;
    }
    return;
  }
  EmitThread(target, lead, e, chain_.start_angle, along_x);
}

// Depths of cut (diameter, from the crest) of the compound thread cycles (ln 3746-3807, 3891-3905): M73
// passes of D up to D short of H-U then D/2 D/4 D/8 D/8 of what is left, M74 passes of D up to H-U, M75
// (patterns 3 and 4) depth sqrt(n)*D (equal area per pass); M33 puts odd passes halfway between their
// neighbours; then the finishing pass of U.
std::vector<double> OkRun::InfeedDepths(double d, double h, double u, int pattern, int mode, bool has_u,
                                        int col) {
  std::vector<double> out;
  const double target = has_u ? h - u : h;
  if (target <= 0) Fail(col, "the thread height H must be larger than the finishing allowance");
  constexpr double kEps = 1e-9;
  if (target / d > 10000) Fail(col, "more than 10000 thread passes: D is too small");
  if (pattern == 73) {
    if (target < d - kEps) Fail(col, "M73 needs H - U >= D");
    double depth = 0;
    while (depth + d <= target - d + kEps) {
      depth += d;
      out.push_back(depth);
    }
    const double rest = target - depth;
    for (double part : {0.5, 0.25, 0.125}) {
      depth += rest * part;
      out.push_back(depth);
    }
    out.push_back(target);
  } else if (pattern == 74) {
    double depth = 0;
    while (depth < target - kEps) {
      depth = std::min(target, depth + d);
      out.push_back(depth);
    }
  } else {
    for (int n = 1;; ++n) {
      double depth = std::sqrt(static_cast<double>(n)) * d;
      if (mode == 33 && n % 2 == 1) {
        depth = 0.5 * (std::sqrt(static_cast<double>(n + 1)) + std::sqrt(static_cast<double>(n - 1))) * d;
      }
      if (depth >= target - kEps) {
        out.push_back(target);
        break;
      }
      out.push_back(depth);
      if (n > 10000) Fail(col, "too many thread passes");
    }
  }
  // Passes that would not go deeper are dropped.
  std::vector<double> clean;
  for (double v : out) {
    if (clean.empty() || v > clean.back() + kEps) clean.push_back(v);
  }
  if (has_u && u > kEps) clean.push_back(h);
  return clean;
}

void OkRun::CompoundThread(const BlockWords& w, int g, int col) {
  // G71 X Z {A|I} B D U H L E F J M Q / G72 X Z {A|K} B D W H L E F J M Q (ln 3640-3905).
  if (modal_.css) Fail(col, "thread cutting is not allowed in G96 (constant surface speed) mode");
  const bool face = g == 72;
  if (!w.Has('X') || !w.Has('Z')) Fail(col, fmt::format("G{} needs X and Z", g));
  if (!w.Has('D') || w.Get('D') <= 0) Fail(col, fmt::format("G{} needs the first depth of cut D > 0", g));
  if (!w.Has('H') || w.Get('H') <= 0) Fail(col, fmt::format("G{} needs the thread height H > 0", g));
  const char allow = face ? 'W' : 'U';
  const bool has_u = w.Has(allow);
  const double u = has_u ? w.Get(allow) : 0;
  if (u < 0) Fail(w.Col(allow), fmt::format("{} must not be negative", allow));
  const double b = w.Has('B') ? w.Get('B') : 0;
  if (b < 0 || b >= 180) Fail(w.Col('B'), "the infeed angle B is 0 <= B < 180");
  const double q = w.Has('Q') ? w.Get('Q') : 1;
  if (q < 0 || q > 9999 || q != std::floor(q)) Fail(w.Col('Q'), "Q (number of starts) is 0-9999");
  const int starts = std::max(1, static_cast<int>(q));
  const double j = w.Has('J') ? w.Get('J') : 1;
  if (j < 1 || j != std::floor(j)) Fail(w.Col('J'), "J (threads within F) must be a whole number >= 1");
  if (f_ <= 0) Fail(col, "thread cutting needs the lead F");
  const double lead = f_ / j;
  const double e = w.Has('E') ? Scale('F', w.Get('E'), true) : 0;
  const double h = w.Get('H'), d = w.Get('D');
  if (has_u && h <= u) Fail(w.Col('H'), fmt::format("the thread height H must be larger than {}", allow));
  const int pattern = modal_.infeed == 75 ? 75 : modal_.infeed;
  const std::vector<double> depths = InfeedDepths(d, h, u, pattern, modal_.thread_mode, has_u, col);
  const AxisArray s = pos_;
  const double sgn = modal_.turret_b ? -1.0 : 1.0;
  auto prog = [&](int axis, char a) {
    const double cur = ToProgram(axis, s[static_cast<size_t>(axis)]);
    return ToMachine(axis, modal_.incremental ? cur + w.Get(a) : w.Get(a));
  };
  const double x_root = prog(kX, 'X'), z_end = prog(kZ, 'Z');
  const int infeed_axis = face ? kZ : kX;
  const int lead_axis = face ? kX : kZ;
  const double root = face ? z_end : x_root;
  // The crest is on the start point's side of the root.
  const double out_dir = Sign(s[infeed_axis] - root);
  // Taper: I (radius, G71) / K (G72) or A.
  double taper = 0;
  const char tw = face ? 'K' : 'I';
  if (w.Has(tw) && w.Has('A')) Fail(w.Col('A'), fmt::format("give the taper with {} or A, not both", tw));
  if (w.Has(tw)) {
    taper = w.Get(tw);
  } else if (w.Has('A')) {
    const double len = std::fabs(s[lead_axis] - (face ? x_root : z_end)) / (face ? 2 : 1);
    taper = len * std::tan(w.Get('A') * kPi / 180.0);
  }
  if (depths.size() * static_cast<size_t>(starts) > 100000) {
    Fail(col, "more than 100000 thread passes (passes x starts Q)");
  }
  const double tan_half = std::tan(b / 2 * kPi / 180.0);
  const bool chamfer = modal_.thread_chamfer;
  const double l = w.Has('L') ? w.Get('L') : lead;
  for (size_t n = 0; n < depths.size(); ++n) {
    const double depth = depths[n];
    // The pass's infeed-axis position at the end of the thread (X as a diameter), and its flank shift along
    // the lead axis for an infeed angle B: M32 along one flank (toward -Z / -X), M34 the other, M33
    // alternating from pass to pass.
    const double level = root + out_dir * (h - depth);
    double flank = (face ? depth : depth / 2) * tan_half;
    if (modal_.thread_mode == 32 || (modal_.thread_mode == 33 && n % 2 == 0)) flank = -flank;
    for (int k = 0; k < starts; ++k) {
      AxisArray p1 = s, p2 = s;
      if (!face) {
        p2[kX] = level;
        p2[kZ] = z_end + flank;
        p1[kZ] = s[kZ] + flank;
        p1[kX] = level - 2 * taper * sgn;
      } else {
        p2[kZ] = level;
        p2[kX] = x_root + 2 * flank * sgn;
        p1[kX] = s[kX] + 2 * flank * sgn;
        p1[kZ] = level - taper;
      }
      // Multi-start threads (ln 3891-3905): every start at this depth, 360/Q apart, before going deeper.
      const double angle = 360.0 * k / starts;
      RunThreadPass(s, p1, p2, lead, e, angle, face, chamfer ? l : 0);
    }
  }
}

}  // namespace cell::interp::okuma
