// Both interpreters' output as one list of moves (machine coordinates, mm, x a radius), and the comparison.
#include <cmath>
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cell/oracle/oracle.h"

namespace cell::oracle {
namespace {

// cell-interp's plane names: the NGC plane and whether the pair is that plane's reverse (seen from the other
// side, so the sense flips; DESIGN §4).
bool PlaneOf(const std::string& name, int* plane, bool* flipped) {
  static const std::map<std::string, std::pair<int, bool>> planes{{"xy", {17, false}}, {"yx", {17, true}},
                                                                  {"zx", {18, false}}, {"xz", {18, true}},
                                                                  {"yz", {19, false}}, {"zy", {19, true}}};
  auto it = planes.find(name);
  if (it == planes.end()) return false;
  *plane = it->second.first;
  *flipped = it->second.second;
  return true;
}

Move CellMove(const nlohmann::json& j, bool lathe, Vec3& pos, Vec3& rot) {
  Move m;
  const std::string op = j["op"];
  m.kind = op == "rapid" ? MoveKind::kRapid : op == "arc" ? MoveKind::kArc : MoveKind::kLine;
  m.line = j.value("line", 0);
  const char* keys[] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i)
    if (j.contains(keys[i])) pos[i] = j[keys[i]].get<double>() / (lathe && i == 0 ? 2 : 1);
  m.end = pos;
  const char* rkeys[] = {"a", "b", "c"};
  for (int i = 0; i < 3; ++i)
    if (j.contains(rkeys[i])) rot[i] = j[rkeys[i]].get<double>();
  for (int i = 0; i < 3; ++i) m.travel[i] = j.value(std::string(rkeys[i]) + "_travel", 0.0);
  m.rot = rot;
  m.feed = j.value("f", 0.0);
  m.per_rev = j.value("f_mode", std::string()) == "per_rev";
  m.inverse = j.value("f_mode", std::string()) == "inverse_time";
  if (m.kind == MoveKind::kArc) {
    for (int i = 0; i < 3; ++i) m.center[i] = j["center"][static_cast<std::size_t>(i)].get<double>();
    if (lathe) m.center[0] /= 2;
    bool flipped = false;
    PlaneOf(j.value("plane", std::string("xy")), &m.plane, &flipped);
    m.cw = (j.value("dir", std::string()) == "cw") != flipped;
    double angle = j.value("angle", 0.0);
    m.turns = angle > 360 + 1e-6 ? static_cast<int>((angle - 1e-6) / 360) : 0;
  }
  return m;
}

// "   12 N..... NAME(a, b, ...)": the name and its numeric arguments.
bool CanonCall(const std::string& line, std::string* name, std::vector<double>* args, std::string* text) {
  auto n = line.find("N..... ");
  if (n == std::string::npos) return false;
  auto open = line.find('(', n);
  if (open == std::string::npos) return false;
  *name = line.substr(n + 7, open - n - 7);
  *text = line.substr(open + 1, line.rfind(')') - open - 1);
  args->clear();
  std::stringstream ss(*text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* endp = nullptr;
    double v = std::strtod(item.c_str(), &endp);
    if (endp != item.c_str()) args->push_back(v);
  }
  return true;
}

struct NgcState {
  double unit = 1;  // mm per unit
  Vec3 g5x{}, g92{};
  int plane = 17;
  double feed = 0;
  double feed_raw = 0;  // as programmed: a rotary-only move's F is deg/min in either unit
  Vec3 last{}, last_rot{};
  bool per_rev = false;
  Vec3 Machine(const Vec3& p) const {
    Vec3 m;
    for (int i = 0; i < 3; ++i) m[i] = p[i] * unit + g5x[i] + g92[i];
    return m;
  }
};

// ARC_FEED(first_end, second_end, first_centre, second_centre, rotation, normal_end, ...) in the plane's
// (first, second, normal) order: XY (x y z), XZ (z x y), YZ (y z x).
Move NgcArc(const std::vector<double>& a, const NgcState& st) {
  static const std::map<int, std::array<int, 3>> order{{17, {0, 1, 2}}, {18, {2, 0, 1}}, {19, {1, 2, 0}}};
  const auto& o = order.at(st.plane);
  Vec3 end{}, c{};
  end[o[0]] = a[0], end[o[1]] = a[1], end[o[2]] = a[5];
  c[o[0]] = a[2], c[o[1]] = a[3], c[o[2]] = a[5];
  Move m;
  m.kind = MoveKind::kArc;
  m.end = st.Machine(end);
  m.center = st.Machine(c);
  m.plane = st.plane;
  m.cw = a[4] < 0;
  m.turns = static_cast<int>(std::fabs(a[4])) - 1;
  return m;
}

}  // namespace

