#include "ifab/sim/world.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ifab::sim {
namespace {

Pose3 Inverse(const Pose3& p) { return p.inverse(Eigen::Isometry); }

// FloorField's Height and Gradient at once (one sincos per wave: the floor's ray casting needs
// both at every Newton step; the same sums as the two functions).
double HeightAndGradient(const FloorField& floor, double x, double y, Eigen::Vector2d* gradient) {
  double h = 0.0;
  Eigen::Vector2d g = Eigen::Vector2d::Zero();
  for (const FloorField::Wave& w : floor.waves) {
    const double a = w.k.x() * x + w.k.y() * y + w.phase;
    h += w.amplitude * std::sin(a);
    g += w.amplitude * std::cos(a) * w.k;
  }
  *gradient = g;
  return h;
}

}  // namespace

double FloorField::Height(double x, double y) const {
  double h = 0.0;
  for (const Wave& w : waves) h += w.amplitude * std::sin(w.k.x() * x + w.k.y() * y + w.phase);
  return h;
}

Eigen::Vector2d FloorField::Gradient(double x, double y) const {
  Eigen::Vector2d g = Eigen::Vector2d::Zero();
  for (const Wave& w : waves) g += w.amplitude * std::cos(w.k.x() * x + w.k.y() * y + w.phase) * w.k;
  return g;
}

double FloorField::WorstStep(double distance, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) const {
  double worst = 0.0;
  const double step = std::max(0.05, std::min(0.25, distance / 4));
  for (double x = lo.x(); x <= hi.x(); x += step) {
    for (double y = lo.y(); y <= hi.y(); y += step) {
      for (int a = 0; a < 8; ++a) {  // chords in 8 directions from (x, y)
        const double ang = a * EIGEN_PI / 8;
        const double x1 = x + distance * std::cos(ang), y1 = y + distance * std::sin(ang);
        if (x1 < lo.x() || x1 > hi.x() || y1 < lo.y() || y1 > hi.y()) continue;
        const double mid = Height(0.5 * (x + x1), 0.5 * (y + y1));
        worst = std::max(worst, std::abs(mid - 0.5 * (Height(x, y) + Height(x1, y1))));
      }
    }
  }
  return worst;
}

World::World(Site site, FloorField floor) : site_(std::move(site)), floor_(std::move(floor)) {
  floor_top_ = site_.ground_z;
  for (const FloorField::Wave& w : floor_.waves) floor_top_ += std::abs(w.amplitude);
  Rebuild();
}

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
  // Objects first, then the floor only if the ray comes down to the floor's highest point before
  // the nearest object hit: the uneven floor's Newton solve (a sincos per wave and step) was the
  // largest cost of the simulated scans, and most arm-laser beams end on a brick.
  std::optional<WorldHit> best;
  double t_best = t_max;
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
  if (d.z() > -1e-12) return best;  // the floor is seen from above only
  // Where the ray passes the floor's highest possible point (ground_z + the waves' amplitudes);
  // a floor hit cannot come earlier.
  if ((floor_top_ - o.z()) / d.z() >= t_best) return best;
  if (auto ground = IntersectGround(o, d, t_min, t_best)) return ground;
  return best;
}

std::optional<WorldHit> World::IntersectGround(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min,
                                               double t_max) const {
  if (d.z() > -1e-12) return std::nullopt;  // the floor is seen from above only
  double t = (site_.ground_z - o.z()) / d.z();
  if (floor_.flat()) {
    if (t > t_min && t < t_max) return WorldHit{t, Eigen::Vector3d::UnitZ(), -1};
    return std::nullopt;
  }
  // f(t) = ray height - floor height; the field is smooth and gentle (slopes of 1e-2), so Newton
  // from the flat floor's hit converges in a few steps for any ray steeper than the slope.
  // A ray that is not converged after 8 steps is nearly as shallow as the floor's slopes (a base
  // laser beam tilted down a fraction of a degree): Newton wanders there, and its last iterate is
  // no floor point (seen: 0.35 m above the floor, in front of a wall), so it is no hit.
  bool converged = false;
  for (int it = 0; it < 8 && !converged; ++it) {
    const Eigen::Vector3d p = o + t * d;
    Eigen::Vector2d grad;
    const double f = p.z() - (site_.ground_z + HeightAndGradient(floor_, p.x(), p.y(), &grad));
    const double df = d.z() - grad.dot(d.head<2>());
    if (df > -1e-9) return std::nullopt;  // grazing the field: treat as no floor hit
    const double dt = f / df;
    t -= dt;
    converged = std::abs(dt) < 1e-7;
  }
  if (!converged || !(t > t_min && t < t_max)) return std::nullopt;
  const Eigen::Vector3d p = o + t * d;
  const Eigen::Vector2d g = floor_.Gradient(p.x(), p.y());
  return WorldHit{t, Eigen::Vector3d(-g.x(), -g.y(), 1.0).normalized(), -1};
}

double World::SupportHeight(double x, double y, double half_extent) const {
  double top = site_.ground_z;
  if (!floor_.flat()) {  // the highest floor point under the footprint (centre and corners)
    top = -std::numeric_limits<double>::infinity();
    for (double sx : {-1.0, 0.0, 1.0})
      for (double sy : {-1.0, 0.0, 1.0}) top = std::max(top, FloorHeight(x + sx * half_extent, y + sy * half_extent));
  }
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
