// GTL in Balt-System programs (manual §5.15, ln 4363-5406): element definitions "p1 = ..." (the operands
// read here, solved in gtl.cpp) and profiles G21 ... G20: open (a point first and last) or closed (the last
// element first, the first element last, ln 5100-5150), connected by intersections (s2: the second,
// ln 5168-5190) or automatic radii and bevels (the contour's corner words), compensated with G41/G42.
#include <fmt/format.h>

#include <cmath>
#include <optional>

#include "interp_internal.h"

namespace cell::interp::balt {
namespace {

using geom::Vec2;

Vec2 Rotate(Vec2 v, double deg) {
  double c = std::cos(deg * kDeg), s = std::sin(deg * kDeg);
  return {v.x * c - v.y * s, v.x * s + v.y * c};
}

struct Token {
  enum Kind { kRef, kS2, kWord } kind = kWord;
  char letter = 0;  // word: upper-case coordinate or I J; lower-case r a d m; ref: o p l c
  bool neg = false;
  Val v;
  int col = 1;
};

// The tokens of a definition; commas only separate (a point may be written "B70,Y40", ln 5225).
std::vector<Token> GtlTokens(const Assignment& a, int p1, int p2) {
  std::vector<Token> toks;
  std::string_view s = a.rhs;
  std::size_t i = 0;
  auto col_at = [&](std::size_t k) { return a.rhs_col + static_cast<int>(k); };
  auto value = [&](Token& t) {
    while (i < s.size() && s[i] == ' ') ++i;
    bool neg = false;
    if (i < s.size() && (s[i] == '-' || s[i] == '+')) {
      neg = s[i] == '-';
      ++i;
    }
    while (i < s.size() && s[i] == ' ') ++i;
    if (i < s.size() && s[i] == 'E' && i + 1 < s.size() && IsDigit(s[i + 1])) {
      ++i;
      int n = 0;
      while (i < s.size() && IsDigit(s[i])) n = n * 10 + (s[i++] - '0');
      t.v.kind = Val::kParam;
      t.v.param = n;
    } else if (i < s.size() && (IsDigit(s[i]) || s[i] == '.')) {
      double n = 0;
      while (i < s.size() && IsDigit(s[i])) n = n * 10 + (s[i++] - '0');
      if (i < s.size() && s[i] == '.') {
        ++i;
        double sc = 0.1;
        while (i < s.size() && IsDigit(s[i])) {
          n += (s[i++] - '0') * sc;
          sc /= 10;
        }
      }
      t.v.kind = Val::kNum;
      t.v.num = n;
    }
    t.v.neg = neg;
  };
  while (i < s.size()) {
    char c = s[i];
    if (c == ' ' || c == ',' || c == '\t') {
      ++i;
      continue;
    }
    Token t;
    t.col = col_at(i);
    if (c == '-' && i + 1 < s.size() && (s[i + 1] == 'l' || s[i + 1] == 'c')) {
      t.neg = true;
      c = s[++i];
    }
    if ((c == 'o' || c == 'p' || c == 'l' || c == 'c') && i + 1 < s.size() &&
        (IsDigit(s[i + 1]) || s[i + 1] == 'E' || s[i + 1] == ' ')) {
      t.kind = Token::kRef;
      t.letter = c;
      ++i;
      value(t);
      if (t.v.kind == Val::kNone || t.v.neg) Fail(t.col, 11, "an element needs its index");
      toks.push_back(t);
      continue;
    }
    if (c == 's' && i + 1 < s.size() && s[i + 1] == '2') {
      t.kind = Token::kS2;
      i += 2;
      toks.push_back(t);
      continue;
    }
    bool coord = c == LetterOfAxis(p1) || c == LetterOfAxis(p2) || c == 'I' || c == 'J';
    if (coord || c == 'r' || c == 'a' || c == 'd' || c == 'm') {
      t.letter = c;
      ++i;
      value(t);
      toks.push_back(t);
      continue;
    }
    if (IsUpper(c)) {
      Fail(t.col, 24,
           fmt::format("'{}' is not a coordinate of the {}{} plane", c, LetterOfAxis(p1), LetterOfAxis(p2)));
    }
    Fail(t.col, 11, fmt::format("'{}' in a GTL definition", c));
  }
  return toks;
}

// Literal words being collected into one operand: a point, a circle (I J r) or a polar point (m a [r]).
struct GtlGroup {
  char kind = 0;  // 'P' point, 'C' circle (I J r), 'M' polar (m a [r])
  double x = 0, y = 0, r = 0, m = 0, an = 0;
  bool hx = false, hy = false, hr = false, ha = false;
  std::optional<gtl::Element> o;

