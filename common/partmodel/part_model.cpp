#include "cell/partmodel/part_model.h"

#include <fmt/format.h>

#include <toml++/toml.h>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include "cell/error/error.h"
#include "cell/toml/parse.h"

namespace cell::partmodel {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

// Exact distance to a capped cylinder (base, unit axis, radius, height); negative inside.
double CylinderDistance(const PartModel::Cylinder& c, const Eigen::Vector3d& p) {
  Eigen::Vector3d d = p - c.base;
  double h = d.dot(c.axis);
  double r = (d - h * c.axis).norm();
  double dr = r - c.radius;
  double dh = std::max(-h, h - c.height);
  double outside = std::hypot(std::max(dr, 0.0), std::max(dh, 0.0));
  return outside + std::min(std::max(dr, dh), 0.0);
}

// Exact distance to a box given in its own frame (centre at the origin, half sizes); negative inside.
double BoxDistance(const PartModel::Box& b, const Eigen::Vector3d& p) {
  Eigen::Vector3d q = (b.to_box * (p - b.center)).cwiseAbs() - b.half;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

Eigen::Matrix3d Rotation(int axis, double deg) {
  return Eigen::AngleAxisd(deg * kDeg, Eigen::Vector3d::Unit(axis)).toRotationMatrix();
}

}  // namespace

void PartModel::AddPlane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal) {
  planes_.push_back({point, normal.normalized()});
}

void PartModel::AddBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max,
                       const Eigen::Vector3d& rotate) {
  Eigen::Matrix3d r = Rotation(2, rotate.z()) * Rotation(1, rotate.y()) * Rotation(0, rotate.x());
  boxes_.push_back({(min + max) / 2, (max - min).cwiseAbs() / 2, r.transpose()});
}

void PartModel::AddBoss(const Eigen::Vector3d& base, const Eigen::Vector3d& axis, double diameter,
                        double height) {
  bosses_.push_back({base, axis.normalized(), diameter / 2, height});
}

void PartModel::AddSphere(const Eigen::Vector3d& center, double diameter) {
  spheres_.push_back({center, diameter / 2});
}

void PartModel::AddBore(const Eigen::Vector3d& top, const Eigen::Vector3d& axis, double diameter,
                        double depth) {
  // The hole region runs from the bottom up past the top by a large margin so that it is open above.
  Eigen::Vector3d a = axis.normalized();
  bores_.push_back({top - depth * a, a, diameter / 2, depth + 1e6});
}

void PartModel::SetRotaryCentre(int axis, const Eigen::Vector3d& point) {
  rotary_.at(static_cast<size_t>(axis)) = point;
}

double PartModel::Distance(const Eigen::Vector3d& p) const {
  double d = std::numeric_limits<double>::infinity();
  for (const auto& pl : planes_) d = std::min(d, (p - pl.point).dot(pl.normal));
  for (const auto& b : boxes_) d = std::min(d, BoxDistance(b, p));
  for (const auto& b : bosses_) d = std::min(d, CylinderDistance(b, p));
  for (const auto& s : spheres_) d = std::min(d, (p - s.center).norm() - s.radius);
  for (const auto& h : bores_) d = std::max(d, -CylinderDistance(h, p));
  return d;
}

Eigen::Vector3d PartModel::ToModel(const Pose& m) const {
  Eigen::Vector3d p(m[0], m[1], m[2]);
  // A table at +angle turned the part clockwise seen from the axis's positive end (a right-hand turn by
  // -angle); the model point under the probe is found by turning back (+angle), C first, then B, then A.
  for (int axis = 2; axis >= 0; --axis) {
    const auto& c = rotary_[static_cast<size_t>(axis)];
    if (!c || m[3 + axis] == 0) continue;
    p = *c + Rotation(axis, m[3 + axis]) * (p - *c);
  }
  return p;
}

double PartModel::Distance(const Pose& machine) const {
  return Distance(ToModel(machine));
}

double PartModel::Speed(const Pose& from, const Pose& to) const {
  Eigen::Vector3d a(from[0], from[1], from[2]), b(to[0], to[1], to[2]);
  double v = (b - a).norm();
  for (int axis = 0; axis < 3; ++axis) {
    const auto& c = rotary_[static_cast<size_t>(axis)];
    double turn = std::fabs(to[3 + axis] - from[3 + axis]) * kDeg;
    if (!c || turn == 0) continue;
    // A point at radius r from the axis moves r * turn; r is at most the larger end radius plus the
    // linear travel (the path is a straight line between the ends).
    double r = std::max((a - *c).norm(), (b - *c).norm()) + v;
    v += r * turn;
  }
  return v;
}

