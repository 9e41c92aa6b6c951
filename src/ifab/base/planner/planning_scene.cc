#include "ifab/base/planner/planning_scene.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "ifab/core/error.h"

namespace ifab::base {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

double SignedArea(const std::vector<Eigen::Vector2d>& p) {
  double a = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) a += Cross(p[i], p[(i + 1) % p.size()]);
  return 0.5 * a;
}

double PointSegmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double l2 = ab.squaredNorm();
  const double t = l2 > 0.0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

// Largest separation of polygon b from polygon a along a's outward edge normals (a CCW).
double MaxSeparation(const Eigen::Vector2d* a, int na, const Eigen::Vector2d* b, int nb) {
  double best = -kInf;
  for (int i = 0; i < na; ++i) {
    const Eigen::Vector2d& p = a[i];
    const Eigen::Vector2d d = a[(i + 1) % na] - p;
    const double len = d.norm();
    if (len <= 0.0) continue;
    const Eigen::Vector2d n(d.y() / len, -d.x() / len);
    double m = kInf;
    for (int j = 0; j < nb; ++j) m = std::min(m, n.dot(b[j] - p));
    best = std::max(best, m);
  }
  return best;
}

double VertexEdgeDistance(const Eigen::Vector2d* a, int na, const Eigen::Vector2d* b, int nb) {
  double best = kInf;
  for (int i = 0; i < na; ++i) {
    for (int j = 0; j < nb; ++j) {
      best = std::min(best, PointSegmentDistance(a[i], b[j], b[(j + 1) % nb]));
    }
  }
  return best;
}

}  // namespace

double SignedDistanceConvex(const Eigen::Vector2d* a, int na, const Eigen::Vector2d* b, int nb) {
  const double sep = std::max(MaxSeparation(a, na, b, nb), MaxSeparation(b, nb, a, na));
  if (sep <= 0.0) return sep;
  return std::min(VertexEdgeDistance(a, na, b, nb), VertexEdgeDistance(b, nb, a, na));
}

bool PointInPolygon(const std::vector<Eigen::Vector2d>& polygon, const Eigen::Vector2d& p) {
  bool inside = false;
  const std::size_t n = polygon.size();
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
    const Eigen::Vector2d& a = polygon[i];
    const Eigen::Vector2d& b = polygon[j];
    if ((a.y() > p.y()) != (b.y() > p.y()) &&
        p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x()) {
      inside = !inside;
    }
  }
  return inside;
}

void PlanningScene::Validate() const {
  IFAB_THROW_UNLESS(boundary.empty() || boundary.size() >= 3,
                    "planning scene: boundary: expected at least 3 vertices, got {}", boundary.size());
  if (!boundary.empty()) {
    IFAB_THROW_UNLESS(std::abs(SignedArea(boundary)) > 1e-9,
                      "planning scene: boundary: expected a polygon of non-zero area");
  }
  IFAB_THROW_UNLESS(obstacle_names.empty() || obstacle_names.size() == obstacles.size(),
                    "planning scene: expected one name per obstacle, got {} names for {} obstacles",
                    obstacle_names.size(), obstacles.size());
  for (std::size_t k = 0; k < obstacles.size(); ++k) {
    const auto& o = obstacles[k];
    IFAB_THROW_UNLESS(o.size() >= 3, "planning scene: obstacles[{}]: expected at least 3 vertices, got {}",
                      k, o.size());
    const double area = SignedArea(o);
    IFAB_THROW_UNLESS(std::abs(area) > 1e-12, "planning scene: obstacles[{}]: expected non-zero area", k);
    for (std::size_t i = 0; i < o.size(); ++i) {
      const Eigen::Vector2d e0 = o[(i + 1) % o.size()] - o[i];
      const Eigen::Vector2d e1 = o[(i + 2) % o.size()] - o[(i + 1) % o.size()];
      IFAB_THROW_UNLESS(Cross(e0, e1) * area >= -1e-12,
                        "planning scene: obstacles[{}]: expected a convex polygon (vertex {} is reflex)",
                        k, (i + 1) % o.size());
    }
  }
}

BaseGeometry BaseGeometry::FromConfig(const ConfigNode& base) {
  base.ExpectKeys({"footprint", "tracks"});
  BaseGeometry g;
  const ConfigNode fp = base["footprint"];
  fp.ExpectKeys({"length", "width", "offset"});
  fp.ReadPositive("length", g.length);
  fp.ReadPositive("width", g.width);
  if (auto off = fp.Find("offset")) {
    const auto v = off->AsNumbers(2);
    g.footprint_offset = {v[0], v[1]};
  }
  const ConfigNode tracks = base["tracks"];
  tracks.ExpectKeys({"gauge", "max_speed"});
  tracks.ReadPositive("gauge", g.track_gauge);
  tracks.ReadPositive("max_speed", g.max_track_speed);
  return g;
}

BaseGeometry BaseGeometry::Load(const std::string& path) {
  return FromConfig(ConfigNode::LoadSection(path, "base"));
}

