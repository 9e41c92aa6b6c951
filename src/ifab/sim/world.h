#pragma once
/// \file
/// The simulated world: the site's static geometry plus the bricks placed so far, with a ray
/// caster fast enough for 40 Hz scans (object bounding boxes, bricks grouped under one box).
/// Part of sim: this is ground truth.

#include <optional>
#include <vector>

#include "ifab/model/geometry.h"
#include "ifab/model/site.h"

namespace ifab::sim {

struct WorldHit {
  double range{0.0};                                 ///< distance along the ray [m]
  Eigen::Vector3d normal{Eigen::Vector3d::UnitZ()};  ///< surface normal at the hit (site frame)
  int object{-1};                                    ///< index into objects(), -1 for the ground
};

class World {
 public:
  explicit World(Site site);

  const Site& site() const { return site_; }
  /// Add a brick (true pose) to the world.
  void AddBrick(const SiteBox& brick);
  const std::vector<SiteBox>& bricks() const { return site_.bricks; }
  /// Faults (faults.h): an obstacle that appears and goes, every brick moved by T (a bump).
  void AddObstacle(const SiteBox& obstacle);
  bool RemoveObstacle(const std::string& name);
  void MoveBricks(const Pose3& T);

  /// First surface hit by the ray origin + t * direction (|direction| = 1), t in (t_min, t_max).
  std::optional<WorldHit> CastRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                                  double t_min, double t_max) const;

  /// Height of the highest surface below (x, y) among bricks and obstacles (ground otherwise);
  /// used to settle a released brick.
  double SupportHeight(double x, double y, double half_extent) const;

 private:
  struct Entry {
    Pose3 T_object_site;  // inverse pose, for casting in the object frame
    Box box;
    Aabb bounds;
  };
  void Rebuild();

  Site site_;
  std::vector<Entry> statics_;  // walls and obstacles
  std::vector<Entry> bricks_;
  Aabb bricks_bounds_;
};

}  // namespace ifab::sim
