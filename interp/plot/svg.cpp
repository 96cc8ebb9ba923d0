// The plot as SVG: page layout, views, grid, moves, marks, legend. Everything is written in page pixels
// (no transforms), so stroke widths and text sizes stay what they say at any scale.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <utility>

#include <fmt/format.h>

#include "cell/interp/plot.h"

namespace cell::interp {

namespace {

using P3 = std::array<double, 3>;
using MoveKind = Plot::MoveKind;

constexpr double kWidth = 1200, kHeight = 800;
constexpr double kTop = 96, kBottom = 52, kSide = 16, kGap = 20;     // page margins
constexpr double kLeft = 64, kBelow = 30, kAbove = 26, kRight = 12;  // inside a view: ticks and its title

// A view of the part: the axis drawn to the right and the axis drawn up (X Y Z indices).
struct View {
  const char* name;
  int h, v;
  bool lathe;  // v is X as a radius; its labels are diameters
};

struct Box {
  double lo_h = std::numeric_limits<double>::max(), hi_h = -std::numeric_limits<double>::max();
  double lo_v = lo_h, hi_v = hi_h;
  void Add(double h, double v) {
    lo_h = std::min(lo_h, h), hi_h = std::max(hi_h, h);
    lo_v = std::min(lo_v, v), hi_v = std::max(hi_v, v);
  }
  bool Empty() const { return lo_h > hi_h; }
};

// Where a view lies on the page and how world millimetres map to page pixels.
struct Frame {
  double left, top, width, height;  // the drawing area (inside the tick margins)
  double h0, v0;                    // the world point at the area's left and top edge
  double scale;                     // pixels per mm
  double X(double h) const { return left + (h - h0) * scale; }
  double Y(double v) const { return top + (v0 - v) * scale; }
};

std::string Num(double v) {
  std::string s = fmt::format("{:.3f}", v);
  while (s.back() == '0') s.pop_back();
  if (s.back() == '.') s.pop_back();
  return s == "-0" ? "0" : s;
}

std::string Escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        // Control characters are not allowed in XML 1.0 text.
        if (static_cast<unsigned char>(c) >= 0x20 || c == '\t') out += c;
    }
  }
  return out;
}

// 1, 2 or 5 times a power of ten, the smallest at least `x`.
double NiceStep(double x) {
  const double p = std::pow(10.0, std::floor(std::log10(x)));
  for (double k : {1.0, 2.0, 5.0, 10.0})
    if (k * p >= x) return k * p;
  return 10 * p;
}

bool DrawsAsArc(const Plot::Move& m) {
  return m.kind == MoveKind::kArc && m.first >= 0 && m.second >= 0 && m.first != m.second;
}

// Points along a move in X Y Z: its ends, and for an arc one point per 5 degrees at most (a helix's normal
// axis moves along in proportion).
std::vector<P3> Samples(const Plot::Move& m) {
  if (!DrawsAsArc(m)) return {m.from, m.to};
  const int f = m.first, s = m.second, n = 3 - f - s;
  const double r = std::hypot(m.from[f] - m.center[f], m.from[s] - m.center[s]);
  const double t0 = std::atan2(m.from[s] - m.center[s], m.from[f] - m.center[f]);
  const double sweep = (m.cw ? -1 : 1) * m.angle * std::numbers::pi / 180;
  const int steps = std::max(2, static_cast<int>(std::ceil(m.angle / 5)));
  std::vector<P3> out;
  for (int k = 0; k <= steps; ++k) {
    const double u = static_cast<double>(k) / steps;
    P3 p = m.from;
    p[f] = m.center[f] + r * std::cos(t0 + u * sweep);
    p[s] = m.center[s] + r * std::sin(t0 + u * sweep);
    p[n] = m.from[n] + u * (m.to[n] - m.from[n]);
    out.push_back(p);
  }
  out.back() = m.to;
  return out;
}

