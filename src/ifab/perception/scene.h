#pragma once
/// \file
/// The model a cloud is registered to (paper Sec. V-A): rigid bodies made of primitives, each
/// body with a pose in the robot base frame. Scene flattens them and answers, under the current
/// poses, the three questions registration asks of every point: which primitive is closest (eq. 7),
/// which face its ray hits first, and whether its ray grazes an edge (shadow points, Sec. V-B).

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ifab/core/se3.h"
#include "ifab/model/geometry.h"

namespace ifab {

/// An object whose pose in the base frame registration estimates: one or more RigidObjects (parts)
/// fixed to each other, e.g. a brick, the ground plane, or the whole site.
struct RegistrationBody {
  std::string name;
  Pose3 T_base_body{Pose3::Identity()};  ///< initial guess
  std::vector<RigidObject> parts;        ///< each part's T_site_object is read as T_body_part
  bool free{true};                       ///< false: held at its guess (still competes for points)
  std::array<bool, 6> fixed{};           ///< [x y z rx ry rz] (cloud frame axes, through the body
                                         ///< origin) held at the guess, e.g. z and tilt set by a floor
};

/// One primitive of one body, with its placement under the current poses.
struct ScenePrimitive {
  int body{0};
  Primitive primitive;
  Pose3 T_body_primitive{Pose3::Identity()};
  Pose3 T_primitive_body{Pose3::Identity()};
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> edges;  ///< in the primitive frame
  // Under the current body poses (SetPoses):
  Pose3 T_base_primitive{Pose3::Identity()};
  Pose3 T_primitive_base{Pose3::Identity()};
  std::optional<Aabb> bounds;  ///< in base; nullopt for an infinite plane
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> edges_base;
};

class Scene {
 public:
  explicit Scene(const std::vector<RegistrationBody>& bodies);

  /// Place every body (one pose per body, in the order given to the constructor).
  void SetPoses(const std::vector<Pose3>& T_base_body);

  struct Nearest {
    int primitive{-1};
    double distance{0.0};
    Eigen::Vector3d point{Eigen::Vector3d::Zero()};  ///< closest point, base frame
    Eigen::Vector3d normal{Eigen::Vector3d::UnitZ()};  ///< outward normal of its face, base frame
    Feature feature{Feature::kFace};
  };
  /// The primitive closest to p (base frame); primitive < 0 if the scene is empty.
  Nearest Closest(const Eigen::Vector3d& p_base) const;

  struct Hit {
    int primitive{-1};
    double t{0.0};
    Eigen::Vector3d normal{Eigen::Vector3d::UnitZ()};  ///< outward normal of the hit face, base
  };
  /// First entering hit of the ray origin + t direction, t in (0, t_max).
  std::optional<Hit> CastRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                             double t_max) const;

  /// True if the segment origin + t direction, t in [0, t_max], passes within `distance` of an edge.
  bool RayPassesNearEdge(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                         double t_max, double distance) const;

  const std::vector<ScenePrimitive>& primitives() const { return primitives_; }
  int num_bodies() const { return num_bodies_; }
  /// Half the diagonal of a body's finite primitives (0 if it has only planes): the lever arm
  /// used to compare rotations with translations.
  double Extent(int body) const { return extents_[static_cast<std::size_t>(body)]; }

 private:
  std::vector<ScenePrimitive> primitives_;
  std::vector<double> extents_;
  int num_bodies_{0};
};

}  // namespace ifab
