// The cell's TOML error convention: file, line and column of a syntax error; an unreadable file is kIo.
#include "cell/toml/parse.h"

#include <gtest/gtest.h>

#include "cell/error/error.h"

namespace cell::tomlfile {
namespace {

TEST(TomlParse, ReadsATable) {
  toml::table t = Parse("[station]\nid = \"KT01\"\n", "KT01.toml");
  EXPECT_EQ(t["station"]["id"].value_or(std::string()), "KT01");
}

TEST(TomlParse, ASyntaxErrorNamesSourceLineAndColumn) {
  try {
    Parse("[plane]\npoint = [0, 0\n", "part.toml");
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kInvalidArgument);
    EXPECT_EQ(std::string(e.what()).rfind("part.toml:2:", 0), 0u) << e.what();
  }
}

TEST(TomlParse, AMissingFileIsAnIoError) {
  try {
    ParseFile("/nonexistent/station.toml");
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kIo);
    EXPECT_NE(std::string(e.what()).find("/nonexistent/station.toml: cannot open"), std::string::npos);
  }
}

}  // namespace
}  // namespace cell::tomlfile