Box Extents(const View& v, const std::vector<Plot::Move>& moves, const P3& start,
            const std::vector<Plot::Label>& labels) {
  Box b;
  b.Add(start[v.h], start[v.v]);
  for (const auto& m : moves)
    for (const P3& p : Samples(m)) b.Add(p[v.h], p[v.v]);
  for (const auto& l : labels) b.Add(l.at[v.h], l.at[v.v]);
  if (v.lathe) b.Add(b.lo_h, 0);  // the spindle's centre line is part of a half-section
  return b;
}

// What a view fits to: its extents, except that along an axis where they reach over three times as far as the
// cutting moves' (a lathe's turret indexing at X800 for a part of 60 mm), the cutting moves' with a margin;
// the rapids out there then leave the view (it is clipped). `full` gets every move's extents.
Box FitBox(const View& v, const std::vector<Plot::Move>& moves, const P3& start,
           const std::vector<Plot::Label>& labels, Box& full) {
  full = Extents(v, moves, start, labels);
  Box fit = full, cut;
  for (const auto& m : moves)
    if (m.kind != MoveKind::kRapid)
      for (const P3& p : Samples(m)) cut.Add(p[v.h], p[v.v]);
  if (cut.Empty()) return fit;
  if (v.lathe) cut.Add(cut.lo_h, 0);
  const double rh = std::max(cut.hi_h - cut.lo_h, 10.0), rv = std::max(cut.hi_v - cut.lo_v, 10.0);
  if (full.hi_h - full.lo_h > 3 * rh) fit.lo_h = cut.lo_h - rh / 4, fit.hi_h = cut.hi_h + rh / 4;
  if (full.hi_v - full.lo_v > 3 * rv) fit.lo_v = cut.lo_v - rv / 4, fit.hi_v = cut.hi_v + rv / 4;
  return fit;
}

// True when some of `full` lies outside the frame (the view's title then says it is fitted to the cuts).
bool Clipped(const Box& full, const Frame& f) {
  const double eps = 1e-6;
  return full.lo_h < f.h0 - eps || full.hi_h > f.h0 + f.width / f.scale + eps || full.hi_v > f.v0 + eps ||
         full.lo_v < f.v0 - f.height / f.scale - eps;
}

// The pixels per mm at which every view's extents (padded by 5 %) fit its area.
double FitScale(const std::vector<Box>& boxes, double width, double height) {
  double scale = std::numeric_limits<double>::max();
  for (const Box& b : boxes) {
    const double rh = std::max(b.hi_h - b.lo_h, 1.0) * 1.1, rv = std::max(b.hi_v - b.lo_v, 1.0) * 1.1;
    scale = std::min({scale, width / rh, height / rv});
  }
  return scale;
}

Frame PlaceFrame(const Box& b, double left, double top, double width, double height, double scale) {
  Frame f{left, top, width, height, 0, 0, scale};
  // The extents centred in the area.
  f.h0 = (b.lo_h + b.hi_h) / 2 - width / scale / 2;
  f.v0 = (b.lo_v + b.hi_v) / 2 + height / scale / 2;
  return f;
}

