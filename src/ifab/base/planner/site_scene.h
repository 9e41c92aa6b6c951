#pragma once
/// \file
/// Adapter from the 3D site model (ifab/model/site.h) to the base planner's 2D scene. Lives in its
/// own target (ifab::base_planner_site) so that the planner itself stays independent of the model.

#include "ifab/base/planner/planning_scene.h"
#include "ifab/model/site.h"

namespace ifab::base {

struct SiteSceneOptions {
  bool include_stack{true};   ///< add the stack's footprint even before its first brick is placed
  bool include_walls{false};  ///< walls stand outside the boundary, which already keeps the base in
};

/// The site boundary, the footprints of its obstacles and of the bricks placed so far (identical
/// footprints, e.g. of a stack's bricks, once), and optionally the stack's footprint.
PlanningScene PlanningSceneFromSite(const Site& site, const SiteSceneOptions& options = {});

}  // namespace ifab::base