std::array<Eigen::Vector2d, 4> BaseGeometry::Corners(const Pose2& T_site_base) const {
  const double hl = 0.5 * length, hw = 0.5 * width;
  const Eigen::Vector2d o = footprint_offset;
  return {T_site_base * Eigen::Vector2d(o.x() - hl, o.y() - hw),
          T_site_base * Eigen::Vector2d(o.x() + hl, o.y() - hw),
          T_site_base * Eigen::Vector2d(o.x() + hl, o.y() + hw),
          T_site_base * Eigen::Vector2d(o.x() - hl, o.y() + hw)};
}

FootprintChecker::Convex FootprintChecker::MakeConvex(const std::vector<Eigen::Vector2d>& v, bool segment) {
  Convex c;
  c.vertices = v;
  c.num_edges = segment ? 1 : static_cast<int>(v.size());
  for (int i = 0; i < static_cast<int>(v.size()); ++i) {
    const Eigen::Vector2d d = v[(i + 1) % v.size()] - v[i];
    c.normals.push_back(Eigen::Vector2d(d.y(), -d.x()).normalized());
  }
  for (const auto& p : v) c.centre += p;
  c.centre /= static_cast<double>(v.size());
  for (const auto& p : v) c.radius = std::max(c.radius, (p - c.centre).norm());
  return c;
}

FootprintChecker::FootprintChecker(PlanningScene scene, BaseGeometry robot)
    : scene_(std::move(scene)), robot_(std::move(robot)) {
  scene_.Validate();
  IFAB_THROW_UNLESS(robot_.length > 0 && robot_.width > 0 && robot_.track_gauge > 0 &&
                        robot_.max_track_speed > 0,
                    "base geometry: expected positive length, width, track gauge and track speed");
  hx_ = 0.5 * robot_.length;
  hy_ = 0.5 * robot_.width;
  // Obstacles counter-clockwise, as the distance functions expect.
  for (auto& o : scene_.obstacles) {
    if (SignedArea(o) < 0.0) std::reverse(o.begin(), o.end());
    obstacles_.push_back(MakeConvex(o, false));
  }
  if (scene_.obstacle_names.empty()) {
    for (std::size_t k = 0; k < scene_.obstacles.size(); ++k) {
      scene_.obstacle_names.push_back(fmt::format("obstacle {}", k));
    }
  }
  const std::size_t nb = scene_.boundary.size();
  for (std::size_t i = 0; i < nb; ++i) {
    edges_.push_back(MakeConvex({scene_.boundary[i], scene_.boundary[(i + 1) % nb]}, true));
  }
}

FootprintChecker::Box FootprintChecker::MakeBox(const Pose2& T_site_base) const {
  const double c = std::cos(T_site_base.theta), s = std::sin(T_site_base.theta);
  const Eigen::Vector2d& o = robot_.footprint_offset;
  return {Eigen::Vector2d(T_site_base.x + c * o.x() - s * o.y(), T_site_base.y + s * o.x() + c * o.y()), c, s};
}

// SignedDistanceConvex specialised to the footprint box: the polygon is moved into the box frame,
// where the box's separating axes and support function are trivial.
double FootprintChecker::BoxDistance(const Box& box, const Convex& poly, double cull) const {
  const int m = static_cast<int>(poly.vertices.size());
  Eigen::Vector2d v[8];
  std::vector<Eigen::Vector2d> heap;
  Eigen::Vector2d* vb = v;
  if (m > 8) {
    heap.resize(m);
    vb = heap.data();
  }
  double min_x = kInf, max_x = -kInf, min_y = kInf, max_y = -kInf;
  for (int i = 0; i < m; ++i) {
    const Eigen::Vector2d d = poly.vertices[i] - box.centre;
    vb[i] = {box.c * d.x() + box.s * d.y(), -box.s * d.x() + box.c * d.y()};
    min_x = std::min(min_x, vb[i].x());
    max_x = std::max(max_x, vb[i].x());
    min_y = std::min(min_y, vb[i].y());
    max_y = std::max(max_y, vb[i].y());
  }
  // Box axes.
  double sep = std::max({min_x - hx_, -hx_ - max_x, min_y - hy_, -hy_ - max_y});
  // Polygon edge normals (a segment has two, opposite).
  for (int i = 0; i < m; ++i) {
    const Eigen::Vector2d& n = poly.normals[i];
    const Eigen::Vector2d nb(box.c * n.x() + box.s * n.y(), -box.s * n.x() + box.c * n.y());
    sep = std::max(sep, -(std::abs(nb.x()) * hx_ + std::abs(nb.y()) * hy_) - nb.dot(vb[i]));
  }
  // Overlapping: minus the penetration depth. Apart by at least cull (sep is a lower bound).
  if (sep <= 0.0 || sep >= cull) return sep;
  // Apart: the nearest features are a polygon vertex and the box, or a box corner and an edge.
  double d2 = kInf;
  for (int i = 0; i < m; ++i) {
    const double dx = std::max(std::abs(vb[i].x()) - hx_, 0.0), dy = std::max(std::abs(vb[i].y()) - hy_, 0.0);
    d2 = std::min(d2, dx * dx + dy * dy);
  }
  const Eigen::Vector2d corners[4] = {{-hx_, -hy_}, {hx_, -hy_}, {hx_, hy_}, {-hx_, hy_}};
  for (int i = 0; i < poly.num_edges; ++i) {
    const Eigen::Vector2d& a = vb[i];
    const Eigen::Vector2d ab = vb[(i + 1) % m] - a;
    const double l2 = ab.squaredNorm();
    for (const auto& p : corners) {
      const double t = l2 > 0.0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
      d2 = std::min(d2, (a + t * ab - p).squaredNorm());
    }
  }
  return std::sqrt(d2);
}