std::vector<Move> ParseCellInterp(const std::string& json_lines, bool lathe, std::string* error,
                                  bool threads) {
  std::vector<Move> out;
  std::stringstream ss(json_lines);
  std::string line;
  Vec3 pos{}, rot{}, regrid{};
  while (std::getline(ss, line)) {
    if (line.empty()) continue;
    auto j = nlohmann::json::parse(line, nullptr, false);
    if (j.is_discarded() || !j.contains("op")) {
      *error = "cell-interp wrote a line that is not a JSON op: " + line;
      return out;
    }
    const std::string op = j["op"];
    if (op == "rapid" || op == "linear" || op == "arc") {
      Move m = CellMove(j, lathe, pos, rot);
      for (int i = 0; i < 3; ++i) m.end[i] += regrid[i], m.center[i] += regrid[i];
      out.push_back(m);
    }
    if (op == "thread" && threads) {
      Move m = CellMove(j, lathe, pos, rot);
      m.kind = MoveKind::kThread;
      m.feed = j.value("lead", 0.0);
      for (int i = 0; i < 3; ++i) m.end[i] += regrid[i];
      out.push_back(m);
    }
    if (op == "regrid") {  // KT-APL G92: the present position is renamed; positions after it are in that grid
      const char* keys[] = {"x", "y", "z"};
      for (int i = 0; i < 3; ++i)
        if (j.contains(keys[i])) {
          double v = j[keys[i]].get<double>() / (lathe && i == 0 ? 2 : 1);
          regrid[i] += pos[i] - v;
          pos[i] = v;
        }
    }
  }
  return out;
}

std::vector<Move> ParseRs274(const std::string& canon, bool lathe, std::string* error) {
  (void)lathe;  // rs274 reports x as a radius in G7 already
  std::vector<Move> out;
  std::stringstream ss(canon);
  std::string line, name, text;
  std::vector<double> a;
  NgcState st;
  while (std::getline(ss, line)) {
    if (!CanonCall(line, &name, &a, &text)) continue;
    if (name == "USE_LENGTH_UNITS") st.unit = text.find("INCHES") != std::string::npos ? 25.4 : 1.0;
    if (name == "SET_G5X_OFFSET" && a.size() >= 4) st.g5x = {a[1] * st.unit, a[2] * st.unit, a[3] * st.unit};
    if (name == "SET_G92_OFFSET" && a.size() >= 3) st.g92 = {a[0] * st.unit, a[1] * st.unit, a[2] * st.unit};
    if (name == "SELECT_PLANE")
      st.plane = text.find("XZ") != std::string::npos ? 18 : text.find("YZ") != std::string::npos ? 19 : 17;
    if (name == "SET_FEED_RATE" && !a.empty()) st.feed = a[0] * st.unit, st.feed_raw = a[0];
    if (name == "SET_FEED_MODE" && a.size() >= 2) st.per_rev = a[1] == 1;
    if (name == "STRAIGHT_TRAVERSE" || name == "STRAIGHT_FEED") {
      if (a.size() < 3) {
        *error = "rs274: short " + line;
        return out;
      }
      Move m;
      m.kind = name == "STRAIGHT_TRAVERSE" ? MoveKind::kRapid : MoveKind::kLine;
      m.end = st.Machine({a[0], a[1], a[2]});
      if (a.size() >= 6) m.rot = {a[3], a[4], a[5]};
      for (int i = 0; i < 3; ++i) m.travel[i] = m.rot[i] - st.last_rot[i];
      st.last_rot = m.rot;
      // After a G92 the same point comes back through other offsets: within 1e-6 mm, in inch within 1.5e-4 in
      // (rs274 prints the point and the offsets to 1e-4 in, so it may come back a step off; a generated
      // linear step is 0.0039 in at least, but a peck cycle's last peck may be one grid step: a move that
      // turns no rotary axis is linear).
      const double same = st.unit > 1 ? 1.5e-4 * st.unit : 1e-6;
      bool rotary_only = std::fabs(m.end[0] - st.last[0]) < same && std::fabs(m.end[1] - st.last[1]) < same &&
                         std::fabs(m.end[2] - st.last[2]) < same && m.travel != Vec3{};
      st.last = m.end;
      m.feed = rotary_only ? st.feed_raw : st.feed, m.per_rev = st.per_rev;
      m.floor = 0.1 * st.unit;  // LinuxCNC raises an inverse-time rate to 0.1 unit/min at least
      out.push_back(m);
    }
    if (name == "ARC_FEED") {
      if (a.size() < 6) {
        *error = "rs274: short " + line;
        return out;
      }
      Move m = NgcArc(a, st);
      st.last = m.end;
      if (a.size() >= 9) m.rot = {a[6], a[7], a[8]};
      m.feed = st.feed, m.per_rev = st.per_rev;
      m.floor = 0.1 * st.unit;  // LinuxCNC raises an inverse-time rate to 0.1 unit/min at least
      out.push_back(m);
    }
  }
  return out;
}

void DropStill(std::vector<Move>& moves) {
  Vec3 pos{}, rot{};
  std::vector<Move> kept;
  for (const Move& m : moves) {
    bool still = m.kind != MoveKind::kArc && std::fabs(m.end[0] - pos[0]) < 1e-9 &&
                 std::fabs(m.end[1] - pos[1]) < 1e-9 && std::fabs(m.end[2] - pos[2]) < 1e-9 && m.rot == rot &&
                 m.travel == Vec3{};
    pos = m.end;
    rot = m.rot;
    if (!still) kept.push_back(m);
  }
  moves.swap(kept);
}

