#pragma once
/// \file
/// The construction site and the workpiece: ground plane, the boundary the base must stay in,
/// walls and static obstacles, the brick feeder, and the bricks placed so far. Loaded from a site
/// YAML (data/sites/*.yaml); the site frame is the workpiece reference (the stack's origin).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "ifab/core/se2.h"
#include "ifab/core/se3.h"
#include "ifab/model/geometry.h"

namespace ifab {

class ConfigNode;

/// A box-shaped thing on the site (wall, obstacle, feeder, brick).
struct SiteBox {
  std::string name;
  Pose3 T_site_box{Pose3::Identity()};  ///< pose of the box centre
  Box box;
};

struct Site {
  double ground_z{0.0};                   ///< height of the floor in the site frame [m]
  std::vector<Eigen::Vector2d> boundary;  ///< polygon (CCW) the base footprint must stay inside
  std::vector<SiteBox> walls;             ///< physical walls (seen by the base laser)
  std::vector<SiteBox> obstacles;         ///< static obstacles, the feeder among them
  Box brick;                              ///< brick size (default German DF 240 x 115 x 52 mm)
  Pose2 stack_origin;                     ///< where the stack is built (x, y, yaw of its bricks)
  std::vector<SiteBox> bricks;            ///< bricks placed so far

  /// Everything solid as primitives in the site frame (ground plane first), for ray casting and
  /// registration.
  std::vector<RigidObject> Objects() const;
  /// Footprints (convex polygons in the ground plane) of walls, obstacles and bricks: the planner's
  /// obstacles.
  std::vector<std::vector<Eigen::Vector2d>> ObstacleFootprints() const;
  /// Pose (centre) of brick number k (0 = on the ground) of the stack as designed.
  Pose3 DesignedBrickPose(int k) const;
};

/// Load a site YAML. Throws InputError naming the file, line and field.
Site LoadSite(const std::string& path);
Site SiteFromConfig(const ConfigNode& config);

/// Footprint of a box on the ground (its 4 bottom corners, CCW).
std::vector<Eigen::Vector2d> Footprint(const SiteBox& box);

}  // namespace ifab
