// The cell's one part model for probing (cell_part_model): the solid a spindle probe touches, used by the
// axis servo (per pallet, `[probe] parts` in the station file or a model from the program store) and by the
// offline interpreter (`cell-interp --probe-model FILE`). Format (toml, documented in docs/axis-servo.md):
//   [[plane]]  point = [x,y,z]  normal = [nx,ny,nz]      half-space: material opposite the normal
//   [[box]]    min = [x,y,z]    max = [x,y,z]   rotate = [rx,ry,rz]   a block (a step, a pad, an angled
//                                                      face when rotated: degrees about X, Y, Z, in that
//                                                      order, about the block's centre)
//   [[boss]]   base = [x,y,z]   axis = [ax,ay,az]  diameter = D  height = H
//   [[sphere]] center = [x,y,z] diameter = D
//   [[bore]]   top = [x,y,z]    axis = [ax,ay,az]  diameter = D  depth = H   (hole, open above `top`)
//   [rotary]   a_center = [x,y,z]  b_center = [..]  c_center = [..]   a point on each rotary table's axis
// Coordinates are machine X Y Z in mm with every rotary table at 0; on a lathe X is a radius here.
// The solid is (planes, boxes, bosses, spheres) minus bores.
// The first format of `--probe-model` is still read: lines `box XMIN YMIN ZMIN XMAX YMAX ZMAX` (mm, `#`
// comments). It described where the probe's latch point stops, so such a model is a point-contact model
// (point_contact(): the offline machine then uses no ball unless PROBE_BALL_DIAMETER is given).
#pragma once

#include <Eigen/Core>
#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace cell::partmodel {

// A machine position as the part model needs it: x y z (mm, the probe ball's centre), a b c (degrees).
using Pose = std::array<double, 6>;

// Where a probe move changes state: already in the requested state at its start (no motion), the event at
// fraction `t` of the move, or no event over the whole move.
struct Trip {
  enum Kind { kNone, kAlready, kEvent } kind = kNone;
  double t = 1.0;
};

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
  struct Box {
    Eigen::Vector3d center, half;
    Eigen::Matrix3d to_box;  // model frame -> the box's own frame (the inverse of its rotation)
  };

  void AddPlane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal);
  // A block between `min` and `max`, turned by `rotate_deg` (about X, then Y, then Z) about its centre.
  void AddBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max,
              const Eigen::Vector3d& rotate_deg = Eigen::Vector3d::Zero());
  void AddBoss(const Eigen::Vector3d& base, const Eigen::Vector3d& axis, double diameter, double height);
  void AddSphere(const Eigen::Vector3d& center, double diameter);
  // A hole of `diameter` going `depth` from `top` against `axis` (axis points out of the hole).
  void AddBore(const Eigen::Vector3d& top, const Eigen::Vector3d& axis, double diameter, double depth);
  // The part sits on rotary table `axis` (0 A about X, 1 B about Y, 2 C about Z) whose axis passes through
  // `point`. A positive table angle turns the part clockwise seen from the positive end of the axis (KT-APL:
  // positive B is clockwise). Tables are applied A, then B, then C.
  void SetRotaryCentre(int axis, const Eigen::Vector3d& point);

  bool empty() const { return planes_.empty() && boxes_.empty() && bosses_.empty() && spheres_.empty(); }
  // Read from the line format: its surfaces are where the latch point stops (no ball).
  bool point_contact() const { return point_contact_; }
  void set_point_contact(bool v) { point_contact_ = v; }

  // Distance bound from p (model frame, tables at 0) to the material: negative inside; never larger than the
  // true distance (sphere tracing relies on it), exact away from CSG edges.
  double Distance(const Eigen::Vector3d& p) const;
  // The same for a probe centre at a machine position (the rotary tables applied).
  double Distance(const Pose& machine) const;

  // A straight probe move from `from` to `to` (linear and rotary axes interpolated together). `make`: the
  // first point where a ball of `ball_radius` centred on the path touches the material (G22); otherwise
  // the first point where it no longer touches (G23). Touching means Distance <= ball_radius.
  Trip Probe(bool make, const Pose& from, const Pose& to, double ball_radius) const;

 private:
  Eigen::Vector3d ToModel(const Pose& machine) const;
  // A bound on how fast a model point moves per unit of t along the move.
  double Speed(const Pose& from, const Pose& to) const;

  std::vector<Plane> planes_;
  std::vector<Box> boxes_;
  std::vector<Cylinder> bosses_;
  std::vector<Sphere> spheres_;
  std::vector<Cylinder> bores_;
  std::array<std::optional<Eigen::Vector3d>, 3> rotary_;
  bool point_contact_ = false;
};

// Throws cell::Error(kInvalidArgument) naming the source, the key and the allowed range; kNotFound if the
// file is missing.
PartModel LoadPartModel(const std::filesystem::path& file);
PartModel ParsePartModel(std::string_view toml_text, const std::string& source);

}  // namespace cell::partmodel
