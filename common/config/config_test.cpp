#include "cell/config/config.h"
#include "cell/config/dds.h"

#include <gtest/gtest.h>
#include <stdlib.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "cell/error/error.h"

namespace fs = std::filesystem;
using cell::config::DdsProfile;
using cell::config::DdsVendor;
using cell::config::ExpandEnvironment;
using cell::config::kDdsVendors;
using cell::config::LoadDdsProfile;
using cell::config::LoadStation;
using cell::config::SourceTreeDir;

namespace {

// A private config dir and data dir per test; the environment is restored afterwards.
class ConfigTest : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/cell-config-test-XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    root_ = tmpl;
    fs::create_directories(root_ / "etc" / "stations");
    for (const char* v :
         {"CELL_CONFIG_DIR", "CELL_DATA_DIR", "CELL_DOMAIN", "XDG_STATE_HOME", "HOME", "CELL_DDS",
          "CELL_DDS_PROFILE", "CELL_DDS_PARTICIPANTS", "CELL_TEST_A", "CELL_TEST_B"}) {
      const char* old = getenv(v);
      saved_.emplace_back(v, old ? std::optional<std::string>(old) : std::nullopt);
    }
    for (const char* v :
         {"CELL_DDS", "CELL_DDS_PROFILE", "CELL_DDS_PARTICIPANTS", "CELL_TEST_A", "CELL_TEST_B"})
      unsetenv(v);
    setenv("CELL_CONFIG_DIR", (root_ / "etc").c_str(), 1);
  }
  void TearDown() override {
    for (auto& [k, v] : saved_) {
      if (v)
        setenv(k.c_str(), v->c_str(), 1);
      else
        unsetenv(k.c_str());
    }
    fs::remove_all(root_);
  }
  void Write(const std::string& id, const std::string& text) {
    std::ofstream(root_ / "etc" / "stations" / (id + ".toml")) << text;
  }
  // The cell::Error message LoadStation(id) throws, or "" when it does not throw.
  std::string LoadError(const std::string& id) {
    try {
      LoadStation(id);
    } catch (const cell::Error& e) {
      return e.what();
    }
    return "";
  }
  fs::path root_;
  std::vector<std::pair<std::string, std::optional<std::string>>> saved_;
};

const char* kGood = R"(
[station]
id = "KT09"
dialect = "ktapl"
description = "test machine"
coded_pallets = true

[machine]          # another reader's table: ignored here
rapid_mm_min = 10000
[axes.x]
min = -500.0

[[tools]]
tool = "1001"
socket = 1
length = 150.5
diameter = 25
life_left_min = 120

[[tools]]
tool = 33412
socket = 2
length = 0
diameter = 0
life_left_min = 0

[[tools]]
tool = "33412.5"
socket = 2
length = 10
diameter = 12.5
life_left_min = 30.5
)";

TEST_F(ConfigTest, LoadsStationAndTools) {
  Write("KT09", kGood);
  auto s = LoadStation("KT09");
  EXPECT_EQ(s.id, "KT09");
  EXPECT_EQ(s.dialect, "ktapl");
  EXPECT_EQ(s.description, "test machine");
  EXPECT_TRUE(s.coded_pallets);
  EXPECT_EQ(s.file, root_ / "etc" / "stations" / "KT09.toml");
  ASSERT_EQ(s.tools.size(), 3u);
  using cell::tooltable::ToolEntry;
  EXPECT_EQ(s.tools[0],
            (ToolEntry{.tool = "1001", .socket = 1, .length = 150.5, .diameter = 25, .life_left_min = 120}));
  EXPECT_EQ(s.tools[1], (ToolEntry{.tool = "33412", .socket = 2}));
  EXPECT_EQ(
      s.tools[2],
      (ToolEntry{.tool = "33412.5", .socket = 2, .length = 10, .diameter = 12.5, .life_left_min = 30.5}));
}

TEST_F(ConfigTest, OptionalFieldsDefault) {
  Write("OK05", "[station]\nid = \"OK05\"\ndialect = \"okuma\"\n");
  auto s = LoadStation("OK05");
  EXPECT_EQ(s.description, "");
  EXPECT_FALSE(s.coded_pallets);
  EXPECT_TRUE(s.tools.empty());
}

