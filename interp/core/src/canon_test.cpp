// The JSON line writer's number format: the fast integer path must print exactly what the correctly
// rounded "{:.6f}" (trimmed to at least four decimals) prints, including near rounding ties.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "cell/interp/canon.h"

namespace cell::interp {
namespace {

std::string Expected(double v) {
  if (std::fabs(v) < 5e-7) v = 0;
  std::string s = fmt::format("{:.6f}", v);
  auto dot = s.find('.');
  while (s.size() > dot + 5 && s.back() == '0') s.pop_back();
  return s;
}

std::string Written(double v) {
  Canon c;
  c.line = 7;
  RapidOp& r = c.Set<RapidOp>();
  r.to.pos[kX] = v;
  r.to.used = 1u << kX;
  std::string out;
  AppendJsonLine(out, c);
  const std::string head = "{\"op\":\"rapid\",\"line\":7,\"x\":";
  EXPECT_EQ(out.compare(0, head.size(), head), 0) << out;
  return out.substr(head.size(), out.size() - head.size() - 1);
}

TEST(CanonJson, NumbersMatchCorrectlyRoundedFormatting) {
  for (double v :
       {0.0,       -0.0,        1.0,    -1.0, 0.5,  1e-7,       -4e-7,           6e-7,           -6e-7, 5e-7,
        0.0000005, 1.0000005,   2.5e-6, 0.1,  0.29, 123.456789, -987654.3210005, 999999.9999995, 1e6,   1e12,
        -3e15,     12345.000050}) {
    EXPECT_EQ(Written(v), Expected(v)) << v;
    EXPECT_EQ(Written(v), Expected(v)) << v << " (again: from the writer's cache of recent numbers)";
  }
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int i = 0; i < 200000; ++i) {
    double scale = std::pow(10.0, static_cast<int>(rng() % 14) - 6);
    double v = unit(rng) * scale;
    if (i % 3 == 0) v = std::round(v * 1e6) / 1e6 + 5e-7;  // on or next to a tie
    ASSERT_EQ(Written(v), Expected(v)) << fmt::format("{:.17g}", v);
    if (i % 7 == 0) {
      ASSERT_EQ(Written(v), Expected(v)) << fmt::format("{:.17g} (cached)", v);
    }
  }
}

TEST(CanonJson, AppendReusesTheBufferAndMatchesToJsonLine) {
  Canon c;
  c.line = 3;
  ArcOp& a = c.Set<ArcOp>();
  a.to.pos = {20, 5, 5};
  a.to.used = 7;
  a.feed.rate = 800;
  a.center = {15, 5, 5};
  a.angle = 180;
  std::string out = "prefix\n";
  AppendJsonLine(out, c);
  EXPECT_EQ(out, "prefix\n" + ToJsonLine(c));
  EXPECT_EQ(ToJsonLine(c),
            "{\"op\":\"arc\",\"line\":3,\"x\":20.0000,\"y\":5.0000,\"z\":5.0000,\"f\":800.0000,"
            "\"center\":[15.0000,5.0000,5.0000],\"dir\":\"cw\",\"plane\":\"xy\",\"angle\":180.0000}");
}

// Each op has its own payload at its own index; a slot reused for another op starts from that op's
// defaults (the ring queue reuses slots).
TEST(Canon, SetGivesTheOpsDefaultsAndTargetAndFeedFindTheirFields) {
  Canon c;
  c.line = 9;
  FileOpOp& f = c.Set<FileOpOp>();
  f.what = "CPY";
  f.args = "a long text that does not fit in the small-string buffer";
  EXPECT_EQ(c.op(), Op::kFileOp);
  EXPECT_EQ(c.target(), nullptr);
  EXPECT_EQ(c.feed(), nullptr);
  ProbeOp& p = c.Set<ProbeOp>();
  EXPECT_EQ(c.op(), Op::kProbe);
  EXPECT_EQ(p.result, ProbeOutcome::kNone);
  ASSERT_NE(c.target(), nullptr);
  ASSERT_NE(c.feed(), nullptr);
  c.target()->pos[kZ] = 4;
  EXPECT_EQ(c.As<ProbeOp>().to.pos[kZ], 4);
  for (Op op : {Op::kRapid, Op::kLinear, Op::kArc, Op::kThread, Op::kRegrid}) {
    Canon m;
    switch (op) {
      case Op::kRapid:
        m.Set<RapidOp>();
        break;
      case Op::kLinear:
        m.Set<LinearOp>();
        break;
      case Op::kArc:
        m.Set<ArcOp>();
        break;
      case Op::kThread:
        m.Set<ThreadOp>();
        break;
      default:
        m.Set<RegridOp>();
        break;
    }
    EXPECT_EQ(m.op(), op);
    EXPECT_NE(m.target(), nullptr) << OpName(op);
    EXPECT_EQ(m.feed() != nullptr, op == Op::kLinear || op == Op::kArc) << OpName(op);
  }
}

// DESIGN §4 lathes: x_mode diameter, per-revolution feed, constant surface speed with a spindle limit on
// the spindle op, spindle-synchronised threads carrying the lead, turret tool with offset and tip code.
TEST(CanonJson, LatheOps) {
  Canon c;
  c.line = 1;
  c.Set<UnitsOp>() = {true, XMode::kDiameter};
  EXPECT_EQ(ToJsonLine(c), R"({"op":"units","line":1,"length":"mm","x_mode":"diameter"})");
  LinearOp& l = c.Set<LinearOp>();
  l.to.pos[kX] = 40;
  l.to.pos[kZ] = -20;
  l.to.used = (1u << kX) | (1u << kZ);
  l.feed = {0.2, FeedMode::kPerRev, false};
  EXPECT_EQ(ToJsonLine(c),
            R"({"op":"linear","line":1,"x":40.0000,"z":-20.0000,"f":0.2000,"f_mode":"per_rev"})");
  SpindleOp& s = c.Set<SpindleOp>();
  s.dir = SpindleDir::kCw;
  s.css = 150;
  s.max_rpm = 2500;
  EXPECT_EQ(ToJsonLine(c),
            R"({"op":"spindle","line":1,"dir":"cw","s":0.0000,"css":150.0000,"max_rpm":2500.0000})");
  // Turn-mills: the work spindle joined as the C axis, and the live tool's own spindle by name.
  s = SpindleOp{};
  s.dir = SpindleDir::kAxis;
  EXPECT_EQ(ToJsonLine(c), R"({"op":"spindle","line":1,"dir":"axis","s":0.0000})");
  s.spindle = SpindleId::kLiveTool;
  s.dir = SpindleDir::kCcw;
  s.rpm = 400;
  EXPECT_EQ(ToJsonLine(c), R"({"op":"spindle","line":1,"spindle":"live_tool","dir":"ccw","s":400.0000})");
  ThreadOp& t = c.Set<ThreadOp>();
  t.to.pos[kX] = 38.2;
  t.to.pos[kZ] = -30;
  t.to.used = (1u << kX) | (1u << kZ);
  t.lead = 1.5;
  t.start_angle = 180;
  EXPECT_EQ(ToJsonLine(c),
            R"({"op":"thread","line":1,"x":38.2000,"z":-30.0000,"lead":1.5000,"start_angle":180.0000})");
  t.lead_change = 0.05;
  EXPECT_NE(ToJsonLine(c).find(R"("lead_change":0.0500)"), std::string::npos);
  ToolChangeOp& tc = c.Set<ToolChangeOp>();
  tc.tool = "3";
  tc.offset = 3;
  tc.tip = 2;
  EXPECT_EQ(ToJsonLine(c), R"({"op":"tool_change","line":1,"tool":"3","offset":3,"tip":2})");
  c.Set<ToolChangeOp>().tool = "1001";  // a machining centre's tool: no lathe keys
  EXPECT_EQ(ToJsonLine(c), R"({"op":"tool_change","line":1,"tool":"1001"})");
}

TEST(CanonJson, OverridesSaysWhetherTheyAreFixed) {
  Canon c;
  c.line = 8;
  c.Set<OverridesOp>().fixed = true;
  EXPECT_EQ(ToJsonLine(c), R"({"op":"overrides","line":8,"fixed":true})");
  c.Set<OverridesOp>();
  EXPECT_EQ(ToJsonLine(c), R"({"op":"overrides","line":8,"fixed":false})");
}

TEST(CanonJson, ToolDataKeepsKtaplKeysAndAddsLatheKeysOnlyWhereSet) {
  Canon c;
  c.line = 2;
  ToolDataOp& t = c.Set<ToolDataOp>();
  t.entry.tool = "33412.5";
  t.entry.length = 0.5;
  t.entry.diameter = -6.35;
  EXPECT_EQ(ToJsonLine(c),
            R"({"op":"tool_data","line":2,"tool":"33412.5","length":0.5000,"diameter":-6.3500})");
  t.pallet = 12;
  EXPECT_NE(ToJsonLine(c).find(R"("pallet":12)"), std::string::npos);
  c.Set<ToolDataOp>().cleared = true;
  EXPECT_EQ(ToJsonLine(c), R"({"op":"tool_data","line":2,"tool":"*","length":0.0000,"diameter":0.0000})");
  ToolDataOp& lathe = c.Set<ToolDataOp>();
  lathe.entry.tool = "5";
  lathe.entry.x_offset = -1.25;
  lathe.entry.z_offset = 2.634;
  lathe.entry.nose_radius = 0.8;
  lathe.entry.tip = 3;
  EXPECT_EQ(ToJsonLine(c),
            R"({"op":"tool_data","line":2,"tool":"5","length":0.0000,"diameter":0.0000,"x_offset":-1.2500,)"
            R"("z_offset":2.6340,"nose_radius":0.8000,"tip":3})");
}

}  // namespace
}  // namespace cell::interp
