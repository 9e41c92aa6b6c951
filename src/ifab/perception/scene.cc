#include "ifab/perception/scene.h"

#include <cmath>
#include <limits>

#include "ifab/core/error.h"

namespace ifab {
namespace {

// Distance from p to an axis-aligned box (0 inside).
double DistanceToAabb(const Aabb& box, const Eigen::Vector3d& p) {
  const Eigen::Vector3d d = (box.lo - p).cwiseMax(p - box.hi).cwiseMax(0.0);
  return d.norm();
}

}  // namespace

Scene::Scene(const std::vector<RegistrationBody>& bodies) : num_bodies_(static_cast<int>(bodies.size())) {
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    Aabb box;
    bool finite = false;
    for (const auto& part : bodies[b].parts) {
      for (const auto& g : part.primitives) {
        ScenePrimitive sp;
        sp.body = static_cast<int>(b);
        sp.primitive = g;
        sp.T_body_primitive = part.T_site_object;
        sp.T_primitive_body = part.T_site_object.inverse();
        sp.edges = Edges(g);
        if (auto bb = Bounds(g, part.T_site_object)) {
          box.Extend(*bb);
          finite = true;
        }
        primitives_.push_back(std::move(sp));
      }
    }
    extents_.push_back(finite ? 0.5 * (box.hi - box.lo).norm() : 0.0);
  }
  std::vector<Pose3> poses;
  for (const auto& b : bodies) poses.push_back(b.T_base_body);
  SetPoses(poses);
}

void Scene::SetPoses(const std::vector<Pose3>& T_base_body) {
  IFAB_CHECK(static_cast<int>(T_base_body.size()) == num_bodies_);
  for (auto& sp : primitives_) {
    sp.T_base_primitive = T_base_body[static_cast<std::size_t>(sp.body)] * sp.T_body_primitive;
    sp.T_primitive_base = sp.T_base_primitive.inverse();
    sp.bounds = Bounds(sp.primitive, sp.T_base_primitive);
    sp.edges_base.clear();
    for (const auto& [a, b] : sp.edges) sp.edges_base.emplace_back(sp.T_base_primitive * a, sp.T_base_primitive * b);
  }
}

Scene::Nearest Scene::Closest(const Eigen::Vector3d& p_base) const {
  Nearest best;
  best.distance = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < primitives_.size(); ++i) {
    const ScenePrimitive& sp = primitives_[i];
    if (sp.bounds && DistanceToAabb(*sp.bounds, p_base) >= best.distance) continue;
    const ClosestPoint cp = ifab::Closest(sp.primitive, sp.T_primitive_base * p_base);
    if (cp.distance < best.distance) {
      best.primitive = static_cast<int>(i);
      best.distance = cp.distance;
      best.point = sp.T_base_primitive * cp.point;
      best.normal = sp.T_base_primitive.linear() * cp.normal;
      best.feature = cp.feature;
    }
  }
  return best;
}

std::optional<Scene::Hit> Scene::CastRay(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                                         double t_max) const {
  const Eigen::Vector3d inv = direction.cwiseInverse();
  std::optional<Hit> best;
  double t_best = t_max;
  for (std::size_t i = 0; i < primitives_.size(); ++i) {
    const ScenePrimitive& sp = primitives_[i];
    if (sp.bounds && !sp.bounds->HitByRay(origin, inv, 0.0, t_best)) continue;
    const Eigen::Vector3d o = sp.T_primitive_base * origin;
    const Eigen::Vector3d d = sp.T_primitive_base.linear() * direction;
    if (auto hit = IntersectRay(sp.primitive, o, d, 0.0, t_best)) {
      t_best = hit->t;
      best = Hit{static_cast<int>(i), hit->t, sp.T_base_primitive.linear() * hit->normal};
    }
  }
  return best;
}

bool Scene::RayPassesNearEdge(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                              double t_max, double distance) const {
  const Eigen::Vector3d inv = direction.cwiseInverse();
  const Eigen::Vector3d margin = Eigen::Vector3d::Constant(distance);
  for (const auto& sp : primitives_) {
    if (sp.edges_base.empty() || !sp.bounds) continue;
    Aabb inflated{sp.bounds->lo - margin, sp.bounds->hi + margin};
    if (!inflated.HitByRay(origin, inv, 0.0, t_max)) continue;
    for (const auto& [a, b] : sp.edges_base)
      if (SegmentRayDistance(a, b, origin, direction, t_max) < distance) return true;
  }
  return false;
}

}  // namespace ifab
