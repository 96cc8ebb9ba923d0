// The manual's listing style imported line for line.
#include "listing.h"

#include <gtest/gtest.h>

namespace cell::interp::emco {
namespace {

TEST(Listing, WordsSeparatorsAndDecimalCommas) {
  EXPECT_EQ(ImportListing("N0010/G01/X40,000/Z5,000/F 120\n"), "N0010 G01 X40.000 Z5.000 F120\n");  // ln 854
  EXPECT_EQ(ImportListing("N0050 / G00 / X32.000\n"), "N0050 G00 X32.000\n");                       // ln 100
  EXPECT_EQ(ImportListing("N0100	G00	X50,000	Z + 10,000\n"), "N0100 G00 X50.000 Z+10.000\n");
  EXPECT_EQ(ImportListing("N.../G84/X24.000/Z-40.000/P0-4,199/\n"), "G84 X24.000 Z-40.000 P0=-4.199\n");
  EXPECT_EQ(ImportListing("N.../G85/Z-1.840/X12.000/P0 = - 3.000\n"), "G85 Z-1.840 X12.000 P0=-3.000\n");
}

TEST(Listing, ParametersPlaceholdersAndContinuations) {
  // "D3 = 2.000" is 2000 um (ln 3241-3249); "F....." keeps the modal feed; the continuation joins the block
  // above and leaves its line empty.
  EXPECT_EQ(ImportListing("N...../G84/X26.000/Z-40.000/\n       D3 = 2.000/F.....\nN0100/M30\n"),
            "G84 X26.000 Z-40.000 D3=2000\n\nN0100 M30\n");
  EXPECT_EQ(ImportListing("N...../G84/X26.000/Z-40.000/\n\nD3 = 2.000/F.....\n"),
            "G84 X26.000 Z-40.000 D3=2000\n\n\n");  // ln 3249-3251, a blank line inside the block
  EXPECT_EQ(ImportListing("N.../G02/X40,000/Z-40,000/I10,000\n K=00,000/F....\n"),
            "G02 X40.000 Z-40.000 I10.000 K00.000\n\n");                      // ln 2118-2119
  EXPECT_EQ(ImportListing("N0100/G04/D420/M03\n"), "N0100 G04 D4=20 M03\n");  // ln 2171
  EXPECT_EQ(ImportListing("O 0015\n%\n"), "O0015\n%\n");
  EXPECT_EQ(ImportListing("N0010/G00/X20./Z30.  (a comment / with a slash)\n"),
            "N0010 G00 X20. Z30. (a comment / with a slash)\n");
}

}  // namespace
}  // namespace cell::interp::emco
