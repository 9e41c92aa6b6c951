#pragma once
/// \file
/// Geometric primitives of the site and workpiece model (paper Sec. V-A): infinite planes,
/// convex polygon faces and boxes. All share one interface (closest point, ray intersection,
/// bounds) and go through one conformance test suite. Coordinates are in the primitive's own
/// object frame; a RigidObject places its faces in the site with one pose.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "ifab/core/se3.h"

namespace ifab {

/// Which feature of a primitive a closest point lies on.
enum class Feature { kFace, kEdge, kVertex };

struct ClosestPoint {
  Eigen::Vector3d point{Eigen::Vector3d::Zero()};   ///< closest point on the primitive
  Eigen::Vector3d normal{Eigen::Vector3d::UnitZ()}; ///< outward normal of the face it lies on
  double distance{0.0};                             ///< |query - point|
  Feature feature{Feature::kFace};
};

/// Infinite plane {p : normal . p = offset}; its outward side is where normal points.
struct Plane {
  Eigen::Vector3d normal{Eigen::Vector3d::UnitZ()};  ///< unit
  double offset{0.0};
};

/// Planar convex polygon; vertices counter-clockwise seen from the outward normal.
class ConvexPolygon {
 public:
  ConvexPolygon() = default;
  /// Throws InputError if fewer than 3 vertices, not planar or not convex.
  explicit ConvexPolygon(std::vector<Eigen::Vector3d> vertices);
  const std::vector<Eigen::Vector3d>& vertices() const { return vertices_; }
  const Eigen::Vector3d& normal() const { return normal_; }
  double offset() const { return offset_; }
  /// True if p (assumed on the polygon's plane) lies inside or on the border.
  bool ContainsProjected(const Eigen::Vector3d& p) const;

 private:
  std::vector<Eigen::Vector3d> vertices_;
  Eigen::Vector3d normal_{Eigen::Vector3d::UnitZ()};
  double offset_{0.0};
};

/// Axis-aligned box centred on its object frame's origin.
struct Box {
  Eigen::Vector3d size{Eigen::Vector3d::Ones()};  ///< full edge lengths [m]
};

using Primitive = std::variant<Plane, ConvexPolygon, Box>;

/// Closest point on a primitive to p (all in the primitive's frame). For a box, a point inside
/// gets the nearest face point.
ClosestPoint Closest(const Primitive& primitive, const Eigen::Vector3d& p);

/// Ray o + t d (|d| = 1) against the primitive: the smallest t in (t_min, t_max) of an entering
/// hit, with the surface normal there.
struct RayHit {
  double t{0.0};
  Eigen::Vector3d normal{Eigen::Vector3d::UnitZ()};
};
std::optional<RayHit> IntersectRay(const Primitive& primitive, const Eigen::Vector3d& origin,
                                   const Eigen::Vector3d& direction, double t_min, double t_max);

/// Edges of a primitive as segments (none for a plane). Used to flag shadow points (Sec. V-B).
std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> Edges(const Primitive& primitive);

/// The six faces of a box as convex polygons (outward normals).
std::vector<ConvexPolygon> BoxFaces(const Box& box);

/// Axis-aligned bounds of a primitive placed at T_site_object; nullopt for an infinite plane.
struct Aabb {
  Eigen::Vector3d lo{Eigen::Vector3d::Constant(1e300)}, hi{Eigen::Vector3d::Constant(-1e300)};
  void Extend(const Eigen::Vector3d& p) { lo = lo.cwiseMin(p); hi = hi.cwiseMax(p); }
  void Extend(const Aabb& b) { lo = lo.cwiseMin(b.lo); hi = hi.cwiseMax(b.hi); }
  /// Slab test: does the ray (with precomputed 1/d) meet the box within [t_min, t_max]?
  bool HitByRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& inv_direction, double t_min,
                double t_max) const;
};
std::optional<Aabb> Bounds(const Primitive& primitive, const Pose3& T_site_object);

/// Distance between a segment [a, b] and the ray o + t d, t in [0, t_max].
double SegmentRayDistance(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                          const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double t_max);

/// A rigid object: primitives sharing one pose in the site (a brick: a box, or six faces).
struct RigidObject {
  std::string name;
  Pose3 T_site_object{Pose3::Identity()};
  std::vector<Primitive> primitives;  ///< in the object frame
};

}  // namespace ifab
