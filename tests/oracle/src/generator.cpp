// The random block list and its NGC form. Every coordinate is on the program unit's grid and every arc's two
// radii are equal exactly (Pythagorean vectors), so neither interpreter rounds and both see one toolpath.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "cell/oracle/oracle.h"
#include "cell/oracle/rng.h"

namespace cell::oracle {
namespace {

constexpr double kMm = 25.4;

// Integer vectors of one length (a*a + b*b = r*r): the arcs' start and end radii.
std::vector<std::array<int, 2>> Representations(int r) {
  std::vector<std::array<int, 2>> out;
  for (int a = -r; a <= r; ++a)
    for (int b = -r; b <= r; ++b)
      if (a * a + b * b == r * r) out.push_back({a, b});
  return out;
}

struct Box {
  Vec3 lo, hi;  // mm, machine coordinates
};

struct Gen {
  const Caps& caps;
  Rng rng;
  Modes cur;
  Vec3 machine{};  // mm
  Vec3 rot{};      // degrees
  Vec3 g92{};      // mm: the position-set offset (LinuxCNC G92)
  bool need_abs = true;
  bool offset_changed = false;
  Box box;
  double calc_b = 0;  // degrees [0, 360): the B the offset in force is turned for (Caps::calculated_offsets)

  double Unit() const { return cur.inch ? kMm : 1.0; }
  double Grid() const { return std::pow(10.0, -(cur.inch ? caps.inch_decimals : caps.mm_decimals)); }
  double Snap(double v) const { return std::round(v / Grid()) * Grid(); }
  Vec3 Fixture() const {  // the work offset in force, turned with B under calculated offsets
    const auto k = static_cast<std::size_t>(cur.offset);
    Vec3 o = kOffsetTable[k];
    if (caps.calculated_offsets && k > 0) {
      const double d = (calc_b - kOffsetB[k]) * M_PI / 180, c = std::cos(d), s = std::sin(d);
      o = {o[0] * c - o[2] * s, o[1], o[0] * s + o[2] * c};
    }
    return o;
  }
  Vec3 Offset() const {  // a lathe has no Y
    Vec3 o = Fixture();
    for (int i = 0; i < 3; ++i) o[i] += g92[i];
    if (caps.lathe) o[1] = 0;
    return o;
  }
  Vec3 ToProgram(const Vec3& mm) const {
    Vec3 p;
    for (int i = 0; i < 3; ++i) p[i] = (mm[i] - Offset()[i]) / Unit();
    return p;
  }
  Vec3 ToMachine(const Vec3& p) const {
    Vec3 m;
    for (int i = 0; i < 3; ++i) m[i] = p[i] * Unit() + Offset()[i];
    return m;
  }
  bool Inside(const Vec3& p) const {  // program coordinates
    Vec3 m = ToMachine(p);
    for (int i = 0; i < 3; ++i)
      if (m[i] < box.lo[i] || m[i] > box.hi[i]) return false;
    return true;
  }
  Vec3 RandomPoint() {
    for (;;) {
      Vec3 p{};
      for (int i = 0; i < 3; ++i) {
        if (caps.lathe && i == 1) continue;
        double mm = box.lo[i] + (box.hi[i] - box.lo[i]) * (rng.Int(0, 10000) / 10000.0);
        p[i] = Snap((mm - Offset()[i]) / Unit());
      }
      if (Inside(p)) return p;
    }
  }
  void ChangeModes();
  double Feed();
  bool Arc(Block& b);
  bool Cycle(Block& b);
  bool Rotary(Block& b);
  Block Next();
};

void Gen::ChangeModes() {
  if (caps.inch && caps.unit_switch && rng.Chance(4)) {
    cur.inch = !cur.inch;
    need_abs = true;
  }
  if (caps.offsets && rng.Chance(4)) {
    int o = rng.Int(0, kOffsets - 1);
    offset_changed = o != cur.offset;
    need_abs = need_abs || offset_changed;
    cur.offset = o;
    if (offset_changed) calc_b = std::fmod(std::fmod(rot[1], 360) + 360, 360);  // where B stands
  }
  if (caps.incremental && rng.Chance(10)) cur.incremental = !cur.incremental;
  if (caps.planes.size() > 1 && rng.Chance(8)) {
    cur.plane = rng.Pick(caps.planes);
    cur.swapped = caps.swapped_planes && rng.Chance(40);
  }
  if (rng.Chance(6)) {  // the feed mode: per minute, per revolution or inverse time, as the dialect has them
    int pick = rng.Int(0, 2);
    cur.per_rev = caps.per_rev && pick == 1;
    cur.inverse = caps.inverse_time && pick == 2;
  }
  if (need_abs) cur.incremental = false;
}

double Gen::Feed() {
  if (cur.inverse) return rng.Int(5, 300) / 10.0;  // 1/min, one decimal
  if (cur.per_rev) {
    static const std::vector<double> mm{0.05, 0.1, 0.15, 0.2, 0.25, 0.3};
    static const std::vector<double> in{0.01, 0.02, 0.03};
    return cur.inch ? rng.Pick(in) : rng.Pick(mm);
  }
  double scale = std::pow(10.0, caps.feed_decimals);
  if (cur.inch) return rng.Int(20, 800) / 10.0;
  return std::round(rng.Int(50, 2000) * scale / (1 + rng.Int(0, 1) * 9)) / scale;
}

// An arc from the current position: centre and end from two integer vectors of one length.
bool Gen::Arc(Block& b) {
  static const std::vector<int> radii{5, 25, 65, 85};
  static const std::vector<double> mm_scale{0.05, 0.1, 0.2, 0.25, 0.5, 1.0};
  static const std::vector<double> in_scale{0.002, 0.004, 0.005, 0.01, 0.02, 0.04};
  auto ax = AxesOf(cur);
  for (int tries = 0; tries < 20; ++tries) {
    int r = rng.Pick(radii);
    double s = cur.inch ? rng.Pick(in_scale) : rng.Pick(mm_scale);
    double rmm = r * s * Unit();
    if (rmm < 0.3 || rmm > 70) continue;
    auto reps = Representations(r);
    auto v1 = rng.Pick(reps), v2 = rng.Pick(reps);
    // rs274 times a whole-circle helix in G93 by its depth alone (its arc length of a full turn is 0).
    if (v1 == v2 && (!caps.full_circle || cur.inverse)) continue;
    Vec3 c = b.start, e = b.start;
    c[ax[0]] = Snap(b.start[ax[0]] - v1[0] * s);
    c[ax[1]] = Snap(b.start[ax[1]] - v1[1] * s);
    e[ax[0]] = Snap(c[ax[0]] + v2[0] * s);
    e[ax[1]] = Snap(c[ax[1]] + v2[1] * s);
    b.cw = rng.Chance(50);
    double ccw = std::atan2(double(v1[0]) * v2[1] - double(v1[1]) * v2[0],
                            double(v1[0]) * v2[0] + double(v1[1]) * v2[1]) *
                 180 / M_PI;
    if (ccw <= 0) ccw += 360;
    double angle = b.cw ? 360 - ccw : ccw;
    if (angle <= 0) angle = 360;  // a full circle
    // The whole circle stays inside the travel (and a lathe's x above the centre line).
    Vec3 lo = c, hi = c;
    lo[ax[0]] -= r * s, hi[ax[0]] += r * s, lo[ax[1]] -= r * s, hi[ax[1]] += r * s;
    if (caps.helix && rng.Chance(30)) {
      double delta = Snap((rng.Int(-100, 100) / 10.0) / Unit());
      if (caps.helix_turns && rng.Chance(40) && angle > 20 && angle < 340) {
        b.turns = rng.Int(1, 2);
        b.pitch = Snap(rng.Int(5, 40) / 10.0 / Unit());
        double depth = Snap(b.pitch * (b.turns + angle / 360));
        delta = rng.Chance(50) ? depth : -depth;
      }
      e[ax[2]] = b.start[ax[2]] + delta;
    }
    if (!Inside(lo) || !Inside(hi) || !Inside(e)) {
      b.turns = 0, b.pitch = 0;
      continue;
    }
    if (caps.lathe && (lo[0] * Unit() + Offset()[0]) < 0.5) continue;
    b.kind = MoveKind::kArc;
    b.center = c;
    b.end = e;
    bool r_here = !caps.radius_form_g17_absolute || (cur.plane == 17 && !cur.incremental);
    if (caps.radius_form && r_here && b.turns == 0 && v1 != v2 && std::fabs(angle - 180) > 2 &&
        rng.Chance(30)) {
      b.radius_form = true;
      b.radius = angle > 180 ? -r * s : r * s;
    }
    return true;
  }
  return false;
}

// A drilling cycle at one to four holes: R below the start (no preliminary move), the bottom below R. On a
// lathe one hole on the centre line, R where the tool is.
bool Gen::Cycle(Block& b) {
  const std::vector<int>& codes = cur.per_rev ? caps.cycles_per_rev : caps.cycles;
  bool plane = caps.lathe || (cur.plane == 17 && !cur.swapped);
  if (codes.empty() || cur.inverse || !plane || cur.incremental || need_abs || !rng.Chance(12)) return false;
  b.kind = MoveKind::kCycle;
  b.cycle = rng.Pick(codes);
  const Caps::Peck* p = PeckOf(b, caps);
  // rs274 prints four decimals of an inch: the pecks that go back stay on the unit's grid in inch
  // (Balt-System's 1 mm re-approach is not on it; KT-APL's 0.1 in is), pecks reduced by K only in mm.
  const double c = p ? (cur.inch && p->clearance_in > 0 ? p->clearance_in : p->clearance / Unit()) : 0;
  if (p) {
    b.discharge = p->discharging && std::fabs(Snap(c) - c) < 1e-9 && (!p->feeding_on || rng.Chance(50));
    if (!b.discharge && !p->feeding_on) return false;
    b.backoff = cur.inch && p->backoff_in > 0 ? p->backoff_in : p->backoff / Unit();
    if (p->backoff_word) {  // LinuxCNC's own (G73) where the unit's grid has it, else another
      double own = cur.inch ? 0.01 : 0.254;
      b.backoff =
          std::fabs(Snap(own) - own) < 1e-9 && rng.Chance(70) ? own : Snap(rng.Int(1, 10) / 10.0 / Unit());
    }
  }
  // A peck longer than the re-approach or back-off, or the cycle never gets deeper (Balt-System FILMS4 13,
  // call 4; EMCO's and Okuma's would come back out of the hole).
  const double least = std::max(b.discharge ? c : 0.0, b.discharge ? 0.0 : b.backoff) + Snap(0.5 / Unit());
  if (caps.lathe) {
    b.r_level = b.start[2];
    b.holes = {{0, 0}};
    if (p && p->equal) {  // n pecks of q: D3 a little over q (equal pecks below D3, judgement call 9)
      int n = rng.Int(2, 5);
      double q = std::max(least, Snap(rng.Int(10, 80) / 10.0 / Unit()));
      b.bottom = b.r_level - Snap(n * q);
      b.peck = std::max(Snap(q * (1 + 0.5 / (n - 1))), q + Grid());
    } else {
      b.bottom = b.r_level - Snap(rng.Int(10, 600) / 10.0 / Unit());
    }
  } else {
    b.r_level = b.start[2] - Snap(rng.Int(0, 50) / 10.0 / Unit());
    b.bottom = b.r_level - Snap(rng.Int(10, 200) / 10.0 / Unit());
  }
  Vec3 deep = b.start;
  deep[2] = b.bottom;
  if (!Inside(deep)) return false;
  b.feed = Feed();
  if (p && !p->equal && p->slow_end == 0) {
    b.peck = std::max(least, Snap(rng.Int(5, 100) / 10.0 / Unit()));
    if (b.discharge && p->reduce && !cur.inch && rng.Chance(50)) {
      b.peck_k = rng.Int(50, 95) / 100.0;
      b.peck_j = std::min(b.peck, std::max(least, Snap(rng.Int(5, 60) / 10.0 / Unit())));
    } else if (b.discharge && p->reduce) {
      b.peck_k = 1;  // a constant peck: K1 without J (ln 3402)
    }
    // LinuxCNC's G73 steps its depth by Q in floating point: at a bottom a whole number of pecks down it
    // pecked once more (a back-off and a feed at the bottom). Such a hole is drilled a grid step deeper.
    double n = (b.r_level - b.bottom) / b.peck;
    if (p->native && std::fabs(n - std::round(n)) < 1e-6) b.bottom -= Grid();
  }
  if (b.cycle == 84) {
    b.tap_pitch = caps.tap_pitch && !cur.per_rev && rng.Chance(50);
    if (b.tap_pitch) {  // F = K x S (S1000): a pitch of the unit's grid
      static const std::vector<double> mm{0.5, 0.7, 0.75, 0.8, 1, 1.25, 1.5, 1.75, 2};
      static const std::vector<double> in{0.025, 0.04, 0.05, 0.1};  // exact in mm (the units property)
      b.feed = (cur.inch ? rng.Pick(in) : rng.Pick(mm)) * 1000;
    } else if (caps.tap_max_feed > 0 && !cur.per_rev) {
      b.feed = std::min(b.feed, std::floor(caps.tap_max_feed / Unit() * 10) / 10);
    }
  }
  for (int i = caps.lathe ? 0 : rng.Int(1, 4); i > 0; --i) {
    Vec3 h = RandomPoint();
    b.holes.push_back({h[0], h[1]});
  }
  b.end = {b.holes.back()[0], b.holes.back()[1], b.r_level};
  return true;
}

// A move of rotary axes (degrees): alone (Balt-System: F in deg/min, at most three axes in a block, ln 2699)
// or, where the dialect has it, with X Y Z in one G00/G01 block (F the dialect's: Caps::rotary_vector_feed).
bool Gen::Rotary(Block& b) {
  if (!(caps.rotary || caps.rotary_linear) || cur.per_rev || need_abs || !rng.Chance(8)) return false;
  bool linear = caps.rotary_linear && (!caps.rotary || cur.inverse || rng.Chance(50));
  if (!linear && cur.inverse) return false;  // rs274 times a rotary-only G93 move by its degrees
  b.kind = caps.index_b || rng.Chance(25) ? MoveKind::kRapid : MoveKind::kLine;
  // An incremental positioning keeps the implicit offset; absolute (the absinc property) it would select one.
  // A calculated offset turns at either, and KT-APL counts the block's increments in the offset before it.
  if ((caps.implicit_offsets || caps.calculated_offsets) && cur.incremental && b.kind == MoveKind::kRapid)
    return false;
  std::vector<int> turn;
  for (int a = 0; a < 3; ++a)
    if ((caps.rotary_axes & (1u << a)) && rng.Chance(50)) turn.push_back(a);
  if (turn.empty()) {
    for (int a = 0; a < 3; ++a)
      if (caps.rotary_axes & (1u << a)) turn.push_back(a);
    int one = rng.Pick(turn);
    turn = {one};
  }
  int room = caps.max_axes ? caps.max_axes : 6;  // axis words left for the linear axes
  if (linear && static_cast<int>(turn.size()) >= room) turn.resize(static_cast<std::size_t>(room - 1));
  room -= static_cast<int>(turn.size());
  for (int a : turn) {
    long v = rng.Int(-3600, 3600);                            // tenths of a degree
    if (caps.index_b && a == 1) v = (v / 10) * 10;            // an index table: whole degrees
    if (caps.implicit_offsets && a == 1 && rng.Chance(35)) {  // often a position that selects an offset
      v = std::lround(kOffsetB[static_cast<std::size_t>(rng.Int(0, kOffsets - 1))] * 10);
      if (rng.Chance(50)) v = -v;
    }
    if (caps.rotary_wrap && !cur.incremental) {
      // The word is the position mod 360 and its sign the sense (KT-APL ln 4481-4546): the travel to it.
      long from = ((std::lround(b.rot_start[a] * 10) % 3600) + 3600) % 3600, to = std::labs(v) % 3600;
      long travel = v < 0 ? -(((from - to) % 3600 + 3600) % 3600) : ((to - from) % 3600 + 3600) % 3600;
      b.rot_end[a] = b.rot_start[a] + travel / 10.0;
    } else {
      b.rot_end[a] = cur.incremental ? b.rot_start[a] + v / 10.0 : v / 10.0;
    }
  }
  // Implicit offsets: an absolute positioning of B selects the offset listed for its position (none if no
  // line lists it); the block's linear words are in the new offset (KT-APL rebases them, ktapl.md call 23).
  // Calculated offsets: the positioning turns the offset in force (a position no line lists keeps it).
  if ((caps.implicit_offsets || caps.calculated_offsets) && b.kind == MoveKind::kRapid && !cur.incremental &&
      b.rot_end[1] != b.rot_start[1]) {
    const int was = cur.offset;
    const int k = OffsetAtB(b.rot_end[1]);
    if (caps.implicit_offsets && (k != 0 || !caps.calculated_offsets)) cur.offset = b.m.offset = k;
    if (caps.calculated_offsets) calc_b = std::fmod(std::fmod(b.rot_end[1], 360) + 360, 360);
    b.start = ToProgram(machine);
    b.offset_by_b = cur.offset != was || (caps.calculated_offsets && cur.offset != 0);
  }
  b.end = b.start;
  if (linear) {
    Vec3 p = RandomPoint();
    if (cur.incremental && rng.Chance(70)) {  // a short step, still inside
      for (int i = 0; i < 3; ++i) p[i] = b.start[i] + Snap(rng.Int(-300, 300) / 10.0 / Unit());
      if (!Inside(p)) p = RandomPoint();
    }
    int first = rng.Int(0, 2);  // the linear axes that move: as many as the block has room for
    for (int k = 0; k < 3; ++k) {
      int i = (first + k) % 3;
      if (k < room && rng.Chance(k == 0 ? 100 : 60)) b.end[i] = p[i];
    }
  }
  return b.rot_end != b.rot_start;
}

Block Gen::Next() {
  ChangeModes();
  Block b;
  b.m = cur;
  b.start = ToProgram(machine);
  b.rot_start = b.rot_end = rot;
  int pick = rng.Int(1, 100);
  if (offset_changed && caps.rapid_after_offset) pick = 1;
  offset_changed = false;
  bool arc = !need_abs && pick > 55 && Arc(b);
  bool cycle = !arc && Cycle(b);
  bool rotary = !arc && !cycle && Rotary(b);
  if (!arc && !cycle && !rotary && !caps.position_set.empty() && !need_abs && rng.Chance(3)) {
    // The present position becomes a random point of the grid (G92); the machine stays.
    b.kind = MoveKind::kSet;
    Vec3 p = RandomPoint();
    if (caps.lathe) p[1] = 0;
    Vec3 base = Fixture();
    if (caps.lathe) base[1] = 0;
    // A machine-position set: the dialect's word (p plus the offset) is the one on the grid.
    if (caps.position_set_machine)
      for (int i = 0; i < 3; ++i) p[i] = Snap(p[i] + base[i] / Unit()) - base[i] / Unit();
    b.end = p;
    for (int i = 0; i < 3; ++i) g92[i] = machine[i] - base[i] - p[i] * Unit();
    need_abs = need_abs || caps.position_set_machine;  // p is off the inch grid then
    b.offset_mm = Fixture();
    return b;
  }
  if (!arc && !cycle && !rotary) {
    b.kind = pick <= 15 ? MoveKind::kRapid : MoveKind::kLine;
    b.end = RandomPoint();
    if (cur.incremental && rng.Chance(70)) {  // a short step, still inside
      for (int i = 0; i < 3; ++i) {
        if (caps.lathe && i == 1) continue;
        b.end[i] = b.start[i] + Snap(rng.Int(-300, 300) / 10.0 / Unit());
      }
      if (!Inside(b.end) || b.end == b.start) b.end = RandomPoint();
    }
    // An incremental step from an off-grid start would round: the first move after a change is absolute.
    if (caps.lathe) b.end[1] = 0;
    need_abs = false;
  }
  if (b.kind != MoveKind::kRapid && b.kind != MoveKind::kCycle) b.feed = Feed();
  if (caps.rotary_whole_feed && RotaryAlone(b) && b.kind != MoveKind::kRapid)
    b.feed = std::max(1.0, std::round(b.feed));  // F3.0 deg/min
  if (rng.Chance(40)) b.omit = static_cast<unsigned>(rng.Next() & 63);
  machine = ToMachine(b.end);
  rot = b.rot_end;
  // After an offset selected or turned by B the axes the block did not name are off the grid.
  if (b.offset_by_b) need_abs = true;
  b.offset_mm = Fixture();
  return b;
}

std::string Fmt(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

}  // namespace

std::array<int, 3> AxesOf(const Modes& m) {
  std::array<int, 3> a{0, 1, 2};
  if (m.plane == 18) a = {2, 0, 1};
  if (m.plane == 19) a = {1, 2, 0};
  if (m.swapped) std::swap(a[0], a[1]);
  return a;
}

const Caps::Peck* PeckOf(const Block& b, const Caps& caps) {
  if (b.kind != MoveKind::kCycle) return nullptr;
  for (const Caps::Peck& p : caps.pecks)
    if (p.code == b.cycle) return &p;
  return nullptr;
}

namespace {

// The re-approach's clearance above the last bottom in the block's unit.
double Clearance(const Block& b, const Caps::Peck& p) {
  return b.m.inch && p.clearance_in > 0 ? p.clearance_in : p.clearance / (b.m.inch ? kMm : 1.0);
}

}  // namespace

std::vector<double> PeckBottoms(const Block& b, const Caps::Peck& p) {
  const double c = Clearance(b, p);
  const double tie = 1e-9;  // a peck that ends on the bottom is the last (the manuals' "<=")
  std::vector<double> out;
  if (p.slow_end > 0) return {b.bottom + (b.m.inch ? p.slow_end_in : p.slow_end), b.bottom};
  if (p.equal) {
    const double depth = b.r_level - b.bottom;
    const int n = static_cast<int>(std::ceil(depth / b.peck - tie));
    for (int k = 1; k < n; ++k) out.push_back(b.r_level - depth * k / n);
    out.push_back(b.bottom);
    return out;
  }
  double last = b.r_level, peck = b.peck;
  while (out.size() < 100000) {
    double next = last - peck;
    if (b.discharge && p.from_clearance && !out.empty()) next += c;
    if (next <= b.bottom + tie) break;
    out.push_back(next);
    last = next;
    if (b.discharge && b.peck_k > 0) peck = std::max(peck * b.peck_k, b.peck_j);
  }
  out.push_back(b.bottom);
  return out;
}

int OffsetAtB(double b) {
  long at = ((std::lround(b * 1000) % 360000) + 360000) % 360000;
  for (int k = 1; k < kOffsets; ++k)
    if (at == std::lround(kOffsetB[static_cast<std::size_t>(k)] * 1000)) return k;
  return 0;
}

bool RotaryAlone(const Block& b) {
  return b.rot_end != b.rot_start && b.end == b.start;
}

bool OmitAxis(const Block& b, int axis) {
  return (b.omit & (1u << axis)) && !b.radius_form && b.end[axis] == b.start[axis];
}

bool OmitCentre(const Block& b, int axis) {
  return (b.omit & (8u << axis)) && b.kind == MoveKind::kArc && !b.radius_form &&
         b.center[axis] == b.start[axis];
}

std::string Num(double v, int decimals, bool point) {
  std::string s = Fmt(v, decimals);
  if (s.find('.') != std::string::npos) {
    while (s.back() == '0') s.pop_back();
    if (s.back() == '.' && !point) s.pop_back();
  }
  if (s == "-0" || s == "-0.") s = s.substr(1);
  return s;
}

std::vector<Block> Generate(const Caps& caps, std::uint64_t seed, int count) {
  Gen g{caps, Rng{seed}, {}, {}, {}, {}, true, false, {}, 0};
  g.cur.plane = caps.planes.front();
  if (caps.inch && !caps.unit_switch) g.cur.inch = caps.inch_only || g.rng.Chance(30);
  if (caps.lathe)
    g.box = Box{{2, 0, -120}, {80, 0, 20}};
  else
    g.box = Box{{-120, -120, -80}, {120, 120, 60}};
  std::vector<Block> out;
  out.reserve(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) out.push_back(g.Next());
  return out;
}

namespace {

// The rate along X Y Z of a G94 move whose F is the rate along the vector of its travels in mm and degrees
// (Caps::rotary_vector_feed): LinuxCNC applies F to X Y Z alone.
double LinearRate(const Block& b) {
  const double unit = b.m.inch ? kMm : 1.0;
  double lin = 0, deg = 0;
  for (int i = 0; i < 3; ++i) {
    lin += (b.end[i] - b.start[i]) * unit * (b.end[i] - b.start[i]) * unit;
    deg += (b.rot_end[i] - b.rot_start[i]) * (b.rot_end[i] - b.rot_start[i]);
  }
  if (b.m.inverse || b.m.per_rev || lin == 0 || deg == 0) return b.feed;
  return b.feed * std::sqrt(lin / (lin + deg));
}

// One NGC block's words for a move (modes are written by the caller).
std::string NgcMove(const Block& b, const Caps& caps) {
  const int d = 6;
  std::string s;
  auto word = [&](char letter, double v) { s += " " + std::string(1, letter) + Num(v, d); };
  auto ax = AxesOf(b.m);
  const char* letters = "XYZ";
  if (b.kind == MoveKind::kRapid) s = "G0";
  if (b.kind == MoveKind::kLine) s = "G1";
  if (b.kind == MoveKind::kArc) s = b.cw != b.m.swapped ? "G2" : "G3";  // seen from the plane's normal
  if (b.kind == MoveKind::kSet) {
    s = "G92";
    for (int i = 0; i < 3; ++i)
      if (!(caps.lathe && i == 1)) word(letters[i], caps.lathe && i == 0 ? 2 * b.end[i] : b.end[i]);
    return s;
  }
  // A lathe drills on the centre line: to X0 at the present Z, the cycle in G17 (LinuxCNC drills along Z
  // there).
  const std::string lathe_to = caps.lathe ? "G0 X0\n" : "";
  const Caps::Peck* p = PeckOf(b, caps);
  const double own_backoff = b.m.inch ? 0.01 : 0.254;  // LinuxCNC's G73
  if (p && !(p->native && std::fabs(b.backoff - own_backoff) < 1e-9)) {
    // The manual's pecks as moves (the dwells between them are not compared): to the hole at the present
    // height, down to R, each peck (after a discharge: up to R, down to the clearance above the last bottom;
    // else the back-off, if any), back to R.
    const double c = Clearance(b, *p);
    const std::string f = " F" + Num(b.feed, d);
    const std::vector<double> bottoms = PeckBottoms(b, *p);
    s = lathe_to;
    for (const auto& h : b.holes) {
      if (!caps.lathe) s += "G0 X" + Num(h[0], d) + " Y" + Num(h[1], d) + "\n";
      s += "G0 Z" + Num(b.r_level, d) + "\n";
      for (std::size_t n = 0; n < bottoms.size(); ++n) {
        if (n > 0 && !b.discharge && b.backoff > 0) s += "G0 Z" + Num(bottoms[n - 1] + b.backoff, d) + "\n";
        if (n > 0 && b.discharge) {
          s += "G0 Z" + Num(b.r_level, d) + "\n";
          std::string to = " Z" + Num(bottoms[n - 1] + c, d);
          s += p->approach_feed > 0
                   ? "G1" + to + " F" + Num(p->approach_feed / (b.m.inch ? kMm : 1.0), d) + "\n"
                   : "G0" + to + "\n";
        }
        bool slow = p->slow_end > 0 && n + 1 == bottoms.size();
        s += "G1 Z" + Num(bottoms[n], d) + (slow ? " F" + Num(p->slow_feed / (b.m.inch ? kMm : 1.0), d) : f) +
             "\n";
      }
      s += "G0 Z" + Num(b.r_level, d) + "\n";
    }
    s.pop_back();
    return s;
  }
  if (b.kind == MoveKind::kCycle) {
    s = lathe_to + (caps.lathe ? "G17\n" : "") + "G99 G" + std::to_string(p ? p->native : b.cycle);
    for (std::size_t h = 0; h < b.holes.size(); ++h) {
      s += " X" + Num(b.holes[h][0], d) + " Y" + Num(b.holes[h][1], d);
      if (h == 0) {
        s += " Z" + Num(b.bottom, d) + " R" + Num(b.r_level, d) + " F" + Num(b.feed, d);
        if (p) s += " Q" + Num(b.peck, d);
        if (b.cycle == 82 || b.cycle == 86 || b.cycle == 89) s += " P1";  // rs274 asks P of G86 too
        // G84: LinuxCNC feeds in, reverses the spindle and feeds out to R at F (the manuals' G84).
      }
      s += "\n";
    }
    return s + (caps.lathe ? "G80\nG18" : "G80");
  }
  // An index table turns with X and Y, Z follows (KT-APL ln 4493-4546): two moves.
  const bool z_after = caps.index_b && b.rot_end[1] != b.rot_start[1] && b.end[2] != b.start[2];
  for (int i = 0; i < 3; ++i) {
    // A rotary move alone names no linear axis: after a G92 rs274's position may be off the word (1e-15 mm,
    // or its 1e-4 in rounding) and it would take F for a linear rate (in inch, 25.4 times the deg/min).
    if ((caps.lathe && i == 1) || RotaryAlone(b) || (z_after && i == 2)) continue;
    double v = b.m.incremental ? b.end[i] - b.start[i] : b.end[i];
    word(letters[i], caps.lathe && i == 0 ? 2 * v : v);
  }
  if (b.kind == MoveKind::kArc) {
    if (b.radius_form) {
      word('R', b.radius);
    } else {
      const char* centre = "IJK";
      for (int k = 0; k < 2; ++k) word(centre[ax[k]], b.center[ax[k]] - b.start[ax[k]]);
    }
    if (b.turns) s += " P" + std::to_string(b.turns + 1);
  }
  const char* rotary = "ABC";
  for (int i = 0; i < 3; ++i)
    if (b.rot_end[i] != b.rot_start[i])
      word(rotary[i], b.m.incremental ? b.rot_end[i] - b.rot_start[i] : b.rot_end[i]);
  if (b.kind != MoveKind::kRapid) word('F', caps.rotary_vector_feed ? LinearRate(b) : b.feed);
  if (z_after) s += "\nG0 Z" + Num(b.m.incremental ? b.end[2] - b.start[2] : b.end[2], d);
  return s;
}

}  // namespace

NgcText WriteNgc(const std::vector<Block>& blocks, const Caps& caps) {
  NgcText out;
  std::string& t = out.text;
  t = "%\nG21 G90 G94 G40 G49 G80 G54 G17\n";
  for (int k = 1; k < kOffsets; ++k) {
    const Vec3& o = kOffsetTable[static_cast<std::size_t>(k)];
    t += "G10 L2 P" + std::to_string(k + 1) + " X" + Num(o[0], 6) + " Y" +  // before G7: a radius
         Num(caps.lathe ? 0 : o[1], 6) + " Z" + Num(o[2], 6) + "\n";
  }
  if (caps.lathe) t += "G7 G18\n";
  t += "S1000 M3\n";
  Modes m;
  m.plane = caps.lathe ? 18 : 17;
  std::array<Vec3, kOffsets> set = kOffsetTable;  // the offsets as G10 L2 set them last
  for (const Block& b : blocks) {
    std::string modes;
    if (b.m.inch != m.inch) modes += b.m.inch ? "G20 " : "G21 ";
    if (b.m.offset != m.offset) modes += "G" + std::to_string(54 + b.m.offset) + " ";
    if (b.m.incremental != m.incremental) modes += b.m.incremental ? "G91 " : "G90 ";
    if (b.m.plane != m.plane) modes += "G" + std::to_string(b.m.plane) + " ";
    if (b.m.per_rev != m.per_rev || b.m.inverse != m.inverse)
      modes += b.m.inverse ? "G93 " : b.m.per_rev ? "G95 " : "G94 ";
    m = b.m;
    // Modes on a line of their own: rs274 sets F before G20/G21 within a block (LinuxCNC's order of
    // execution).
    if (!modes.empty()) modes.back() = '\n';
    const auto k = static_cast<std::size_t>(b.m.offset);
    if (caps.calculated_offsets && k > 0 && b.offset_mm != set[k]) {  // the offset turned with B (G47)
      const double u = b.m.inch ? kMm : 1.0;
      modes += "G10 L2 P" + std::to_string(k + 1) + " X" + Num(b.offset_mm[0] / u, 6) + " Y" +
               Num(b.offset_mm[1] / u, 6) + " Z" + Num(b.offset_mm[2] / u, 6) + "\n";
      set[k] = b.offset_mm;
    }
    std::string line = modes + NgcMove(b, caps);
    out.blocks.push_back(line);
    t += line + "\n";
  }
  t += "M2\n%\n";
  return out;
}

}  // namespace cell::oracle
