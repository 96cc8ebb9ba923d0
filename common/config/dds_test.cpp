// Which DDS stack and profile a process uses (cell/config/dds.h): precedence, names, files, expansion.
#include "cell/config/dds.h"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "cell/config/config.h"
#include "cell/error/error.h"

namespace fs = std::filesystem;
using namespace cell::config;

namespace {

class DdsConfig : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/cell-dds-test-XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    root_ = tmpl;
    fs::create_directories(root_ / "dds");
    fs::create_directories(root_ / "stations");
    for (const char* v : {"CELL_CONFIG_DIR", "CELL_DDS", "CELL_DDS_PROFILE", "CELL_TEST_A", "CELL_TEST_B"}) {
      const char* old = getenv(v);
      saved_.emplace_back(v, old ? std::optional<std::string>(old) : std::nullopt);
      unsetenv(v);
    }
    setenv("CELL_CONFIG_DIR", root_.c_str(), 1);
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
  template <class F>
  std::string ErrorOf(F f) {
    try {
      f();
    } catch (const cell::Error& e) {
      return e.what();
    }
    return "";
  }
  fs::path root_;
  std::vector<std::pair<std::string, std::optional<std::string>>> saved_;
};

TEST_F(DdsConfig, StationFileWinsOverCellDdsWhichWinsOverTheDefault) {
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

TEST_F(DdsConfig, UnknownStacksAreErrorsNamingTheSetting) {
  setenv("CELL_DDS", "opendds", 1);
  EXPECT_EQ(ErrorOf([] { DdsVendor(); }), "CELL_DDS=opendds: expected one of fastdds, cyclonedds");
  // Even when a station file decides: a typo in the environment must not pass silently.
  EXPECT_NE(ErrorOf([] { DdsVendor("fastdds"); }), "");
  unsetenv("CELL_DDS");
  EXPECT_EQ(ErrorOf([] { DdsVendor("cyclone"); }),
            "station dds = 'cyclone': expected one of fastdds, cyclonedds");
}

TEST_F(DdsConfig, StationFileCarriesItsStack) {
  std::ofstream(root_ / "stations" / "OK09.toml")
      << "[station]\nid = \"OK09\"\ndialect = \"okuma\"\ndds = \"cyclonedds\"\n";
  EXPECT_EQ(LoadStation("OK09").dds, "cyclonedds");
  std::ofstream(root_ / "stations" / "OK08.toml") << "[station]\nid = \"OK08\"\ndialect = \"okuma\"\n";
  EXPECT_EQ(LoadStation("OK08").dds, "");  // follows CELL_DDS
  std::ofstream(root_ / "stations" / "OK07.toml")
      << "[station]\nid = \"OK07\"\ndialect = \"okuma\"\ndds = \"rti\"\n";
  std::string err = ErrorOf([] { LoadStation("OK07"); });
  EXPECT_NE(err.find("OK07.toml:4: [station] dds = 'rti': must be one of fastdds, cyclonedds"),
            std::string::npos)
      << err;
}

TEST_F(DdsConfig, ProfileNameResolvesPerStack) {
  EXPECT_EQ(DdsProfile("fastdds"), fs::path());  // unset: the built-in loopback profile
  std::ofstream(root_ / "dds" / "lan.fastdds.xml") << "<dds/>";
  std::ofstream(root_ / "dds" / "lan.cyclonedds.xml") << "<CycloneDDS/>";
  setenv("CELL_DDS_PROFILE", "lan", 1);
  EXPECT_EQ(DdsProfile("fastdds"), root_ / "dds" / "lan.fastdds.xml");
  EXPECT_EQ(DdsProfile("cyclonedds"), root_ / "dds" / "lan.cyclonedds.xml");
  setenv("CELL_DDS_PROFILE", "wan", 1);
  EXPECT_EQ(ErrorOf([] { DdsProfile("cyclonedds"); }),
            "CELL_DDS_PROFILE=wan: no cyclonedds profile " + (root_ / "dds" / "wan.cyclonedds.xml").string());
  setenv("CELL_DDS_PROFILE", "lan.xml", 1);  // neither a name nor a path
  EXPECT_NE(ErrorOf([] { DdsProfile("fastdds"); }).find("a profile name is 1-64 letters"), std::string::npos);
  const std::string file = (root_ / "dds" / "lan.fastdds.xml").string();
  setenv("CELL_DDS_PROFILE", file.c_str(), 1);  // a path: used as is
  EXPECT_EQ(DdsProfile("fastdds"), fs::path(file));
}

TEST_F(DdsConfig, ShippedLanProfilesExistForEveryStack) {
  setenv("CELL_CONFIG_DIR", (SourceTreeDir() / "deploy").c_str(), 1);
  for (const char* name : {"lan", "lan-multicast"}) {
    setenv("CELL_DDS_PROFILE", name, 1);
    for (auto v : kDdsVendors) EXPECT_TRUE(fs::exists(DdsProfile(v))) << name << " " << v;
  }
}

TEST_F(DdsConfig, ExpandsVariablesAndDefaults) {
  setenv("CELL_TEST_A", "10.0.0.1", 1);
  EXPECT_EQ(ExpandEnvironment("<a>${CELL_TEST_A}</a>", "p"), "<a>10.0.0.1</a>");
  EXPECT_EQ(ExpandEnvironment("${CELL_TEST_B:-${CELL_TEST_A}}", "p"), "10.0.0.1");  // nested default
  EXPECT_EQ(ExpandEnvironment("${CELL_TEST_B:-}x", "p"), "x");
  setenv("CELL_TEST_B", "10.0.0.9", 1);
  EXPECT_EQ(ExpandEnvironment("${CELL_TEST_B:-${CELL_TEST_A}}", "p"), "10.0.0.9");
  EXPECT_EQ(ExpandEnvironment("cost $5, $$HOME, {x}", "p"), "cost $5, $HOME, {x}");
}

TEST_F(DdsConfig, UnsetOrMalformedReferencesAreErrors) {
  EXPECT_EQ(ErrorOf([] { ExpandEnvironment("<a>${CELL_TEST_A}</a>", "lan.xml"); }),
            "lan.xml: ${CELL_TEST_A} is used but CELL_TEST_A is not set in the environment");
  EXPECT_NE(ErrorOf([] { ExpandEnvironment("${CELL_TEST_A", "p"); }).find("not closed"), std::string::npos);
  EXPECT_NE(ErrorOf([] { ExpandEnvironment("${CELL_TEST_A:-x", "p"); }).find("not closed"),
            std::string::npos);
  EXPECT_NE(ErrorOf([] { ExpandEnvironment("${A-B}", "p"); }).find("not a variable name"), std::string::npos);
  EXPECT_NE(ErrorOf([] { ExpandEnvironment("${CELL_TEST_A:=x}", "p"); }).find("only ${NAME:-default}"),
            std::string::npos);
}

TEST_F(DdsConfig, LoadsAndExpandsAProfileFile) {
  std::ofstream(root_ / "p.xml") << "<Peer address=\"${CELL_TEST_A}\"/>";
  setenv("CELL_TEST_A", "192.168.7.2", 1);
  EXPECT_EQ(LoadDdsProfile(root_ / "p.xml"), "<Peer address=\"192.168.7.2\"/>");
  EXPECT_NE(ErrorOf([&] { LoadDdsProfile(root_ / "none.xml"); }).find("cannot read DDS profile"),
            std::string::npos);
}

}  // namespace
