#pragma once
/// \file
/// Test and benchmark fixture: the brick-stacking site of the paper (Sec. VI, Fig. 5/6) as a
/// planning scene, until the site model (data/sites/brick_stack.yaml) provides it. Site frame
/// origin at the brick stack. Numbers are estimates read off the paper's figures.

#include <vector>

#include "ifab/base/planner/planning_scene.h"
#include "ifab/core/angles.h"

namespace ifab::base::testing {

/// Axis-aligned rectangle centred at (cx, cy), counter-clockwise.
inline std::vector<Eigen::Vector2d> Rectangle(double cx, double cy, double sx, double sy) {
  return {{cx - sx / 2, cy - sy / 2}, {cx + sx / 2, cy - sy / 2}, {cx + sx / 2, cy + sy / 2}, {cx - sx / 2, cy + sy / 2}};
}

/// 8 x 6 m boundary, the brick stack (0.24 x 0.115 m) at the origin, the feeder (0.6 x 0.4 m) at (0, -2.2).
inline PlanningScene BrickStackingScene() {
  PlanningScene s;
  s.boundary = Rectangle(0.0, 0.0, 8.0, 6.0);
  s.obstacles = {Rectangle(0.0, 0.0, 0.24, 0.115), Rectangle(0.0, -2.2, 0.6, 0.4)};
  s.obstacle_names = {"brick stack", "brick feeder"};
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