// Grid lines every 1, 2 or 5 x 10^n mm (at least 70 px apart), labelled below and to the left; the zero
// lines darker, a lathe's centre line dash-dotted.
void Grid(std::string& out, const View& v, const Frame& f) {
  const double step = NiceStep(70 / f.scale);
  const double h1 = f.h0 + f.width / f.scale, v1 = f.v0 - f.height / f.scale;
  out += "<g class=\"grid\" stroke=\"#e4e4e4\" stroke-width=\"1\">\n";
  for (double h = std::ceil(f.h0 / step) * step; h <= h1; h += step)
    out += fmt::format("<line x1=\"{0:.2f}\" y1=\"{1:.2f}\" x2=\"{0:.2f}\" y2=\"{2:.2f}\"/>\n", f.X(h), f.top,
                       f.top + f.height);
  for (double y = std::ceil(v1 / step) * step; y <= f.v0; y += step)
    out += fmt::format("<line x1=\"{1:.2f}\" y1=\"{0:.2f}\" x2=\"{2:.2f}\" y2=\"{0:.2f}\"/>\n", f.Y(y),
                       f.left, f.left + f.width);
  out += "</g>\n<g class=\"ticks\" fill=\"#555\" font-size=\"11\">\n";
  for (double h = std::ceil(f.h0 / step) * step; h <= h1; h += step)
    out += fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\" text-anchor=\"middle\">{}</text>\n", f.X(h),
                       f.top + f.height + 15, Num(std::abs(h) < step / 1e6 ? 0 : h));
  for (double y = std::ceil(v1 / step) * step; y <= f.v0; y += step) {
    const double val = std::abs(y) < step / 1e6 ? 0 : y;
    if (v.lathe && val < 0) continue;  // below a lathe's centre line there are no diameters
    out += fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\" text-anchor=\"end\">{}</text>\n", f.left - 5,
                       f.Y(y) + 4, v.lathe ? "Ø" + Num(2 * val) : Num(val));
  }
  out += "</g>\n";
  if (f.h0 < 0 && h1 > 0)
    out += fmt::format(
        "<line class=\"axis\" x1=\"{0:.2f}\" y1=\"{1:.2f}\" x2=\"{0:.2f}\" y2=\"{2:.2f}\" "
        "stroke=\"#999\" stroke-width=\"1\"/>\n",
        f.X(0), f.top, f.top + f.height);
  if (v1 < 0 && f.v0 > 0)
    out += fmt::format(
        "<line class=\"axis\" x1=\"{1:.2f}\" y1=\"{0:.2f}\" x2=\"{2:.2f}\" y2=\"{0:.2f}\" "
        "stroke=\"#999\" stroke-width=\"1\"{3}/>\n",
        f.Y(0), f.left, f.left + f.width, v.lathe ? " stroke-dasharray=\"14 3 2 3\"" : "");
}

// A bar of a round length (1, 2 or 5 x 10^n mm, 60-160 px) in the area's lower right corner.
void ScaleBar(std::string& out, const Frame& f) {
  double len = NiceStep(100 / f.scale);
  while (len * f.scale > 160) {
    // One step down the 1-2-5 sequence: 5 -> 2, 2 -> 1, 1 -> 0.5.
    const double mantissa = len / std::pow(10.0, std::floor(std::log10(len) + 1e-9));
    len *= mantissa > 3 ? 0.4 : 0.5;
  }
  const double x1 = f.left + f.width - 12, x0 = x1 - len * f.scale, y = f.top + f.height - 12;
  out += fmt::format(
      "<g class=\"scale-bar\" stroke=\"#222\" stroke-width=\"1.5\"><path fill=\"none\" d=\"M {0:.2f} {2:.2f} "
      "v -6 M {0:.2f} {3:.2f} H {1:.2f} M {1:.2f} {2:.2f} v -6\"/><text x=\"{4:.2f}\" y=\"{5:.2f}\" "
      "stroke=\"none\" fill=\"#222\" text-anchor=\"middle\">{6} mm</text></g>\n",
      x0, x1, y + 3, y, (x0 + x1) / 2, y - 6, Num(len));
}

// Stroke attributes of a kind of move; cycle moves in their own colour, rapids dashed in every case.
// Threads and probe moves keep their own colour inside a cycle too (a threading cycle's passes are threads).
const char* Colour(MoveKind k, bool cycle) {
  if (k == MoveKind::kThread) return "#1e8449";
  if (k == MoveKind::kProbe) return "#e67e22";
  if (cycle) return "#8e44ad";
  return k == MoveKind::kRapid ? "#c0392b" : "#1f4e9c";
}

std::string Stroke(MoveKind k, bool cycle) {
  std::string s = fmt::format(
      "fill=\"none\" stroke=\"{}\" stroke-linecap=\"round\" stroke-linejoin=\"round\"", Colour(k, cycle));
  s += k == MoveKind::kRapid ? " stroke-width=\"1\" stroke-dasharray=\"6 4\"" : " stroke-width=\"1.6\"";
  return s;
}

