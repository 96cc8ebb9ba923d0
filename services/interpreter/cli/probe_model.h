// Offline probe model for cell-interp --probe-model: the part is a set of axis-aligned boxes (millimetres).
//   # comment
//   box XMIN YMIN ZMIN XMAX YMAX ZMAX
// A G22 move stops where the probe centre first enters a box; a G23 move stops where it leaves one.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "cell/interp/interp.h"

namespace cell::interp {

class ProbeModelEnvironment : public Environment {
 public:
  bool Load(const std::string& text, std::string* err) {
    std::istringstream in(text);
    std::string line;
    int n = 0;
    while (std::getline(in, line)) {
      ++n;
      auto hash = line.find('#');
      if (hash != std::string::npos) line.resize(hash);
      std::istringstream ls(line);
      std::string kw;
      if (!(ls >> kw)) continue;
      Box b;
      if (kw != "box" || !(ls >> b.lo[0] >> b.lo[1] >> b.lo[2] >> b.hi[0] >> b.hi[1] >> b.hi[2])) {
        *err = "line " + std::to_string(n) + ": expected 'box XMIN YMIN ZMIN XMAX YMAX ZMAX'";
        return false;
      }
      boxes_.push_back(b);
    }
    return true;
  }

  ProbeResult Probe(bool contact, const std::array<double, kAxisCount>& from,
                    const std::array<double, kAxisCount>& to) override {
    ProbeResult r;
    r.at = to;
    bool inside0 = Inside(from);
    if (inside0 == contact) {
      r.already = true;
      r.at = from;
      return r;
    }
    // March along the move (0.001 mm steps, bisection refine) to find the state change.
    double len = 0;
    for (int i = 0; i < 3; ++i) len += (to[i] - from[i]) * (to[i] - from[i]);
    int steps = static_cast<int>(std::min(200000.0, std::max(1.0, std::sqrt(len) / 0.01)));
    double prev = 0;
    for (int k = 1; k <= steps; ++k) {
      double t = static_cast<double>(k) / steps;
      if (Inside(At(from, to, t)) == contact) {
        double lo = prev, hi = t;
        for (int it = 0; it < 40; ++it) {
          double mid = (lo + hi) / 2;
          (Inside(At(from, to, mid)) == contact ? hi : lo) = mid;
        }
        r.event = true;
        r.at = At(from, to, hi);
        return r;
      }
      prev = t;
    }
    return r;
  }

 private:
  struct Box {
    double lo[3], hi[3];
  };
  static std::array<double, kAxisCount> At(const std::array<double, kAxisCount>& a,
                                           const std::array<double, kAxisCount>& b, double t) {
    std::array<double, kAxisCount> r{};
    for (int i = 0; i < kAxisCount; ++i) r[i] = a[i] + (b[i] - a[i]) * t;
    return r;
  }
  bool Inside(const std::array<double, kAxisCount>& p) const {
    for (const auto& b : boxes_) {
      if (p[0] >= b.lo[0] && p[0] <= b.hi[0] && p[1] >= b.lo[1] && p[1] <= b.hi[1] && p[2] >= b.lo[2] &&
          p[2] <= b.hi[2]) {
        return true;
      }
    }
    return false;
  }
  std::vector<Box> boxes_;
};

}  // namespace cell::interp
