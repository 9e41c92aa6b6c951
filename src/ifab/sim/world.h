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

/// An uneven floor: ground_z plus a smooth height field, a sum of plane waves (as-built draw,
/// data/sim/as_built.yaml). Empty: the flat floor z = ground_z.
struct FloorField {
  struct Wave {
    Eigen::Vector2d k{Eigen::Vector2d::Zero()};  ///< wave vector [rad/m]
    double amplitude{0.0};                       ///< [m]
    double phase{0.0};                           ///< [rad]
  };
  std::vector<Wave> waves;
  bool flat() const { return waves.empty(); }
  /// Height above ground_z at (x, y) [m].
  double Height(double x, double y) const;
  /// d(height)/dx, d(height)/dy.
  Eigen::Vector2d Gradient(double x, double y) const;
  /// The DIN 18202 step measure over points `distance` apart: the largest deviation of the floor
  /// at a chord's midpoint from the straight line through its ends, over a grid of chords in the
  /// box [lo, hi] [m].
  double WorstStep(double distance, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) const;
};

struct WorldHit {
  double range{0.0};                                 ///< distance along the ray [m]
  Eigen::Vector3d normal{Eigen::Vector3d::UnitZ()};  ///< surface normal at the hit (site frame)
  int object{-1};                                    ///< index into objects(), -1 for the ground
};

class World {
 public:
  explicit World(Site site, FloorField floor = {});

  const Site& site() const { return site_; }
  /// Add a brick (true pose) to the world.
  void AddBrick(const SiteBox& brick);
  const std::vector<SiteBox>& bricks() const { return site_.bricks; }
  const FloorField& floor() const { return floor_; }
  /// Floor height at (x, y) in the site frame [m].
  double FloorHeight(double x, double y) const { return site_.ground_z + floor_.Height(x, y); }
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
  /// The ray's first hit on the floor within (t_min, t_max) (flat: one plane; uneven: Newton on
  /// the height field from the flat floor's hit).
  std::optional<WorldHit> IntersectGround(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min,
                                          double t_max) const;

  Site site_;
  FloorField floor_;
  double floor_top_{0.0};  // ground_z + the sum of the waves' amplitudes: no floor point is higher
  std::vector<Entry> statics_;  // walls and obstacles
  std::vector<Entry> bricks_;
  Aabb bricks_bounds_;
};

}  // namespace ifab::sim