// A canned cycle's block makes several moves, rapids and feeds both (positioning, feed in, retract); the
// moves of such a block are cycle moves (docs/plot.md). A compensated corner (feeds only) or an M06 block
// (rapids only) is not.
std::vector<bool> CycleMoves(const std::vector<Plot::Move>& moves) {
  std::vector<bool> cycle(moves.size(), false);
  for (std::size_t i = 0; i < moves.size();) {
    std::size_t j = i;
    bool rapid = false, feed = false;
    for (; j < moves.size() && moves[j].block == moves[i].block; ++j)
      (moves[j].kind == MoveKind::kRapid ? rapid : feed) = true;
    if (rapid && feed && j - i > 1)
      std::fill(cycle.begin() + static_cast<long>(i), cycle.begin() + static_cast<long>(j), true);
    i = j;
  }
  return cycle;
}

// An arc in the view's plane as SVG arc commands from where the pen stands; full circles as two halves.
std::string ArcPath(const Plot::Move& m, const View& v, const Frame& f) {
  const bool ccw = m.first == v.h ? !m.cw : m.cw;  // the plane's first axis to the left turns the sense
  const ViewArc a = ToViewArc(m.from[v.h], m.from[v.v], m.center[v.h], m.center[v.v], ccw, m.angle);
  const double r = a.r * f.scale;
  std::string d = fmt::format("M {:.2f} {:.2f}", f.X(m.from[v.h]), f.Y(m.from[v.v]));
  double rest = m.angle;
  if (rest >= 360 - 1e-9) {
    const double oh = 2 * m.center[v.h] - m.from[v.h], ov = 2 * m.center[v.v] - m.from[v.v];
    d += fmt::format(
        " A {0:.2f} {0:.2f} 0 0 {1:d} {2:.2f} {3:.2f} A {0:.2f} {0:.2f} 0 0 {1:d} {4:.2f} {5:.2f}", r,
        a.sweep, f.X(oh), f.Y(ov), f.X(m.from[v.h]), f.Y(m.from[v.v]));
    rest = std::fmod(rest, 360.0);
    if (rest < 1e-6) return d;
  }
  d += fmt::format(" A {0:.2f} {0:.2f} 0 {1:d} {2:d} {3:.2f} {4:.2f}", r, rest > 180, a.sweep, f.X(m.to[v.h]),
                   f.Y(m.to[v.v]));
  return d;
}

std::string MovePath(const Plot::Move& m, const View& v, const Frame& f) {
  const bool in_plane =
      DrawsAsArc(m) && ((m.first == v.h && m.second == v.v) || (m.first == v.v && m.second == v.h));
  if (in_plane) return ArcPath(m, v, f);
  std::string d;
  for (const P3& p : Samples(m))
    d += fmt::format("{} {:.2f} {:.2f}", d.empty() ? "M" : " L", f.X(p[v.h]), f.Y(p[v.v]));
  return d;
}

// One path element per move, grouped by kind and cycle so that each group carries its stroke once.
// A cutting move seen end-on (a drill's or an end mill's plunge in the plan) would be invisible: a small
// circle marks where it goes in.
std::string Plunge(const Plot::Move& m, bool cycle, const View& v, const Frame& f) {
  // Only along the spindle (Z) seen from above: a Y move seen end-on in the elevation is no plunge.
  if (m.kind == MoveKind::kRapid || v.h == kZ || v.v == kZ) return "";
  const double dx = f.X(m.to[v.h]) - f.X(m.from[v.h]), dy = f.Y(m.to[v.v]) - f.Y(m.from[v.v]);
  if (std::hypot(dx, dy) >= 1 ||
      std::hypot(m.to[0] - m.from[0], m.to[1] - m.from[1], m.to[2] - m.from[2]) < 1e-6)
    return "";
  if (DrawsAsArc(m) && m.angle >= 1) return "";  // an arc seen edge-on is still a line
  return fmt::format(
      "<circle class=\"plunge\" cx=\"{:.2f}\" cy=\"{:.2f}\" r=\"3\" fill=\"none\" stroke=\"{}\" "
      "stroke-width=\"1.2\"/>\n",
      f.X(m.to[v.h]), f.Y(m.to[v.v]), Colour(m.kind, cycle));
}

