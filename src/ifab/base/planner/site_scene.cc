#include "ifab/base/planner/site_scene.h"

namespace ifab::base {
namespace {

bool SameFootprint(const std::vector<Eigen::Vector2d>& a, const std::vector<Eigen::Vector2d>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if ((a[i] - b[i]).norm() > 1e-3) return false;
  }
  return true;
}

}  // namespace

PlanningScene PlanningSceneFromSite(const Site& site, const SiteSceneOptions& options) {
  PlanningScene scene;
  scene.boundary = site.boundary;
  const auto add = [&](const std::string& name, std::vector<Eigen::Vector2d> footprint) {
    for (const auto& o : scene.obstacles) {
      if (SameFootprint(o, footprint)) return;
    }
    scene.obstacles.push_back(std::move(footprint));
    scene.obstacle_names.push_back(name);
  };
  if (options.include_walls) {
    for (const auto& w : site.walls) add(w.name, Footprint(w));
  }
  for (const auto& o : site.obstacles) add(o.name, Footprint(o));
  if (options.include_stack) {
    SiteBox stack;
    stack.name = "brick stack";
    stack.box = site.brick;
    stack.T_site_box = site.DesignedBrickPose(0);
    add(stack.name, Footprint(stack));
  }
  for (const auto& b : site.bricks) add(b.name.empty() ? "brick" : b.name, Footprint(b));
  return scene;
}

}  // namespace ifab::base
