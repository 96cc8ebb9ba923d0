// The two look-ahead stages between the Okuma executor and the command queue, in the plane of a lathe
// (Vec2 x = Z, y = X as a radius; the ops carry X as a diameter):
//
//   ContourStage  automatic chamfering / rounding G75/G76 (manual ln 1302-1496) and lines given by an angle
//                 alone (ln 1473-1496, 8988-9018): the corner of a line depends on the next move, so the line
//                 is held (with what the blocks after it produce) until that move arrives.
//   NoseComp      tool-nose radius compensation G40/G41/G42 (ln 2177-3096): the nose-R centre of a block's
//   end
//                 is the intersection of this element's offset with the next element's offset, so each move
//                 is held until the next one is known; start-up, cancel, I/K entry and exit vectors, the
//                 two-blocks-without-motion rules and the alarms are the manual's. Positions written are the
//                 nose-R centre moved by the tool's tip vector (the imaginary tool tip the machine
//                 positions).
//
// Both take and give `Staged` items: commands, and the markers that keep G41/G42/G40 and block ends in order
// with the commands while a chamfer is held.
#pragma once

#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "cell/interp/canon.h"
#include "cell/interp/geometry/arc.h"
#include "cell/interp/geometry/offset_path.h"
#include "expr.h"

namespace cell::interp::okuma {

using geom::Vec2;

// What a move leaves to the next one.
struct CornerSpec {
  enum Kind : uint8_t { kNone, kChamfer, kRound };
  Kind kind = kNone;
  double size = 0;         // G75 chamfer leg / G76 radius (mm)
  bool open_end = false;   // an angle-only line: its end is where the next line meets it
  Vec2 dir;                // its direction
  bool end_angle = false;  // this line is its end point and an angle: it may close an open line
  Vec2 end_dir;
  int col = 1;
  bool any() const { return kind != kNone || open_end || end_angle; }
};

struct Staged {
  enum Kind : uint8_t { kOp, kCompOn, kCompOff, kBlockEnd };
  Kind kind = kOp;
  Canon c;
  AxisArray from{};   // kOp moves: the position before the move; kCompOn: the current position
  CornerSpec corner;  // kOp
  double efeed = 0;   // kOp: the LAP feed E in force
  // kCompOn / kCompOff
  int side = 0;  // geom::kLeft / kRight
  double radius = 0;
  Vec2 tip;  // from the nose centre to the imaginary tool tip (mm)
  bool has_ik = false;
  Vec2 ik;  // entry / exit vector (Z, X radius)
  // kBlockEnd
  bool xz = false;  // the block had X or Z
};

// Plane coordinates of a target: (Z, X radius).
inline Vec2 PlaneOf(const AxisArray& p) {
  return {p[kZ], p[kX] / 2};
}
inline void SetPlane(AxisArray& p, Vec2 v) {
  p[kZ] = v.x;
  p[kX] = 2 * v.y;
}
inline bool IsMove(Op op) {
  return op == Op::kRapid || op == Op::kLinear || op == Op::kArc || op == Op::kThread;
}

class ContourStage {
 public:
  bool engaged() const { return held_; }
  void Take(Staged&& s);
  // End of the program: a held line has no next move (alarm).
  void Finish();
  std::vector<Staged>& Ready() { return ready_; }

 private:
  void Resolve(Staged& next);
  std::vector<Staged> ready_;
  bool held_ = false;
  Staged line_;  // the held line (its `from` is where it starts)
  std::vector<Staged> behind_;
};

class NoseComp {
 public:
  bool engaged() const { return state_ != kOff || plan_ != kNoPlan; }
  bool on() const { return state_ == kOn; }
  void Take(Staged&& s);
  void Finish();
  std::vector<Staged>& Ready() { return ready_; }

 private:
  enum State { kOff, kOn, kResidual };
  enum Plan { kNoPlan, kPlanStart, kPlanCancel };
  struct Elem {
    geom::Path path;
    int side = geom::kRight;
  };
  struct Pending {
    Staged s;
    Elem e;
    bool startup = false;  // the start-up move (its end touches the next element at its start)
    bool has_ik = false;
    Vec2 ik;
  };

  void Op(Staged&& s);
  void BlockEnd(bool xz);
  Vec2 Corner(const Elem& a, const Elem& b) const;
  Vec2 OwnEnd(const Elem& a) const { return geom::OffsetEnd(a.path, r_, a.side); }
  void Release(Vec2 end_centre);
  void ReleaseAtCancel();
  void Out(Staged&& s);
  void CheckInsideArc(const Elem& e) const;

  std::vector<Staged> ready_;
  State state_ = kOff;
  Plan plan_ = kNoPlan;
  double r_ = 0;
  Vec2 tip_;
  int side_ = geom::kRight;
  bool plan_ik_ = false;
  Vec2 plan_ikv_;
  std::optional<Pending> pend_;
  std::deque<Staged> held_;
  Vec2 prog_;         // programmed plane position (end of the last programmed move)
  Vec2 centre_;       // the nose-R centre after what was written
  AxisArray last_{};  // every axis after what was written
  bool have_last_ = false;
  bool block_motion_ = false;
  int quiet_blocks_ = 0;        // blocks without X/Z since the last motion
  bool since_startup_ = false;  // no motion yet since G41/G42
};

}  // namespace cell::interp::okuma
