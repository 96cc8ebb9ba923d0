// E59 (EMCOTRONIC manual ln 4176-4188, M30x2; D6 = 1227, the catalogue's correction of the misprinted 1277)
// on turret position 2 at 600 rpm: the thread from Z2 to Z-42, minor diameter 27.546. Its cycle is worked out
// by hand in emco_station_test (20.12 .. 21.36 s); predict_cell_test predicts the same program.
#pragma once

namespace cell::testing {

inline constexpr const char* kEmcoThreadE59 =
    "%\n"
    "N0010 T0202 G00 X50. Z10.\n"
    "N0020 G97 S600 M04\n"
    "N0030 G00 X31. Z2.\n"
    "N0040 G85 X27.546 Z-42. D3=600 D6=1227 F2000\n"
    "N0050 G00 X50. Z10.\n"
    "N0060 M30\n";

}  // namespace cell::testing
