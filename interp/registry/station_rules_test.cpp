// Station files loaded through the registry's rules (cell/interp/station_rules.h): the dialect's name from
// the one table of dialects, tools held to the dialect's own ranges, messages naming the file and line.
#include "cell/interp/station_rules.h"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

#include "cell/error/error.h"

namespace fs = std::filesystem;

namespace {

// A private config dir per test; CELL_CONFIG_DIR is restored afterwards.
class StationRulesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/cell-station-rules-test-XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    root_ = tmpl;
    fs::create_directories(root_ / "stations");
    if (const char* old = getenv("CELL_CONFIG_DIR")) saved_ = old;
    setenv("CELL_CONFIG_DIR", root_.c_str(), 1);
  }
  void TearDown() override {
    if (saved_)
      setenv("CELL_CONFIG_DIR", saved_->c_str(), 1);
    else
      unsetenv("CELL_CONFIG_DIR");
    fs::remove_all(root_);
  }
  void Write(const std::string& id, const std::string& text) {
    std::ofstream(root_ / "stations" / (id + ".toml")) << text;
  }
  // The cell::Error message loading `id` with the registry's rules throws, or "" when it does not throw.
  std::string LoadError(const std::string& id) {
    try {
      cell::interp::LoadStation(id);
    } catch (const cell::Error& e) {
      return e.what();
    }
    return "";
  }
  fs::path root_;
  std::optional<std::string> saved_;
};

TEST_F(StationRulesTest, DialectsAreTheRegistrys) {
  const std::string file = (root_ / "stations").string();
  Write("KT01", "[station]\nid = \"KT01\"\ndialect = \"fanuc\"\n");
  EXPECT_EQ(LoadError("KT01"),
            file + "/KT01.toml:3: [station] dialect = 'fanuc': must be one of ktapl, okuma, emco, balt");
  Write("KT01", "[station]\nid = \"KT01\"\n");
  EXPECT_NE(LoadError("KT01").find("KT01.toml:1: [station]: missing key 'dialect' (one of ktapl"),
            std::string::npos);
  // An alias, any case, becomes the dialect's own name.
  Write("OK01", "[station]\nid = \"OK01\"\ndialect = \"OSP\"\n");
  EXPECT_EQ(cell::interp::LoadStation("OK01").dialect, "okuma");
}

// Issue 13 item 4: a station file's tools fit the station dialect's ranges, the same ones its tool-table form
// enforces (KT-APL TLD, manual ln 4041-4059): an out-of-range entry is refused with the file, the line and
// the TLD letter; signed compensations are legal (ln 4063, E45: D-.25).
TEST_F(StationRulesTest, ToolsFitTheDialectsRanges) {
  const std::string head = "[station]\nid = \"KT01\"\ndialect = \"ktapl\"\n[[tools]]\ntool = \"33412\"\n";
  auto err = [&](const std::string& tool) {
    Write("KT01", head + tool);
    return LoadError("KT01");
  };
  EXPECT_EQ(err("socket = 12\nlength = 0.508\ndiameter = -6.35\nlife_left_min = 225\n"), "");
  EXPECT_EQ(err("socket = 999\nlength = -999.999\ndiameter = 999.999\nlife_left_min = 5999\n"), "");
  EXPECT_NE(err("socket = 1\nlength = 1000.0\n")
                .find("KT01.toml:4: [[tools]] entry 1 (tool 33412): TLD P VALUE 1000 MM OUTSIDE +-999.999 MM "
                      "(manual ln 4041-4049)"),
            std::string::npos)
      << LoadError("KT01");
  EXPECT_NE(err("socket = 1\ndiameter = -1000\n").find("TLD D VALUE -1000 MM OUTSIDE +-999.999 MM"),
            std::string::npos);
  EXPECT_NE(err("socket = 1000\n").find("(tool 33412): TLD S VALUE 1000 OUTSIDE 1-999"), std::string::npos);
  EXPECT_NE(err("socket = 1\nlife_left_min = 6000\n").find("TLD L TOOL LIFE 6000 MIN OUTSIDE 0-5999 MIN"),
            std::string::npos);
  // A KT-APL data set has P and D only (TLD, ln 3975-4097).
  EXPECT_NE(err("socket = 1\nx_offset = -1.5\n").find("a KT-APL tool has no lathe offsets"),
            std::string::npos);
  // A lathe station keeps its own (the default: finite numbers).
  Write("OK01",
        "[station]\nid = \"OK01\"\ndialect = \"okuma\"\n[[tools]]\ntool = \"1\"\nsocket = 1\n"
        "length = 1000\n");
  EXPECT_EQ(LoadError("OK01"), "");
}

// Issue 35 item 4: a coded-pallet module (KT04, `coded_pallets = true`) takes process compensations for
// pallets 1-127 only (KT-APL ln 4081-4083), in a tool load as in a program; a table machine 1-255.
TEST_F(StationRulesTest, ACodedPalletStationTakesPallets1To127) {
  cell::config::StationConfig cfg;
  cfg.id = "KT04";
  cfg.dialect = "ktapl";
  cfg.coded_pallets = true;
  const std::string ok = "G71\n(TLD,T1001P150.D20.)\n(TLD,T1001W127P.1)\n";
  EXPECT_EQ(cell::interp::ParseStationTools(cfg, ok, "t.tld", {}).process_comps().size(), 1u);
  const std::string coded = "G71\n(TLD,T1001P150.D20.)\n(TLD,T1001W200P.1)\n";
  try {
    cell::interp::ParseStationTools(cfg, coded, "t.tld", {});
    ADD_FAILURE() << "W200 accepted on a coded-pallet station";
  } catch (const cell::Error& e) {
    EXPECT_EQ(
        std::string(e.what()),
        "t.tld:3:11: error: TLD W VALUE 200 OUTSIDE 1-127: KT04 has coded pallets (KT-APL ln 4081-4083)");
  }
  cfg.coded_pallets = false;
  EXPECT_EQ(cell::interp::ParseStationTools(cfg, coded, "t.tld", {}).process_comps()[0].pallet, 200);
}

}  // namespace
