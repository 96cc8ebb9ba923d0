// Automatic chamfering and rounding G75/G76 and angle-only lines (manual ln 1302-1496): the held line's
// corner is computed when the next move is known (see staged.h).
#include <fmt/format.h>

#include <cmath>

#include "staged.h"

namespace cell::interp::okuma {
namespace {

constexpr double kEps = 1e-9;

}  // namespace

void ContourStage::Take(Staged&& s) {
  const bool move = s.kind == Staged::kOp && IsMove(s.c.op());
  if (!held_) {
    if (move && (s.corner.kind != CornerSpec::kNone || s.corner.open_end)) {
      line_ = std::move(s);
      held_ = true;
      return;
    }
    ready_.push_back(std::move(s));
    return;
  }
  if (!move) {
    behind_.push_back(std::move(s));
    return;
  }
  Resolve(s);
  held_ = false;
  if (s.corner.kind != CornerSpec::kNone || s.corner.open_end) {
    line_ = std::move(s);
    held_ = true;
    return;
  }
  ready_.push_back(std::move(s));
}

void ContourStage::Resolve(Staged& next) {
  Target& held_to = *line_.c.target();
  const Vec2 p0 = PlaneOf(line_.from);
  const Vec2 e = PlaneOf(next.c.target()->pos);
  Vec2 c = PlaneOf(held_to.pos);
  if (line_.corner.open_end) {
    // The corner of two lines given by angles (ln 1473-1487): where the held line meets the next one, which
    // ends at its X, Z along its angle A.
    if (!next.corner.end_angle) {
      Fail(1, "after a line given by an angle only, the next block must give X, Z and A");
    }
    const Vec2 d1 = line_.corner.dir, d2 = next.corner.end_dir;
    const double den = geom::Cross(d1, d2);
    if (std::fabs(den) < 1e-12) Fail(1, "no intersection: the two taper angles are parallel");
    const double t = geom::Cross(e - p0, d2) / den;
    if (t < -kEps) Fail(1, "no intersection ahead of the line given by an angle only");
    c = p0 + t * d1;
    SetPlane(held_to.pos, c);
    SetPlane(next.from, c);  // the next line starts at the corner (its own chamfer is measured from there)
  }
  if (line_.corner.kind == CornerSpec::kNone) {
    ready_.push_back(std::move(line_));
  } else {
    // G75 / G76 (ln 1310-1418, 1421-1469): the corner between two lines is cut back by the chamfer size on
    // each leg, or rounded by a tangent arc of radius L.
    if (line_.c.op() != Op::kLinear || next.c.op() != Op::kLinear) {
      Fail(1, "automatic chamfering is possible only at a corner between two lines (G01)");
    }
    const double l1 = geom::Norm(c - p0), l2 = geom::Norm(e - c);
    if (l1 < kEps || l2 < kEps) Fail(1, "automatic chamfering needs a move on both sides of the corner");
    const Vec2 d1 = (1.0 / l1) * (c - p0), d2 = (1.0 / l2) * (e - c);
    const double turn = geom::Cross(d1, d2);
    const double theta = std::atan2(std::fabs(turn), geom::Dot(d1, d2));
    if (theta < 1e-6) Fail(1, "automatic chamfering: the two lines make no corner");
    const double size = line_.corner.size;
    const double t = line_.corner.kind == CornerSpec::kChamfer ? size : size * std::tan(theta / 2);
    if (t > l1 + kEps)
      Fail(1, "the move of the automatic chamfering block is shorter than the chamfer size L");
    if (t > l2 + kEps)
      Fail(1, "the move after the automatic chamfering block is shorter than the chamfer size L");
    const Vec2 b = c - t * d1, d = c + t * d2;
    SetPlane(held_to.pos, b);
    Staged ins;
    ins.kind = Staged::kOp;
    ins.c.line = line_.c.line;
    ins.efeed = line_.efeed;
    ins.from = held_to.pos;
    const Feed feed = line_.c.As<LinearOp>().feed;
    Target to = held_to;
    to.travel = {};
    to.travel_mask = 0;
    SetPlane(to.pos, d);
    if (line_.corner.kind == CornerSpec::kChamfer) {
      LinearOp& l = ins.c.Set<LinearOp>();
      l.to = to;
      l.feed = feed;
    } else {
      ArcOp& a = ins.c.Set<ArcOp>();
      a.to = to;
      a.feed = feed;
      const int side = turn > 0 ? geom::kLeft : geom::kRight;
      const Vec2 centre = b + size * geom::SideNormal(d1, side);
      a.cw = turn < 0;
      a.angle = theta * 180.0 / 3.14159265358979323846;
      a.plane = {static_cast<std::int8_t>(kZ), static_cast<std::int8_t>(kX)};
      a.center = {2 * centre.y, to.pos[kY], centre.x};
    }
    // A chamfer as long as the move leaves nothing of the move itself.
    if (geom::Norm(b - p0) > kEps || line_.c.target()->travel_mask != 0) ready_.push_back(std::move(line_));
    ready_.push_back(std::move(ins));
  }
  for (auto& s : behind_) ready_.push_back(std::move(s));
  behind_.clear();
}

void ContourStage::Finish() {
  if (!held_) return;
  held_ = false;
  if (line_.corner.open_end) Fail(1, "a line given by an angle only needs a next block with X, Z and A");
  Fail(1, "automatic chamfering (G75/G76) needs a next line to make the corner with");
}

}  // namespace cell::interp::okuma
