// KT-APL cutter diameter compensation (G40/G41/G42/G43/G46; manual ln 1599-1676 and 6437-6696).
//
// Two layers:
// - geometry on the two axes of the active plane (offset lines and arcs, corner intersections, fill-in
//   arcs), free functions on Vec2/Path;
// - Compensator: the look-ahead. While compensation is on, the executor hands it every canonical
//   command (in programmed, uncompensated positions). A motion block's compensated end depends on the next
//   motion block, so it is held (with the ops of the blocks after it) until that block, G40 or the end of
//   the program is known; then it is written with its compensated end point, followed by a fill-in arc
//   where the path turns away from the compensation side, and made final (Ready()) once the block after
//   it has passed its checks too (the manual's "current" and "previous look ahead block", ln 6627).
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <string>
#include <vector>

#include "cell/interp/canon.h"
#include "cell/interp/geometry/offset_path.h"

namespace cell::interp::ktapl::cc {

// The geometry (Vec2, Path, Corner, offsets, intersections) is the core's
// (cell/interp/geometry/offset_path.h).
using namespace ::cell::interp::geom;  // NOLINT: the compensator is written in the geometry's terms

// A compensation error: the manual's alarm number (empty for the control's other rejections) and text.
struct CompError {
  enum At { kAtMotion, kAtCode, kAtBlock };
  std::string alarm;
  std::string text;
  At at = kAtMotion;  // where to report it: the block's first axis word, its G40-G42 word, column 1
};

// The one-block look-ahead. Usage by the executor, per block: RampOn / SetSide / Cancel / Perpendicular
// for the block's G41/G42/G40/G43 (before its ops), every canonical command through Take while engaged(),
// EndBlock after the block; Finish at the end of the program. Commands that are final collect in Ready()
// (the executor moves them to its output after each call). Errors are thrown as CompError.
class Compensator {
 public:
  std::vector<Canon>& Ready() { return ready_; }

  // Something to do: compensation on, a residual offset after G40 without motion, or a plan for this block.
  bool engaged() const { return engaged_; }
  // G41/G42 is in effect (a compensated block is held).
  bool on() const { return state_ == kOn; }
  int p1() const { return p1_; }
  int p2() const { return p2_; }

  struct Setup {
    int p1 = kX, p2 = kY;                  // plane axes (first, second)
    double radius = 0;                     // mm, >= 0
    int side = kLeft;                      // after axis inversion and the sign of the comp
    std::array<double, kAxisCount> pos{};  // programmed position before the block
    double min_move = 0.001;               // ramp-on minimum in-plane move, mm
    int g = 41;                            // the programmed code, for messages
  };
  // The block carries G41/G42 while compensation is off: its move is the ramp-on.
  void RampOn(const Setup& s);
  // G41/G42 while on: the side for the next motion blocks (a change retraces without a ramp).
  void SetSide(int side, int g);
  // G40 in the block (ramp-off with its move, or removal without motion at the end of the block).
  void Cancel();
  // G43 in the block: its move is a perpendicular excursion (no intersection checks at either end).
  void Perpendicular();
  // G46 modal state (fill-in arcs bypassed).
  void SetBypass(bool on) { bypass_ = on; }

  // A canonical command of the current block (motion in programmed positions).
  void Take(Canon&& c);
  // After each executed block; `counts` is false for blocks with nothing in them.
  void EndBlock(bool counts);
  // End of the program (M02/M30 or the end of the text): the held block ends at its own offset point.
  void Finish();

 private:
  enum State { kOff, kOn, kResidual };
  enum Plan { kNoPlan, kPlanRampOn, kPlanCancel, kPlanPerpendicular };
  enum Kind { kNormal, kRamp, kPerpendicular };
  struct Pending {
    Canon c;
    Path path;
    Kind kind = kNormal;
    int side = kLeft;
    int g = 41;
    Vec2 start;             // compensated start (where the cutter is when the block begins)
    double trim_start = 0;  // mm / degrees (kNormal)
  };

  Vec2 PlaneOf(const std::array<double, kAxisCount>& pos) const { return {pos[p1_], pos[p2_]}; }
  void SetPlane(std::array<double, kAxisCount>& pos, Vec2 v) const {
    pos[p1_] = v.x;
    pos[p2_] = v.y;
  }
  void Update() { engaged_ = state_ != kOff || plan_ != kNoPlan; }
  void Out(Canon&& c);
  // Moves what is staged to Ready().
  void Settle();
  void TakeOne(Canon&& c);
  Vec2 OwnEnd(const Pending& p) const;
  // Writes the held block ending at `end` (arcs: cut back by `trim_end` degrees), then the moves made at the
  // corner (`corner`: a fill-in arc, or G46's lines to and from the tangents' intersection), then the ops
  // held behind it.
  void Release(Vec2 end, double trim_end, std::vector<Canon> corner = {});
  void ReleaseHeld();
  Canon FillIn(const Corner& k, const Canon& next) const;
  Canon CornerLine(Vec2 to, const Canon& next) const;
  void TakeOther(Canon&& c);
  void TakeRampOn(Canon&& c, const Path& p, bool in_plane);
  void TakeResidual(Canon&& c, const Path& p, bool in_plane);
  void TakeHeld(Canon&& c, const Path& p, bool in_plane);
  void Join(Pending& next, const Path& p);
  std::string AxesText() const;

  std::vector<Canon> ready_;
  // Written but not final while compensation is on: the last released block (with its fill-in arc and the
  // ops behind it) until the block after it has passed its own corner checks (judgement call 88).
  std::vector<Canon> staged_;
  std::deque<Canon> held_;  // ops of the blocks after the held one (bounded: error 0003 after 4 blocks)
  bool engaged_ = false;
  State state_ = kOff;
  Plan plan_ = kNoPlan;
  bool bypass_ = false;
  int p1_ = kX, p2_ = kY;
  double r_ = 0;
  int side_ = kLeft;
  int g_ = 41;
  double min_move_ = 0.001;
  Vec2 prog_;                              // programmed plane position (start of the next programmed move)
  Vec2 actual_;                            // where the cutter is in the plane after the ops written so far
  std::array<double, kAxisCount> last_{};  // every axis after the ops written so far
  Pending pend_;
  // Per block.
  bool block_motion_ = false;  // a move in the plane was taken in this block
  bool block_clears_ = false;  // tool change, regrid or probe: the slides no longer carry an offset
  int no_motion_blocks_ = 0;
};

}  // namespace cell::interp::ktapl::cc
