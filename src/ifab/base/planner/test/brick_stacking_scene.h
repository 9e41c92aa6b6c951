#pragma once
/// \file
/// Test and benchmark fixture: the brick-stacking site (paper Sec. VI, Fig. 5/6) as a planning
/// scene, written out by hand so that planner tests need not load the site model. It mirrors
/// data/sites/brick_stack.yaml (site_scene_test checks that they agree). Site frame origin at the
/// brick stack.

#include <cmath>
#include <vector>

#include "ifab/base/planner/planning_scene.h"
#include "ifab/core/angles.h"

namespace ifab::base::testing {

/// Axis-aligned rectangle centred at (cx, cy), counter-clockwise.
inline std::vector<Eigen::Vector2d> Rectangle(double cx, double cy, double sx, double sy) {
  return {{cx - sx / 2, cy - sy / 2}, {cx + sx / 2, cy - sy / 2}, {cx + sx / 2, cy + sy / 2}, {cx - sx / 2, cy + sy / 2}};
}

/// Rectangle of size (sx, sy) centred at (cx, cy) and turned by yaw, counter-clockwise.
inline std::vector<Eigen::Vector2d> RotatedRectangle(double cx, double cy, double sx, double sy, double yaw) {
  std::vector<Eigen::Vector2d> r = Rectangle(0, 0, sx, sy);
  const double c = std::cos(yaw), s = std::sin(yaw);
  for (auto& p : r) p = Eigen::Vector2d(cx + c * p.x() - s * p.y(), cy + s * p.x() + c * p.y());
  return r;
}

/// 9 x 7 m lab bay, two pillars, a cabinet and a crate near the walls, the brick stack
/// (0.24 x 0.115 m) at the origin.
inline PlanningScene BrickStackingScene() {
  PlanningScene s;
  s.boundary = Rectangle(0.0, 0.0, 9.0, 7.0);
  s.obstacles = {Rectangle(-3.2, 2.2, 0.4, 0.4), Rectangle(3.3, -2.4, 0.4, 0.4), Rectangle(2.6, 3.0, 1.2, 0.5),
                 RotatedRectangle(-3.6, -2.6, 0.8, 0.8, 0.3), Rectangle(0.0, 0.0, 0.24, 0.115)};
  s.obstacle_names = {"pillar_a", "pillar_b", "cabinet", "crate", "brick stack"};
  return s;
}

/// BrickStackingScene with a site-fixed brick feeder (0.6 x 0.4 m at (0, -2.2)) next to the
/// building positions: a harder scene, where some poses leave no room to turn on the spot.
inline PlanningScene BrickStackingSceneWithFeeder() {
  PlanningScene s = BrickStackingScene();
  s.obstacles.push_back(Rectangle(0.0, -2.2, 0.6, 0.4));
  s.obstacle_names.push_back("brick feeder");
  return s;
}

/// The In situ Fabricator's base (estimates, as data/robots/insitu_fabricator_base.yaml).
inline BaseGeometry InsituFabricatorBase() {
  BaseGeometry g;
  g.length = 1.8;
  g.width = 1.2;
  g.track_gauge = 1.0;
  g.max_track_speed = 0.3;
  return g;
}

/// Four building positions around the stack, arm (base x) facing it, visited in a loop (Fig. 6).
inline Pose2 FacingStack(double x, double y) { return Pose2(x, y, std::atan2(-y, -x)); }
inline std::vector<Pose2> BuildingPositions() {
  return {FacingStack(-1.6, 0.0), FacingStack(-0.6, 1.45), FacingStack(1.6, 0.5), FacingStack(1.2, -1.0)};
}

}  // namespace ifab::base::testing
