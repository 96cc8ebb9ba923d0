// LAP (Lathe Auto-Programming, manual SECTION 8, seed ln 4939-6434): the rough-cutting tool paths of AP modes
// I (bar turning G85), II (copy turning G86), IV (high-speed bar turning G85 with a G83 blank) and V (bar
// copying G86 with a blank), and the passes of AP mode III (continuous threads G88), computed from a captured
// finish contour. Geometry is in the lathe plane (Vec2 x = Z, y = X as a radius, machine coordinates);
// the executor turns the moves into canonical commands.
#pragma once

#include <vector>

#include "cell/interp/geometry/offset_path.h"

namespace cell::interp::okuma {

// One element of a captured contour.
struct LapElement {
  geom::Path path;
  bool rapid = false;   // G00 (allowed in the first element only)
  double f = 0;         // the finish feed written in the contour
  double e = 0;         // the roughing feed along the contour (E), 0 = the call's F
  bool thread = false;  // AP III: a G33/G34/G35 element
  double lead = 0, lead_change = 0;
  bool lead_along_x = false;
};

struct LapChange {
  bool set = false;
  bool axis_x = true;  // XA/XB (longitudinal) or ZA/ZB (transverse)
  double at = 0;       // the change point on the infeed axis (radius for X), machine coordinates
  double d = 0;        // depth of cut after it (the infeed axis' units: X radius, Z)
  double f = 0;
};

struct LapParams {
  int mode = 1;             // AP mode 1-5
  bool transverse = false;  // G82
  double d = 0;             // depth of cut on the infeed axis (X as a radius)
  double f = 0;             // rough feed
  double u = 0;             // finish allowance on X (radius)
  double w = 0;             // finish allowance on Z
  bool m85 = false;         // no return to the start point
  LapChange a, b;           // G84 change points
  double relief = 0.1;      // mm, each axis (X as a diameter value: 0.05 radius)
  double clearance = 2.0;   // LAP4 clearance Lc, mm
  // AP III
  double h = 0;          // thread height (radius)
  double tip_angle = 0;  // B, degrees
  int thread_mode = 32;  // M32 M33 M34
  int infeed = 73;       // M73 M74 M75
};

struct LapMove {
  enum Kind { kRapid, kLinear, kArc, kThread } kind = kRapid;
  geom::Vec2 to;
  double f = 0;
  geom::Vec2 center;
  bool cw = false;
  double sweep = 0;
  double lead = 0, lead_change = 0, start_angle = 0;
  bool lead_along_x = false;
};

// The rough cycle of AP mode I, II, IV or V from `start` (the AP start point). Throws RunError (col 1) with
// the manual's conditions.
std::vector<LapMove> LapRough(const LapParams& p, geom::Vec2 start, const std::vector<LapElement>& contour,
                              const std::vector<LapElement>& blank);

// AP mode III: the thread passes along the contour.
std::vector<LapMove> LapThread(const LapParams& p, geom::Vec2 start, const std::vector<LapElement>& contour,
                               const std::vector<double>& depths);

}  // namespace cell::interp::okuma