// [params]: the dialect's machine settings as text, by its own names (EMCO's operator monitor).
TEST_F(ConfigTest, ParamsAsText) {
  Write("EM05",
        "[station]\nid = \"EM05\"\ndialect = \"emco\"\n[params]\nO11 = 9\nS02 = 500\nSKIP = true\n"
        "\"PSO1.Z\" = 90.5\nUNITS = \"mm\"\n");
  auto s = LoadStation("EM05");
  EXPECT_EQ(s.params, (std::map<std::string, std::string>{
                          {"O11", "9"}, {"S02", "500"}, {"SKIP", "1"}, {"PSO1.Z", "90.5"}, {"UNITS", "mm"}}));
  Write("EM06", "[station]\nid = \"EM06\"\ndialect = \"emco\"\n[params]\nO11 = [1, 2]\n");
  EXPECT_NE(LoadError("EM06").find("[params] O11: must be a string, number or boolean, not an array"),
            std::string::npos);
  Write("EM07", "[station]\nid = \"EM07\"\ndialect = \"emco\"\n[params]\n\"a b\" = 1\n");
  EXPECT_NE(LoadError("EM07").find("[params]: 'a b': names are 1-32 letters, digits, '_', '.' or '-'"),
            std::string::npos);
}

TEST_F(ConfigTest, ListStationsSortedTomlOnly) {
  Write("KT02", kGood);
  Write("KT01", kGood);
  std::ofstream(root_ / "etc" / "stations" / "README") << "x";
  std::ofstream(root_ / "etc" / "stations" / "KT03.toml.dist") << "x";
  EXPECT_EQ(cell::config::ListStations(), (std::vector<std::string>{"KT01", "KT02"}));
  setenv("CELL_CONFIG_DIR", (root_ / "nowhere").c_str(), 1);
  EXPECT_THROW(cell::config::ListStations(), cell::Error);
}

TEST_F(ConfigTest, ErrorsNameFileKeyAndAllowedValues) {
  const std::string file = (root_ / "etc" / "stations").string();
  // Which dialects exist is the registry's (interp/registry station_rules_test); here only the name's form.
  Write("KT01", "[station]\nid = \"KT01\"\ndialect = \"fa nuc\"\n");
  EXPECT_EQ(LoadError("KT01"), file +
                                   "/KT01.toml:3: [station] dialect = 'fa nuc': must be a dialect name (1-32 "
                                   "letters, digits, '_' or '-')");

  Write("KT01", "[station]\nid = \"KT02\"\ndialect = \"ktapl\"\n");
  EXPECT_EQ(LoadError("KT01"),
            file + "/KT01.toml:2: [station] id = 'KT02': must equal the file name's stem 'KT01'");

  Write("KT01", "[station]\nid = \"KT01\"\n");
  EXPECT_EQ(LoadError("KT01"), file + "/KT01.toml:1: [station]: missing key 'dialect'");

  Write("KT01", "[machine]\nx = 1\n");
  EXPECT_NE(LoadError("KT01").find("KT01.toml: missing table [station]"), std::string::npos);

  Write("KT01", "[station]\nid = \"KT01\"\ndialect = \"ktapl\"\ncoded_pallet = true\n");
  EXPECT_NE(LoadError("KT01").find("KT01.toml:4: [station]: unknown key 'coded_pallet'"), std::string::npos);

  Write("KT01", "[station]\nid = \"KT01\"\ndialect = \"ktapl\"\ncoded_pallets = 1\n");
  EXPECT_NE(LoadError("KT01").find("coded_pallets must be true or false, not an integer"), std::string::npos);

  Write("KT01", "[station]\nid = \"KT01\"\ndialect = [\n");
  EXPECT_NE(LoadError("KT01").find("KT01.toml:3:"), std::string::npos) << LoadError("KT01");
}

