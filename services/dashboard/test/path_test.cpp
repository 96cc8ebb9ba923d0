// The page's form of a plot (PathJson): what the live toolpath follows. Without DDS: a plot fed by hand.
#include <gtest/gtest.h>

#include "cell/dashboard/path.h"

namespace cell::dashboard {
namespace {

using interp::Canon;

template <class T>
Canon Move(int line, double x, double y, double z) {
  Canon c;
  c.line = line;
  T& m = c.Set<T>();
  m.to.pos[interp::kX] = x, m.to.pos[interp::kY] = y, m.to.pos[interp::kZ] = z;
  m.to.used = 7;
  return c;
}

// A rapid to the start, a feed move, a quarter circle counter-clockwise about (10, 10) in the XY plane: three
// motion ops, two drawn; the arc carries its centre, plane (X, Y) and sense, the lines none.
TEST(PathJson, MovesInOrderWithTheirEndsAndArcs) {
  interp::Plot plot({interp::MachineKind::kMachiningCentre, "P"});
  plot.Add(Move<interp::RapidOp>(10, 0, 0, 5));
  plot.Add(Move<interp::LinearOp>(20, 20, 10, 5));
  Canon arc = Move<interp::ArcOp>(30, 10, 20, 5);
  auto& a = arc.As<interp::ArcOp>();
  a.center = {10, 10, 5};
  a.plane.first = interp::kX, a.plane.second = interp::kY;
  a.cw = false;
  a.angle = 90;
  plot.Add(arc);
  const nlohmann::json j = PathJson(plot);
  EXPECT_EQ(j["motion_ops"], 3);
  EXPECT_EQ(j["start"], nlohmann::json::array({0, 0, 5}));
  ASSERT_EQ(j["moves"].size(), 2u);
  EXPECT_EQ(j["moves"][0]["kind"], "feed");
  EXPECT_EQ(j["moves"][0]["line"], 20);
  EXPECT_EQ(j["moves"][0]["from"], nlohmann::json::array({0, 0, 5}));
  EXPECT_EQ(j["moves"][0]["to"], nlohmann::json::array({20, 10, 5}));
  EXPECT_FALSE(j["moves"][0].contains("center"));
  EXPECT_EQ(j["moves"][1]["kind"], "arc");
  EXPECT_EQ(j["moves"][1]["center"], nlohmann::json::array({10, 10, 5}));
  EXPECT_EQ(j["moves"][1]["plane"], nlohmann::json::array({0, 1}));
  EXPECT_EQ(j["moves"][1]["cw"], false);
  const std::string svg = j["svg"];
  EXPECT_NE(svg.find("data-seq=\"1\""), std::string::npos);
}

TEST(PathJson, NoMotion) {
  interp::Plot plot({interp::MachineKind::kLathe, "P"});
  const nlohmann::json j = PathJson(plot);
  EXPECT_EQ(j["motion_ops"], 0);
  EXPECT_TRUE(j["start"].is_null());
  EXPECT_TRUE(j["moves"].empty());
}

}  // namespace
}  // namespace cell::dashboard
