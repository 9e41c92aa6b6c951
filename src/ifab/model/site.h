#pragma once
/// \file
/// The construction site and the workpiece: ground plane, the boundary the base must stay in,
/// walls and static obstacles, the brick feeder, the bricks placed so far, and any other rigid
/// objects made of infinite planes, convex polygon faces and boxes (a calibration board, a
/// stand). Loaded from a site YAML (data/sites/*.yaml); the site frame is the workpiece reference
/// (the stack's origin), or for `ifab register --frame sensor` the cloud's own frame.
///
/// Poses in YAML: `pose: [x, y, z, roll, pitch, yaw]` (metres, radians; a rotation beyond +-pi
/// is taken for degrees and rejected) or `xyz: [x, y, z]` with `rpy_deg: [roll, pitch, yaw]`.

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

/// A rigid object of primitives (planes, polygons, boxes) that share one pose.
struct SiteObject {
  std::string name;
  Pose3 T_site_object{Pose3::Identity()};
  std::vector<RigidObject> parts;  ///< each part's T_site_object is read as T_object_part
};

struct Site {
  bool has_ground{true};                  ///< a horizontal floor plane (YAML: only if ground_z is given)
  double ground_z{0.0};                   ///< height of the floor in the site frame [m]
  std::vector<Eigen::Vector2d> boundary;  ///< polygon (CCW) the base footprint must stay inside;
                                          ///< empty if the YAML has none (only planning needs it)
  std::vector<SiteBox> walls;             ///< physical walls (seen by the base laser)
  std::vector<SiteBox> obstacles;         ///< static obstacles, the feeder among them
  Box brick;                              ///< brick size (default German DF 240 x 115 x 52 mm)
  Pose2 stack_origin;                     ///< where the stack is built (x, y, yaw of its bricks)
  std::vector<SiteBox> bricks;            ///< bricks placed so far
  std::vector<SiteObject> objects;        ///< planes:, polygons:, boxes: and objects: of the YAML

  /// Everything solid as primitives in the site frame (ground plane first, if any), for ray
  /// casting and registration; each SiteObject's parts come out placed in the site.
  std::vector<RigidObject> Objects() const;
  /// The rigid bodies of the site, each with its parts (T_site_object = T_body_part): "ground"
  /// (if any), then every wall, obstacle, brick and object by its name.
  std::vector<SiteObject> Bodies() const;
  /// Throws InputError naming `file` if there is no boundary (the commands that plan need it).
  void RequireBoundary(const std::string& file, const std::string& command) const;
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
