// The manual's printed listing style (`cell-interp --dialect emco --listing`, manual ln 854, 1039-1086,
// 2022-2047, ...) turned into the tape format, line for line:
//
//   N0010/G01/X40,000/Z5,000/F 120            ->  N0010 G01 X40.000 Z5.000 F120
//   N...../G84/X26.000/Z-40.000/              ->  G84 X26.000 Z-40.000 D3=2000
//         D3 = 2.000/F.....                   ->  (empty: joined to the line above)
//
// "/" separates words (it is typography, not the block skip: skip blocks are written on tape); ',' is the
// decimal point; blanks inside a word go ("F 120", "Z + 10,000", "P0 = - 3.000"); a D value's '.' or ','
// before three digits is the German thousands separator ("D3 = 2.000" is 2000 um, ln 3241-3249); "K=00,000"
// loses its '='; placeholder words of dots only ("N.....", "F.....") are dropped, so the modal value
// stays; a line that continues the block above (it follows a line ending in "/", blank lines between, or
// starts with a blank, and is not a new N, O or % line) is joined to it and leaves an empty line, so line
// numbers stay those of the listing.
#pragma once

#include <string>
#include <string_view>

namespace cell::interp::emco {

std::string ImportListing(std::string_view text);

}  // namespace cell::interp::emco
