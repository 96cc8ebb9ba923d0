#include "cell/servo/part_model.h"

#include <fmt/format.h>

#include <toml++/toml.h>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "cell/error/error.h"

namespace cell::servo {
namespace {

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

}  // namespace

void PartModel::AddPlane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal) {
  planes_.push_back({point, normal.normalized()});
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

double PartModel::Distance(const Eigen::Vector3d& p) const {
  double d = std::numeric_limits<double>::infinity();
  for (const auto& pl : planes_) d = std::min(d, (p - pl.point).dot(pl.normal));
  for (const auto& b : bosses_) d = std::min(d, CylinderDistance(b, p));
  for (const auto& s : spheres_) d = std::min(d, (p - s.center).norm() - s.radius);
  for (const auto& h : bores_) d = std::max(d, -CylinderDistance(h, p));
  return d;
}

double PartModel::FirstContact(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double ball_radius) const {
  if (empty()) return -1.0;
  const double len = (b - a).norm();
  auto gap = [&](double t) { return Distance(a + t * (b - a)) - ball_radius; };
  if (gap(0.0) <= 0.0) return 0.0;
  if (len <= 0.0) return -1.0;
  // Sphere tracing: Distance() never over-estimates the distance to the material, so stepping by the gap
  // cannot jump over a contact. A floor on the step keeps grazing paths finite; bisection refines.
  const double min_step = 1e-4 / len;
  double t = 0.0;
  while (t < 1.0) {
    double g = gap(t);
    double next = std::min(1.0, t + std::max(g / len, min_step));
    if (gap(next) <= 0.0) {
      double lo = t, hi = next;
      for (int i = 0; i < 60 && (hi - lo) * len > 1e-9; ++i) {
        double mid = 0.5 * (lo + hi);
        (gap(mid) <= 0.0 ? hi : lo) = mid;
      }
      return hi;
    }
    if (next >= 1.0) break;
    t = next;
  }
  return -1.0;
}

PartModel ParsePartModel(std::string_view text, const std::string& source) {
  toml::table root;
  try {
    root = toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    throw Error(Errc::kInvalidArgument, fmt::format("{}:{}:{}: {}", source, e.source().begin.line,
                                                    e.source().begin.column, e.description()));
  }
  auto fail = [&](const std::string& key, const std::string& why) -> void {
    throw Error(Errc::kInvalidArgument, fmt::format("{}: {}: {}", source, key, why));
  };
  auto vec = [&](const toml::table& t, const std::string& prefix, const char* key) {
    const toml::array* a = t[key].as_array();
    Eigen::Vector3d v;
    if (!a || a->size() != 3) fail(prefix + key, "missing or not an array of 3 numbers [x, y, z] (mm)");
    for (int i = 0; i < 3; ++i) {
      auto d = (*a)[i].value<double>();
      if (!d || !std::isfinite(*d)) fail(prefix + key, "must be an array of 3 finite numbers");
      v[i] = *d;
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
  PartModel m;
  for (auto&& [key, node] : root) {
    std::string k(key.str());
    if (k != "plane" && k != "boss" && k != "sphere" && k != "bore")
      fail(k, "unknown feature; allowed [[plane]], [[boss]], [[sphere]], [[bore]]");
    const toml::array* arr = node.as_array();
    if (!arr) fail(k, fmt::format("must be an array of tables ([[{}]])", k));
    for (size_t i = 0; i < arr->size(); ++i) {
      const toml::table* t = (*arr)[i].as_table();
      std::string prefix = fmt::format("{}[{}].", k, i);
      if (!t) fail(k, "must be an array of tables");
      if (k == "plane") m.AddPlane(vec(*t, prefix, "point"), unit(*t, prefix, "normal"));
      if (k == "boss")
        m.AddBoss(vec(*t, prefix, "base"), unit(*t, prefix, "axis"), num(*t, prefix, "diameter", 1e4),
                  num(*t, prefix, "height", 1e4));
      if (k == "sphere") m.AddSphere(vec(*t, prefix, "center"), num(*t, prefix, "diameter", 1e4));
      if (k == "bore")
        m.AddBore(vec(*t, prefix, "top"), unit(*t, prefix, "axis"), num(*t, prefix, "diameter", 1e4),
                  num(*t, prefix, "depth", 1e4));
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

}  // namespace cell::servo
