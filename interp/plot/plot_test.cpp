// The plot of a run: path elements per op kind and view, arcs as SVG arcs with their parameters worked out by
// hand, a lathe's radius view, cycle moves, labels, and a page xmllint reads as well-formed XML.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <fmt/format.h>

#include "cell/interp/plot.h"

namespace cell::interp {
namespace {

int Count(const std::string& text, const std::string& what) {
  int n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

Canon Units(bool diameter) {
  Canon c;
  c.Set<UnitsOp>().x_mode = diameter ? XMode::kDiameter : XMode::kRadius;
  c.As<UnitsOp>().metric = true;
  return c;
}

template <class T>
Canon Move(int line, double x, double y, double z) {
  Canon c;
  c.line = line;
  T& m = c.Set<T>();
  m.to.pos[kX] = x, m.to.pos[kY] = y, m.to.pos[kZ] = z;
  m.to.used = 7;
  return c;
}

Canon Arc(int line, double x, double y, double z, std::array<double, 3> center, int first, int second,
          bool cw, double angle) {
  Canon c = Move<ArcOp>(line, x, y, z);
  ArcOp& a = c.As<ArcOp>();
  a.center = center;
  a.plane.first = static_cast<std::int8_t>(first);
  a.plane.second = static_cast<std::int8_t>(second);
  a.cw = cw;
  a.angle = angle;
  return c;
}

Canon Tool(int line, const std::string& tool, int offset = 0) {
  Canon c;
  c.line = line;
  c.Set<ToolChangeOp>().tool = tool;
  c.As<ToolChangeOp>().offset = offset;
  return c;
}

// The data-scale of a view (pixels per mm).
double ScaleOf(const std::string& svg, const std::string& view) {
  const std::size_t at = svg.find("data-view=\"" + view + "\" data-scale=\"");
  EXPECT_NE(at, std::string::npos) << view;
  return std::stod(svg.substr(svg.find("data-scale=\"", at) + 12));
}

TEST(ToViewArc, ParametersByHand) {
  // A quarter from (10,0) to (0,10) about the origin, counter-clockwise: radius 10, the small arc, and
  // counter-clockwise on the page is sweep-flag 0 (SVG's y points down, so its positive sense is clockwise).
  ViewArc a = ToViewArc(10, 0, 0, 0, true, 90);
  EXPECT_DOUBLE_EQ(a.r, 10);
  EXPECT_FALSE(a.large);
  EXPECT_FALSE(a.sweep);
  // The other way round, 270 degrees clockwise from (3,4) about (0,0): radius 5, the large arc, sweep 1.
  a = ToViewArc(3, 4, 0, 0, false, 270);
  EXPECT_DOUBLE_EQ(a.r, 5);
  EXPECT_TRUE(a.large);
  EXPECT_TRUE(a.sweep);
}

// A mill: plan and elevation each draw every move but the first (its start is not known) once.
TEST(Plot, OnePathElementPerMoveAndView) {
  Plot p({MachineKind::kMachiningCentre, "T"});
  p.Add(Units(false));
  p.Add(Tool(1, "1001"));                                   // before any position: labelled at the start
  p.Add(Move<RapidOp>(2, 0, 0, 50));                        // the start
  p.Add(Move<RapidOp>(3, 10, 0, 2));                        // rapid 1
  p.Add(Move<LinearOp>(4, 10, 0, -5));                      // feed 1
  p.Add(Arc(5, 0, 10, -5, {0, 0, -5}, kX, kY, false, 90));  // arc 1, in the plan's plane
  p.Add(Move<LinearOp>(6, 0, 20, -5));                      // feed 2
  p.Add(Move<ProbeOp>(7, 0, 30, -5));                       // probe 1
  p.Add(Tool(8, "1002"));
  EXPECT_EQ(p.Drawn(Plot::MoveKind::kRapid), 1);
  EXPECT_EQ(p.Drawn(Plot::MoveKind::kFeed), 2);
  EXPECT_EQ(p.Drawn(Plot::MoveKind::kArc), 1);
  EXPECT_EQ(p.Drawn(Plot::MoveKind::kProbe), 1);
  const std::string svg = p.Svg();
  EXPECT_EQ(Count(svg, "<path class=\"rapid\""), 2);
  EXPECT_EQ(Count(svg, "<path class=\"feed\""), 4);
  EXPECT_EQ(Count(svg, "<path class=\"arc\""), 2);
  EXPECT_EQ(Count(svg, "<path class=\"probe\""), 2);
  EXPECT_EQ(Count(svg, "<circle class=\"probe-point\""), 2);
  // The elevation fits to the cutting moves (all at Z-5, counted as 10 mm: the start at Z50 is more than
  // three times that away), so the label of the tool changed there is held at the view's edge.
  EXPECT_EQ(Count(svg, ">T1001</text>"), 1);
  EXPECT_EQ(Count(svg, ">T1001 (off view)</text>"), 1);
  EXPECT_NE(svg.find("elevation XZ (X right, Z up) · fitted to the cuts"), std::string::npos);
  EXPECT_EQ(Count(svg, ">T1002</text>"), 2);
  EXPECT_NE(
      svg.find("5 moves drawn: 1 rapid, 2 feed, 1 arc, 0 thread, 1 probe (0 in cycles) · 2 tool changes"),
      std::string::npos);
  EXPECT_NE(svg.find("extents X 0 … 10 · Y 0 … 30 · Z -5 … 50"), std::string::npos);
  EXPECT_EQ(svg.find("<script"), std::string::npos);
}

// The XY arc above is a true arc in the plan (one A command) and a polyline in the elevation.
TEST(Plot, ArcInItsPlaneIsAnSvgArc) {
  Plot p({MachineKind::kMachiningCentre, "T"});
  p.Add(Move<LinearOp>(1, 10, 0, -5));
  p.Add(Arc(2, 0, 10, -5, {0, 0, -5}, kX, kY, false, 90));
  const std::string svg = p.Svg();
  // By hand: radius 10 mm is 10 * scale px; counter-clockwise seen from +Z with Y up is sweep 0, small arc.
  const double s = ScaleOf(svg, "plan");
  EXPECT_NE(svg.find(fmt::format(" A {0:.2f} {0:.2f} 0 0 0 ", 10 * s)), std::string::npos) << svg;
  EXPECT_EQ(Count(svg, " A "), 1);
}

// G18 (first Z, second X) clockwise seen from +Y: the elevation looks from -Y (X right, Z up), so it turns
// counter-clockwise there: sweep 0. A full circle is two half arcs.
TEST(Plot, ZxArcInTheElevationAndFullCircles) {
  Plot p({MachineKind::kMachiningCentre, "T"});
  p.Add(Move<LinearOp>(1, 20, 0, 0));
  p.Add(Arc(2, 10, 0, 10, {10, 0, 0}, kZ, kX, true, 90));
  std::string svg = p.Svg();
  const double s = ScaleOf(svg, "elevation");
  EXPECT_NE(svg.find(fmt::format(" A {0:.2f} {0:.2f} 0 0 0 ", 10 * s)), std::string::npos) << svg;

  Plot q({MachineKind::kMachiningCentre, "T"});
  q.Add(Move<LinearOp>(1, 20, 0, 0));
  q.Add(Arc(2, 20, 0, 0, {10, 0, 0}, kX, kY, true, 360));
  svg = q.Svg();
  const double r = 10 * ScaleOf(svg, "plan");
  EXPECT_EQ(Count(svg, fmt::format(" A {0:.2f} {0:.2f} 0 0 1 ", r)), 2) << svg;
}

// A lathe: X values are diameters; the half-section draws the radius (an R5 corner is a 5 mm arc, not 10) and
// labels the diameter.
TEST(Plot, LatheHalfSectionInRadius) {
  Plot p({MachineKind::kLathe, "T"});
  p.Add(Units(true));
  p.Add(Move<RapidOp>(1, 80, 0, 2));
  p.Add(Tool(1, "3", 3));
  p.Add(Move<LinearOp>(2, 80, 0, -20));
  // From (Z-20, r40) to (Z-25, r45) about (Z-25, r40): a quarter counter-clockwise with Z right, X up.
  p.Add(Arc(3, 90, 0, -25, {80, 0, -25}, kZ, kX, false, 90));
  p.Add(Move<ThreadOp>(4, 90, 0, -60));
  const std::string svg = p.Svg();
  const double s = ScaleOf(svg, "half-section");
  EXPECT_NE(svg.find(fmt::format(" A {0:.2f} {0:.2f} 0 0 0 ", 5 * s)), std::string::npos) << svg;
  EXPECT_EQ(Count(svg, "<path class=\"thread\""), 1);
  EXPECT_NE(svg.find(">Ø80</text>"), std::string::npos) << svg;             // the diameter, not the radius 40
  EXPECT_NE(svg.find("stroke-dasharray=\"14 3 2 3\""), std::string::npos);  // the centre line
  EXPECT_NE(svg.find("extents Z -60 … 2 · X Ø 80 … 90"), std::string::npos) << svg;
  EXPECT_NE(svg.find(">T3 (offset 3)</text>"), std::string::npos);
}

// A block that makes rapids and feeds (a drilling cycle: position, feed in, retract) is drawn as a cycle; a
// block of feeds alone is not.
TEST(Plot, CycleMovesAreMarked) {
  Plot p({MachineKind::kMachiningCentre, "T"});
  p.Add(Move<RapidOp>(1, 0, 0, 10));
  p.Add(Move<RapidOp>(2, 5, 5, 2));
  p.Add(Move<LinearOp>(2, 5, 5, -10));
  p.Add(Move<RapidOp>(2, 5, 5, 2));
  p.Add(Move<LinearOp>(3, 10, 5, 2));
  p.Add(Move<LinearOp>(3, 10, 10, 2));
  const std::string svg = p.Svg();
  EXPECT_NE(svg.find("(3 in cycles)"), std::string::npos) << svg;
  EXPECT_EQ(Count(svg, "data-cycle=\"true\""), 4);  // rapids and feeds of the cycle, in two views
  // The drill's feed along Z is seen end-on in the plan only: one plunge circle; the Y move of line 3 is
  // seen end-on in the elevation, and is no plunge.
  EXPECT_EQ(Count(svg, "<circle class=\"plunge\""), 1);
}

// What a live view (the dashboard) needs from the page: each path's index among the drawn moves
// (data-seq, the same in every view) and each view's mapping from millimetres to the page, checked against
// the move's own end point: the feed move to X100 Y50 ends at page x = left + (100 - h0) * scale.
TEST(Plot, LiveViewAttributes) {
  Plot plot({MachineKind::kMachiningCentre, "live"});
  plot.Add(Units(false));
  plot.Add(Move<RapidOp>(1, 0, 0, 50));
  plot.Add(Move<LinearOp>(2, 100, 50, 0));
  plot.Add(Move<RapidOp>(3, 0, 0, 50));
  ASSERT_EQ(plot.moves().size(), 2u);
  EXPECT_TRUE(plot.started());
  EXPECT_EQ(plot.start()[2], 50);
  const std::string svg = plot.Svg();
  EXPECT_EQ(Count(svg, "data-seq=\"0\""), 2);  // plan and elevation
  EXPECT_EQ(Count(svg, "data-seq=\"1\""), 2);
  EXPECT_EQ(Count(svg, "data-seq=\"2\""), 0);
  auto attr = [&](std::size_t from, const std::string& name) {
    const std::size_t at = svg.find(name + "=\"", from) + name.size() + 2;
    return std::stod(svg.substr(at, svg.find('"', at) - at));
  };
  const std::size_t plan = svg.find("data-view=\"plan\"");
  ASSERT_NE(plan, std::string::npos);
  EXPECT_EQ(attr(plan, "data-h"), kX);
  EXPECT_EQ(attr(plan, "data-v"), kY);
  const double x = attr(plan, "data-left") + (100 - attr(plan, "data-h0")) * attr(plan, "data-scale");
  const double y = attr(plan, "data-top") + (attr(plan, "data-v0") - 50) * attr(plan, "data-scale");
  // The feed move's path in the plan: "M x0 y0 L x y", its end where the mapping puts X100 Y50.
  const std::size_t d = svg.find("data-seq=\"0\" d=\"M ", plan);
  ASSERT_NE(d, std::string::npos) << svg;
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  ASSERT_EQ(std::sscanf(svg.c_str() + d, "data-seq=\"0\" d=\"M %lf %lf L %lf %lf", &x0, &y0, &x1, &y1), 4);
  EXPECT_NEAR(x1, x, 0.01);
  EXPECT_NEAR(y1, y, 0.01);
  EXPECT_NEAR(x1 - x0, 100 * attr(plan, "data-scale"), 0.02);
}

TEST(Plot, NoMotion) {
  Plot p({MachineKind::kLathe, "EMPTY"});
  p.Add(Units(true));
  EXPECT_NE(p.Svg().find(">no motion</text>"), std::string::npos);
}

// Well-formed XML whatever the title and note say (xmllint: deploy/install-deps installs libxml2-utils).
TEST(Plot, WellFormedXml) {
  Plot p({MachineKind::kMachiningCentre, "A&B <\"x\"> \x01"});
  p.SetNote("line 3: <E-STOP> & more");
  p.Add(Move<RapidOp>(1, 0, 0, 10));
  p.Add(Arc(2, 0, 0, 10, {0, 5, 10}, kX, kY, true, 360));
  p.Add(Move<RapidOp>(3, 0, 0, 10));
  const auto file =
      std::filesystem::temp_directory_path() / ("plot_test_" + std::to_string(::getpid()) + ".svg");
  std::ofstream(file) << p.Svg();
  EXPECT_EQ(std::system(("xmllint --noout --nonet '" + file.string() + "'").c_str()), 0);
  std::filesystem::remove(file);
}

}  // namespace
}  // namespace cell::interp
