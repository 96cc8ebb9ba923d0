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
  c.op = Op::kRapid;
  c.line = 7;
  c.pos[kX] = v;
  c.used = 1u << kX;
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
  c.op = Op::kArc;
  c.line = 3;
  c.pos = {20, 5, 5};
  c.used = 7;
  c.feed = 800;
  c.center = {15, 5, 5};
  c.plane = "xy";
  c.turns = 180;
  std::string out = "prefix\n";
  AppendJsonLine(out, c);
  EXPECT_EQ(out, "prefix\n" + ToJsonLine(c));
  EXPECT_EQ(ToJsonLine(c),
            "{\"op\":\"arc\",\"line\":3,\"x\":20.0000,\"y\":5.0000,\"z\":5.0000,\"f\":800.0000,"
            "\"center\":[15.0000,5.0000,5.0000],\"dir\":\"cw\",\"plane\":\"xy\",\"angle\":180.0000}");
}

TEST(CanonJson, ResetGivesAFreshCommand) {
  Canon c;
  c.op = Op::kFileOp;
  c.line = 9;
  c.pos[kB] = 90;
  c.used = 0x1ff;
  c.travel[kB] = 90;
  c.travel_mask = 1u << kB;
  c.feed = 5;
  c.f_mode = FeedMode::kInverseTime;
  c.exact_stop = true;
  c.center = {1, 2, 3};
  c.cw = false;
  c.plane = "zx";
  c.turns = 360;
  c.metric = true;
  c.value = 1;
  c.value2 = 2;
  c.text = "a long text that does not fit in the small-string buffer";
  c.text2 = "CPY";
  c.code = 7;
  c.flag = true;
  c.Reset();
  for (Op op : {Op::kRapid, Op::kArc, Op::kFileOp, Op::kSpindle, Op::kProbe}) {
    Canon fresh;
    fresh.op = op;
    c.op = op;
    EXPECT_EQ(ToJsonLine(c), ToJsonLine(fresh));
  }
  EXPECT_EQ(c.op, Op::kProbe);
  EXPECT_TRUE(c.text.empty() && c.text2.empty() && c.plane.empty() && c.cw && !c.flag && c.code == 0);
}

}  // namespace
}  // namespace cell::interp