double FootprintChecker::BoundaryClearance(const Box& box, double cull) const {
  if (edges_.empty()) return kInf;
  const double r = robot_.CircumRadius();
  double d = kInf;
  for (const Convex& e : edges_) {
    // The footprint lies within r of its centre, so the centre's distance to the edge less r is a
    // lower bound (much tighter than the bounding circle of a long edge).
    if (PointSegmentDistance(box.centre, e.vertices[0], e.vertices[1]) - r >= cull) continue;
    d = std::min(d, BoxDistance(box, e, cull));
  }
  if (d > 0.0 && !PointInPolygon(scene_.boundary, box.centre)) {
    // Entirely outside: the farther out, the worse.
    double out = kInf;
    for (const Convex& e : edges_) out = std::min(out, PointSegmentDistance(box.centre, e.vertices[0], e.vertices[1]));
    return -std::max(out, 1e-6);
  }
  return d;
}

double FootprintChecker::Clearance(const Pose2& T_site_base) const { return Clearance(T_site_base, nullptr); }

double FootprintChecker::Clearance(const Pose2& T_site_base, std::string* closest) const {
  const Box box = MakeBox(T_site_base);
  double d = BoundaryClearance(box, kInf);
  if (closest) *closest = "boundary";
  const double r = robot_.CircumRadius();
  for (std::size_t k = 0; k < obstacles_.size(); ++k) {
    // Bounding circles give a lower bound on the distance: an obstacle that cannot come closer
    // than the closest so far is skipped, and the others are culled at it (BoxDistance is exact
    // below its cull distance), so the minimum is the same as checking each exactly.
    const Convex& o = obstacles_[k];
    if ((box.centre - o.centre).norm() - o.radius - r >= d) continue;
    const double dk = BoxDistance(box, o, d);
    if (dk < d) {
      d = dk;
      if (closest) *closest = scene_.obstacle_names[k];
    }
  }
  return d;
}

double FootprintChecker::Cost(const Pose2& T_site_base, double margin, double collision_penalty) const {
  return Cost(T_site_base, std::cos(T_site_base.theta), std::sin(T_site_base.theta), margin, collision_penalty);
}

double FootprintChecker::Cost(const Pose2& T_site_base, double c, double s, double margin,
                              double collision_penalty) const {
  const Eigen::Vector2d& off = robot_.footprint_offset;
  const Box box{Eigen::Vector2d(T_site_base.x + c * off.x() - s * off.y(), T_site_base.y + s * off.x() + c * off.y()),
                c, s};
  const double r = robot_.CircumRadius();
  double cost = 0.0;
  const auto add = [&](double d) {
    if (d < margin) cost += margin - d;
    if (d < 0.0) cost += collision_penalty;
  };
  add(BoundaryClearance(box, margin));
  for (const Convex& o : obstacles_) {
    if ((box.centre - o.centre).norm() - o.radius - r >= margin) continue;
    add(BoxDistance(box, o, margin));
  }
  return cost;
}

bool FootprintChecker::CentreInsideBoundary(const Pose2& T_site_base) const {
  return scene_.boundary.empty() || PointInPolygon(scene_.boundary, T_site_base * robot_.footprint_offset);
}

int FootprintChecker::OverlappingObstacle(const Pose2& T_site_base) const {
  const Box box = MakeBox(T_site_base);
  for (std::size_t k = 0; k < obstacles_.size(); ++k) {
    if (BoxDistance(box, obstacles_[k], 0.0) < 0.0) return static_cast<int>(k);
  }
  return -1;
}

double FootprintChecker::PointClearance(const Eigen::Vector2d& p) const {
  double d = kInf;
  const std::size_t nb = scene_.boundary.size();
  if (nb > 0) {
    double e = kInf;
    for (std::size_t i = 0; i < nb; ++i) {
      e = std::min(e, PointSegmentDistance(p, scene_.boundary[i], scene_.boundary[(i + 1) % nb]));
    }
    d = PointInPolygon(scene_.boundary, p) ? e : -e;
  }
  for (const auto& o : scene_.obstacles) {
    d = std::min(d, SignedDistanceConvex(&p, 1, o.data(), static_cast<int>(o.size())));
  }
  return d;
}

}  // namespace ifab::base
