// One part in every dialect of its kind (issue 33 item 3, docs/testing.md "Parts"): the finished contour of
// each program, in the part's frame, and where two of them first differ. The moves are compare.cpp's (the
// differential's parser of cell-interp's output: mm, machine frame, x a radius).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "cell/oracle/oracle.h"

namespace cell::oracle {
namespace {

std::vector<std::string> ProgramLines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

// A line's 1-based number: a number as it stands, or an N-word the line begins with (N101 matches "N101 G00"
// and "N101G00", not "N1010").
int LineOf(const std::string& word, const std::vector<std::string>& lines) {
  if (!word.empty() && std::isdigit(static_cast<unsigned char>(word[0]))) return std::atoi(word.c_str());
  for (std::size_t i = 0; i < lines.size(); ++i) {
    auto at = lines[i].find_first_not_of(" \t");
    if (at == std::string::npos || lines[i].compare(at, word.size(), word) != 0) continue;
    auto next = at + word.size();
    if (next >= lines[i].size() || !std::isdigit(static_cast<unsigned char>(lines[i][next])))
      return static_cast<int>(i) + 1;
  }
  return 0;
}

// "A-B,C" (each a line number or an N-word) as ranges.
bool Ranges(const std::string& spec, const std::vector<std::string>& lines, std::vector<LineRange>* out) {
  std::stringstream ss(spec);
  for (std::string item; std::getline(ss, item, ',');) {
    auto dash = item.find('-');
    LineRange r{LineOf(item.substr(0, dash), lines), 0};
    r.last = dash == std::string::npos ? r.first : LineOf(item.substr(dash + 1), lines);
    if (r.first <= 0 || r.last < r.first) return false;
    out->push_back(r);
  }
  return true;
}

// One `program FILE key value ...` line of part.txt.
bool ReadProgram(std::stringstream& words, const std::string& dir, PartProgram* p, std::string* error) {
  words >> p->file;
  auto lines = ProgramLines(dir + "/" + p->file);
  if (lines.empty()) return *error = "no program " + dir + "/" + p->file, false;
  for (std::string key, value; words >> key >> value;) {
    bool ok = true;
    if (key == "dialect")
      p->dialect = value;
    else if (key == "params")
      p->params = value;
    else if (key == "tools")
      p->tools = value;
    else if (key == "finish")
      ok = Ranges(value, lines, &p->finish);
    else if (key == "thread")
      ok = Ranges(value, lines, &p->thread);
    else if (key == "bottoms")
      ok = Ranges(value, lines, &p->bottoms);
    else if (key == "pass")
      ok = (p->last_pass = value == "last");
    else if (key == "corner-arcs")
      ok = (p->corner_arcs = std::atof(value.c_str())) > 0;
    else if (key == "origin")
      ok = std::sscanf(value.c_str(), "%lf,%lf,%lf", &p->origin[0], &p->origin[1], &p->origin[2]) == 3;
    else
      ok = false;
    if (!ok) return *error = p->file + ": bad '" + key + " " + value + "'", false;
  }
  if (p->dialect.empty() || p->finish.empty()) return *error = p->file + ": needs dialect and finish", false;
  return true;
}

bool InRanges(int line, const std::vector<LineRange>& ranges) {
  for (const LineRange& r : ranges)
    if (line >= r.first && line <= r.last) return true;
  return false;
}

double Dist(const Vec3& a, const Vec3& b) {
  return std::hypot(std::hypot(a[0] - b[0], a[1] - b[1]), a[2] - b[2]);
}

// Whether line p0-p1 continued by p1-p2 is one straight line: p1 within tol of p0-p2, the same way on.
bool Collinear(const Vec3& p0, const Vec3& p1, const Vec3& p2, double tol) {
  Vec3 u{}, v{};
  double dot = 0;
  for (int i = 0; i < 3; ++i) u[i] = p2[i] - p0[i], v[i] = p1[i] - p0[i], dot += u[i] * v[i];
  double len = Dist(p0, p2);
  if (len < tol || dot <= 0 || dot >= len * len) return false;
  double t = dot / (len * len);
  Vec3 foot{p0[0] + u[0] * t, p0[1] + u[1] * t, p0[2] + u[2] * t};
  return Dist(foot, p1) < tol;
}

// The same circle on: an arc split in two (at a quadrant, a block boundary) is one element.
bool SameArc(const Move& a, const Move& b, double tol) {
  return a.kind == MoveKind::kArc && b.kind == MoveKind::kArc && a.plane == b.plane && a.cw == b.cw &&
         Dist(a.center, b.center) < tol;
}

// Adds an element at `from`, joining it to the last one where they are one line or one arc cut on.
void Append(Contour& c, const Vec3& from, Move m, double tol) {
  if (m.kind == MoveKind::kLine && Dist(from, m.end) < tol) return;  // goes nowhere
  if (!c.elements.empty() && Dist(c.elements.back().end, from) < tol) {
    Move& last = c.elements.back();
    if ((last.kind == MoveKind::kLine && m.kind == MoveKind::kLine &&
         Collinear(c.starts.back(), from, m.end, tol)) ||
        SameArc(last, m, tol)) {
      last.end = m.end;
      return;
    }
  }
  c.starts.push_back(from);
  c.elements.push_back(m);
}

std::optional<std::string> ElementField(const Move& a, const Move& b, double tol) {
  static const char* axes = "xyz";
  if (a.kind != b.kind) return std::string("kind");
  for (int i = 0; i < 3; ++i)
    if (std::fabs(a.end[i] - b.end[i]) > tol) return std::string("end ") + axes[i];
  if (a.kind == MoveKind::kThread && std::fabs(a.feed - b.feed) > tol) return std::string("lead");
  if (a.kind != MoveKind::kArc) return std::nullopt;
  if (a.plane != b.plane) return std::string("plane");
  static const std::array<std::array<int, 2>, 3> in_plane{{{0, 1}, {2, 0}, {1, 2}}};
  for (int i : in_plane[static_cast<std::size_t>(a.plane - 17)])
    if (std::fabs(a.center[i] - b.center[i]) > tol) return std::string("centre ") + axes[i];
  if (a.cw != b.cw) return std::string("direction");
  return std::nullopt;
}

// Where lines a0-a1 and b0-b1 meet, in the plane of axes (i, j); false when parallel.
bool Meet(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1, int i, int j, Vec3* at) {
  double dx = a1[i] - a0[i], dy = a1[j] - a0[j], ex = b1[i] - b0[i], ey = b1[j] - b0[j];
  double den = dx * ey - dy * ex;
  if (std::fabs(den) < 1e-12) return false;
  double t = ((b0[i] - a0[i]) * ey - (b0[j] - a0[j]) * ex) / den;
  *at = a0;
  (*at)[i] += dx * t, (*at)[j] += dy * t;
  return true;
}

// An outside-corner arc of radius r between two lines becomes the corner where the lines meet.
void CornerArcsToPoints(Contour& c, double r, double tol) {
  static const std::array<std::array<int, 2>, 3> in_plane{{{0, 1}, {2, 0}, {1, 2}}};
  for (std::size_t k = 1; k + 1 < c.elements.size(); ++k) {
    const Move& arc = c.elements[k];
    if (arc.kind != MoveKind::kArc || std::fabs(Dist(arc.end, arc.center) - r) > tol) continue;
    Move& before = c.elements[k - 1];
    const Move& after = c.elements[k + 1];
    if (before.kind != MoveKind::kLine || after.kind != MoveKind::kLine) continue;
    if (Dist(before.end, c.starts[k]) > tol || Dist(arc.end, c.starts[k + 1]) > tol) continue;
    auto [i, j] = in_plane[static_cast<std::size_t>(arc.plane - 17)];
    Vec3 at{};
    if (!Meet(c.starts[k - 1], before.end, c.starts[k + 1], after.end, i, j, &at)) continue;
    before.end = at;
    c.starts[k + 1] = at;
    c.elements.erase(c.elements.begin() + static_cast<std::ptrdiff_t>(k));
    c.starts.erase(c.starts.begin() + static_cast<std::ptrdiff_t>(k));
  }
}

// The plunges on `ranges` that end at the least x, as points (kSet, starting where they end).
void AppendBottoms(Contour& c, const std::vector<Move>& moves, const std::vector<LineRange>& ranges,
                   const Vec3& origin, double tol) {
  std::vector<Move> feeds;
  double least = 1e300;
  for (const Move& m : moves)
    if (m.kind == MoveKind::kLine && InRanges(m.line, ranges))
      feeds.push_back(m), least = std::min(least, m.end[0]);
  for (Move m : feeds) {
    if (m.end[0] > least + tol) continue;
    for (int i = 0; i < 3; ++i) m.end[i] -= origin[i];
    m.kind = MoveKind::kSet;
    c.starts.push_back(m.end);
    c.elements.push_back(m);
  }
}

}  // namespace

bool ReadPart(const std::string& dir, Part* part, std::string* error) {
  std::ifstream in(dir + "/part.txt");
  if (!in) return *error = "no " + dir + "/part.txt", false;
  part->name = dir.substr(dir.find_last_of('/') + 1);
  for (std::string line; std::getline(in, line);) {
    std::stringstream words(line);
    std::string head;
    if (!(words >> head) || head[0] == '#') continue;
    PartProgram p;
    if (head != "program" || !ReadProgram(words, dir, &p, error)) {
      if (error->empty()) *error = dir + "/part.txt: not a program line: " + line;
      return false;
    }
    part->programs.push_back(p);
  }
  if (part->programs.size() < 2) return *error = dir + ": a part needs two programs", false;
  return true;
}

Contour FinishedContour(const std::vector<Move>& moves, const PartProgram& p, double tol) {
  Contour c;
  Vec3 pos{}, thread_from{};
  const Move* thread = nullptr;
  auto local = [&](Vec3 v) {
    for (int i = 0; i < 3; ++i) v[i] -= p.origin[i];
    return v;
  };
  std::vector<std::pair<Vec3, Move>> cut;  // where each finish move starts, and the move
  for (const Move& m : moves) {
    Move e = m;
    e.end = local(m.end);
    e.center = local(m.center);
    if ((m.kind == MoveKind::kLine || m.kind == MoveKind::kArc) && InRanges(m.line, p.finish)) {
      if (p.last_pass && !cut.empty() && m.line < cut.back().second.line) cut.clear();  // a pass again
      cut.emplace_back(pos, e);
    }
    if (m.kind == MoveKind::kThread && InRanges(m.line, p.thread)) thread = &m, thread_from = pos;
    pos = e.end;
  }
  for (const auto& [from, e] : cut) Append(c, from, e, tol);
  if (p.corner_arcs > 0) CornerArcsToPoints(c, p.corner_arcs, tol);
  if (!p.bottoms.empty()) AppendBottoms(c, moves, p.bottoms, p.origin, tol);
  if (thread) {  // the last pass is the finished thread
    Move t = *thread;
    t.end = local(t.end);
    c.starts.push_back(thread_from);
    c.elements.push_back(t);
  }
  return c;
}

std::optional<Disagreement> CompareContours(const Contour& a, const Contour& b, double tol) {
  std::size_t n = std::min(a.elements.size(), b.elements.size());
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k)
      if (std::fabs(a.starts[i][k] - b.starts[i][k]) > tol)
        return Disagreement{i + 1, std::string("start ") + "xyz"[k], ""};
    if (auto f = ElementField(a.elements[i], b.elements[i], tol)) return Disagreement{i + 1, *f, ""};
  }
  if (a.elements.size() != b.elements.size())
    return Disagreement{n + 1, "element count",
                        std::to_string(a.elements.size()) + " against " + std::to_string(b.elements.size())};
  return std::nullopt;
}

}  // namespace cell::oracle
