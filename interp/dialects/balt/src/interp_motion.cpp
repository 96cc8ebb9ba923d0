// Balt-System motion (manual §5.8.1, 5.8.8, 5.12-5.13): the block's end point in program coordinates
// (G90/G91, a stored GTL point for the plane), G00/G01 with the feed codes G93/G94 (t)/G95, rotary,
// rollover and indexing axes, G79 machine coordinates, G33 threads, DLO limits and DSA protected areas
// checked before the move, and the hand-off of every move to the output or the contour.
#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <optional>

#include "interp_internal.h"

namespace cell::interp::balt {

BaltRun::Targets BaltRun::ReadTargets(const ParsedBlock& pb, bool incremental, bool allow_point) {
  Targets t;
  t.prog = Prog();
  for (const Word& w : pb.words) {
    int a = AxisOfLetter(w.letter);
    if (a < 0) continue;
    double v = ValueOf(w.v, w.col);
    if (IsRotaryAxis(a)) {
      if (index_step_[a] > 0) {
        // An indexing table takes a number of indexes (ln 3909-3938).
        if (v != std::floor(v) || std::fabs(v) > 99999)
          Fail(w.col, 13, "an indexing axis takes a whole number of indexes");
        v *= index_step_[a];
      }
    } else {
      v *= UnitFactor();
    }
    t.raw[a] = v;
    t.neg_zero[a] = w.v.neg && v == 0;
    t.prog[a] = incremental ? t.prog[a] + v : v;
    t.mask |= 1u << a;
  }
  if (pb.elem.kind && !(gtl_profile_ || gtl_block_)) {
    if (pb.elem.kind != 'p' || !allow_point)
      Fail(pb.elem.col, 25, "a GTL element here needs G21 (a GTL profile)");
    // ln 2701: a stored point gives the plane's abscissa and ordinate (always absolute).
    gtl::Element p = ResolveRef(pb.elem);
    if ((t.mask & ((1u << mode_.p1) | (1u << mode_.p2))) != 0) {
      Fail(pb.elem.col, 24, "a point and plane coordinates in one block");
    }
    t.prog[mode_.p1] = p.p.x;
    t.prog[mode_.p2] = p.p.y;
    t.raw[mode_.p1] = p.p.x;
    t.raw[mode_.p2] = p.p.y;
    t.mask |= (1u << mode_.p1) | (1u << mode_.p2);
  }
  t.plane_mask = t.mask & ((1u << mode_.p1) | (1u << mode_.p2));
  return t;
}

void BaltRun::Move(const ParsedBlock& pb, const BlockG& g, const Targets& t) {
  switch (mode_.motion) {
    case Motion::kRapid:
    case Motion::kLinear:
      LinearMove(pb, g, t, mode_.motion == Motion::kRapid);
      return;
    case Motion::kCw:
    case Motion::kCcw:
      ArcMove(pb, g, t);
      return;
    case Motion::kThread:
      ThreadMove(pb, t);
      return;
  }
}

// Machine targets of rotary axes (ln 3940-4038): degrees; a rollover axis in G90 goes to the angle modulo
// 360 in the direction of the sign ("B-0"), in G91 by the increment; others by the difference.
void BaltRun::RotaryTargets(const Targets& t, AxisArray& mach, AxisArray& travel, std::uint32_t& travel_mask,
                            bool g79) {
  for (int a : {kA, kB, kC}) {
    if (!(t.mask & (1u << a))) continue;
    double from = pos_[a];
    double to = mach[a];
    double tr;
    if (rollover_mask_ & (1u << a)) {
      if (mode_.incremental && !g79) {
        tr = t.raw[a];
      } else {
        double target = std::fmod(std::fabs(t.raw[a]) + (g79 ? 0 : origin_[a]), 360.0);
        if (target < 0) target += 360;
        bool negative = t.raw[a] < 0 || t.neg_zero[a];
        double fwd = std::fmod(target - std::fmod(from, 360.0) + 720.0, 360.0);
        tr = negative ? (fwd == 0 ? 0 : fwd - 360.0) : fwd;
      }
      to = from + tr;
    } else {
      tr = to - from;
    }
    mach[a] = to;
    if (std::fabs(tr) > 1e-9) {
      travel[a] = tr;
      travel_mask |= 1u << a;
    }
  }
}

// The feed of a feed move (ln 2490-2496, 3685-3725, 3982-3984): mm/min (G94; F = length / t with a t word),
// inverse time (G93, F in every block), per revolution (G95); deg/min when only rotary axes move.
double BaltRun::BlockFeed(const ParsedBlock& pb, double length_mm, bool rotary_only, FeedMode* mode, int col,
                          double turned) {
  const Word* t = nullptr;
  if (pb.letters & LetterBit('t')) {
    for (const Word& w : pb.words) {
      if (w.letter == 't') t = &w;
    }
  }
  if (mode_.feed == FeedCode::kG93) {
    const bool given = (pb.letters & LetterBit('F')) != 0;
    *mode = FeedMode::kInverseTime;
    if (t) {
      double secs = ValueOf(t->v, t->col);
      if (secs <= 0) Fail(t->col, 13, "t is a time in seconds");
      return 60.0 / secs;
    }
    if (!given) Fail(col, 86, "G93: F in every block");
    return block_feed_;
  }
  if (t) {
    double secs = ValueOf(t->v, t->col);
    if (secs <= 0) Fail(t->col, 13, "t is a time in seconds");
    *mode = rotary_only ? FeedMode::kDegPerMinute : FeedMode::kPerMinute;
    return length_mm / (secs / 60.0);
  }
  if (!feed_) Fail(col, 86, "no F programmed");
  if (mode_.feed == FeedCode::kG95) {
    *mode = FeedMode::kPerRev;
    return *feed_;
  }
  if (rotary_only) {
    *mode = FeedMode::kDegPerMinute;
    return *feed_ / UnitFactor();  // F is degrees per minute
  }
  *mode = FeedMode::kPerMinute;
  // Rotary axes turning with linear ones (ln 3961-3976: F = A * sqrt(X^2 + Y^2 + Z^2 + B^2 + C^2) / L, the
  // travels in mm and degrees): F is the rate along that vector, so the linear axes run at F times their
  // share of it (judgement call 21).
  if (turned > 0 && length_mm > 0) return *feed_ * length_mm / std::hypot(length_mm, turned);
  return *feed_;
}

void BaltRun::LinearMove(const ParsedBlock& pb, const BlockG& g, const Targets& t_in, bool rapid) {
  // A copy of the targets only for paraxial words to change (most blocks have none; G79 takes none).
  std::optional<Targets> para;
  if (!g.g79 && (pb.letters & (LetterBit('u') | LetterBit('v') | LetterBit('w')))) [[unlikely]] {
    para.emplace(t_in);
    Paraxial(pb, *para);
  }
  const Targets& t = para ? *para : t_in;
  AxisArray mach;
  int col = pb.words.empty() ? 1 : pb.words[0].col;
  for (const Word& w : pb.words) {
    if (AxisOfLetter(w.letter) >= 0 || w.letter == 'G') {
      col = w.col;
      if (w.letter != 'G') break;
    }
  }
  if (g.g79) {
    // ln 3601: machine coordinates for this block, no origin, rotation, mirror or scale; the tool length
    // still applies (a judgement call).
    mach = pos_;
    for (int a = 0; a < kAxisCount; ++a) {
      if (!(t.mask & (1u << a))) continue;
      mach[a] = t.raw[a] + (a == len_axis_ ? tool_len_ : 0);
    }
  } else {
    mach = ToMachine(t.prog);
  }
  AxisArray travel{};
  std::uint32_t travel_mask = 0;
  // Indexing axes turn before the other axes of the block (ln 3918).
  std::uint32_t index_mask = 0;
  if (t.mask & kRotaryAxes) [[unlikely]] {
    RotaryTargets(t, mach, travel, travel_mask, g.g79);
    for (int a : {kA, kB, kC}) {
      if ((t.mask & (1u << a)) && index_step_[a] > 0) index_mask |= 1u << a;
    }
  }
  std::uint32_t moved = t.mask;
  if (!identity_ && (t.mask & ((1u << mode_.p1) | (1u << mode_.p2))))
    moved |= (1u << mode_.p1) | (1u << mode_.p2);
  geom::Path path;
  path.start = {pos_[mode_.p1], pos_[mode_.p2]};
  path.end = {mach[mode_.p1], mach[mode_.p2]};
  double len = 0;
  bool linear_moves = false;
  for (int a : {kX, kY, kZ, kU, kV, kW}) {  // the linear axes, in index order
    double d = mach[a] - pos_[a];
    len += d * d;
    if (std::fabs(d) > 1e-9) linear_moves = true;
  }
  len = std::sqrt(len);
  Feed feed;
  if (!rapid) {
    double rot = 0, turned = 0;  // turned: the continuous rotary axes (an index table turns first)
    if (travel_mask) {
      for (int a : {kA, kB, kC}) {
        rot += travel[a] * travel[a];
        if (!(index_mask & (1u << a))) turned += travel[a] * travel[a];
      }
    }
    feed.rate = BlockFeed(pb, linear_moves ? len : std::sqrt(rot), !linear_moves && travel_mask != 0,
                          &feed.mode, col, linear_moves ? std::sqrt(turned) : 0);
    // G28 blends (no corner deceleration, ln 2969); G29 stops; G27 decelerates to 0 at each block end with
    // the default ERF=0 (ln 4317) and, as the canon carries no form error, with any ERF (balt.md).
    feed.exact_stop = mode_.dynamic != Dynamic::kG28 || g.decel;
  }
  if (!g.g79 && lim_mask_) CheckLimits(pos_, mach, nullptr, col);
  if (AreasActive()) CheckAreas(pos_, mach, nullptr, col);
  if (index_mask && (t.mask & ~index_mask)) {
    AxisArray first = pos_;
    AxisArray first_travel{};
    for (int a : {kA, kB, kC}) {
      if (index_mask & (1u << a)) {
        first[a] = mach[a];
        first_travel[a] = travel[a];
      }
    }
    geom::Path none;
    none.start = none.end = path.start;
    EmitMotion(Op::kRapid, first, index_mask, Feed{}, none, first_travel, travel_mask & index_mask, 0);
    travel_mask &= ~index_mask;
    moved &= ~index_mask;
  }
  EmitMotion(rapid || index_mask == moved ? Op::kRapid : Op::kLinear, mach, moved, feed, path, travel,
             travel_mask, 0);
  prog_ = t.prog;  // paraxial factors included: axes left out of the next block stay where they are
  prog_valid_ = !g.g79;
}

// G33 (ln 2838-2934): a spindle-synchronised straight move; K the lead (compulsory), I its change per
// revolution, R the start angle (multi-start threads; allowed in every thread, a judgement call).
void BaltRun::ThreadMove(const ParsedBlock& pb, const Targets& t) {
  if (contour_.engaged()) Fail(1, 25, "G33 is not allowed with cutter compensation");
  const Word* k = nullptr;
  const Word* i = nullptr;
  const Word* r = nullptr;
  int col = 1;
  for (const Word& w : pb.words) {
    if (w.letter == 'K') k = &w;
    if (w.letter == 'I') i = &w;
    if (w.letter == 'R') r = &w;
    if (w.letter == 'G') col = w.col;
  }
  if (!k) Fail(col, 12, "G33 needs the pitch K");
  if (std::popcount(t.mask) > 2) Fail(col, 23, "more than two axes in a thread");
  if (!speed_set_ || spindle_ == SpindleDir::kStop || spindle_ == SpindleDir::kOrient) {
    Fail(col, 10, "the spindle is not turning");
  }
  double lead = ValueOf(k->v, k->col) * UnitFactor();
  if (lead <= 0) Fail(k->col, 13, "the pitch K is positive");
  AxisArray mach = ToMachine(t.prog);
  double change = i ? ValueOf(i->v, i->col) * UnitFactor() : 0;
  if (change < 0) {
    // ln 2910: a decreasing pitch must not reach zero: I <= K^2 / (2 L).
    double len = 0;
    for (int a = 0; a < kAxisCount; ++a) len += (mach[a] - pos_[a]) * (mach[a] - pos_[a]);
    len = std::sqrt(len);
    if (len > 0 && -change > lead * lead / (2 * len) + 1e-9) Fail(i->col, 10, "the pitch would reach zero");
  }
  CheckLimits(pos_, mach, nullptr, col);
  CheckAreas(pos_, mach, nullptr, col);
  EmitUnitsOnce();
  used_ |= t.mask;
  ThreadOp& th = Out<ThreadOp>();
  th.to.pos = mach;
  th.to.used = used_;
  th.lead = lead;
  th.lead_change = change;
  th.start_angle = r ? ValueOf(r->v, r->col) : 0;
  pos_ = mach;
  prog_ = t.prog;
  prog_valid_ = true;
}

// DLO (ln 795-821): a move ending (or an arc passing) beyond the limits is refused before it starts.
void BaltRun::CheckLimits(const AxisArray& from, const AxisArray& to, const geom::Path* arc, int col) {
  if (!lim_mask_) return;
  (void)from;
  for (int a = 0; a < kAxisCount; ++a) {
    if (!(lim_mask_ & (1u << a))) continue;
    double lo = to[a], hi = to[a];
    if (arc && (a == mode_.p1 || a == mode_.p2)) {
      // The arc's extent on this axis: its ends and the quadrant points it passes.
      const bool first = a == mode_.p1;
      double rad = Norm(arc->start - arc->center);
      for (int q = 0; q < 4; ++q) {
        geom::Vec2 p = arc->center + rad * geom::Vec2{q == 0 ? 1.0 : (q == 2 ? -1.0 : 0.0),
                                                      q == 1 ? 1.0 : (q == 3 ? -1.0 : 0.0)};
        if (geom::Sweep(arc->start, p, arc->center, arc->cw) <= arc->sweep + 1e-9) {
          lo = std::min(lo, first ? p.x : p.y);
          hi = std::max(hi, first ? p.x : p.y);
        }
      }
    }
    if (lo < lim_lo_[a] - 1e-6 || hi > lim_hi_[a] + 1e-6) {
      Fail(col, 3,
           fmt::format("{} outside {:.3f} .. {:.3f} (DLO)", LetterOfAxis(a), lim_lo_[a] - origin_[a],
                       lim_hi_[a] - origin_[a]));
    }
  }
}

// DSA / ASC (ln 823-861): no move may enter an active protected area of the plane.
void BaltRun::CheckAreas(const AxisArray& from, const AxisArray& to, const geom::Path* arc, int col) {
  for (std::size_t n = 1; n < areas_.size(); ++n) {
    const Area& ar = areas_[n];
    if (!ar.active) continue;
    auto inside = [&](double x, double y) {
      return x > ar.lo1 + 1e-9 && x < ar.hi1 - 1e-9 && y > ar.lo2 + 1e-9 && y < ar.hi2 - 1e-9;
    };
    bool hit = false;
    const int steps = 256;
    for (int k = 0; k <= steps && !hit; ++k) {
      double s = static_cast<double>(k) / steps;
      double x, y;
      if (arc && ar.p1 == mode_.p1 && ar.p2 == mode_.p2) {
        double rad = Norm(arc->start - arc->center);
        double a0 = std::atan2(arc->start.y - arc->center.y, arc->start.x - arc->center.x);
        double ang = a0 + (arc->cw ? -1 : 1) * arc->sweep * kDeg * s;
        x = arc->center.x + rad * std::cos(ang);
        y = arc->center.y + rad * std::sin(ang);
      } else {
        x = from[ar.p1] + (to[ar.p1] - from[ar.p1]) * s;
        y = from[ar.p2] + (to[ar.p2] - from[ar.p2]) * s;
      }
      hit = inside(x, y);
    }
    if (hit) Fail(col, 84, fmt::format("the move enters protected area {}", n));
  }
}

void BaltRun::EmitDwell(double seconds) {
  if (seconds <= 0) return;
  Out<DwellOp>().seconds = seconds;
}

void BaltRun::EmitMotion(Op op, const AxisArray& mach_in, std::uint32_t moved, const Feed& feed,
                         const geom::Path& path, const AxisArray& travel, std::uint32_t travel_mask,
                         double helix_turns) {
  bool change = travel_mask != 0 || op == Op::kArc;
  for (int a = 0; a < kAxisCount && !change; ++a) {
    if (std::fabs(mach_in[a] - pos_[a]) > 1e-9) change = true;
  }
  used_ |= moved;
  if (!change) {
    pos_ = mach_in;
    return;  // a block that commands the current position does not move
  }
  EmitUnitsOnce();
  idle_ = 0;
  // The written position: the rotary axes at 0-360 once one has been used (only then a copy).
  const AxisArray* out = &mach_in;
  AxisArray wrapped;
  if (used_ & kRotaryAxes) [[unlikely]] {
    wrapped = mach_in;
    for (int a : {kA, kB, kC}) {
      double v = std::fmod(wrapped[a], 360.0);
      if (v < 0) v += 360.0;
      if (v >= 360.0 - 1e-9) v = 0;
      wrapped[a] = v;
    }
    out = &wrapped;
  }
  Target* to = nullptr;
  // A routed move is made in stage_, free once CommitStage has handed on what it held (an optional Canon here
  // cost every move its set-up and clean-up); the queue's slot otherwise.
  Canon* routed = nullptr;
  // Moves in the plane: one coordinate alone of at least kTiny settles it without std::hypot (a length is
  // never below its larger coordinate).
  const geom::Vec2 step = path.end - path.start;
  const bool in_plane = op == Op::kArc || std::fabs(step.x) >= geom::kTiny ||
                        std::fabs(step.y) >= geom::kTiny || geom::Norm(step) >= geom::kTiny;
  // A corner word in the next block keeps this move open (ln 3160-3200).
  if (in_plane && !gtl_profile_ && !contour_.on() && op != Op::kRapid) hold_next_ = NextIsCornerWord();
  const bool route = Routed();
  if (route) {
    CommitStage();
    routed = &stage_;
    routed->line = cur_line_;
  }
  switch (op) {
    case Op::kRapid:
      to = route ? &routed->Set<RapidOp>().to : &out_.Emplace<RapidOp>(cur_line_).to;
      break;
    case Op::kLinear: {
      LinearOp& l = route ? routed->Set<LinearOp>() : out_.Emplace<LinearOp>(cur_line_);
      l.feed = feed;
      to = &l.to;
      break;
    }
    default: {
      ArcOp& a = route ? routed->Set<ArcOp>() : out_.Emplace<ArcOp>(cur_line_);
      a.feed = feed;
      a.cw = path.cw;
      a.angle = path.sweep + 360.0 * helix_turns;
      a.plane = {static_cast<std::int8_t>(mode_.p1), static_cast<std::int8_t>(mode_.p2)};
      AxisArray c = pos_;
      c[mode_.p1] = path.center.x;
      c[mode_.p2] = path.center.y;
      a.center = {c[kX], c[kY], c[kZ]};
      if (mode_.p1 == kU || mode_.p2 == kU) a.center[0] = c[kU];
      if (mode_.p1 == kV || mode_.p2 == kV) a.center[1] = c[kV];
      if (mode_.p1 == kW || mode_.p2 == kW) a.center[2] = c[kW];
      to = &a.to;
      break;
    }
  }
  to->pos = *out;
  to->used = used_;
  to->travel = travel;
  to->travel_mask = travel_mask;
  if (route && GtlDefers()) {
    profile_.deferred.push_back(std::move(*routed));  // at the end of the element being traversed
  } else if (route) {
    if (!contour_.engaged()) contour_.Sync(pos_);
    try {
      contour_.Take(std::move(*routed), in_plane ? &path : nullptr, gtl_profile_ || hold_next_);
    } catch (const ContourError& e) {
      ContourFail(e);
    }
    ContourDrain();
  }
  const AxisArray& written = *out;  // `wrapped` or mach_in: both outlive the routed command
  pos_ = mach_in;
  if (rollover_mask_) [[unlikely]] {
    for (int a : {kA, kB, kC}) {
      if (rollover_mask_ & (1u << a)) pos_[a] = written[a];
    }
  }
}

}  // namespace cell::interp::balt
