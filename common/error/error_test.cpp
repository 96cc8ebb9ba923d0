#include "cell/error/error.h"

#include <gtest/gtest.h>

TEST(Error, CarriesCodeAndReason) {
  try {
    throw cell::Error(cell::Errc::kNotFound, "program 'X' not in HOST");
  } catch (const cell::Error& e) {
    EXPECT_EQ(e.code(), cell::Errc::kNotFound);
    EXPECT_STREQ(e.what(), "program 'X' not in HOST");
    EXPECT_EQ(cell::ErrcName(e.code()), "not found");
  }
}