TEST_F(ConfigTest, ToolErrors) {
  const std::string head = "[station]\nid = \"KT01\"\ndialect = \"ktapl\"\n[[tools]]\n";
  auto err = [&](const std::string& tool) {
    Write("KT01", head + tool);
    return LoadError("KT01");
  };
  EXPECT_NE(err("tool = \"1001.8\"\nsocket = 1\nlength = 1\ndiameter = 1\nlife_left_min = 1\n")
                .find("KT01.toml:5: [[tools]] entry 1: tool = '1001.8': must be 1-7 digits with an optional "
                      "suffix .1-.7"),
            std::string::npos);
  EXPECT_NE(err("tool = 12345678\nsocket = 1\nlength = 1\ndiameter = 1\nlife_left_min = 1\n")
                .find("tool = '12345678'"),
            std::string::npos);
  EXPECT_NE(err("tool = 1.5\nsocket = 1\nlength = 1\ndiameter = 1\nlife_left_min = 1\n")
                .find("tool must be a string such as \"1001\" or \"33412.5\" (or an integer), not a float"),
            std::string::npos);
  EXPECT_NE(err("tool = \"1\"\nsocket = 0\nlength = 1\ndiameter = 1\nlife_left_min = 1\n")
                .find("KT01.toml:6: [[tools]] entry 1 (tool 1): socket must be an integer in 1..9999"),
            std::string::npos);
  // Compensations are signed (KT-APL manual example E45: D-.25); life and nose radius are not.
  EXPECT_EQ(err("tool = \"1\"\nsocket = 1\nlength = -1\ndiameter = -0.25\nlife_left_min = 1\n"), "");
  EXPECT_NE(err("tool = \"1\"\nsocket = 1\nlength = 1\nlife_left_min = -1\n")
                .find("life_left_min = -1: must be a non-negative number"),
            std::string::npos);
  EXPECT_NE(err("tool = \"1\"\nlength = 1\n").find("[[tools]] entry 1: missing key 'socket'"),
            std::string::npos);
  EXPECT_NE(err("tool = \"1\"\nsocket = 1\ntip = 10\n").find("tip must be a tip position code 0..9"),
            std::string::npos);
  EXPECT_NE(err("tool = \"1\"\nsocket = 1\nlength_axis = \"Q\"\n").find("length_axis = 'Q'"),
            std::string::npos);
  // A lathe's offsets on a lathe station (that a KT-APL data set has P and D only is the dialect's rule:
  // interp/registry station_rules_test).
  Write("OK01",
        "[station]\nid = \"OK01\"\ndialect = \"okuma\"\n[[tools]]\n"
        "tool = \"1\"\nsocket = 1\nx_offset = -1.5\nz_offset = 2\nnose_radius = 0.4\ntip = 3\n");
  EXPECT_EQ(LoadError("OK01"), "");
  EXPECT_NE(err("tool = \"1\"\nsocket = 1\nlength = 1\ndiameter = \"big\"\nlife_left_min = 1\n")
                .find("diameter must be a number, not a string"),
            std::string::npos);
  EXPECT_NE(
      err("tool = \"1\"\nsocket = 1\nlength = 1\ndiameter = 1\nlife_left_min = 1\nwear = 2\n")
          .find("unknown key 'wear' (allowed: tool, socket, length, diameter, life_left_min, length_axis"),
      std::string::npos);
  const std::string one = "tool = \"7\"\nsocket = 3\nlength = 1\ndiameter = 1\nlife_left_min = 1\n";
  EXPECT_NE(err(one + "[[tools]]\n" + one).find("[[tools]] entry 2: tool 7 is already listed in entry 1"),
            std::string::npos);
  EXPECT_NE(
      err(one + "[[tools]]\n" + "tool = \"8\"\nsocket = 3\nlength = 1\ndiameter = 1\nlife_left_min = 1\n")
          .find("[[tools]] entry 2: socket 3 already holds tool 7"),
      std::string::npos);
}

// Without the registry's rules a dialect is kept as written and tools are not held to a dialect's ranges
// (those are checked by the processes that run programs: interp/registry station_rules_test).
TEST_F(ConfigTest, WithoutRulesTheDialectIsAName) {
  Write("KT01",
        "[station]\nid = \"KT01\"\ndialect = \"Kt-Apl\"\n[[tools]]\ntool = \"33412\"\nsocket = 1\n"
        "length = 1000.0\n");
  auto s = LoadStation("KT01");
  EXPECT_EQ(s.dialect, "Kt-Apl");
  ASSERT_EQ(s.tools.size(), 1u);
  EXPECT_EQ(s.tools[0].length, 1000.0);
}