void InverseToPerMinute(std::vector<Move>& moves) {
  Vec3 pos{};
  for (Move& m : moves) {
    if (m.inverse) {
      double len = 0;
      if (m.kind == MoveKind::kArc) {
        static const std::array<std::array<int, 3>, 3> order{{{0, 1, 2}, {2, 0, 1}, {1, 2, 0}}};
        const auto& o = order[static_cast<std::size_t>(m.plane - 17)];
        double r = std::hypot(pos[o[0]] - m.center[o[0]], pos[o[1]] - m.center[o[1]]);
        double a0 = std::atan2(pos[o[1]] - m.center[o[1]], pos[o[0]] - m.center[o[0]]);
        double a1 = std::atan2(m.end[o[1]] - m.center[o[1]], m.end[o[0]] - m.center[o[0]]);
        double sweep = m.cw ? a0 - a1 : a1 - a0;
        while (sweep <= 1e-12) sweep += 2 * M_PI;
        sweep += 2 * M_PI * m.turns;
        len = std::hypot(r * sweep, m.end[o[2]] - pos[o[2]]);
      } else {
        len = std::hypot(std::hypot(m.end[0] - pos[0], m.end[1] - pos[1]), m.end[2] - pos[2]);
      }
      m.feed *= len;
      m.inverse = false;
      m.was_inverse = true;
    }
    pos = m.end;
  }
}

std::string Describe(const Move& m) {
  char buf[256];
  const char* kind = m.kind == MoveKind::kRapid    ? "rapid"
                     : m.kind == MoveKind::kArc    ? "arc"
                     : m.kind == MoveKind::kThread ? "thread"
                     : m.kind == MoveKind::kSet    ? "point"
                                                   : "linear";
  std::snprintf(buf, sizeof buf, "%s to (%.4f, %.4f, %.4f) abc (%.4f, %.4f, %.4f)", kind, m.end[0], m.end[1],
                m.end[2], m.rot[0], m.rot[1], m.rot[2]);
  std::string s = buf;
  if (m.kind == MoveKind::kArc) {
    std::snprintf(buf, sizeof buf, " centre (%.4f, %.4f, %.4f) %s G%d turns %d", m.center[0], m.center[1],
                  m.center[2], m.cw ? "cw" : "ccw", m.plane, m.turns);
    s += buf;
  }
  if (m.kind != MoveKind::kRapid) {
    if (m.kind == MoveKind::kThread)
      std::snprintf(buf, sizeof buf, " lead %.4f mm", m.feed);
    else
      std::snprintf(buf, sizeof buf, " F%.4f %s", m.feed, m.per_rev ? "mm/rev" : "mm/min");
    s += buf;
  }
  return s;
}

namespace {

std::optional<std::string> FirstField(const Move& c, const Move& n, double tol) {
  const char* axes = "xyz";
  if (c.kind != n.kind) return "kind";
  for (int i = 0; i < 3; ++i)
    if (std::fabs(c.end[i] - n.end[i]) > tol) return std::string("end ") + axes[i];
  // Rotary positions: cell-interp states them in [0, 360) with the signed travel beside.
  for (int i = 0; i < 3; ++i) {
    double d = std::remainder(c.rot[i] - n.rot[i], 360.0);
    if (std::fabs(d) > tol) return std::string("end ") + "abc"[i];
    if (std::fabs(c.travel[i] - n.travel[i]) > tol) return std::string("travel ") + "abc"[i];
  }
  if (c.kind == MoveKind::kArc) {
    if (c.plane != n.plane) return "plane";
    // The centre in the plane: on a helix cell-interp states the normal axis at the start, rs274 at the end.
    static const std::array<std::array<int, 2>, 3> in_plane{{{0, 1}, {2, 0}, {1, 2}}};
    for (int i : in_plane[static_cast<std::size_t>(c.plane - 17)])
      if (std::fabs(c.center[i] - n.center[i]) > tol) return std::string("centre ") + axes[i];
    if (c.cw != n.cw) return "direction";
    if (c.turns != n.turns) return "turns";
  }
  if (c.kind != MoveKind::kRapid) {
    if (c.per_rev != n.per_rev) return "feed mode";
    bool floored = c.was_inverse && c.feed < n.floor && std::fabs(n.feed - n.floor) < tol;
    if (std::fabs(c.feed - n.feed) > tol && !floored) return "feed";
  }
  return std::nullopt;
}

}  // namespace

std::optional<Disagreement> Compare(const std::vector<Move>& cell, const std::vector<Move>& ngc, double tol) {
  std::size_t n = std::min(cell.size(), ngc.size());
  for (std::size_t i = 0; i < n; ++i)
    if (auto f = FirstField(cell[i], ngc[i], tol))
      return Disagreement{i, *f,
                          "cell-interp: " + Describe(cell[i]) + "\n  rs274:       " + Describe(ngc[i])};
  if (cell.size() != ngc.size())
    return Disagreement{
        n, "move count",
        "cell-interp " + std::to_string(cell.size()) + " moves, rs274 " + std::to_string(ngc.size())};
  return std::nullopt;
}

}  // namespace cell::oracle
