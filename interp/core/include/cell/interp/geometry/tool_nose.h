// Lathe tool-nose geometry for tool-nose radius compensation: where the theoretical tip P of a turning tool
// (the point its X/Z offsets are measured to) lies relative to the centre S of its nose radius, by the tip
// position code of the ISO/DIN layout that lathe controls share (EMCO "L", Okuma and Fanuc "tip"). The plane
// is the lathe's ZX plane as the arc geometry uses it: Vec2 x = Z, y = X as a radius, X up and Z to the
// right.
//
//        2   6   1          1 (+Z,+X)  2 (-Z,+X)  3 (-Z,-X)  4 (+Z,-X)
//        7  0/9  5          5 (+Z)     6 (+X)     7 (-Z)     8 (-X)
//        3   8   4          0 and 9: the tip is the centre (no offset)
//
// An outside turning tool cutting toward the chuck touches the diameter with the bottom of its nose and a
// shoulder with its left side: code 3.
#pragma once

#include "cell/interp/geometry/vec2.h"

namespace cell::interp::geom {

// P - S for tip code `tip` (0-9) and nose radius `radius` (mm); codes outside 1-8 give the centre.
Vec2 NoseTipOffset(int tip, double radius);

}  // namespace cell::interp::geom