void Moves(std::string& out, const std::vector<Plot::Move>& moves, const View& v, const Frame& f) {
  const std::vector<bool> cycle = CycleMoves(moves);
  std::string plunges;
  for (MoveKind k :
       {MoveKind::kRapid, MoveKind::kFeed, MoveKind::kArc, MoveKind::kThread, MoveKind::kProbe}) {
    for (bool in_cycle : {false, true}) {
      std::string group;
      for (std::size_t i = 0; i < moves.size(); ++i) {
        if (moves[i].kind != k || cycle[i] != in_cycle) continue;
        group += fmt::format("<path class=\"{}\" data-line=\"{}\" data-seq=\"{}\" d=\"{}\"/>\n",
                             Plot::KindName(k), moves[i].line, i, MovePath(moves[i], v, f));
        plunges += Plunge(moves[i], in_cycle, v, f);
      }
      if (group.empty()) continue;
      out += fmt::format("<g class=\"moves\" data-kind=\"{}\" data-cycle=\"{}\" {}>\n", Plot::KindName(k),
                         in_cycle, Stroke(k, in_cycle));
      out += group + "</g>\n";
    }
  }
  out += plunges;
}

// Probe end points (filled where the probe touched) and the start.
void Marks(std::string& out, const std::vector<Plot::Move>& moves, const P3& start, const View& v,
           const Frame& f) {
  for (const auto& m : moves) {
    if (m.kind != MoveKind::kProbe) continue;
    out += fmt::format(
        "<circle class=\"probe-point\" cx=\"{:.2f}\" cy=\"{:.2f}\" r=\"3.5\" fill=\"{}\" "
        "stroke=\"#e67e22\" stroke-width=\"1.5\"/>\n",
        f.X(m.to[v.h]), f.Y(m.to[v.v]), m.contact ? "#e67e22" : "#fff");
  }
  out += fmt::format(
      "<circle class=\"start\" cx=\"{:.2f}\" cy=\"{:.2f}\" r=\"5\" fill=\"none\" "
      "stroke=\"#27ae60\" stroke-width=\"2\"><title>start</title></circle>\n",
      f.X(start[v.h]), f.Y(start[v.v]));
}

// Tool changes and indexing where they happen; one off the view (a turret indexing far out) is held at the
// view's edge in its direction, with an open mark. Labels at one place are stacked.
void Labels(std::string& out, const std::vector<Plot::Label>& labels, const View& v, const Frame& f) {
  std::map<std::pair<long, long>, int> stacked;
  for (const auto& l : labels) {
    const double x0 = f.X(l.at[v.h]), y0 = f.Y(l.at[v.v]);
    const double x = std::clamp(x0, f.left + 6, f.left + f.width - 6);
    const double y = std::clamp(y0, f.top + 12, f.top + f.height - 4);
    const bool off = x != x0 || y != y0;
    const int n = stacked[{std::lround(x / 6), std::lround(y / 6)}]++;
    // Near the right edge the text goes to the left of its mark (about 7 px per character).
    const bool left = x + 6 + 7 * static_cast<double>(l.text.size()) > f.left + f.width;
    // Near the top edge a stack grows downwards, not into the view's title.
    const double ty = y < f.top + 48 ? y + 12 + 13 * n : y - 9 - 13 * n;
    out += fmt::format(
        "<g class=\"label\"><path d=\"M {0:.2f} {1:.2f} l -4 -8 h 8 z\" fill=\"{6}\" stroke=\"#222\"/>"
        "<text x=\"{2:.2f}\" y=\"{3:.2f}\" fill=\"#222\" font-size=\"11\"{5}>{4}</text></g>\n",
        x, y, left ? x - 6 : x + 6, ty, Escape(off ? l.text + " (off view)" : l.text),
        left ? " text-anchor=\"end\"" : "", off ? "#fff" : "#222");
  }
}

