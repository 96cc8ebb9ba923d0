// Rewrites of a generated block list that must keep its motion (issue 33 item 2): the same path absolute and
// incremental, and in another unit. The property runner (tests/oracle/properties.cpp) writes each rewrite
// with the dialect's module and compares cell-interp's moves.
#include <cmath>

#include "cell/oracle/oracle.h"

namespace cell::oracle {

std::vector<Block> Absolute(std::vector<Block> blocks) {
  for (Block& b : blocks) b.m.incremental = false;
  return blocks;
}

std::vector<Block> Incremental(std::vector<Block> blocks, const Caps& caps) {
  if (!caps.incremental) return blocks;
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    Block& b = blocks[i];
    // After a unit or offset change the start is off the grid: an increment from it would round.
    // So after an implicit offset selection (the axes the block did not name) and a machine-position set.
    bool on_grid = i > 0 && blocks[i - 1].m.inch == b.m.inch && blocks[i - 1].m.offset == b.m.offset &&
                   !blocks[i - 1].offset_by_b &&
                   !(caps.position_set_machine && blocks[i - 1].kind == MoveKind::kSet);
    // An implicit offset is selected by an absolute positioning of B only.
    bool writable = b.kind != MoveKind::kCycle && b.kind != MoveKind::kSet && !b.offset_by_b &&
                    !(caps.radius_form_g17_absolute && b.radius_form);
    b.m.incremental = on_grid && writable;
  }
  return blocks;
}

std::vector<Block> ConvertibleFeeds(std::vector<Block> blocks, const Caps& caps) {
  const double step = 5 * std::pow(10.0, -caps.feed_decimals);
  for (Block& b : blocks)
    if (b.m.inch && !b.m.per_rev && !b.m.inverse && b.feed > 0 && !RotaryAlone(b))
      b.feed = std::max(step, std::round(b.feed / step) * step);
  return blocks;
}

std::vector<Block> ExactArcs(std::vector<Block> blocks, int decimals) {
  const double grid = std::pow(10.0, decimals);
  auto units = [&](double v) { return std::llround(v * grid); };
  auto r2 = [&](const Block& b, const Vec3& p) {
    auto ax = AxesOf(b.m);
    long long a = units(p[ax[0]]) - units(b.center[ax[0]]), o = units(p[ax[1]]) - units(b.center[ax[1]]);
    return a * a + o * o;
  };
  for (Block& b : blocks) {
    if (b.kind != MoveKind::kArc) continue;
    bool exact = r2(b, b.start) == r2(b, b.end);
    if (exact && b.radius_form)
      exact = std::fabs(b.radius * b.radius * grid * grid - double(r2(b, b.end))) < 1e-6;
    if (!exact) b.kind = MoveKind::kLine, b.radius_form = false, b.turns = 0, b.pitch = 0;
  }
  return blocks;
}

std::vector<Block> InchToMm(std::vector<Block> blocks, const Caps& caps, bool (*convert)(std::size_t)) {
  const double grid = std::pow(10.0, caps.mm_decimals);
  auto mm = [&](double v) { return std::round(v * 25.4 * grid) / grid; };
  auto vec = [&](Vec3& v) {
    for (double& c : v) c = mm(c);
  };
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    Block& b = blocks[i];
    if (!b.m.inch || !convert(i)) continue;
    b.m.inch = false;
    vec(b.start), vec(b.end), vec(b.center);
    b.radius = mm(b.radius), b.pitch = mm(b.pitch);
    b.r_level = mm(b.r_level), b.bottom = mm(b.bottom);
    b.peck = mm(b.peck), b.peck_j = mm(b.peck_j), b.backoff = mm(b.backoff);
    for (auto& h : b.holes) h = {mm(h[0]), mm(h[1])};
    // 0.5 in/min is 12.7 mm/min; 0.01 in/rev 0.254 mm/rev: exact on the mm feed grids (ConvertibleFeeds).
    // A rotary move alone is fed in deg/min in either unit (Balt-System judgement call 21).
    if (!b.m.inverse && !RotaryAlone(b)) b.feed = std::round(b.feed * 25.4 * 1e6) / 1e6;
  }
  return blocks;
}

void MirrorMoves(std::vector<Move>& moves, unsigned axes) {
  static const std::array<std::array<int, 2>, 3> in_plane{{{0, 1}, {2, 0}, {1, 2}}};
  for (Move& m : moves) {
    for (int i = 0; i < 3; ++i)
      if (axes & (1u << i)) m.end[i] = -m.end[i], m.center[i] = -m.center[i];
    if (m.kind != MoveKind::kArc) continue;
    const auto& ax = in_plane[static_cast<std::size_t>(m.plane - 17)];
    if (((axes >> ax[0]) & 1u) != ((axes >> ax[1]) & 1u)) m.cw = !m.cw;
  }
}

void RotateMoves(std::vector<Move>& moves, double degrees) {
  const double c = std::cos(degrees * M_PI / 180), s = std::sin(degrees * M_PI / 180);
  auto turn = [&](Vec3& v) { v = {c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]}; };
  for (Move& m : moves) turn(m.end), turn(m.center);
}

void ScaleMoves(std::vector<Move>& moves, double factor) {
  for (Move& m : moves)
    for (int i = 0; i < 3; ++i) m.end[i] *= factor, m.center[i] *= factor;
}

}  // namespace cell::oracle