  // The group as an operand (when there is one), and a new group.
  void Close(std::vector<gtl::Operand>& ops, int rhs_col) {
    if (!kind) return;
    auto place = [&](Vec2 v) { return o ? o->p + Rotate(v, o->a) : v; };
    gtl::Operand op;
    op.literal = true;
    if (kind == 'P') {
      op.kind = gtl::Operand::kPoint;
      op.e.kind = gtl::Element::kPoint;
      op.e.p = place({x, y});
    } else {
      Vec2 c = kind == 'C' ? Vec2{x, y} : Vec2{m * std::cos(an * kDeg), m * std::sin(an * kDeg)};
      bool circle = kind == 'C' || hr;
      if (kind == 'C' && !hr) Fail(rhs_col, 12, "a circle needs its radius r");
      op.kind = circle ? gtl::Operand::kCircle : gtl::Operand::kPoint;
      op.e.kind = circle ? gtl::Element::kCircle : gtl::Element::kPoint;
      op.e.p = place(c);
      op.e.r = r;
    }
    ops.push_back(op);
    *this = GtlGroup();
  }
};

}  // namespace

gtl::Element BaltRun::ResolveRef(const ElemRef& r) {
  double idx = ValueOf(r.index, r.col);
  if (idx != std::floor(idx) || idx < 0 || idx > gtl::Geometry::kMaxIndex) {
    Fail(r.col, 18, fmt::format("{}{:g} (elements are 0-255)", r.kind, idx));
  }
  const gtl::Element* e = gtl_.Get(r.kind, static_cast<int>(idx));
  if (!e) Fail(r.col, 15, fmt::format("{}{:g} is not defined", r.kind, idx));
  return r.neg ? e->Reversed() : *e;
}

// "NAME INDEX = <definition>" (ln 4420-4513).
void BaltRun::DefineElement(const Assignment& a) {
  const char kind = a.name[0];
  double idx = ValueOf(a.gindex, a.col);
  if (idx != std::floor(idx) || idx < 0 || idx > gtl::Geometry::kMaxIndex) {
    Fail(a.col, 18, fmt::format("{}{:g} (elements are 0-255)", kind, idx));
  }
  if (mode_.incremental) Fail(a.col, 25, "GTL works in G90 only");
  const std::vector<Token> toks = GtlTokens(a, mode_.p1, mode_.p2);
  // Operands.
  const double unit = UnitFactor();
  std::vector<gtl::Operand> ops;
  std::optional<gtl::Element> origin;
  bool any_origin = false;
  double origin_angle = 0;
  GtlGroup g;
  auto close = [&]() { g.Close(ops, a.rhs_col); };
  for (const Token& t : toks) {
    if (t.kind == Token::kS2) {
      close();
      gtl::Operand op;
      op.kind = gtl::Operand::kS2;
      ops.push_back(op);
      continue;
    }
    if (t.kind == Token::kRef) {
      close();
      if (t.letter == 'o') {
        origin = ResolveRef(ElemRef{'o', false, t.v, t.col});
        if (!any_origin) origin_angle = origin->a;
        any_origin = true;
        continue;
      }
      gtl::Operand op;
      op.e = ResolveRef(ElemRef{t.letter, t.neg, t.v, t.col});
      op.kind = t.letter == 'p' ? gtl::Operand::kPoint
                                : (t.letter == 'l' ? gtl::Operand::kLine : gtl::Operand::kCircle);
      ops.push_back(op);
      continue;
    }
    double v = ValueOf(t.v, t.col);
    switch (t.letter) {
      case 'I':
      case 'J': {
        bool first = t.letter == 'I';
        if (g.kind != 'C' || (first ? g.hx : g.hy)) {
          close();
          g.kind = 'C';
          g.o = origin;
          origin.reset();
        }
        (first ? g.x : g.y) = v * unit;
        (first ? g.hx : g.hy) = true;
        break;
      }
      case 'r':
        if ((g.kind == 'C' || g.kind == 'M') && !g.hr) {
          g.r = v * unit;
          g.hr = true;
        } else {
          close();
          gtl::Operand op;
          op.kind = gtl::Operand::kRadius;
          op.v = v * unit;
          ops.push_back(op);
        }
        break;
      case 'm':
        close();
        g.kind = 'M';
        g.m = v * unit;
        g.o = origin;
        origin.reset();
        break;
      case 'a':
        if (g.kind == 'M' && !g.ha) {
          g.an = v;
          g.ha = true;
        } else {
          close();
          gtl::Operand op;
          op.kind = gtl::Operand::kAngle;
          op.v = v + origin_angle;  // angles in the frame of the origin the definition uses
          ops.push_back(op);
        }
        break;
      case 'd': {
        close();
        gtl::Operand op;
        op.kind = gtl::Operand::kDistance;
        op.v = v * unit;
        ops.push_back(op);
        break;
      }
      default: {
        bool first = t.letter == LetterOfAxis(mode_.p1);
        if (g.kind != 'P' || (first ? g.hx : g.hy)) {
          close();
          g.kind = 'P';
          g.o = origin;
          origin.reset();
        }
        (first ? g.x : g.y) = v * unit;
        (first ? g.hx : g.hy) = true;
        break;
      }
    }
  }
  close();
  if (ops.empty()) Fail(a.rhs_col, 12, "the definition is empty");
  try {
    gtl_.Set(kind, static_cast<int>(idx), gtl::Define(kind, ops));
  } catch (const gtl::GeomError& e) {
    Fail(a.rhs_col, e.code, e.text);
  }
}

std::string BaltRun::DisplayElement(char kind, int index, int col) {
  const gtl::Element* e = gtl_.Get(kind, index);
  if (!e) Fail(col, 15, fmt::format("{}{} is not defined", kind, index));
  const double u = UnitFactor();
  auto n = [](double v) {
    std::string s = fmt::format("{:.4f}", std::fabs(v) < 5e-5 ? 0.0 : v);
    while (s.back() == '0') s.pop_back();
    if (s.back() == '.') s.pop_back();
    return s;
  };
  switch (kind) {
    case 'p':
      return fmt::format("{}{} {}{}", LetterOfAxis(mode_.p1), n(e->p.x / u), LetterOfAxis(mode_.p2),
                         n(e->p.y / u));
    case 'l':  // distance from the origin and angle (ln 6708-6710)
      return fmt::format("d{} a{}", n(std::fabs(Cross(e->d, e->p)) / u), n(e->AngleDeg()));
    default:
      return fmt::format("I{} J{} r{}", n(e->p.x / u), n(e->p.y / u), n(e->r / u));
  }
}

geom::Vec2 BaltRun::PlaneToMachine(geom::Vec2 p) const {
  AxisArray prog = prog_valid_ ? prog_ : ToProgram(pos_);
  prog[mode_.p1] = p.x;
  prog[mode_.p2] = p.y;
  AxisArray m = ToMachine(prog);
  return {m[mode_.p1], m[mode_.p2]};
}

// Where element a (being traversed) meets b: the intersection the profile's rules select (ln 5168-5190):
// along the line for a line and a circle, left / right of the centres for two circles, s2 the second.
geom::Vec2 BaltRun::GtlConnect(const gtl::Element& a, const gtl::Element& b, bool s2) {
  Vec2 pts[2];
  int n = gtl::Intersect(a, b, pts);
  if (n == 0) Fail(1, 77, "the elements do not intersect");
  return (s2 && n == 2) ? pts[1] : pts[0];
}

namespace {

// A short piece of an element ending at (or starting from) a point: a closed profile's neighbour, to find
// the compensated corner where it starts or ends.
geom::Path Piece(const gtl::Element& e, Vec2 at, bool ending) {
  geom::Path p;
  if (e.kind == gtl::Element::kLine) {
    p.start = ending ? at + (-10.0) * e.d : at;
    p.end = ending ? at : at + 10.0 * e.d;
    return p;
  }
  p.arc = true;
  p.center = e.p;
  p.cw = e.r < 0;
  double step = (p.cw ? -10.0 : 10.0) * (ending ? -1 : 1);
  Vec2 other = e.p + Rotate(at - e.p, step);
  p.start = ending ? other : at;
  p.end = ending ? at : other;
  p.sweep = 10;
  return p;
}

}  // namespace

geom::Path BaltRun::ToMachinePath(const geom::Path& p) const {
  geom::Path m = p;
  m.start = PlaneToMachine(p.start);
  m.end = PlaneToMachine(p.end);
  if (p.arc) {
    m.center = PlaneToMachine(p.center);
    if (MirrorFlipsPlane()) m.cw = !m.cw;
  }
  return m;
}

// One element of a profile from `from` to `to` (program plane coordinates), at the feed, into the contour.
void BaltRun::GtlSegment(const gtl::Element& e, Vec2 from, Vec2 to, int line) {
  if (!feed_) Fail(1, 86, "no F programmed for the profile");
  geom::Path p;
  p.start = from;
  p.end = to;
  if (e.kind == gtl::Element::kCircle) {
    p.arc = true;
    p.center = e.p;
    p.cw = e.r < 0;
  } else if (geom::Norm(to - from) < geom::kTiny) {
    return;  // the element is only touched
  }
  geom::Path m = ToMachinePath(p);
  if (m.arc) m.sweep = geom::Sweep(m.start, m.end, m.center, m.cw);
  Canon c;
  c.line = line;
  AxisArray target = pos_;
  target[mode_.p1] = m.end.x;
  target[mode_.p2] = m.end.y;
  used_ |= (1u << mode_.p1) | (1u << mode_.p2);
  Feed f;
  f.rate = *feed_;
  f.mode = mode_.feed == FeedCode::kG95 ? FeedMode::kPerRev : FeedMode::kPerMinute;
  f.exact_stop = mode_.dynamic != Dynamic::kG28;  // G27 stops at block ends, G28 blends (ln 2967-2969, 4317)
  Target* t;
  if (m.arc) {
    ArcOp& a = c.Set<ArcOp>();
    a.feed = f;
    a.cw = m.cw;
    a.angle = m.sweep;
    a.plane = {static_cast<std::int8_t>(mode_.p1), static_cast<std::int8_t>(mode_.p2)};
    AxisArray cc = pos_;
    cc[mode_.p1] = m.center.x;
    cc[mode_.p2] = m.center.y;
    a.center = {cc[kX], cc[kY], cc[kZ]};
    if (mode_.p1 == kU || mode_.p2 == kU) a.center[0] = cc[kU];
    if (mode_.p1 == kV || mode_.p2 == kV) a.center[1] = cc[kV];
    if (mode_.p1 == kW || mode_.p2 == kW) a.center[2] = cc[kW];
    t = &a.to;
  } else {
    LinearOp& l = c.Set<LinearOp>();
    l.feed = f;
    t = &l.to;
  }
  t->pos = target;
  for (int a : {kA, kB, kC}) {
    t->pos[a] = std::fmod(t->pos[a], 360.0);
    if (t->pos[a] < 0) t->pos[a] += 360.0;
  }
  t->used = used_;
  CheckLimits(pos_, target, m.arc ? &m : nullptr, 1);
  CheckAreas(pos_, target, m.arc ? &m : nullptr, 1);
  EmitUnitsOnce();
  idle_ = 0;
  if (!contour_.engaged()) contour_.Sync(pos_);
  try {
    contour_.Take(std::move(c), &m, true);
  } catch (const ContourError& err) {
    ContourFail(err);
  }
  pos_ = target;
  Prog();
  prog_[mode_.p1] = to.x;
  prog_[mode_.p2] = to.y;
  GtlFlushDeferred();
}

void BaltRun::GtlFlushDeferred() {
  std::vector<Canon> d = std::move(profile_.deferred);
  profile_.deferred.clear();
  try {
    for (auto& c : d) contour_.Take(std::move(c), nullptr, false);
  } catch (const ContourError& err) {
    ContourFail(err);
  }
  ContourDrain();
}

bool BaltRun::GtlDefers() const {
  return gtl_profile_ && (profile_.has_elem || (profile_.closed && !profile_.started));
}

void BaltRun::GtlBlock(const ParsedBlock& pb, const BlockG& g, const Targets& t) {
  const int col = g.first_col;
  if (mode_.incremental) Fail(col, 25, "GTL works in G90 only (ln 4369)");
  if (mode_.feed == FeedCode::kG93) Fail(col, 25, "G93 in a GTL profile");
  // Only G27, G28, G04, G41, G42 inside a profile (ln 5060), and G20 G40 to close it.
  if (gtl_profile_ && (g.any_motion || g.plane || g.cycle || g.g79 || g.probe || g.absinc || g.unit ||
                       g.feed || g.speed || g.dyn == 29 || g.gtl == 21 || (g.comp == 40 && g.gtl != 20))) {
    Fail(col, 25, "only G27, G28, G04, G41, G42 inside a GTL profile");
  }
  std::uint32_t plane_bits = (1u << mode_.p1) | (1u << mode_.p2);
  if (t.mask & plane_bits) Fail(col, 24, "a GTL profile moves the plane's axes through its elements");
  const Word* corner = nullptr;
  for (const Word& w : pb.words) {
    if (w.letter == 'r' || w.letter == 'b') corner = &w;
    if (w.letter == 'u' || w.letter == 'v' || w.letter == 'w') Fail(w.col, 25, "paraxial factors in GTL");
    if (w.letter == 'I' || w.letter == 'J' || w.letter == 'R' || w.letter == 'K')
      Fail(w.col, 24, "in a GTL profile block");
  }
  if (!gtl_profile_) {
    if (g.gtl != 21) {
      if (pb.elem.kind || t.mask) Fail(col, 25, "G20 without an open profile");
      return;  // G20 alone: the power-up state
    }
    if (!pb.elem.kind) Fail(col, 12, "G21 names the profile's first element (a point) or its last element");
    if (corner) Fail(corner->col, 77, "a profile may not start with a radius or a bevel");
    if (!feed_) Fail(col, 86, "no F programmed for the profile");
    gtl::Element e = ResolveRef(pb.elem);
    gtl_profile_ = true;
    profile_ = Profile();
    profile_.g21_pos = pos_;
    profile_.g21_used = used_;
    if (e.kind == gtl::Element::kPoint) {
      // Open profile: to the first point at the feed (the start move when compensated).
      profile_.start = e.p;
      profile_.g21_line = cur_line_;
      GtlApproach(e.p);
      profile_.started = true;
    } else {
      profile_.closed = true;
      profile_.last = e;
      profile_.last_s2 = pb.s2;
      profile_.g21_line = cur_line_;
    }
    if (t.mask) LinearMove(pb, g, t, false);  // axes off the plane in the G21 block
    return;
  }
  if (corner && !pb.elem.kind) {
    if (!profile_.has_elem) Fail(corner->col, 77, "a profile may not start with a radius or a bevel");
    if (profile_.pending_corner) Fail(corner->col, 77, "two corner words in a row");
    double v = ValueOf(corner->v, corner->col);
    if (corner->letter == 'b' && corner->v.neg) Fail(corner->col, 13, "a bevel is written without a sign");
    profile_.pending_corner = true;
    profile_.corner = corner->letter;
    profile_.corner_value = v * UnitFactor();
    profile_.corner_line = cur_line_;
    return;
  }
  if (!pb.elem.kind) {
    if (t.mask) LinearMove(pb, g, t, false);  // a move off the plane, deferred to the element's end
    if (g.gtl == 20) Fail(col, 12, "G20 names the profile's last point or first element");
    return;
  }
  gtl::Element e = ResolveRef(pb.elem);
  if (g.gtl == 20) {
    if (profile_.pending_corner) Fail(col, 77, "a profile may not end with a radius or a bevel");
    if (!profile_.has_elem) Fail(col, 77, "the profile has no element");
    if (contour_.on() && g.comp != 40) Fail(col, 25, "a compensated profile ends with G20 G40");
    if (!profile_.closed) {
      if (e.kind != gtl::Element::kPoint) Fail(pb.elem.col, 77, "an open profile ends at a point");
      GtlCheckOn(profile_.elem, e.p, pb.elem.col);
      GtlSegment(profile_.elem, profile_.start, e.p, profile_.line);
    } else {
      if (e.kind == gtl::Element::kPoint)
        Fail(pb.elem.col, 77, "a closed profile ends with its first element");
      Vec2 x = GtlConnect(profile_.elem, e, profile_.s2);
      GtlSegment(profile_.elem, profile_.start, x, profile_.line);
      try {
        contour_.TakeVirtual(ToMachinePath(Piece(e, x, false)));
      } catch (const ContourError& err) {
        ContourFail(err);
      }
    }
    GtlFlushDeferred();
    try {
      contour_.Release();
    } catch (const ContourError& err) {
      ContourFail(err);
    }
    ContourDrain();
    gtl_profile_ = false;
    if (t.mask) LinearMove(pb, g, t, false);
    return;
  }
  if (e.kind == gtl::Element::kPoint) Fail(pb.elem.col, 77, "a point inside a profile (ln 5064)");
  if (!profile_.has_elem) {
    Vec2 start = profile_.start;
    if (profile_.closed) {
      // The closed profile starts where its last and first elements meet (ln 5110).
      start = GtlConnect(profile_.last, e, profile_.last_s2);
      GtlApproach(start);
      try {
        contour_.TakeVirtual(ToMachinePath(Piece(profile_.last, start, true)));
      } catch (const ContourError& err) {
        ContourFail(err);
      }
      profile_.started = true;
      GtlFlushDeferred();
    } else {
      GtlCheckOn(e, start, pb.elem.col);
    }
    profile_.elem = e;
    profile_.start = start;
  } else {
    GtlJoin(e, pb.elem.col);
  }
  profile_.has_elem = true;
  profile_.s2 = pb.s2;
  profile_.line = cur_line_;
  if (t.mask) LinearMove(pb, g, t, false);
}

// The element being traversed ends where it meets `next` (ln 5168-5215): at their intersection; or an
// automatic radius r (a circle of that radius and direction tangent to both, the shorter way round, as the
// definition "c = a, b, r" gives it: the elements need not intersect); or a bevel b between two lines; r0
// rolls the compensated cutter round the intersection.
void BaltRun::GtlJoin(const gtl::Element& next, int col) {
  const gtl::Element& a = profile_.elem;
  const char kind = profile_.pending_corner ? profile_.corner : 0;
  const double v = profile_.corner_value;
  profile_.pending_corner = false;
  auto ahead = [&](Vec2 x) {
    // A line is travelled forwards: the end must not lie behind its start.
    if (a.kind == gtl::Element::kLine && Dot(x - profile_.start, a.d) < -1e-6) {
      Fail(col, 77, "the profile would run backwards along the line (s2?)");
    }
  };
  if (kind == 'r' && std::fabs(v) > 1e-9) {
    // The radius turns with the corner: where the elements cross only against its sign (GTL Example 3,
    // N23 "r5" at a right turn, ln 5353), the sign is taken as misprinted (a judgement call).
    double radius = v;
    Vec2 cross[2];
    int n = gtl::Intersect(a, next, cross);
    bool matches = false, opposes = false;
    for (int k = 0; k < n; ++k) {
      double turn = Cross(gtl::Tangent(a, cross[k]), gtl::Tangent(next, cross[k]));
      if (std::fabs(turn) < 1e-9) continue;
      ((turn > 0) == (v > 0) ? matches : opposes) = true;
    }
    if (opposes && !matches) radius = -v;
    gtl::Operand oa, ob, orad;
    oa.kind = a.kind == gtl::Element::kLine ? gtl::Operand::kLine : gtl::Operand::kCircle;
    oa.e = a;
    ob.kind = next.kind == gtl::Element::kLine ? gtl::Operand::kLine : gtl::Operand::kCircle;
    ob.e = next;
    orad.kind = gtl::Operand::kRadius;
    orad.v = radius;
    gtl::Element fillet;
    try {
      fillet = gtl::Define('c', {oa, ob, orad});
    } catch (const gtl::GeomError& e) {
      Fail(col, 77, fmt::format("no radius {:g} joins the elements: {}", v / UnitFactor(), e.text));
    }
    Vec2 t1 = gtl::TouchPoint(fillet, a), t2 = gtl::TouchPoint(fillet, next);
    ahead(t1);
    GtlSegment(a, profile_.start, t1, profile_.line);
    GtlSegment(fillet, t1, t2, profile_.corner_line);
    profile_.start = t2;
  } else if (kind == 'b') {
    if (a.kind != gtl::Element::kLine || next.kind != gtl::Element::kLine)
      Fail(col, 77, "a bevel joins two lines");
    Vec2 x = GtlConnect(a, next, profile_.s2);
    Vec2 t1 = x + (-v) * a.d, t2 = x + v * next.d;
    ahead(t1);
    if (Dot(t1 - profile_.start, a.d) < -1e-6) Fail(col, 77, "the bevel is longer than the line");
    GtlSegment(a, profile_.start, t1, profile_.line);
    gtl::Element chamfer;
    chamfer.kind = gtl::Element::kLine;
    chamfer.p = t1;
    chamfer.d = (1.0 / std::max(1e-12, geom::Norm(t2 - t1))) * (t2 - t1);
    GtlSegment(chamfer, t1, t2, profile_.corner_line);
    profile_.start = t2;
  } else {
    Vec2 x = GtlConnect(a, next, profile_.s2);
    ahead(x);
    GtlSegment(a, profile_.start, x, profile_.line);
    if (kind == 'r') {
      try {
        contour_.Corner('r', 0, profile_.corner_line);  // r0: the cutter rolls round the corner
      } catch (const ContourError& err) {
        ContourFail(err);
      }
    }
    profile_.start = x;
  }
  profile_.elem = next;
}

void BaltRun::GtlCheckOn(const gtl::Element& e, Vec2 p, int col) {
  double off = e.kind == gtl::Element::kLine ? std::fabs(Cross(e.d, p - e.p))
                                             : std::fabs(geom::Norm(p - e.p) - std::fabs(e.r));
  if (off > 0.01) Fail(col, 77, "the profile's point is not on its element");
}

// The move to a profile's start point (feed; the start move of compensation).
void BaltRun::GtlApproach(Vec2 p) {
  const int line = profile_.g21_line;
  Vec2 m = PlaneToMachine(p);
  AxisArray target = profile_.g21_pos;  // the approach belongs to the G21 block
  target[mode_.p1] = m.x;
  target[mode_.p2] = m.y;
  geom::Path path;
  path.start = {pos_[mode_.p1], pos_[mode_.p2]};
  path.end = m;
  Feed f;
  f.rate = *feed_;
  f.mode = mode_.feed == FeedCode::kG95 ? FeedMode::kPerRev : FeedMode::kPerMinute;
  f.exact_stop = mode_.dynamic != Dynamic::kG28;  // G27 stops at block ends, G28 blends (ln 2967-2969, 4317)
  CheckLimits(pos_, target, nullptr, 1);
  CheckAreas(pos_, target, nullptr, 1);
  EmitUnitsOnce();
  idle_ = 0;
  used_ |= (1u << mode_.p1) | (1u << mode_.p2);
  Canon c;
  c.line = line;
  LinearOp& l = c.Set<LinearOp>();
  l.feed = f;
  l.to.pos = target;
  l.to.used = profile_.g21_used | (1u << mode_.p1) | (1u << mode_.p2);
  if (!contour_.engaged()) contour_.Sync(pos_);
  try {
    contour_.Take(std::move(c), &path, true);
  } catch (const ContourError& err) {
    ContourFail(err);
  }
  ContourDrain();
  pos_[mode_.p1] = m.x;
  pos_[mode_.p2] = m.y;
  Prog();
  prog_[mode_.p1] = p.x;
  prog_[mode_.p2] = p.y;
}

}  // namespace cell::interp::balt