TEST_F(ConfigTest, UnknownStationListsConfiguredOnes) {
  Write("KT01", kGood);
  Write("KT02", kGood);
  try {
    LoadStation("XX99");
    FAIL() << "no throw";
  } catch (const cell::Error& e) {
    EXPECT_EQ(e.code(), cell::Errc::kNotFound);
    EXPECT_NE(std::string(e.what()).find("station 'XX99' is not configured"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("(configured: KT01, KT02)"), std::string::npos) << e.what();
  }
  try {
    LoadStation("../passwd");
    FAIL() << "no throw";
  } catch (const cell::Error& e) {
    EXPECT_EQ(e.code(), cell::Errc::kInvalidArgument);
  }
}

TEST_F(ConfigTest, Domain) {
  unsetenv("CELL_DOMAIN");
  EXPECT_EQ(cell::config::Domain(), 101);
  setenv("CELL_DOMAIN", "0", 1);
  EXPECT_EQ(cell::config::Domain(), 0);
  setenv("CELL_DOMAIN", "232", 1);
  EXPECT_EQ(cell::config::Domain(), 232);
  for (const char* bad : {"233", "-1", "abc", "12x", "1000", " 5"}) {
    setenv("CELL_DOMAIN", bad, 1);
    try {
      cell::config::Domain();
      ADD_FAILURE() << bad << " accepted";
    } catch (const cell::Error& e) {
      EXPECT_EQ(std::string(e.what()), std::string("CELL_DOMAIN='") + bad +
                                           "': must be a DDS domain id, an integer in 0..232 (default 101)");
    }
  }
}

TEST_F(ConfigTest, DataDirPrecedenceAndCreation) {
  setenv("CELL_DATA_DIR", (root_ / "data" / "deep").c_str(), 1);
  EXPECT_EQ(cell::config::DataDir(), root_ / "data" / "deep");
  EXPECT_TRUE(fs::is_directory(root_ / "data" / "deep"));
  // Issue 13: a data directory made here is its owner's only, whatever the umask.
  EXPECT_EQ(fs::status(root_ / "data" / "deep").permissions() & fs::perms::all, fs::perms::owner_all);

  unsetenv("CELL_DATA_DIR");
  setenv("XDG_STATE_HOME", (root_ / "xdg").c_str(), 1);
  EXPECT_EQ(cell::config::DataDir(), root_ / "xdg" / "cell");
  EXPECT_TRUE(fs::is_directory(root_ / "xdg" / "cell"));

  setenv("XDG_STATE_HOME", "relative/ignored", 1);
  setenv("HOME", (root_ / "home").c_str(), 1);
  EXPECT_EQ(cell::config::DataDir(), root_ / "home" / ".local" / "state" / "cell");
  EXPECT_TRUE(fs::is_directory(root_ / "home" / ".local" / "state" / "cell"));

  std::ofstream(root_ / "file") << "x";
  setenv("CELL_DATA_DIR", (root_ / "file" / "sub").c_str(), 1);
  EXPECT_THROW(cell::config::DataDir(), cell::Error);
}

TEST_F(ConfigTest, ConfigDirPrecedence) {
  EXPECT_EQ(cell::config::ConfigDir(), root_ / "etc");
  unsetenv("CELL_CONFIG_DIR");
  // This test binary lives in the build tree: the source tree's deploy/.
  const char* src = getenv("CELL_SOURCE_DIR");
  ASSERT_NE(src, nullptr) << "run under ctest (CELL_SOURCE_DIR)";
  EXPECT_EQ(fs::weakly_canonical(cell::config::ConfigDir()), fs::weakly_canonical(fs::path(src) / "deploy"));
  EXPECT_EQ(fs::weakly_canonical(cell::config::SourceTreeDir()), fs::weakly_canonical(src));
  EXPECT_EQ(cell::config::DefaultConfigDir("/usr/local/bin/cell-scheduler"), "/etc/cell");
  EXPECT_EQ(cell::config::DefaultConfigDir("/opt/cell/bin/cell-scheduler"), "/etc/cell");
  EXPECT_EQ(cell::config::DefaultConfigDir("/usrlocal/bin/x").filename(), "deploy");
  EXPECT_EQ(cell::config::DefaultConfigDir("/home/me/cell/build/bin/x").filename(), "deploy");
}

// The shipped station files are valid and give the route tests overlapping tool sets.
TEST(ShippedStations, LoadAndOverlap) {
  const char* src = getenv("CELL_SOURCE_DIR");
  ASSERT_NE(src, nullptr) << "run under ctest (CELL_SOURCE_DIR)";
  setenv("CELL_CONFIG_DIR", (fs::path(src) / "deploy").c_str(), 1);
  auto ids = cell::config::ListStations();
  for (const char* want : {"KT01", "KT02", "KT03", "KT04", "OK01", "EM01"}) {
    EXPECT_NE(std::find(ids.begin(), ids.end(), want), ids.end()) << want;
  }
  auto has = [](const cell::config::StationConfig& s, const std::string& tool) {
    return std::any_of(s.tools.begin(), s.tools.end(), [&](auto& t) { return t.tool == tool; });
  };
  for (const auto& id : ids) {
    auto s = LoadStation(id);
    EXPECT_EQ(s.id, id);
    EXPECT_FALSE(s.tools.empty()) << id;
    EXPECT_FALSE(s.description.empty()) << id;
  }
  auto kt01 = LoadStation("KT01"), kt02 = LoadStation("KT02");
  EXPECT_EQ(kt01.dialect, "ktapl");
  EXPECT_EQ(LoadStation("OK01").dialect, "okuma");
  EXPECT_EQ(LoadStation("EM01").dialect, "emco");
  EXPECT_EQ(LoadStation("EM01").params.at("O11"), "9");
  for (const char* t : {"1001", "1002", "1003"}) {
    EXPECT_TRUE(has(kt01, t) && has(kt02, t)) << t;
  }
  EXPECT_TRUE(has(kt02, "2001"));
  EXPECT_FALSE(has(kt01, "2001"));
  unsetenv("CELL_CONFIG_DIR");
}

// The cell::Error message f throws, or "" when it does not throw.
template <class F>
std::string ErrorOf(F f) {
  try {
    f();
  } catch (const cell::Error& e) {
    return e.what();
  }
  return "";
}

// Which DDS stack and profile a process uses (cell/config/dds.h): precedence, names, files, expansion.
TEST_F(ConfigTest, DdsStationFileWinsOverCellDdsWhichWinsOverTheDefault) {
  EXPECT_EQ(DdsVendor().vendor, "fastdds");
  EXPECT_EQ(DdsVendor().source, "the default");
  setenv("CELL_DDS", "cyclonedds", 1);
  EXPECT_EQ(DdsVendor().vendor, "cyclonedds");
  EXPECT_EQ(DdsVendor().source, "CELL_DDS");
  EXPECT_EQ(DdsVendor("fastdds").vendor, "fastdds");  // the station's own stack
  EXPECT_EQ(DdsVendor("fastdds").source, "the station file");
  unsetenv("CELL_DDS");
  EXPECT_EQ(DdsVendor("cyclonedds").vendor, "cyclonedds");
}

TEST_F(ConfigTest, DdsUnknownStacksAreErrorsNamingTheSetting) {
  setenv("CELL_DDS", "opendds", 1);
  EXPECT_EQ(ErrorOf([] { DdsVendor(); }), "CELL_DDS=opendds: expected one of fastdds, cyclonedds");
  // Even when a station file decides: a typo in the environment must not pass silently.
  EXPECT_NE(ErrorOf([] { DdsVendor("fastdds"); }), "");
  unsetenv("CELL_DDS");
  EXPECT_EQ(ErrorOf([] { DdsVendor("cyclone"); }),
            "station dds = 'cyclone': expected one of fastdds, cyclonedds");
}

TEST_F(ConfigTest, DdsStationFileCarriesItsStack) {
  std::ofstream(root_ / "etc" / "stations" / "OK09.toml")
      << "[station]\nid = \"OK09\"\ndialect = \"okuma\"\ndds = \"cyclonedds\"\n";
  EXPECT_EQ(LoadStation("OK09").dds, "cyclonedds");
  std::ofstream(root_ / "etc" / "stations" / "OK08.toml")
      << "[station]\nid = \"OK08\"\ndialect = \"okuma\"\n";
  EXPECT_EQ(LoadStation("OK08").dds, "");  // follows CELL_DDS
  std::ofstream(root_ / "etc" / "stations" / "OK07.toml")
      << "[station]\nid = \"OK07\"\ndialect = \"okuma\"\ndds = \"rti\"\n";
  std::string err = ErrorOf([] { LoadStation("OK07"); });
  EXPECT_NE(err.find("OK07.toml:4: [station] dds = 'rti': must be one of fastdds, cyclonedds"),
            std::string::npos)
      << err;
}

TEST_F(ConfigTest, DdsProfileNameResolvesPerStack) {
  EXPECT_EQ(DdsProfile("fastdds"), fs::path());  // unset: the built-in loopback profile
  fs::create_directories(root_ / "etc" / "dds");
  std::ofstream(root_ / "etc" / "dds" / "lan.fastdds.xml") << "<dds/>";
  std::ofstream(root_ / "etc" / "dds" / "lan.cyclonedds.xml") << "<CycloneDDS/>";
  setenv("CELL_DDS_PROFILE", "lan", 1);
  EXPECT_EQ(DdsProfile("fastdds"), root_ / "etc" / "dds" / "lan.fastdds.xml");
  EXPECT_EQ(DdsProfile("cyclonedds"), root_ / "etc" / "dds" / "lan.cyclonedds.xml");
  setenv("CELL_DDS_PROFILE", "wan", 1);
  EXPECT_EQ(ErrorOf([] { DdsProfile("cyclonedds"); }),
            "CELL_DDS_PROFILE=wan: no cyclonedds profile " +
                (root_ / "etc" / "dds" / "wan.cyclonedds.xml").string());
  setenv("CELL_DDS_PROFILE", "lan.xml", 1);  // neither a name nor a path
  EXPECT_NE(ErrorOf([] { DdsProfile("fastdds"); }).find("a profile name is 1-64 letters"), std::string::npos);
  const std::string file = (root_ / "etc" / "dds" / "lan.fastdds.xml").string();
  setenv("CELL_DDS_PROFILE", file.c_str(), 1);  // a path: used as is
  EXPECT_EQ(DdsProfile("fastdds"), fs::path(file));
}

TEST_F(ConfigTest, DdsShippedLanProfilesExistForEveryStack) {
  setenv("CELL_CONFIG_DIR", (SourceTreeDir() / "deploy").c_str(), 1);
  for (const char* name : {"lan", "lan-multicast"}) {
    setenv("CELL_DDS_PROFILE", name, 1);
    for (auto v : kDdsVendors) EXPECT_TRUE(fs::exists(DdsProfile(v))) << name << " " << v;
  }
}

TEST_F(ConfigTest, DdsExpandsVariablesAndDefaults) {
  setenv("CELL_TEST_A", "10.0.0.1", 1);
  EXPECT_EQ(ExpandEnvironment("<a>${CELL_TEST_A}</a>", "p"), "<a>10.0.0.1</a>");
  EXPECT_EQ(ExpandEnvironment("${CELL_TEST_B:-${CELL_TEST_A}}", "p"), "10.0.0.1");  // nested default
  EXPECT_EQ(ExpandEnvironment("${CELL_TEST_B:-}x", "p"), "x");
  setenv("CELL_TEST_B", "10.0.0.9", 1);
  EXPECT_EQ(ExpandEnvironment("${CELL_TEST_B:-${CELL_TEST_A}}", "p"), "10.0.0.9");
  EXPECT_EQ(ExpandEnvironment("cost $5, $$HOME, {x}", "p"), "cost $5, $HOME, {x}");
}

TEST_F(ConfigTest, DdsUnsetOrMalformedReferencesAreErrors) {
  EXPECT_EQ(ErrorOf([] { ExpandEnvironment("<a>${CELL_TEST_A}</a>", "lan.xml"); }),
            "lan.xml: ${CELL_TEST_A} is used but CELL_TEST_A is not set in the environment");
  EXPECT_NE(ErrorOf([] { ExpandEnvironment("${CELL_TEST_A", "p"); }).find("not closed"), std::string::npos);
  EXPECT_NE(ErrorOf([] { ExpandEnvironment("${CELL_TEST_A:-x", "p"); }).find("not closed"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { ExpandEnvironment("${A-B}", "p"); }).find("not a variable name"), std::string::npos);
  EXPECT_NE(ErrorOf([] { ExpandEnvironment("${CELL_TEST_A:=x}", "p"); }).find("only ${NAME:-default}"),
            std::string::npos);
}

TEST_F(ConfigTest, DdsLoadsAndExpandsAProfileFile) {
  std::ofstream(root_ / "p.xml") << "<Peer address=\"${CELL_TEST_A}\"/>";
  setenv("CELL_TEST_A", "192.168.7.2", 1);
  EXPECT_EQ(LoadDdsProfile(root_ / "p.xml"), "<Peer address=\"192.168.7.2\"/>");
  EXPECT_NE(ErrorOf([&] { LoadDdsProfile(root_ / "none.xml"); }).find("cannot read DDS profile"),
            std::string::npos);
}

}  // namespace

