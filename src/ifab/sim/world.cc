#include "ifab/sim/world.h"

#include <algorithm>
#include <limits>

namespace ifab::sim {
namespace {

Pose3 Inverse(const Pose3& p) { return p.inverse(Eigen::Isometry); }

}  // namespace

World::World(Site site) : site_(std::move(site)) { Rebuild(); }

void World::Rebuild() {
  statics_.clear();
  bricks_.clear();
  bricks_bounds_ = Aabb{};
  auto make = [](const SiteBox& b) {
    return Entry{Inverse(b.T_site_box), b.box, *Bounds(Primitive{b.box}, b.T_site_box)};
  };
  for (const auto* group : {&site_.walls, &site_.obstacles})
    for (const auto& b : *group) statics_.push_back(make(b));
  for (const auto& b : site_.bricks) {
    bricks_.push_back(make(b));
    bricks_bounds_.Extend(bricks_.back().bounds);
  }
}

void World::AddObstacle(const SiteBox& obstacle) {
  site_.obstacles.push_back(obstacle);
  Rebuild();
}

bool World::RemoveObstacle(const std::string& name) {
  auto& o = site_.obstacles;
  const auto it = std::find_if(o.begin(), o.end(), [&](const SiteBox& b) { return b.name == name; });
  if (it == o.end()) return false;
  o.erase(it);
  Rebuild();
  return true;
}

void World::MoveBricks(const Pose3& T) {
  for (auto& b : site_.bricks) b.T_site_box = T * b.T_site_box;
  Rebuild();
}

void World::AddBrick(const SiteBox& brick) {
  site_.bricks.push_back(brick);
  bricks_.push_back(Entry{Inverse(brick.T_site_box), brick.box, *Bounds(Primitive{brick.box}, brick.T_site_box)});
  bricks_bounds_.Extend(bricks_.back().bounds);
}

std::optional<WorldHit> World::CastRay(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min,
                                       double t_max) const {
  std::optional<WorldHit> best;
  double t_best = t_max;
  // Ground plane z = ground_z, seen from above.
  if (d.z() < -1e-12) {
    const double t = (site_.ground_z - o.z()) / d.z();
    if (t > t_min && t < t_best) {
      t_best = t;
      best = WorldHit{t, Eigen::Vector3d::UnitZ(), -1};
    }
  }
  const Eigen::Vector3d inv_d = d.cwiseInverse();
  auto cast_group = [&](const std::vector<Entry>& entries, int index_offset) {
    for (std::size_t k = 0; k < entries.size(); ++k) {
      const Entry& e = entries[k];
      if (!e.bounds.HitByRay(o, inv_d, t_min, t_best)) continue;
      const Eigen::Vector3d o_obj = e.T_object_site * o;
      const Eigen::Vector3d d_obj = e.T_object_site.linear() * d;
      if (auto hit = IntersectRay(Primitive{e.box}, o_obj, d_obj, t_min, t_best)) {
        t_best = hit->t;
        best = WorldHit{hit->t, e.T_object_site.linear().transpose() * hit->normal,
                        index_offset + static_cast<int>(k)};
      }
    }
  };
  cast_group(statics_, 0);
  if (!bricks_.empty() && bricks_bounds_.HitByRay(o, inv_d, t_min, t_best))
    cast_group(bricks_, static_cast<int>(statics_.size()));
  return best;
}

double World::SupportHeight(double x, double y, double half_extent) const {
  double top = site_.ground_z;
  auto consider = [&](const std::vector<Entry>& entries) {
    for (const auto& e : entries) {
      if (x + half_extent < e.bounds.lo.x() || x - half_extent > e.bounds.hi.x() ||
          y + half_extent < e.bounds.lo.y() || y - half_extent > e.bounds.hi.y())
        continue;
      top = std::max(top, e.bounds.hi.z());
    }
  };
  consider(statics_);
  consider(bricks_);
  return top;
}

}  // namespace ifab::sim