void DrawView(std::string& out, const View& v, const Frame& f, bool zoomed,
              const std::vector<Plot::Move>& moves, const std::vector<Plot::Label>& labels, const P3& start) {
  // The mapping from millimetres to the page, for a live view that draws the tool over the plot: page x =
  // left + (h - h0) * scale, page y = top + (v0 - v) * scale, h and v the X Y Z indices (X as a radius).
  out += fmt::format(
      "<g class=\"view\" data-view=\"{}\" data-scale=\"{:.6f}\" data-h=\"{}\" data-v=\"{}\" "
      "data-left=\"{:.3f}\" data-top=\"{:.3f}\" data-h0=\"{:.6f}\" data-v0=\"{:.6f}\">\n",
      v.name, f.scale, v.h, v.v, f.left, f.top, f.h0, f.v0);
  std::string title = v.lathe ? "half-section XZ (Z right, X as radius up, labelled Ø)"
                      : std::string(v.name) == "plan" ? "plan XY (X right, Y up)"
                                                      : "elevation XZ (X right, Z up)";
  if (zoomed) title += " · fitted to the cuts";  // rapids beyond are clipped (docs/plot.md)
  out += fmt::format("<text x=\"{:.2f}\" y=\"{:.2f}\" font-size=\"13\" font-weight=\"bold\">{}</text>\n",
                     f.left, f.top - 9, Escape(title));
  out += fmt::format(
      "<clipPath id=\"clip-{0}\"><rect x=\"{1:.2f}\" y=\"{2:.2f}\" width=\"{3:.2f}\" "
      "height=\"{4:.2f}\"/></clipPath>\n<rect x=\"{1:.2f}\" y=\"{2:.2f}\" width=\"{3:.2f}\" "
      "height=\"{4:.2f}\" fill=\"none\" stroke=\"#bbb\"/>\n",
      v.name, f.left, f.top, f.width, f.height);
  Grid(out, v, f);
  out += fmt::format("<g clip-path=\"url(#clip-{})\">\n", v.name);
  Moves(out, moves, v, f);
  Marks(out, moves, start, v, f);
  out += "</g>\n";
  Labels(out, labels, v, f);
  ScaleBar(out, f);
  out += "</g>\n";
}

// Title, what is drawn, units and extents; the moves by kind; a note (a run that stopped) in red.
std::string Header(const PlotOptions& o, const std::string& note, const std::vector<Plot::Move>& moves,
                   const std::vector<Plot::Label>& labels, const P3& start, bool started) {
  const bool lathe = o.machine == MachineKind::kLathe;
  std::string out = fmt::format("<text x=\"{}\" y=\"28\" font-size=\"20\" font-weight=\"bold\">{}</text>\n",
                                kSide, Escape(o.title));
  std::string what = lathe ? "lathe: XZ half-section" : "machining centre: plan and elevation";
  what += " · units mm";
  if (started) {
    P3 lo = start, hi = start;
    for (const auto& m : moves)
      for (const P3& p : Samples(m))
        for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
    auto range = [&](int a, double k) { return Num(k * lo[a]) + " … " + Num(k * hi[a]); };
    what += lathe ? " · extents Z " + range(kZ, 1) + " · X Ø " + range(kX, 2)
                  : " · extents X " + range(kX, 1) + " · Y " + range(kY, 1) + " · Z " + range(kZ, 1);
  }
  out += fmt::format("<text x=\"{}\" y=\"50\" font-size=\"13\">{}</text>\n", kSide, Escape(what));
  int count[5] = {}, cycle = 0, tools = 0;
  const std::vector<bool> in_cycle = CycleMoves(moves);
  for (std::size_t i = 0; i < moves.size(); ++i)
    ++count[static_cast<int>(moves[i].kind)], cycle += in_cycle[i];
  for (const auto& l : labels) tools += !l.text.empty() && l.text[0] == 'T';
  out += fmt::format(
      "<text class=\"counts\" x=\"{}\" y=\"70\" font-size=\"13\">{} moves drawn: {} rapid, {} feed, {} arc, "
      "{} "
      "thread, {} probe ({} in cycles) · {} tool changes</text>\n",
      kSide, moves.size(), count[0], count[1], count[2], count[3], count[4], cycle, tools);
  if (!note.empty())
    out += fmt::format("<text x=\"{}\" y=\"88\" font-size=\"13\" fill=\"#c0392b\">{}</text>\n", kSide,
                       Escape(note));
  return out;
}