Trip PartModel::Probe(bool make, const Pose& from, const Pose& to, double ball_radius) const {
  Trip trip;
  if (empty()) {
    if (!make) trip.kind = Trip::kAlready;  // nothing to touch: never in contact
    return trip;
  }
  auto at = [&](double t) {
    Pose p;
    for (size_t i = 0; i < p.size(); ++i) p[i] = from[i] + t * (to[i] - from[i]);
    return p;
  };
  // gap > 0: not touching; the event is where the sign of the gap reaches the requested state.
  auto gap = [&](double t) { return Distance(at(t)) - ball_radius; };
  auto reached = [&](double g) { return make ? g <= 0.0 : g > 0.0; };
  if (reached(gap(0.0))) {
    trip.kind = Trip::kAlready;
    trip.t = 0.0;
    return trip;
  }
  const double speed = Speed(from, to);
  if (speed <= 0.0) return trip;
  // Sphere tracing: the distance bound never over-estimates, and no model point moves faster than `speed`,
  // so a step of |gap| / speed cannot pass over a change of state. A floor keeps grazing paths finite;
  // bisection refines the step in which the state changed.
  const double min_step = 1e-4 / speed;
  double t = 0.0;
  while (t < 1.0) {
    double g = gap(t);
    double next = std::min(1.0, t + std::max(std::fabs(g) / speed, min_step));
    if (reached(gap(next))) {
      double lo = t, hi = next;
      for (int i = 0; i < 80 && (hi - lo) * speed > 1e-10; ++i) {
        double mid = 0.5 * (lo + hi);
        (reached(gap(mid)) ? hi : lo) = mid;
      }
      trip.kind = Trip::kEvent;
      trip.t = hi;
      return trip;
    }
    t = next;
  }
  return trip;
}

namespace {

// The line format: `box XMIN YMIN ZMIN XMAX YMAX ZMAX` per line, `#` comments. True when the text is in it
// (its first statement starts with the word `box` and a number, which toml cannot).
bool IsLineFormat(std::string_view text) {
  std::istringstream in{std::string(text)};
  std::string line;
  while (std::getline(in, line)) {
    line.resize(std::min(line.size(), line.find('#')));
    std::istringstream ls(line);
    std::string kw;
    double v = 0;
    if (!(ls >> kw)) continue;
    return kw == "box" && static_cast<bool>(ls >> v);
  }
  return false;
}

PartModel ParseLineFormat(std::string_view text, const std::string& source) {
  PartModel m;
  std::istringstream in{std::string(text)};
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    line.resize(std::min(line.size(), line.find('#')));
    std::istringstream ls(line);
    std::string kw, extra;
    Eigen::Vector3d lo, hi;
    if (!(ls >> kw)) continue;
    if (kw != "box" || !(ls >> lo[0] >> lo[1] >> lo[2] >> hi[0] >> hi[1] >> hi[2]) || (ls >> extra))
      throw Error(Errc::kInvalidArgument,
                  fmt::format("{}:{}: expected 'box XMIN YMIN ZMIN XMAX YMAX ZMAX' (mm)", source, n));
    if (!(hi.array() > lo.array()).all())
      throw Error(Errc::kInvalidArgument,
                  fmt::format("{}:{}: box max must be greater than min on every axis", source, n));
    m.AddBox(lo, hi);
  }
  m.set_point_contact(true);
  return m;
}

}  // namespace

