// A point or vector in a plane (geometry of arcs and compensation).
#pragma once

#include <cmath>

namespace cell::interp::geom {

// x = the plane's first axis, y = its second (G17 X,Y; G18 Z,X; G19 Y,Z), millimetres.
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

}  // namespace cell::interp::geom
