// Station machine configuration: the shipped station files load; bad or missing values name file, key
// and allowed range; tables owned by others are ignored.
#include <gtest/gtest.h>

#include <string>

#include "cell/error/error.h"
#include "cell/machine/machine_config.h"

namespace cell::machine {
namespace {

const std::string kStations = std::string(CELL_SOURCE_DIR) + "/deploy/stations/";

TEST(Config, ShippedStationsLoad) {
  for (const char* id : {"KT01", "KT02", "KT03", "KT04"}) {
    MachineConfig c = LoadMachineConfig(kStations + id + ".toml");
    EXPECT_EQ(c.station_id, id);
    EXPECT_EQ(c.dialect, "ktapl");
    EXPECT_TRUE(c.axes[kX].present && c.axes[kY].present && c.axes[kZ].present);
    EXPECT_EQ(c.axes[kB].type, AxisType::kIndex);
    EXPECT_GT(c.axes[kB].index_increment, 0);
    EXPECT_DOUBLE_EQ(c.in_position, 0.025);
    EXPECT_DOUBLE_EQ(c.servo_period_s, 0.001);
    EXPECT_FALSE(c.tools.entries().empty());  // from the station's [[tools]]
  }
  MachineConfig ok = LoadMachineConfig(kStations + "OK01.toml");
  EXPECT_EQ(ok.kind, "lathe");
  EXPECT_TRUE(ok.axes[kX].diameter);
  EXPECT_FALSE(ok.axes[kY].present);
  EXPECT_EQ(ok.axes[kC].type, AxisType::kRotary);  // the C axis of the M-tool spindle (Okuma ln 745-939)
  EXPECT_GE(ok.axes[kX].max * 2, 500.0);           // travel admits E-102's X500 Z800 (ln 9148-9163)
  EXPECT_GE(ok.axes[kZ].max, 800.0);
  MachineConfig em = LoadMachineConfig(kStations + "EM01.toml");  // its [params] belong to the interpreter
  EXPECT_EQ(em.dialect, "emco");
  EXPECT_EQ(em.kind, "lathe");
  EXPECT_TRUE(em.axes[kX].diameter);
  EXPECT_EQ(em.magazine_sockets, 8);
}

const char* kMinimal = R"(
[station]
id = "T1"
dialect = "ktapl"
owner_specific = "ignored"
[scheduler]
anything = [1, 2, 3]
[machine]
kind = "hmc"
[axes.x]
min = 0
max = 500
max_velocity = 10000
rapid = 20000
max_acceleration = 2000
max_jerk = 50000
following_error_limit = 0.5
drive = { motor_inertia = 0.002, load_inertia = 0.001, viscous_friction = 0.002, max_torque = 20, units_per_rev = 10 }
[axes.z]
min = 0
max = 500
max_velocity = 10000
rapid = 20000
max_acceleration = 2000
max_jerk = 50000
following_error_limit = 0.5
drive = { motor_inertia = 0.002, load_inertia = 0.001, viscous_friction = 0.002, max_torque = 20, units_per_rev = 10 }
[spindle]
max_rpm = 4000
acceleration = 2000
[magazine]
sockets = 30
[times]
tool_change = 5
pallet_change = 20
)";

std::string Replace(std::string s, const std::string& from, const std::string& to) {
  auto p = s.find(from);
  EXPECT_NE(p, std::string::npos) << from;
  return s.replace(p, from.size(), to);
}

std::string ErrorOf(const std::string& text) {
  try {
    ParseMachineConfig(text, "stations/T1.toml");
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), Errc::kInvalidArgument);
    return e.what();
  }
  return "";
}

TEST(Config, MinimalParsesAndIgnoresForeignTables) {
  MachineConfig c = ParseMachineConfig(kMinimal, "stations/T1.toml");
  EXPECT_EQ(c.station_id, "T1");
  EXPECT_DOUBLE_EQ(c.axes[kX].max_acceleration, 2000);
  EXPECT_DOUBLE_EQ(c.path_tolerance, 0.02);  // default
  EXPECT_GT(c.axes[kX].drive.bandwidth_hz, 0);
}

TEST(Config, CoAxesUVWAreLinearAxesLikeXYZ) {
  // A KT-APL U-head (manual ln 7126-7150): [axes.u] as any linear axis; V and W the same.
  const std::string u =
      "[axes.u]\nmin = -5\nmax = 60\nmax_velocity = 250\nrapid = 250\n"
      "max_acceleration = 500\nmax_jerk = 20000\nfollowing_error_limit = 0.5\n"
      "drive = { motor_inertia = 0.001, load_inertia = 0.0005, viscous_friction = 0.001, "
      "max_torque = 10, units_per_rev = 5 }\n[spindle]";
  MachineConfig c = ParseMachineConfig(Replace(kMinimal, "[spindle]", u), "stations/T1.toml");
  EXPECT_TRUE(c.axes[kU].present);
  EXPECT_EQ(c.axes[kU].type, AxisType::kLinear);
  EXPECT_DOUBLE_EQ(c.axes[kU].max, 60);
  EXPECT_FALSE(c.axes[kV].present || c.axes[kW].present);
  std::string e =
      ErrorOf(Replace(kMinimal, "[spindle]", Replace(u, "[axes.u]\n", "[axes.w]\ntype = \"rotary\"\n")));
  EXPECT_NE(e.find("axes.w.type: axes x, y, z, u, v, w are linear"), std::string::npos) << e;
  e = ErrorOf(Replace(kMinimal, "[spindle]", Replace(u, "[axes.u]", "[axes.q]")));
  EXPECT_NE(e.find("axes.q: unknown axis; allowed x, y, z, a, b, c, u, v, w"), std::string::npos) << e;
}