PartModel ParsePartModel(std::string_view text, const std::string& source) {
  if (IsLineFormat(text)) return ParseLineFormat(text, source);
  toml::table root = tomlfile::Parse(text, source);
  auto fail = [&](const std::string& key, const std::string& why) -> void {
    throw Error(Errc::kInvalidArgument, fmt::format("{}: {}: {}", source, key, why));
  };
  auto vec = [&](const toml::table& t, const std::string& prefix, const char* key) {
    const toml::array* a = t[key].as_array();
    Eigen::Vector3d v;
    if (!a || a->size() != 3) fail(prefix + key, "missing or not an array of 3 numbers [x, y, z] (mm)");
    for (size_t i = 0; i < 3; ++i) {
      auto d = (*a)[i].value<double>();
      if (!d || !std::isfinite(*d)) fail(prefix + key, "must be an array of 3 finite numbers");
      v[static_cast<Eigen::Index>(i)] = *d;
    }
    return v;
  };
  auto num = [&](const toml::table& t, const std::string& prefix, const char* key, double hi) {
    auto d = t[key].value<double>();
    if (!d) fail(prefix + key, fmt::format("missing; allowed range (0, {:g}] mm", hi));
    if (!(*d > 0 && *d <= hi)) fail(prefix + key, fmt::format("{:g} is outside (0, {:g}] mm", *d, hi));
    return *d;
  };
  auto unit = [&](const toml::table& t, const std::string& prefix, const char* key) {
    Eigen::Vector3d v = vec(t, prefix, key);
    if (v.norm() < 1e-9) fail(prefix + key, "must be a non-zero direction");
    return v;
  };
  auto only = [&](const toml::table& t, const std::string& prefix, std::initializer_list<const char*> keys) {
    for (auto&& [k, v] : t) {
      (void)v;
      bool ok = false;
      for (const char* want : keys) ok = ok || k.str() == want;
      if (!ok) {
        std::string allowed;
        for (const char* want : keys) allowed += fmt::format("{}{}", allowed.empty() ? "" : ", ", want);
        fail(prefix + std::string(k.str()), "unknown key; allowed " + allowed);
      }
    }
  };
  PartModel m;
  for (auto&& [key, node] : root) {
    std::string k(key.str());
    if (k == "rotary") {
      const toml::table* t = node.as_table();
      if (!t) fail(k, "must be a table ([rotary])");
      only(*t, "rotary.", {"a_center", "b_center", "c_center"});
      for (int axis = 0; axis < 3; ++axis) {
        const char* name = axis == 0 ? "a_center" : axis == 1 ? "b_center" : "c_center";
        if (t->contains(name)) m.SetRotaryCentre(axis, vec(*t, "rotary.", name));
      }
      continue;
    }
    if (k != "plane" && k != "box" && k != "boss" && k != "sphere" && k != "bore")
      fail(k, "unknown feature; allowed [[plane]], [[box]], [[boss]], [[sphere]], [[bore]], [rotary]");
    const toml::array* arr = node.as_array();
    if (!arr) fail(k, fmt::format("must be an array of tables ([[{}]])", k));
    for (size_t i = 0; i < arr->size(); ++i) {
      const toml::table* t = (*arr)[i].as_table();
      std::string prefix = fmt::format("{}[{}].", k, i);
      if (!t) fail(k, "must be an array of tables");
      if (k == "plane") {
        only(*t, prefix, {"point", "normal"});
        m.AddPlane(vec(*t, prefix, "point"), unit(*t, prefix, "normal"));
      } else if (k == "box") {
        only(*t, prefix, {"min", "max", "rotate"});
        Eigen::Vector3d lo = vec(*t, prefix, "min"), hi = vec(*t, prefix, "max");
        if (!(hi.array() > lo.array()).all()) fail(prefix + "max", "must be greater than min on every axis");
        Eigen::Vector3d rot = t->contains("rotate") ? vec(*t, prefix, "rotate") : Eigen::Vector3d::Zero();
        m.AddBox(lo, hi, rot);
      } else if (k == "boss") {
        only(*t, prefix, {"base", "axis", "diameter", "height"});
        m.AddBoss(vec(*t, prefix, "base"), unit(*t, prefix, "axis"), num(*t, prefix, "diameter", 1e4),
                  num(*t, prefix, "height", 1e4));
      } else if (k == "sphere") {
        only(*t, prefix, {"center", "diameter"});
        m.AddSphere(vec(*t, prefix, "center"), num(*t, prefix, "diameter", 1e4));
      } else {
        only(*t, prefix, {"top", "axis", "diameter", "depth"});
        m.AddBore(vec(*t, prefix, "top"), unit(*t, prefix, "axis"), num(*t, prefix, "diameter", 1e4),
                  num(*t, prefix, "depth", 1e4));
      }
    }
  }
  return m;
}

PartModel LoadPartModel(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw Error(Errc::kNotFound, fmt::format("{}: part model not found", file.string()));
  std::stringstream ss;
  ss << in.rdbuf();
  return ParsePartModel(ss.str(), file.string());
}

}  // namespace cell::partmodel
