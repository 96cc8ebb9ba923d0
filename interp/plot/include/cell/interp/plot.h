// A program's toolpath drawn from its canonical commands as one plain SVG (no scripts, no styles from
// outside): a machining centre as plan (XY) and elevation (XZ) side by side at one scale, a lathe as the XZ
// half-section (Z to the right, X as the radius upward, the diameter labelled). Rapids dashed, feed moves
// solid, arcs as SVG arcs in the view of their plane (polylines in the other view), cycle moves, threads and
// probe moves marked, tool changes and rotary indexing annotated; scale bar, units and extents on the page.
// docs/plot.md says what each mark means.
//
//   cell::interp::Plot plot({dialect.machine(), "GEAR.MIN (okuma)"});
//   for (each canonical command c of the run) plot.Add(c);
//   std::string svg = plot.Svg();
#pragma once

#include <array>
#include <string>
#include <vector>

#include "cell/interp/canon.h"
#include "cell/interp/dialect.h"

namespace cell::interp {

// An arc as an SVG arc command draws it, from its start, end and centre in a view's coordinates (first
// axis right, second up, millimetres), `ccw` the sense seen in that view and `angle` the degrees swept.
struct ViewArc {
  double r = 0;
  bool large = false;  // large-arc-flag: more than 180 degrees
  bool sweep = false;  // sweep-flag: clockwise on the page (the page's y points down)
};
ViewArc ToViewArc(double sx, double sy, double cx, double cy, bool ccw, double angle);

struct PlotOptions {
  MachineKind machine = MachineKind::kMachiningCentre;  // the dialect's or the station's (docs/plot.md)
  std::string title;                                    // what the page is headed with (program, dialect)
};

class Plot {
 public:
  explicit Plot(PlotOptions options);
  // Every command of a run, in order; those without motion or annotation are ignored.
  void Add(const Canon& c);
  // A line under the title, e.g. the diagnostic of a run that stopped.
  void SetNote(std::string note) { note_ = std::move(note); }
  std::string Svg() const;

  enum class MoveKind { kRapid, kFeed, kArc, kThread, kProbe };
  // "rapid", "feed", "arc", "thread", "probe": the SVG's class names and the dashboard's JSON kinds.
  static const char* KindName(MoveKind kind);
  // Motion ops drawn so far (each is one path element per view; the first motion op only sets where the
  // path starts: the position before it is the machine's, which the program does not say).
  int Drawn(MoveKind kind) const;

  struct Move {
    MoveKind kind = MoveKind::kFeed;
    int line = 0;
    int block = 0;  // consecutive ops of one program line share a block (cycle detection)
    std::array<double, 3> from{}, to{};  // X Y Z in mm, X as a radius
    // Arcs
    std::array<double, 3> center{};
    int first = kX, second = kY;  // the plane as the program selected it
    bool cw = true;
    double angle = 0;
    bool contact = false;  // probe: the probe touched
  };
  struct Label {
    std::array<double, 3> at{};
    std::string text;
  };
  // What a live view overlays the page with (the dashboard): the drawn moves in order (the SVG's
  // `data-seq` is the index here) and where the path starts; nothing when the run made no move.
  const std::vector<Move>& moves() const { return moves_; }
  bool started() const { return started_; }
  const std::array<double, 3>& start() const { return start_; }

 private:
  void AddMove(const Canon& c, MoveKind kind, const Target& to);
  void AddLabel(std::string text);
  std::array<double, 3> Point(const Target& t) const;

  PlotOptions options_;
  std::string note_;
  bool diameter_ = false;  // X values are diameters (units op x_mode)
  bool started_ = false;
  std::array<double, 3> at_{};
  int last_line_ = -1;
  int block_ = 0;
  std::vector<Move> moves_;
  std::vector<Label> labels_;
  std::vector<std::string> pending_;  // labels before the first position is known: placed at the start
  std::array<double, 3> start_{};
};

}  // namespace cell::interp