TEST(Config, BadValueNamesFileKeyAndRange) {
  std::string e = ErrorOf(Replace(kMinimal, "max_jerk = 50000\nfollowing", "max_jerk = -3\nfollowing"));
  EXPECT_NE(e.find("stations/T1.toml"), std::string::npos) << e;
  EXPECT_NE(e.find("axes.x.max_jerk"), std::string::npos) << e;
  EXPECT_NE(e.find("(0, 1e+09]"), std::string::npos) << e;
  EXPECT_NE(e.find("-3"), std::string::npos) << e;

  e = ErrorOf(
      Replace(kMinimal, "[machine]\nkind = \"hmc\"", "[machine]\nkind = \"hmc\"\nservo_period_ms = 50"));
  EXPECT_NE(e.find("machine.servo_period_ms"), std::string::npos) << e;
  EXPECT_NE(e.find("[0.1, 10]"), std::string::npos) << e;

  e = ErrorOf(Replace(kMinimal, "sockets = 30", "sockets = \"many\""));
  EXPECT_NE(e.find("magazine.sockets"), std::string::npos) << e;

  e = ErrorOf(
      Replace(kMinimal, "[machine]\nkind = \"hmc\"", "[machine]\nkind = \"hmc\"\npath_tolerence = 0.1"));
  EXPECT_NE(e.find("machine.path_tolerence: unknown key (allowed: "), std::string::npos) << e;
  EXPECT_NE(e.find("path_tolerance"), std::string::npos) << e;

  e = ErrorOf(Replace(kMinimal, "max = 500\nmax_velocity", "max = -1\nmax_velocity"));
  EXPECT_NE(e.find("axes.x.max"), std::string::npos) << e;

  e = ErrorOf(Replace(kMinimal, "max_torque = 20, units_per_rev = 10 }\n[axes.z]",
                      "max_torque = 0.5, units_per_rev = 10 }\n[axes.z]"));
  EXPECT_NE(e.find("axes.x.drive.max_torque"), std::string::npos) << e;
}

// The machine's tool model for G38: the tools in [magazine] broken sockets are broken.
TEST(Config, BrokenSocketsOfTheMagazine) {
  MachineConfig c = ParseMachineConfig(Replace(kMinimal, "sockets = 30", "sockets = 30\nbroken = [4, 12]"),
                                       "stations/T1.toml");
  EXPECT_EQ(c.broken_sockets, (std::vector<int>{4, 12}));
  std::string e = ErrorOf(Replace(kMinimal, "sockets = 30", "sockets = 30\nbroken = [31]"));
  EXPECT_NE(e.find("magazine.broken"), std::string::npos) << e;
  EXPECT_NE(e.find("[1, 30]"), std::string::npos) << e;
  e = ErrorOf(Replace(kMinimal, "sockets = 30", "sockets = 30\nbroken = 4"));
  EXPECT_NE(e.find("magazine.broken"), std::string::npos) << e;
}

TEST(Config, MissingValuesAreNamed) {
  std::string e = ErrorOf(Replace(kMinimal, "following_error_limit = 0.5\ndrive", "drive"));
  EXPECT_NE(e.find("axes.x.following_error_limit: missing"), std::string::npos) << e;
  e = ErrorOf(Replace(kMinimal, "[times]\ntool_change = 5\n", "[times]\n"));
  EXPECT_NE(e.find("times.tool_change: missing"), std::string::npos) << e;
  e = ErrorOf(Replace(kMinimal, "[machine]\nkind = \"hmc\"", "[machinex]\nkind = \"hmc\""));
  EXPECT_NE(e.find("missing table [machine]"), std::string::npos) << e;
  try {
    LoadMachineConfig("/nonexistent/ZZ99.toml");
    FAIL();
  } catch (const Error& err) {
    EXPECT_EQ(err.code(), Errc::kNotFound);
    EXPECT_NE(std::string(err.what()).find("ZZ99.toml"), std::string::npos);
  }
}

TEST(Config, LatheNeedsDiameterX) {
  std::string lathe = Replace(kMinimal, "kind = \"hmc\"", "kind = \"lathe\"");
  std::string e = ErrorOf(lathe);
  EXPECT_NE(e.find("axes.x.diameter"), std::string::npos) << e;
  MachineConfig c = ParseMachineConfig(Replace(lathe, "[axes.x]\n", "[axes.x]\ndiameter = true\n"), "x");
  EXPECT_TRUE(c.axes[kX].diameter);
}

}  // namespace
}  // namespace cell::machine
