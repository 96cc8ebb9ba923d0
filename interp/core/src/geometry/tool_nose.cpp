#include "cell/interp/geometry/tool_nose.h"

namespace cell::interp::geom {

Vec2 NoseTipOffset(int tip, double radius) {
  // Unit directions from the nose centre to the tip, indexed by code (0 and 9: none).
  static constexpr double kZ[10] = {0, 1, -1, -1, 1, 1, 0, -1, 0, 0};
  static constexpr double kX[10] = {0, 1, 1, -1, -1, 0, 1, 0, -1, 0};
  if (tip < 0 || tip > 9) return {};
  return {kZ[tip] * radius, kX[tip] * radius};
}

}  // namespace cell::interp::geom
