// KT-APL cutter diameter compensation (G40/G41/G42/G43/G46; manual ln 1599-1676 and 6437-6696).
//
// Two layers:
// - geometry on the two axes of the active plane (offset lines and arcs, corner intersections, fill-in
//   arcs), free functions on Vec2/Path;
// - Compensator: the one-block look-ahead. While compensation is on, the executor hands it every canonical
//   command (in programmed, uncompensated positions). A motion block's compensated end depends on the next
//   motion block, so it is held (with the ops of the blocks after it) until that block, G40 or the end of
//   the program is known; then it is made final (Ready()) with its compensated end point, followed by a
//   fill-in arc where the path turns away from the compensation side.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <deque>
#include <string>
#include <vector>

#include "cell/interp/canon.h"

namespace cell::interp::ktapl::cc {

// A point or vector in the compensation plane: x = the plane's first axis, y = its second (G17 X,Y; G18
// Z,X; G19 Y,Z; App. H), millimetres.
struct Vec2 {
  double x = 0, y = 0;
};
inline Vec2 operator+(Vec2 a, Vec2 b) {
  return {a.x + b.x, a.y + b.y};
}
inline Vec2 operator-(Vec2 a, Vec2 b) {
  return {a.x - b.x, a.y - b.y};
}
inline Vec2 operator*(double k, Vec2 a) {
  return {k * a.x, k * a.y};
}
inline double Dot(Vec2 a, Vec2 b) {
  return a.x * b.x + a.y * b.y;
}
inline double Cross(Vec2 a, Vec2 b) {
  return a.x * b.y - a.y * b.x;
}
inline double Norm(Vec2 a) {
  return std::hypot(a.x, a.y);
}

// Below this (mm) two points are the same and a move has no extent in the plane.
constexpr double kTiny = 1e-6;

// Compensation side: the cutter left (G41) or right (G42) of the path, looking along the cut.
constexpr int kLeft = 1;
constexpr int kRight = -1;

// A programmed path in the plane: a line, or an arc about `center` (cw/ccw in the plane's orientation,
// `sweep` degrees, 360 for a full circle).
struct Path {
  bool arc = false;
  Vec2 start, end, center;
  bool cw = false;
  double sweep = 0;
};

// Unit tangent (direction of travel) at the start and at the end.
Vec2 StartTangent(const Path& p);
Vec2 EndTangent(const Path& p);
// Unit normal toward `side` of a direction of travel.
inline Vec2 SideNormal(Vec2 t, int side) {
  return {-side * t.y, side * t.x};
}
// True when the compensation side is the inside of the arc (G41 on a ccw arc, G42 on a cw arc).
bool InsideArc(const Path& p, int side);
// Radius of the offset arc (programmed radius at the start or end -/+ r); < 0 when r is too large.
double OffsetRadiusAtStart(const Path& p, double r, int side);
double OffsetRadiusAtEnd(const Path& p, double r, int side);
// The cutter centre at 90 degrees to the path at its start / end.
Vec2 OffsetStart(const Path& p, double r, int side);
Vec2 OffsetEnd(const Path& p, double r, int side);
// Extent of a path: mm for a line, degrees for an arc (its sweep).
double Extent(const Path& p);
// Length (mm) of the offset path left when it is cut back by `trim_start` at its start and `trim_end` at
// its end (mm for lines, degrees for arcs; negative = extended). Negative: it would run backwards.
double RemainingLength(const Path& p, double r, int side, double trim_start, double trim_end);

// Intersections of a line (point, unit direction) with a line or a circle, and of two circles; the
// functions return how many points they wrote.
int IntersectLineLine(Vec2 p, Vec2 d, Vec2 q, Vec2 e, Vec2* out);
int IntersectLineCircle(Vec2 p, Vec2 d, Vec2 c, double r, Vec2 out[2]);
int IntersectCircleCircle(Vec2 c1, double r1, Vec2 c2, double r2, Vec2 out[2]);

// The corner where path `a` ends and path `b` starts, with the cutter on `side` at distance `r`.
struct Corner {
  enum Kind {
    kNone,    // the offset paths meet (tangent paths, or r == 0)
    kToward,  // the path turns toward the compensation: the offset paths are cut back to their intersection
    kAway,    // the path turns away: a fill-in arc about the programmed corner, or (G46) the offset paths
              // extended to their intersection
  };
  Kind kind = kNone;
  bool intersects = true;  // kToward: false when the offset paths do not intersect (error 0002)
  Vec2 a_end, b_start;     // compensated end of a, compensated start of b
  double a_trim = 0;       // a cut back at its end (mm / degrees; negative = extended)
  double b_trim = 0;       // b cut back at its start
  bool fill_in = false;    // a fill-in arc from a_end to b_start about a.end
  bool fill_cw = false;
  double fill_sweep = 0;  // degrees
};
// bypass_fill_in (G46): a turn away meets at the intersection of the extended offset paths instead of a
// fill-in arc (a fill-in arc is still used when they do not meet ahead of both ends, e.g. a reversal).
Corner ComputeCorner(const Path& a, const Path& b, double r, int side, bool bypass_fill_in);

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
  Vec2 OwnEnd(const Pending& p) const;
  // Writes the held block ending at `end` (arcs: cut back by `trim_end` degrees), then `fill` if any, then
  // the ops held behind it.
  void Release(Vec2 end, double trim_end, const Canon* fill);
  void ReleaseHeld();
  Canon FillIn(const Corner& k, const Canon& next) const;
  std::string AxesText() const;

  std::vector<Canon> ready_;
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
