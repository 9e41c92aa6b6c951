#include "ifab/model/site.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "ifab/core/config.h"

namespace ifab {
namespace {

Pose3 ReadPose(const ConfigNode& node) {
  const auto v = node.AsNumbers(6);
  return PoseFromXyzRpy(v[0], v[1], v[2], v[3], v[4], v[5]);
}

Box ReadBoxSize(const ConfigNode& node) {
  const Eigen::Vector3d s = node.AsVector3();
  if ((s.array() <= 0.0).any()) node.Fail("3 positive numbers");
  return Box{s};
}

SiteBox ReadSiteBox(const ConfigNode& node, const std::string& default_name, const Box* default_size) {
  node.ExpectKeys({"name", "size", "pose"});
  SiteBox b;
  b.name = node.Get<std::string>("name", default_name);
  if (auto s = node.Find("size")) b.box = ReadBoxSize(*s);
  else if (default_size) b.box = *default_size;
  else node["size"];  // throws: required
  b.T_site_box = ReadPose(node["pose"]);
  return b;
}

double SignedArea(const std::vector<Eigen::Vector2d>& poly) {
  double a = 0;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const auto& p = poly[i];
    const auto& q = poly[(i + 1) % poly.size()];
    a += p.x() * q.y() - q.x() * p.y();
  }
  return 0.5 * a;
}

// Whether segments ab and cd share a point (touching counts).
bool SegmentsMeet(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                  const Eigen::Vector2d& d) {
  const auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& p, const Eigen::Vector2d& q) {
    const double v = (p - o).x() * (q - o).y() - (p - o).y() * (q - o).x();
    return (v > 0) - (v < 0);
  };
  const auto within = [](const Eigen::Vector2d& p, const Eigen::Vector2d& q, const Eigen::Vector2d& r) {
    return std::min(p.x(), q.x()) <= r.x() && r.x() <= std::max(p.x(), q.x()) && std::min(p.y(), q.y()) <= r.y() &&
           r.y() <= std::max(p.y(), q.y());
  };
  const int d1 = cross(c, d, a), d2 = cross(c, d, b), d3 = cross(a, b, c), d4 = cross(a, b, d);
  if (d1 * d2 < 0 && d3 * d4 < 0) return true;
  return (d1 == 0 && within(c, d, a)) || (d2 == 0 && within(c, d, b)) || (d3 == 0 && within(a, b, c)) ||
         (d4 == 0 && within(a, b, d));
}

// The boundary must be a simple polygon: a repeated point would give a zero-length wall (whose
// direction normalises to NaN), crossing edges no inside at all.
void CheckSimplePolygon(const ConfigNode& boundary, const std::vector<Eigen::Vector2d>& poly) {
  const std::size_t n = poly.size();
  for (std::size_t i = 1; i < n; ++i)
    if ((poly[i] - poly[i - 1]).norm() < 1e-9)
      boundary[i].Fail(fmt::format("a point different from boundary[{}] (no repeated points)", i - 1));
  if ((poly[n - 1] - poly[0]).norm() < 1e-9)
    boundary[n - 1].Fail("a point different from boundary[0] (the polygon closes by itself)");
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 2; j < n; ++j) {
      if (i == 0 && j == n - 1) continue;  // adjacent through the closing edge
      if (SegmentsMeet(poly[i], poly[(i + 1) % n], poly[j], poly[(j + 1) % n]))
        boundary.Fail(fmt::format("a simple polygon (edges {}-{} and {}-{} cross)", i, (i + 1) % n, j, (j + 1) % n));
    }
}

}  // namespace