namespace {

// [[io.aux]]: a device M codes drive through one output, optionally interlocked against spindle rotation.
TEST_F(ConfigTest, IoAuxEntries) {
  Write("OK05", R"([station]
id = "OK05"
dialect = "okuma"
[[io.aux]]
name = "chuck"
output = "CHUCK"
m_on = 83
m_off = 84
interlock = true
interlock_on = 184
interlock_off = 185
note = "ln 2015"
[[io.aux]]
name = "air blow"
output = "O10.2"
m_on = 51
)");
  auto s = LoadStation("OK05");
  ASSERT_EQ(s.aux.size(), 2u);
  EXPECT_EQ(s.aux[0], (cell::config::AuxOutput{"chuck", "CHUCK", 83, 84, true, 184, 185, "ln 2015"}));
  EXPECT_EQ(s.aux[1], (cell::config::AuxOutput{"air blow", "O10.2", 51, -1, false, -1, -1, ""}));
}

TEST_F(ConfigTest, IoAuxRefusals) {
  const std::string head = "[station]\nid = \"OK05\"\ndialect = \"okuma\"\n[[io.aux]]\nname = \"chuck\"\n";
  auto error = [&](const std::string& rest) {
    Write("OK05", head + rest);
    return LoadError("OK05");
  };
  EXPECT_NE(error("output = \"CHUCK\"\nm_on = 83\nm_of = 84\n").find("unknown key 'm_of'"),
            std::string::npos);
  EXPECT_NE(error("output = \"chuck\"\nm_on = 83\n").find("output = 'chuck'"), std::string::npos);
  EXPECT_NE(error("output = \"CHUCK\"\n").find("give m_on, m_off or both"), std::string::npos);
  EXPECT_NE(error("output = \"CHUCK\"\nm_on = 1000\n").find("m_on must be an M code"), std::string::npos);
  EXPECT_NE(error("output = \"CHUCK\"\nm_on = 83\ninterlock_on = 184\n").find("need interlock = true"),
            std::string::npos);
  EXPECT_NE(error("output = \"CHUCK\"\nm_on = 83\n[[io.aux]]\nname = \"x\"\noutput = \"X\"\nm_on = 83\n")
                .find("M83 is already used by chuck"),
            std::string::npos);
}

TEST_F(ConfigTest, SerialTable) {
  const std::string head = "[station]\nid = \"EM05\"\ndialect = \"emco\"\n";
  Write("EM05", head);
  EXPECT_FALSE(LoadStation("EM05").serial);
  Write("EM05", head + "[serial]\ndevice = \"/dev/ttyS1\"\nbaud = 4800\nparity = \"odd\"\nend = \"%\"\n");
  auto s = LoadStation("EM05").serial;
  ASSERT_TRUE(s);
  cell::config::SerialTable want;
  want.device = "/dev/ttyS1";
  want.baud = 4800;
  want.parity = "odd";
  want.end = "%";
  EXPECT_EQ(*s, want);
  auto error = [&](const std::string& rest) {
    Write("EM05", head + "[serial]\n" + rest);
    return LoadError("EM05");
  };
  EXPECT_NE(error("device = \"/dev/ttyS1\"\nbaudrate = 4800\n")
                .find("EM05.toml:6: [serial]: unknown key 'baudrate'"),
            std::string::npos);
  EXPECT_NE(error("device = \"/dev/ttyS1\"\nbaud = \"fast\"\n").find("[serial] baud must be an integer"),
            std::string::npos);
  EXPECT_NE(error("baud = 2400\n").find("device must be the line's absolute path"), std::string::npos);
}

// OK01 ships the chuck and the tailstock of the OSP-E100L manual (ln 1969-1978, 2008-2023).
TEST(ShippedStations, Ok01ChuckAndTailstock) {
  const char* src = getenv("CELL_SOURCE_DIR");
  ASSERT_NE(src, nullptr) << "run under ctest (CELL_SOURCE_DIR)";
  setenv("CELL_CONFIG_DIR", (fs::path(src) / "deploy").c_str(), 1);
  auto s = LoadStation("OK01");
  ASSERT_EQ(s.aux.size(), 2u);
  EXPECT_EQ(s.aux[0], (cell::config::AuxOutput{"chuck", "CHUCK", 83, 84, true, 184, 185,
                                               "OSP-E100L manual ln 2015-2023"}));
  EXPECT_EQ(s.aux[1], (cell::config::AuxOutput{"tailstock", "TAILSTOCK", 56, 55, true, 166, 167,
                                               "OSP-E100L manual ln 2008-2013"}));
}

}  // namespace

