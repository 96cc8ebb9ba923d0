// Part model for probe simulation: a solid made of planes (half-spaces), bosses, spheres, minus bores.
// Format (toml, documented in docs/axis-servo.md):
//   [[plane]]  point = [x,y,z]  normal = [nx,ny,nz]      material on the side opposite the normal
//   [[boss]]   base = [x,y,z]   axis = [ax,ay,az]  diameter = D  height = H
//   [[sphere]] center = [x,y,z] diameter = D
//   [[bore]]   top = [x,y,z]    axis = [ax,ay,az]  diameter = D  depth = H   (hole, open above `top`)
// Coordinates are machine X Y Z in mm; on a lathe X is a radius here (the physical coordinate).
#pragma once

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace cell::servo {

class PartModel {
 public:
  struct Plane {
    Eigen::Vector3d point, normal;
  };
  struct Cylinder {
    Eigen::Vector3d base, axis;
    double radius, height;
  };
  struct Sphere {
    Eigen::Vector3d center;
    double radius;
  };

  void AddPlane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal);
  void AddBoss(const Eigen::Vector3d& base, const Eigen::Vector3d& axis, double diameter, double height);
  void AddSphere(const Eigen::Vector3d& center, double diameter);
  // A hole of `diameter` going `depth` from `top` against `axis` (axis points out of the hole).
  void AddBore(const Eigen::Vector3d& top, const Eigen::Vector3d& axis, double diameter, double depth);

  bool empty() const { return planes_.empty() && bosses_.empty() && spheres_.empty(); }

  // Distance bound from p to the material (negative inside); exact away from CSG edges.
  double Distance(const Eigen::Vector3d& p) const;

  // First point on the straight path a -> b where a ball of `ball_radius` centred on the path touches the
  // material. Returns the fraction t in [0,1] of the path, or a negative value when there is no contact.
  double FirstContact(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double ball_radius) const;

 private:
  std::vector<Plane> planes_;
  std::vector<Cylinder> bosses_;
  std::vector<Sphere> spheres_;
  std::vector<Cylinder> bores_;
};

// Throws cell::Error(kInvalidArgument) naming file, key and allowed range; kNotFound if missing.
PartModel LoadPartModel(const std::filesystem::path& file);
PartModel ParsePartModel(std::string_view toml_text, const std::string& source);

}  // namespace cell::servo
