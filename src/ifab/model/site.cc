#include "ifab/model/site.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "ifab/core/config.h"

namespace ifab {
namespace {

// A rotation in radians beyond a half-turn is never needed, and is what degrees typed into a
// radian field look like (20 deg read as 20 rad is 1146 deg): reject it rather than misread it.
void RejectDegreesAsRadians(const ConfigNode& node, double angle) {
  if (std::abs(angle) > M_PI + 1e-9)
    node.Fail("a pose [x, y, z, roll, pitch, yaw] in metres and radians (a rotation beyond +-pi looks like "
              "degrees: write `xyz: [x, y, z]` and `rpy_deg: [roll, pitch, yaw]` instead)");
}

Pose3 ReadPose(const ConfigNode& node) {
  const auto v = node.AsNumbers(6);
  for (int k = 3; k < 6; ++k) RejectDegreesAsRadians(node, v[static_cast<std::size_t>(k)]);
  return PoseFromXyzRpy(v[0], v[1], v[2], v[3], v[4], v[5]);
}

// The pose of an item: `pose` (radians) or `xyz` with `rpy_deg`; identity if none and optional.
Pose3 ReadPlacement(const ConfigNode& item, bool required) {
  const bool has_pose = item.Has("pose"), has_xyz = item.Has("xyz"), has_rpy = item.Has("rpy_deg");
  if (has_pose && (has_xyz || has_rpy))
    item["pose"].Fail("either `pose` (m, rad) or `xyz` and `rpy_deg` (m, deg), not both");
  if (has_pose) return ReadPose(item["pose"]);
  if (has_xyz || has_rpy || required) {
    const Eigen::Vector3d t = item["xyz"].AsVector3();
    const Eigen::Vector3d rpy = has_rpy ? Eigen::Vector3d(item["rpy_deg"].AsVector3() * M_PI / 180.0) : Eigen::Vector3d::Zero();
    return PoseFromXyzRpy(t.x(), t.y(), t.z(), rpy.x(), rpy.y(), rpy.z());
  }
  return Pose3::Identity();
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

Eigen::Vector3d ReadUnitVector(const ConfigNode& node) {
  const Eigen::Vector3d v = node.AsVector3();
  if (!(v.norm() > 1e-9)) node.Fail("a non-zero 3-vector");
  return v.normalized();
}

// {normal: [..], offset: d} or {normal: [..], point: [..]}: the plane n . p = d.
Plane ReadPlane(const ConfigNode& node) {
  node.ExpectKeys({"name", "normal", "offset", "point"});
  Plane plane;
  plane.normal = ReadUnitVector(node["normal"]);
  if (node.Has("offset") == node.Has("point")) node.Fail("a plane with `normal` and one of `offset` [m] or `point` [m]");
  if (node.Has("offset")) {
    // The offset along the given normal, rescaled if the normal was not of unit length.
    const double norm = node["normal"].AsVector3().norm();
    plane.offset = node.Get<double>("offset") / norm;
  } else {
    plane.offset = plane.normal.dot(node["point"].AsVector3());
  }
  return plane;
}

ConvexPolygon ReadPolygon(const ConfigNode& node) {
  const ConfigNode v = node["vertices"];
  v.ExpectSequence();
  if (v.size() < 3) v.Fail("at least 3 vertices [x, y, z] (m)");
  std::vector<Eigen::Vector3d> vertices;
  for (std::size_t i = 0; i < v.size(); ++i) vertices.push_back(v[i].AsVector3());
  try {
    return ConvexPolygon(std::move(vertices));
  } catch (const InputError& e) {
    v.Fail(fmt::format("the vertices of a planar convex polygon ({})", e.what()));
  }
}

// One part of an object: {plane: {...}} | {polygon: {vertices, pose?}} | {box: {size, pose?}}.
RigidObject ReadPart(const ConfigNode& node, const std::string& name) {
  node.ExpectKeys({"plane", "polygon", "box"});
  if (node.Keys().size() != 1) node.Fail("one of {plane: ...}, {polygon: ...}, {box: ...}");
  RigidObject part;
  part.name = name;
  if (auto p = node.Find("plane")) {
    part.primitives.push_back(ReadPlane(*p));
  } else if (auto g = node.Find("polygon")) {
    g->ExpectKeys({"vertices", "pose", "xyz", "rpy_deg"});
    part.primitives.push_back(ReadPolygon(*g));
    part.T_site_object = ReadPlacement(*g, false);
  } else {
    const ConfigNode b = node["box"];
    b.ExpectKeys({"size", "pose", "xyz", "rpy_deg"});
    part.primitives.push_back(ReadBoxSize(b["size"]));
    part.T_site_object = ReadPlacement(b, false);
  }
  return part;
}

// planes:, polygons:, boxes: (one object each) and objects: (several parts sharing one pose).
void ReadObjects(const ConfigNode& c, Site& site) {
  auto each = [&](const char* key, auto&& read) {
    if (auto list = c.Find(key)) {
      list->ExpectSequence();
      for (std::size_t i = 0; i < list->size(); ++i) {
        const ConfigNode item = (*list)[i];
        item.ExpectMap();
        SiteObject o;
        o.name = item.Get<std::string>("name", fmt::format("{}_{}", key, i));
        read(item, o);
        site.objects.push_back(std::move(o));
      }
    }
  };
  each("planes", [](const ConfigNode& item, SiteObject& o) {
    o.parts.push_back({o.name, Pose3::Identity(), {ReadPlane(item)}});
  });
  each("polygons", [](const ConfigNode& item, SiteObject& o) {
    item.ExpectKeys({"name", "vertices", "pose", "xyz", "rpy_deg"});
    o.T_site_object = ReadPlacement(item, false);
    o.parts.push_back({o.name, Pose3::Identity(), {ReadPolygon(item)}});
  });
  each("boxes", [](const ConfigNode& item, SiteObject& o) {
    item.ExpectKeys({"name", "size", "pose", "xyz", "rpy_deg"});
    o.T_site_object = ReadPlacement(item, true);
    o.parts.push_back({o.name, Pose3::Identity(), {ReadBoxSize(item["size"])}});
  });
  each("objects", [](const ConfigNode& item, SiteObject& o) {
    item.ExpectKeys({"name", "parts", "pose", "xyz", "rpy_deg"});
    o.T_site_object = ReadPlacement(item, false);
    const ConfigNode parts = item["parts"];
    parts.ExpectSequence();
    if (parts.size() == 0) parts.Fail("at least one part");
    for (std::size_t k = 0; k < parts.size(); ++k) o.parts.push_back(ReadPart(parts[k], o.name));
  });
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
  c.ExpectKeys({"ground_z", "boundary", "walls", "obstacles", "brick", "stack", "bricks", "planes", "polygons",
                "boxes", "objects"});
  Site site;
  // The floor is an ordinary object: present only when the file gives its height.
  site.has_ground = c.Has("ground_z");
  c.Read("ground_z", site.ground_z);
  ReadObjects(c, site);

  if (c.Has("walls") && !c.Has("boundary")) c["walls"].Fail("a `boundary` polygon for the walls to stand on");
  if (const auto boundary_node = c.Find("boundary")) {
  const ConfigNode& boundary = *boundary_node;
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
  }

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
    RejectDegreesAsRadians((*s)["origin"], v[2]);
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

std::vector<SiteObject> Site::Bodies() const {
  std::vector<SiteObject> bodies;
  if (has_ground)
    bodies.push_back({"ground", Pose3::Identity(), {{"ground", Pose3::Identity(), {Plane{Eigen::Vector3d::UnitZ(), ground_z}}}}});
  auto add = [&](const std::vector<SiteBox>& boxes) {
    for (const auto& b : boxes) bodies.push_back({b.name, b.T_site_box, {{b.name, Pose3::Identity(), {b.box}}}});
  };
  add(walls);
  add(obstacles);
  add(bricks);
  bodies.insert(bodies.end(), objects.begin(), objects.end());
  return bodies;
}

std::vector<RigidObject> Site::Objects() const {
  std::vector<RigidObject> out;
  for (const SiteObject& body : Bodies())
    for (const RigidObject& part : body.parts) out.push_back({part.name, body.T_site_object * part.T_site_object, part.primitives});
  return out;
}

void Site::RequireBoundary(const std::string& file, const std::string& command) const {
  if (boundary.size() < 3)
    ThrowInputError("{}: boundary: required by `{}` (the polygon the base must stay inside), but the site has none", file,
                    command);
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
