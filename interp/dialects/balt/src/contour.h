// Balt-System contouring on the programmed path in the interpolation plane: cutter radius compensation
// G41/G42/G40 (manual §5.8.5, ln 3064-3264), the corner words r (automatic radius, r0 = the cutter rolls
// round the corner) and b (bevel) of ISO and GTL profiles, and the start and end of GTL profiles (§5.15,
// ln 5049-5234). Built on the core's offset geometry (cell/interp/geometry/offset_path.h).
//
// The executor hands every command of a block to Take while the contour is engaged (compensation on, a move
// held for a corner word or a GTL profile, a residual offset after G40): moves with their programmed trace in
// the plane (machine coordinates), other commands as they are. A move's compensated end depends on the next
// move, so it is held (with the commands after it) until that move, G40 or the end is known; finished
// commands collect until TakeChecked() hands out those whose geometry is settled.
//
// The rules (ln 3080-3216): the start move (the G41/G42 block, or the first move in the plane after it) is
// linear and ends with the cutter at 90 degrees to the next element; corners join at the intersection of the
// offset elements (where an arc meets a corner turning away, of its tangent's offset: balt.md judgement call
// 50; a fill-in arc about the corner only where they do not meet, or with r0); a G40 block's
// move leaves the last element at 90 degrees and goes to its programmed end point (an arc in a G40 block is
// cut compensated and left straight to its end point); G40 without a move leaves the cutter at the offset
// point until the next move in the plane.
#pragma once

#include <deque>
#include <string>
#include <vector>

#include "cell/interp/canon.h"
#include "cell/interp/geometry/offset_path.h"

namespace cell::interp::balt {

// A contour error: FILMS4 77 UNDEFINED PROFILE (geometry) or 25 UNDEFINED COMMAND (a block the contour does
// not allow), with a reason.
struct ContourError {
  int code = 77;
  std::string text;
};

class Contour {
 public:
  // The commands whose geometry is settled, for the executor to write; the rest of what has been computed
  // waits until the element after it has been checked too. A corner is written only once the element it
  // starts is known to be long enough for the compensation: an element found too short when the one after it
  // arrives (FILMS4 77) used to leave the corner before it already written, up to a millimetre inside the
  // contour (issue 33's no-gouge property). The control reads that block ahead before it moves.
  std::vector<Canon> TakeChecked();
  // Whether TakeChecked has anything to hand out (most blocks, without compensation: no).
  bool HasReady() const { return !ready_.empty(); }
  // Anything to do: compensation on or planned, a held move, a corner word, a residual offset.
  bool engaged() const { return on_ || residual_ || held_ || plan_ != kNoPlan || corner_; }
  bool on() const { return on_; }  // G41/G42 in effect
  int p1() const { return p1_; }
  int p2() const { return p2_; }
  void SetPlane(int p1, int p2) {
    p1_ = p1;
    p2_ = p2;
  }
  // Where the tool is (every axis) while the contour is not engaged: the executor's programmed position.
  void Sync(const AxisArray& pos);
  // The cutter's position in the plane after everything handed out (machine coordinates).
  geom::Vec2 actual() const { return actual_; }

  // G41 (side kLeft) / G42 (kRight) with radius r: the next move in the plane starts compensation.
  void Start(int side, double r, int g);
  // G40: the next move in the plane, in this block, is the exit move.
  void Stop();
  // A corner word between the held move and the next one: 'r' radius v (0: roll round the corner), 'b'
  // bevel v; `line` is the corner word's block.
  void Corner(char kind, double v, int line);
  // A command of the current block. `path` is the programmed trace in the plane of a move that travels in
  // it (nullptr for other commands and moves that do not); `hold` keeps such a move open without
  // compensation (a GTL profile, a corner word next).
  void Take(Canon&& c, const geom::Path* path, bool hold);
  // A GTL closed profile's neighbour element, only to find the corner where the profile starts or ends.
  void TakeVirtual(const geom::Path& path);
  // After each block: a G40 without a move in the plane leaves the held element at its offset point.
  void EndBlock();
  // Writes what is held: the held move ends at its own offset point (the end of a GTL profile, the end of
  // the program). Compensation ends; the cutter keeps its offset until the next move in the plane.
  void Release();
  void Reset();

 private:
  enum Plan { kNoPlan, kStartPlan, kStopPlan };
  enum Kind { kNormal, kRamp, kVirtual };
  struct Pending {
    Canon c;
    geom::Path path;
    Kind kind = kNormal;
    geom::Vec2 start;       // compensated start (where the cutter is when it begins)
    double trim_start = 0;  // arcs: degrees cut off at the start by the corner
    bool roll = false;      // r0 after it
    double extra = 0;       // arcs: the full turns of a helix beyond the plane sweep (degrees)
  };

  geom::Vec2 Plane(const AxisArray& p) const { return {p[p1_], p[p2_]}; }
  void SetPlaneOf(AxisArray& p, geom::Vec2 v) const {
    p[p1_] = v.x;
    p[p2_] = v.y;
  }
  double R() const { return on_ ? r_ : 0; }
  void Out(Canon&& c);
  void ReleaseAfter();
  void EmitHeld(geom::Vec2 end, double trim_end);
  void Join(Pending& next);
  void ApplyCorner(Pending& next);
  Canon FillIn(const geom::Corner& k, geom::Vec2 corner, int line, const Feed* feed,
               std::uint32_t used) const;
  Canon Straight(const Canon& like, geom::Vec2 to) const;
  Canon Segment(geom::Vec2 to, int line, const Feed* feed, std::uint32_t used) const;
  // A feed move to `to` in the plane (a rapid without a feed), the rest of `t` as it is.
  Canon StraightTo(int line, Target t, geom::Vec2 to, const Feed* feed) const;

  void Checked() { checked_ = ready_.size(); }  // everything written so far is settled
  std::vector<Canon> ready_;
  std::size_t checked_ = 0;  // ready_[0, checked_) is settled
  std::deque<Canon> after_;  // commands after the held move: written when it is
  bool on_ = false;
  bool residual_ = false;
  Plan plan_ = kNoPlan;
  int p1_ = kX, p2_ = kY;
  int side_ = geom::kLeft;
  double r_ = 0;
  int g_ = 41;
  int next_side_ = geom::kLeft;
  double next_r_ = 0;
  bool held_ = false;
  Pending hold_;
  bool ramp_ = false;  // a start move waiting for the corner of a virtual element
  Pending ramp_move_;
  bool corner_ = false;
  char corner_kind_ = 'r';
  double corner_v_ = 0;
  int corner_line_ = 0;
  bool after_corner_ = false;  // a corner word was the last thing: a move off the plane is not allowed
  geom::Vec2 actual_;
  geom::Vec2 prog_;  // programmed plane position (end of the last programmed move)
  AxisArray last_{};
  std::uint32_t used_ = 0;
};

}  // namespace cell::interp::balt
