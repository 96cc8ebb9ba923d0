// The offline machine of cell-interp: queue busters answered at once. Probe moves run against the cell's
// part model (cell_part_model, `--probe-model FILE`, the same toml the axis servo reads) with a probe ball
// of PROBE_BALL_DIAMETER mm (--params, default 6 as the station's probe.ball_diameter; 0 for a model in
// the line format); without a model
// nothing is ever touched. The clock and system parameters come from --params when given (CLOCK=YYYY-MM-DD
// HH:MM:SS for DAT and inspection-file stamps, L3000-L3999 for what the machine would report, e.g.
// L3060=345879 the control's serial number), so a run's output is reproducible.
#pragma once

#include <array>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <optional>
#include <string>

#include "cell/interp/interp.h"
#include "cell/partmodel/part_model.h"

namespace cell::interp {

class OfflineEnvironment : public Environment {
 public:
  // Reads the settings above from the run's params; returns "" or a one-line reason.
  std::string Configure(const std::map<std::string, std::string>& params) {
    for (const auto& [key, value] : params) {
      if (key == "PROBE_BALL_DIAMETER") {
        char* end = nullptr;
        double d = std::strtod(value.c_str(), &end);
        if (end == value.c_str() || !(d >= 0 && d <= 50)) return "PROBE_BALL_DIAMETER must be 0-50 (mm)";
        ball_radius_ = d / 2;
        ball_given_ = true;
      } else if (key == "CLOCK") {
        std::array<int, 6> t{};
        if (std::sscanf(value.c_str(), "%d-%d-%d%*[ T]%d:%d:%d", &t[0], &t[1], &t[2], &t[3], &t[4], &t[5]) <
            5)
          return "CLOCK must be YYYY-MM-DD HH:MM[:SS]";
        clock_ = t;
      } else if (key.size() == 5 && key[0] == 'L' && key[1] == '3') {
        char* end = nullptr;
        double v = std::strtod(value.c_str(), &end);
        if (end == value.c_str()) return key + " must be a number";
        system_[key] = v;
      }
    }
    return "";
  }
  // A model in the line format is point contact (part_model.h): no ball unless the params name one.
  void SetPartModel(partmodel::PartModel m) {
    part_ = std::move(m);
    if (part_.point_contact() && !ball_given_) ball_radius_ = 0;
  }

  ProbeResult Probe(const ProbeMove& m) override {
    ProbeResult r;
    r.at = m.to;
    // The part model is in machine coordinates of the stylus ball's centre: Z less the probe's length (to the
    // ball's tip) plus the ball's radius.
    const double dz = ball_radius_ - m.length;
    partmodel::Pose from = {m.from[kX], m.from[kY], m.from[kZ] + dz, m.from[kA], m.from[kB], m.from[kC]};
    partmodel::Pose to = {m.to[kX], m.to[kY], m.to[kZ] + dz, m.to[kA], m.to[kB], m.to[kC]};
    partmodel::Trip t = part_.Probe(m.make, from, to, ball_radius_);
    if (t.kind == partmodel::Trip::kAlready) {
      r.already = true;
      r.at = m.from;
    } else if (t.kind == partmodel::Trip::kEvent) {
      r.event = true;
      for (size_t i = 0; i < r.at.size(); ++i) r.at[i] = m.from[i] + t.t * (m.to[i] - m.from[i]);
    }
    return r;
  }
  std::optional<double> SystemVariable(const std::string& name) override {
    auto it = system_.find(name);
    if (it == system_.end()) return std::nullopt;
    return it->second;
  }
  std::array<int, 6> Now() override { return clock_ ? *clock_ : Environment::Now(); }

 private:
  partmodel::PartModel part_;
  double ball_radius_ = 3.0;
  bool ball_given_ = false;
  std::optional<std::array<int, 6>> clock_;
  std::map<std::string, double> system_;
};

}  // namespace cell::interp
