#pragma once
/// \file
/// The 2D world the base planner sees (paper Sec. III: "the base navigation sub-system assumes a
/// 2D world"): a site boundary polygon, convex obstacle footprints (the brick stack, the feeder,
/// anything already built), and the robot's rectangular footprint and tracks. Independent of the
/// 3D site model; the caller projects the site onto the ground plane.

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "ifab/core/config.h"
#include "ifab/core/se2.h"

namespace ifab::base {

/// Planar scene in the site frame [m].
struct PlanningScene {
  std::vector<Eigen::Vector2d> boundary;  ///< site boundary polygon (may be non-convex); empty = no boundary
  std::vector<std::vector<Eigen::Vector2d>> obstacles;  ///< convex obstacle footprints
  std::vector<std::string> obstacle_names;              ///< optional, one per obstacle (messages)

  /// Throw InputError if a polygon is degenerate or an obstacle is not convex.
  void Validate() const;
};

/// Rectangular footprint and skid-steer tracks of the base.
struct BaseGeometry {
  double length{1.8};  ///< footprint extent along base x [m]
  double width{1.2};   ///< footprint extent along base y [m]
  Eigen::Vector2d footprint_offset{0.0, 0.0};  ///< footprint centre in the base frame [m]
  double track_gauge{1.0};      ///< distance between the track centre lines B [m]
  double max_track_speed{0.3};  ///< highest admissible track speed [m/s]

  /// Reads the `base` section of data/robots/insitu_fabricator_base.yaml (footprint, tracks).
  static BaseGeometry FromConfig(const ConfigNode& base);
  /// Loads `path` and reads its `base` section.
  static BaseGeometry Load(const std::string& path);

  /// Footprint corners in the site frame, counter-clockwise.
  std::array<Eigen::Vector2d, 4> Corners(const Pose2& T_site_base) const;
  /// Radius of the circle around the footprint centre that holds the footprint.
  double CircumRadius() const { return 0.5 * std::hypot(length, width); }
};

/// Signed distance between two convex polygons (counter-clockwise vertex lists; a polygon of two
/// vertices is a segment): the Euclidean distance when apart, minus the penetration depth when they
/// overlap.
double SignedDistanceConvex(const Eigen::Vector2d* a, int na, const Eigen::Vector2d* b, int nb);

/// True if p lies inside the polygon (crossing number; any orientation).
bool PointInPolygon(const std::vector<Eigen::Vector2d>& polygon, const Eigen::Vector2d& p);

/// Clearance queries of the robot footprint against a scene. Immutable after construction and
/// safe to share between threads.
class FootprintChecker {
 public:
  FootprintChecker(PlanningScene scene, BaseGeometry robot);

  /// Signed clearance [m] of the footprint at T_site_base to the boundary and every obstacle:
  /// negative when it overlaps an obstacle or leaves the boundary.
  double Clearance(const Pose2& T_site_base) const;

  /// Clearance, also naming what is closest ("boundary" or the obstacle's name).
  double Clearance(const Pose2& T_site_base, std::string* closest) const;

  /// Obstacle cost of STOMP (non-smooth): sum over the boundary and each obstacle of
  /// max(0, margin - d) plus collision_penalty if d < 0. Objects farther than margin cost
  /// nothing and are culled by bounding circles.
  double Cost(const Pose2& T_site_base, double margin, double collision_penalty) const;
  /// The same, with cos and sin of T_site_base.theta already at hand.
  double Cost(const Pose2& T_site_base, double cos_theta, double sin_theta, double margin,
              double collision_penalty) const;

  /// True if the centre of the footprint is inside the boundary (or there is no boundary).
  bool CentreInsideBoundary(const Pose2& T_site_base) const;
  /// Index of an obstacle overlapping the footprint, or -1.
  int OverlappingObstacle(const Pose2& T_site_base) const;
  /// Largest clearance an inscribed disc of the footprint could have at point p: used by the
  /// reachability grid (distance from p to the nearest object, negative inside).
  double PointClearance(const Eigen::Vector2d& p_site) const;

  const PlanningScene& scene() const { return scene_; }
  const BaseGeometry& robot() const { return robot_; }

 private:
  // A convex polygon (or a segment: two vertices, one edge) with outward unit edge normals and a
  // bounding circle, all in the site frame.
  struct Convex {
    std::vector<Eigen::Vector2d> vertices;
    std::vector<Eigen::Vector2d> normals;  // normals[i] of edge vertices[i] -> vertices[i+1]
    int num_edges{0};
    Eigen::Vector2d centre{0, 0};
    double radius{0.0};
  };
  // The footprint at one pose: centre and rotation of the box.
  struct Box {
    Eigen::Vector2d centre;
    double c, s;
  };
  Box MakeBox(const Pose2& T_site_base) const;
  // Signed distance; when it is at least `cull`, a lower bound >= cull may be returned instead.
  double BoxDistance(const Box& box, const Convex& poly, double cull) const;
  double BoundaryClearance(const Box& box, double cull) const;
  static Convex MakeConvex(const std::vector<Eigen::Vector2d>& vertices, bool segment);

  PlanningScene scene_;
  BaseGeometry robot_;
  double hx_{0.9}, hy_{0.6};      // footprint half extents
  std::vector<Convex> obstacles_;  // counter-clockwise
  std::vector<Convex> edges_;      // boundary edges as segments
};

}  // namespace ifab::base