// What each mark means, along the foot of the page.
std::string Legend() {
  std::string out = fmt::format("<g class=\"legend\" font-size=\"12\" transform=\"translate({} {})\">\n",
                                kSide, kHeight - 18);
  double x = 0;
  auto item = [&](const std::string& sample, const char* text) {
    out += sample + fmt::format("<text x=\"{:.0f}\" y=\"4\">{}</text>\n", x + 34, text);
    x += 34 + 8.0 * static_cast<double>(std::string_view(text).size()) + 22;
  };
  auto line = [&](MoveKind k, bool cycle) {
    return fmt::format("<path d=\"M {:.0f} 0 h 28\" {}/>", x, Stroke(k, cycle));
  };
  item(line(MoveKind::kRapid, false), "rapid");
  item(line(MoveKind::kFeed, false), "feed (lines, arcs)");
  item(line(MoveKind::kFeed, true) + line(MoveKind::kRapid, true), "cycle");
  item(line(MoveKind::kThread, false), "thread");
  item(line(MoveKind::kProbe, false) +
           fmt::format("<circle cx=\"{:.0f}\" cy=\"0\" r=\"3.5\" fill=\"#e67e22\"/>", x + 28),
       "probe (filled: touched)");
  item(fmt::format("<circle cx=\"{:.0f}\" cy=\"0\" r=\"3\" fill=\"none\" stroke=\"#1f4e9c\"/>", x + 14),
       "plunge");
  item(fmt::format("<path d=\"M {:.0f} 4 l -4 -8 h 8 z\" fill=\"#222\"/>", x + 14), "tool change, index");
  item(fmt::format("<circle cx=\"{:.0f}\" cy=\"0\" r=\"5\" fill=\"none\" stroke=\"#27ae60\" "
                   "stroke-width=\"2\"/>",
                   x + 14),
       "start");
  return out + "</g>\n";
}

}  // namespace

const char* Plot::KindName(MoveKind k) {
  switch (k) {
    case MoveKind::kRapid:
      return "rapid";
    case MoveKind::kFeed:
      return "feed";
    case MoveKind::kArc:
      return "arc";
    case MoveKind::kThread:
      return "thread";
    case MoveKind::kProbe:
      return "probe";
  }
  return "feed";
}

std::string Plot::Svg() const {
  std::string out = fmt::format(
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" "
      "width=\"{0}\" height=\"{1}\" viewBox=\"0 0 {0} {1}\" font-family=\"DejaVu Sans, Arial, sans-serif\" "
      "font-size=\"12\">\n<title>{2}</title>\n<rect width=\"{0}\" height=\"{1}\" fill=\"#fff\"/>\n",
      kWidth, kHeight, Escape(options_.title));
  const bool lathe = options_.machine == MachineKind::kLathe;
  out += Header(options_, note_, moves_, labels_, start_, started_);
  if (!started_) {
    out += fmt::format("<text x=\"{}\" y=\"{}\" text-anchor=\"middle\" font-size=\"16\">no motion</text>\n",
                       kWidth / 2, kHeight / 2);
    return out + "</svg>\n";
  }
  const std::vector<View> views =
      lathe ? std::vector<View>{{"half-section", kZ, kX, true}}
            : std::vector<View>{{"plan", kX, kY, false}, {"elevation", kX, kZ, false}};
  std::vector<Box> boxes, full(views.size());
  for (std::size_t i = 0; i < views.size(); ++i)
    boxes.push_back(FitBox(views[i], moves_, start_, labels_, full[i]));
  const double n = static_cast<double>(views.size());
  const double view_width = (kWidth - 2 * kSide - kGap * (n - 1)) / n;
  const double width = view_width - kLeft - kRight, height = kHeight - kTop - kBottom - kAbove - kBelow;
  const double scale = FitScale(boxes, width, height);  // one scale for every view: X reads alike in both
  for (std::size_t i = 0; i < views.size(); ++i) {
    const double left = kSide + static_cast<double>(i) * (view_width + kGap) + kLeft;
    const Frame f = PlaceFrame(boxes[i], left, kTop + kAbove, width, height, scale);
    DrawView(out, views[i], f, Clipped(full[i], f), moves_, labels_, start_);
  }
  out += Legend();
  return out + "</svg>\n";
}

}  // namespace cell::interp
