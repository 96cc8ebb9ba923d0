// The upper-case address letters of the canonical axes (X Y Z A B C U V W), shared by the dialects whose
// programs name axes by those letters.
#pragma once

#include "cell/interp/canon.h"

namespace cell::interp {

// Axis index of an address letter (X..W), or -1.
constexpr int AxisOfLetter(char c) {
  switch (c) {
    case 'X':
      return kX;
    case 'Y':
      return kY;
    case 'Z':
      return kZ;
    case 'A':
      return kA;
    case 'B':
      return kB;
    case 'C':
      return kC;
    case 'U':
      return kU;
    case 'V':
      return kV;
    case 'W':
      return kW;
    default:
      return -1;
  }
}

// The upper-case address letter of an axis, or '?'.
constexpr char LetterOfAxis(int axis) {
  constexpr char kLetters[kAxisCount] = {'X', 'Y', 'Z', 'A', 'B', 'C', 'U', 'V', 'W'};
  return axis >= 0 && axis < kAxisCount ? kLetters[axis] : '?';
}

}  // namespace cell::interp
