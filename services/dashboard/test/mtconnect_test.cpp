// MTConnect documents against the 2.4 schemas (xmllint --noout --nonet --schema, the `_1.0.xsd` variants
// that libxml2 reads): probe, current, sample, assets and errors, and the devices' structure.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "cell/dashboard/cell_view.h"
#include "test_stations.h"

namespace cell::dashboard {

namespace testing {

std::string SchemaDir() {
  if (const char* d = std::getenv("CELL_MTCONNECT_SCHEMAS"); d && *d) return d;
  // The repository carries them (tests/schemas/README.md), so a clone validates with nothing beside it.
  const std::string dir = cell::testing::SourceDir() + "/tests/schemas/mtconnect";
  return std::filesystem::exists(dir + "/MTConnectStreams_2.4_1.0.xsd") ? dir : "";
}

std::string Validate(const std::string& xml, const std::string& schema) {
  const std::string dir = SchemaDir();
  if (dir.empty()) return "MTConnect schemas not found (tests/schemas/mtconnect in CELL_SOURCE_DIR)";
  static int n = 0;
  std::string file = "/tmp/cell-mtc-" + std::to_string(getpid()) + "-" + std::to_string(n++) + ".xml";
  std::ofstream(file) << xml;
  auto r = cell::testing::RunCommand({"xmllint", "--noout", "--nonet", "--schema", dir + "/" + schema, file});
  std::filesystem::remove(file);
  return r.code == 0 ? "" : r.err + r.out;
}

}  // namespace testing

namespace {

using testing::Status;
using testing::TwoStations;
using testing::Validate;

constexpr const char* kDevices = "MTConnectDevices_2.4_1.0.xsd";
constexpr const char* kStreams = "MTConnectStreams_2.4_1.0.xsd";
constexpr const char* kAssets = "MTConnectAssets_2.4_1.0.xsd";
constexpr const char* kError = "MTConnectError_2.4_1.0.xsd";

// A cell with something in every data item: status, alarm, tools, axes.
void Busy(CellView& v) {
  v.Online("KT01", true);
  v.Online("OK01", true);
  StatusIn s = Status("KT01", "ACTIVE", "PUMP<341>&", 42, 3);
  s.tool = "1002";
  s.part_count = 7;
  v.Status(s);
  StatusIn f = Status("OK01", "FEED_HOLD", "O1234", 5, 0);
  f.condition = "FAULT";
  f.alarm_code = "2041";
  f.alarm_text = "axis X overtravel";
  v.Status(f);
  v.Tools("KT01", testing::Tools({{"1001", 1, 152.4, 25.4, 240, false, false},
                                  {"33412.5", 2, 100, 10, 0, true, false}}));
  v.Tools("OK01", testing::Tools({{"1", 1, 0, 0.8, 480, false, true}}));
  AxesIn a;
  a.station = "KT01";
  a.actual[0] = 12.5;
  a.actual[1] = -3;
  a.actual[2] = 100.25;
  a.actual[4] = 90;
  a.spindle_rpm = 2400;
  a.path_feed = 600;
  v.Axes(a);
}

TEST(MTConnect, ProbeHasOneDevicePerStationWithItsOwnAxes) {
  CellView v(TwoStations());
  Busy(v);
  std::string probe = v.Probe(-1);
  EXPECT_EQ(Validate(probe, kDevices), "") << probe;
  EXPECT_NE(probe.find("<Device id=\"KT01\" uuid=\"KT01\" name=\"KT01\">"), std::string::npos);
  EXPECT_NE(probe.find("<Device id=\"OK01\" uuid=\"OK01\" name=\"OK01\">"), std::string::npos);
  // KT01: Linear X Y Z, Rotary B (its index table) and the spindle as Rotary C.
  for (const char* c : {"<Linear id=\"KT01_X\" name=\"X\">", "<Linear id=\"KT01_Y\" name=\"Y\">",
                        "<Linear id=\"KT01_Z\" name=\"Z\">", "<Rotary id=\"KT01_B\" name=\"B\">",
                        "<Rotary id=\"KT01_C\" name=\"C\">", "<Path id=\"KT01_path\""})
    EXPECT_NE(probe.find(c), std::string::npos) << c;
  // The lathe has X and Z and its spindle C, no Y and no B.
  EXPECT_NE(probe.find("<Linear id=\"OK01_X\" name=\"X\">"), std::string::npos);
  EXPECT_EQ(probe.find("OK01_Y"), std::string::npos);
  EXPECT_EQ(probe.find("OK01_B"), std::string::npos);
  EXPECT_NE(probe.find("<Rotary id=\"OK01_C\" name=\"C\">"), std::string::npos);
  for (const char* t : {"EXECUTION", "CONTROLLER_MODE", "PROGRAM", "LINE_NUMBER", "PART_COUNT", "TOOL_NUMBER",
                        "\"SYSTEM\"", "ROTARY_VELOCITY", "AVAILABILITY", "ASSET_CHANGED"})
    EXPECT_NE(probe.find(t), std::string::npos) << t;
  std::string one = v.Probe(1);
  EXPECT_EQ(Validate(one, kDevices), "");
  EXPECT_EQ(one.find("KT01"), std::string::npos);
}

TEST(MTConnect, CurrentAndSampleValidateAndCarryTheState) {
  CellView v(TwoStations());
  std::string fresh = v.Current(-1);
  EXPECT_EQ(Validate(fresh, kStreams), "") << fresh;
  EXPECT_NE(fresh.find(">UNAVAILABLE</Execution>"), std::string::npos);
  Busy(v);
  std::string cur = v.Current(-1);
  EXPECT_EQ(Validate(cur, kStreams), "") << cur;
  EXPECT_NE(cur.find(">ACTIVE</Execution>"), std::string::npos);
  EXPECT_NE(cur.find(">PUMP&lt;341&gt;&amp;</Program>"), std::string::npos);
  EXPECT_NE(cur.find(">42</LineNumber>"), std::string::npos);
  EXPECT_NE(cur.find(">FEED_HOLD</Execution>"), std::string::npos);
  EXPECT_NE(cur.find("nativeCode=\"2041\" conditionId=\"2041\">axis X overtravel</Fault>"),
            std::string::npos);
  EXPECT_NE(cur.find(">12.5</Position>"), std::string::npos);
  EXPECT_NE(cur.find(">90</Angle>"), std::string::npos);
  EXPECT_NE(cur.find(">2400</RotaryVelocity>"), std::string::npos);
  EXPECT_NE(cur.find(">10</PathFeedrate>"), std::string::npos);  // 600 mm/min = 10 mm/s
  auto s = v.Sample(std::nullopt, 1000, -1);
  EXPECT_EQ(s.status, 200);
  EXPECT_EQ(Validate(s.body, kStreams), "") << s.body;
  auto one = v.Sample(1, 5, 0);
  EXPECT_EQ(Validate(one.body, kStreams), "") << one.body;
  EXPECT_EQ(one.body.find("OK01"), std::string::npos);
}

// A turn-mill (OK01 as shipped: X, Z, C and a live tool): the live tool is a second spindle, Rotary LT with
// its RotaryVelocity (named SB, Okuma's address); the work spindle's RotaryMode is CONTOUR while it is joined
// as C (M110), SPINDLE otherwise. Both documents validate against the 2.4 schemas.
TEST(MTConnect, ALiveToolIsASecondSpindleAndAJoinedCIsAContouringAxis) {
  StationDef ok{"OK01",
                "okuma",
                "Okuma turn-mill",
                "lathe",
                {{"X", 0, false, true}, {"Z", 2, false, false}, {"C", 5, true, false}}};
  ok.live_tool = true;
  CellView v({ok});
  v.Online("OK01", true);
  v.Status(Status("OK01", "ACTIVE", "O1", 3, 0));
  std::string probe = v.Probe(-1);
  EXPECT_EQ(Validate(probe, kDevices), "") << probe;
  EXPECT_NE(probe.find("<Rotary id=\"OK01_C\" name=\"C\">"), std::string::npos);
  EXPECT_NE(probe.find("<Rotary id=\"OK01_LT\" name=\"LT\">"), std::string::npos) << probe;
  EXPECT_NE(probe.find("id=\"OK01_LT_speed\""), std::string::npos);
  // The value of a data item in a Streams document.
  auto value = [](const std::string& doc, const std::string& id) {
    const size_t at = doc.find("dataItemId=\"" + id + "\"");
    if (at == std::string::npos) return std::string("(absent)");
    const size_t gt = doc.find('>', at), lt = doc.find('<', gt);
    return doc.substr(gt + 1, lt - gt - 1);
  };
  AxesIn a;
  a.station = "OK01";
  a.live_tool_rpm = -450;  // M14 SB=450
  a.c_joined = true;
  a.time_ns = 1'000'000'000;
  v.Axes(a);
  std::string cur = v.Current(-1);
  EXPECT_EQ(Validate(cur, kStreams), "") << cur;
  EXPECT_EQ(value(cur, "OK01_LT_speed"), "450");
  EXPECT_EQ(value(cur, "OK01_LT_mode"), "SPINDLE");
  EXPECT_EQ(value(cur, "OK01_C_mode"), "CONTOUR");
  EXPECT_EQ(value(cur, "OK01_C_speed"), "0");
  a.c_joined = false;  // M109
  a.live_tool_rpm = 0;
  a.spindle_rpm = 800;
  a.time_ns = 2'000'000'000;
  v.Axes(a);
  cur = v.Current(-1);
  EXPECT_EQ(value(cur, "OK01_C_mode"), "SPINDLE");
  EXPECT_EQ(value(cur, "OK01_C_speed"), "800");
  EXPECT_EQ(value(cur, "OK01_LT_speed"), "0");
  // A station without a live tool has no such component.
  EXPECT_EQ(CellView(TwoStations()).Probe(-1).find("_LT"), std::string::npos);
}

TEST(MTConnect, AssetsAreTheToolTablesAsCuttingTools) {
  CellView v(TwoStations());
  EXPECT_EQ(Validate(v.AssetsDoc(""), kAssets), "");
  Busy(v);
  std::string a = v.AssetsDoc("");
  EXPECT_EQ(Validate(a, kAssets), "") << a;
  EXPECT_NE(a.find("assetId=\"KT01.T1001\""), std::string::npos);
  EXPECT_NE(a.find("assetId=\"KT01.T33412.5\""), std::string::npos);
  EXPECT_NE(a.find("<Status>EXPIRED</Status>"), std::string::npos);  // worn
  EXPECT_NE(a.find("<Status>BROKEN</Status>"), std::string::npos);
  EXPECT_NE(a.find(">152.4</FunctionalLength>"), std::string::npos);
  EXPECT_NE(a.find("<Location type=\"POT\">1</Location>"), std::string::npos);
  std::string one = v.AssetsDoc("OK01.T1");
  EXPECT_EQ(Validate(one, kAssets), "");
  EXPECT_EQ(one.find("KT01"), std::string::npos);
  std::string missing = v.AssetsDoc("KT01.T9");
  EXPECT_EQ(Validate(missing, kError), "") << missing;
  EXPECT_NE(missing.find("ASSET_NOT_FOUND"), std::string::npos);
}

TEST(MTConnect, OutOfRangeAndErrorDocumentsValidate) {
  ViewOptions o;
  o.buffer_size = 64;
  CellView v(TwoStations(), o);
  for (int i = 1; i <= 100; ++i) {
    v.Online("KT01", true);
    v.Status(Status("KT01", "ACTIVE", "P", i));
  }
  const auto next = v.NextSequence();
  for (auto [from, count] : {std::pair<std::int64_t, std::int64_t>{1, 10},
                             {static_cast<std::int64_t>(next) + 1, 10},
                             {static_cast<std::int64_t>(next) - 10, 0},
                             {static_cast<std::int64_t>(next) - 10, 65}}) {
    auto r = v.Sample(from, count, -1);
    EXPECT_EQ(r.status, 404) << from << " " << count;
    EXPECT_NE(r.body.find("errorCode=\"OUT_OF_RANGE\""), std::string::npos);
    EXPECT_EQ(Validate(r.body, kError), "") << r.body;
  }
  auto at_end = v.Sample(static_cast<std::int64_t>(next), 10, -1);  // from = nextSequence: empty, valid
  EXPECT_EQ(at_end.status, 200);
  EXPECT_EQ(Validate(at_end.body, kStreams), "");
  for (const char* code : {"INVALID_REQUEST", "NO_DEVICE", "INVALID_URI", "UNSUPPORTED"})
    EXPECT_EQ(Validate(v.ErrorDoc(code, "why <&>"), kError), "") << code;
}

}  // namespace
}  // namespace cell::dashboard