Site SiteFromConfig(const ConfigNode& c) {
  c.ExpectKeys({"ground_z", "boundary", "walls", "obstacles", "brick", "stack", "bricks"});
  Site site;
  c.Read("ground_z", site.ground_z);

  const ConfigNode boundary = c["boundary"];
  boundary.ExpectSequence();
  if (boundary.size() < 3) boundary.Fail("a polygon of at least 3 [x, y] points");
  for (std::size_t i = 0; i < boundary.size(); ++i) {
    const auto v = boundary[i].AsNumbers(2);
    site.boundary.emplace_back(v[0], v[1]);
  }
  CheckSimplePolygon(boundary, site.boundary);
  const double area = SignedArea(site.boundary);
  if (std::abs(area) < 1e-6) boundary.Fail("a polygon with non-zero area");
  if (area < 0) std::reverse(site.boundary.begin(), site.boundary.end());

  if (auto w = c.Find("walls")) {
    // Physical walls along the boundary: {height, thickness}, built outside the polygon.
    w->ExpectKeys({"height", "thickness"});
    double height = 2.5, thickness = 0.2;
    w->ReadPositive("height", height);
    w->ReadPositive("thickness", thickness);
    for (std::size_t i = 0; i < site.boundary.size(); ++i) {
      const Eigen::Vector2d a = site.boundary[i], b = site.boundary[(i + 1) % site.boundary.size()];
      const Eigen::Vector2d dir = (b - a).normalized();
      const Eigen::Vector2d outward(dir.y(), -dir.x());  // CCW polygon: right-hand side is outside
      const Eigen::Vector2d centre = 0.5 * (a + b) + 0.5 * thickness * outward;
      SiteBox wall;
      wall.name = "wall_" + std::to_string(i);
      wall.box.size = {(b - a).norm() + 2 * thickness, thickness, height};
      wall.T_site_box = PoseFromXyzRpy(centre.x(), centre.y(), site.ground_z + 0.5 * height, 0, 0,
                                       std::atan2(dir.y(), dir.x()));
      site.walls.push_back(wall);
    }
  }
  if (auto obs = c.Find("obstacles")) {
    obs->ExpectSequence();
    for (std::size_t i = 0; i < obs->size(); ++i)
      site.obstacles.push_back(ReadSiteBox((*obs)[i], "obstacle_" + std::to_string(i), nullptr));
  }
  site.brick.size = {0.240, 0.115, 0.052};
  if (auto b = c.Find("brick")) {
    b->ExpectKeys({"size"});
    site.brick = ReadBoxSize((*b)["size"]);
  }
  if (auto s = c.Find("stack")) {
    s->ExpectKeys({"origin"});
    const auto v = (*s)["origin"].AsNumbers(3);
    site.stack_origin = Pose2(v[0], v[1], v[2]);
  }
  if (auto bricks = c.Find("bricks")) {
    bricks->ExpectSequence();
    for (std::size_t i = 0; i < bricks->size(); ++i)
      site.bricks.push_back(ReadSiteBox((*bricks)[i], "brick_" + std::to_string(i), &site.brick));
  }
  return site;
}

Site LoadSite(const std::string& path) { return SiteFromConfig(ConfigNode::LoadFile(path)); }

std::vector<RigidObject> Site::Objects() const {
  std::vector<RigidObject> objects;
  objects.push_back({"ground", Pose3::Identity(), {Plane{Eigen::Vector3d::UnitZ(), ground_z}}});
  auto add = [&](const std::vector<SiteBox>& boxes) {
    for (const auto& b : boxes) objects.push_back({b.name, b.T_site_box, {b.box}});
  };
  add(walls);
  add(obstacles);
  add(bricks);
  return objects;
}

std::vector<Eigen::Vector2d> Footprint(const SiteBox& b) {
  std::vector<Eigen::Vector2d> out;
  const Eigen::Vector3d h = 0.5 * b.box.size;
  for (auto [sx, sy] : {std::pair{-1.0, -1.0}, {1.0, -1.0}, {1.0, 1.0}, {-1.0, 1.0}}) {
    const Eigen::Vector3d p = b.T_site_box * Eigen::Vector3d(sx * h.x(), sy * h.y(), -h.z());
    out.emplace_back(p.x(), p.y());
  }
  return out;
}

std::vector<std::vector<Eigen::Vector2d>> Site::ObstacleFootprints() const {
  std::vector<std::vector<Eigen::Vector2d>> out;
  for (const auto* group : {&walls, &obstacles, &bricks})
    for (const auto& b : *group) out.push_back(Footprint(b));
  return out;
}

Pose3 Site::DesignedBrickPose(int k) const {
  const double z = ground_z + brick.size.z() * (k + 0.5);
  return PoseFromXyzRpy(stack_origin.x, stack_origin.y, z, 0, 0, stack_origin.theta);
}

}  // namespace ifab