// Discovery sized to the cell (DESIGN §3, issue 43): two participants per station plus 16, at least 32, in
// steps of 8, at most the 120 a domain's port range holds less 8 for clients; CELL_DDS_PARTICIPANTS (up to
// 120) overrides, checked.
TEST_F(ConfigTest, DdsParticipantsFollowTheConfiguredStations) {
  using cell::config::DdsParticipants;
  auto Id = [](int i) { return std::string(i < 10 ? "KT0" : "KT") + std::to_string(i); };
  EXPECT_EQ(DdsParticipants(), 32);  // no station: the floor
  for (int i = 1; i <= 8; ++i) Write(Id(i), "");
  EXPECT_EQ(DdsParticipants(), 32);  // 2 * 8 + 16
  for (int i = 9; i <= 32; ++i) Write(Id(i), "");
  EXPECT_EQ(DdsParticipants(), 80);  // 2 * 32 + 16: the 32-station cell's 68 processes and its tools
  for (int i = 33; i <= 45; ++i) Write(Id(i), "");
  EXPECT_EQ(DdsParticipants(), 112);  // 2 * 45 + 16 = 106, rounded up to 112
  for (int i = 46; i <= 60; ++i) Write(Id(i), "");
  // Capped below the (250 - 10) / 2 = 120 slots of a domain's ports, leaving kClientSlots for the clients
  // of the host services (docs/operations.md §9.4).
  EXPECT_EQ(DdsParticipants(), 112);
  setenv("CELL_DDS_PARTICIPANTS", "48", 1);
  EXPECT_EQ(DdsParticipants(), 48);
  for (const char* bad : {"7", "121", "4x", "", " 40"}) {
    setenv("CELL_DDS_PARTICIPANTS", bad, 1);
    if (std::string(bad).empty()) {
      EXPECT_EQ(DdsParticipants(), 112) << "empty is unset";
      continue;
    }
    try {
      DdsParticipants();
      ADD_FAILURE() << "accepted CELL_DDS_PARTICIPANTS=" << bad;
    } catch (const cell::Error& e) {
      EXPECT_NE(std::string(e.what()).find("CELL_DDS_PARTICIPANTS"), std::string::npos) << e.what();
    }
  }
}

// The shipped LAN profiles size their peer ranges with ${CELL_DDS_PARTICIPANTS}: unset, it expands to what
// the loopback profile would use.
TEST_F(ConfigTest, ProfilesExpandTheParticipantRange) {
  EXPECT_EQ(cell::config::ExpandEnvironment("<r>${CELL_DDS_PARTICIPANTS}</r>", "p"), "<r>32</r>");
  setenv("CELL_DDS_PARTICIPANTS", "64", 1);
  EXPECT_EQ(cell::config::ExpandEnvironment("<r>${CELL_DDS_PARTICIPANTS}</r>", "p"), "<r>64</r>");
}
