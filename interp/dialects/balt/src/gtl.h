// GTL, Balt-System's geometric programming (manual §5.15, ln 4363-5406): oriented points, lines, circles and
// reference origins in the interpolation plane, the definitions of Table 5.7 and the intersections a profile
// connects its elements with. Pure geometry on the core's Vec2: the executor (interp_gtl.cpp) reads the
// operands from the block and runs the profiles.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "cell/interp/geometry/vec2.h"

namespace cell::interp::balt::gtl {

using geom::Vec2;

// An oriented element (ln 4371-4408): a line has a direction (unit vector), a circle a signed radius
// (positive CCW, negative CW); an origin a position and a rotation.
struct Element {
  enum Kind : unsigned char { kNone, kOrigin, kPoint, kLine, kCircle };
  Kind kind = kNone;
  Vec2 p;        // point; a point of the line; the circle's centre; the origin's position
  Vec2 d{1, 0};  // line: unit direction
  double r = 0;  // circle: signed radius
  double a = 0;  // origin: rotation, degrees CCW
  Element Reversed() const;
  double AngleDeg() const;  // line direction, degrees
};

// A geometry error: the manual's FILMS4 code (77 UNDEFINED PROFILE, 11 SYNTAX ERROR for a definition that
// matches no form of Table 5.7) and a reason.
struct GeomError {
  int code = 77;
  std::string text;
};

// One operand of a definition, as read from the block.
struct Operand {
  enum Kind : unsigned char { kPoint, kLine, kCircle, kAngle, kDistance, kRadius, kS2 };
  Kind kind = kPoint;
  Element e;             // kPoint, kLine, kCircle (already in absolute plane coordinates)
  double v = 0;          // kAngle (degrees), kDistance, kRadius
  bool literal = false;  // written as coordinates (X.. Y.., I.. J.. r..), not as an element name
};

// The element `kind` ('o', 'p', 'l', 'c') defined by `ops` (Table 5.7). Throws GeomError.
Element Define(char kind, const std::vector<Operand>& ops);

// Where a circle touches a line or circle it is tangent to (with the same direction at the contact).
Vec2 TouchPoint(const Element& circle, const Element& e);

// Direction of travel of a line or circle at a point of it.
Vec2 Tangent(const Element& e, Vec2 at);

// Intersections of two lines or circles in the order a profile numbers them (ln 5168-5190): along the
// line's direction for a line and a circle, left then right of the line from the first circle's centre to
// the second's for two circles; one point for two lines or a tangency. Returns the count (0-2).
int Intersect(const Element& a, const Element& b, Vec2 out[2]);

// The stored elements: origins, points, lines and circles 0-255 (ln 4430).
class Geometry {
 public:
  static constexpr int kMaxIndex = 255;
  const Element* Get(char kind, int index) const;
  void Set(char kind, int index, const Element& e);
  void Clear();

 private:
  std::array<Element, kMaxIndex + 1>* Table(char kind);
  const std::array<Element, kMaxIndex + 1>* Table(char kind) const;
  std::array<Element, kMaxIndex + 1> o_{}, p_{}, l_{}, c_{};
};

}  // namespace cell::interp::balt::gtl
