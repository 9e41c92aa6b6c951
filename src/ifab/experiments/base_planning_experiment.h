#pragma once
/// \file
/// The base-planning experiment: many seeded random start/goal pairs in a site, planned with the
/// STOMP base planner, summarised for `ifab run base-planning` (results.json keys: cases,
/// success_rate, plan_ms_median, plan_ms_p95, max_lateral_velocity_mps, min_clearance_m).

#include <nlohmann/json.hpp>

#include <cstdint>
#include <vector>

#include "ifab/base/planner/stomp_planner.h"
#include "ifab/core/config.h"

namespace ifab::experiments {

struct BasePlanningExperimentOptions {
  int cases{500};                         ///< random start/goal pairs
  std::uint64_t seed{1};                  ///< seed of case k is derived from this and k
  double building_position_fraction{0.5};  ///< share of poses drawn like building positions
  Eigen::Vector2d workpiece{0.0, 0.0};    ///< centre the building positions face [m] (the stack)
  double building_radius_min{1.4};        ///< building positions' distance from the workpiece [m]
  double building_radius_max{1.7};
  double building_heading_noise{0.26};    ///< max deviation of their heading from facing it [rad]
  Eigen::Vector4d building_region{-2.0, 2.0, -1.0, 1.5};  ///< building positions lie in [xmin, xmax] x [ymin, ymax] (paper Fig. 6)
  double free_pose_boundary_margin{-1.0};  ///< other poses keep their centre this far inside the
                                           ///< boundary [m]; < 0: the footprint's circumradius
                                           ///< (room to turn in place)
  double pose_min_clearance{0.05};        ///< every sampled pose keeps this footprint clearance [m]
  int max_failures_listed{50};            ///< failed cases written out in full

  /// Read an `experiment` YAML section; fields not named keep their defaults.
  static BasePlanningExperimentOptions FromConfig(const ConfigNode& node);
};

/// One planned case.
struct BasePlanningCase {
  Pose2 start, goal;
  base::PlanResult result;
};

/// Draw a start or goal pose as the experiment does (exposed for tests and benchmarks).
Pose2 SampleExperimentPose(const base::FootprintChecker& checker, const BasePlanningExperimentOptions& options,
                           RandomStream& rng);

/// Plan every case (one after another, so plan times are single-plan wall times) and summarise.
/// The planner's num_threads decides how its rollouts run.
nlohmann::json RunBasePlanningExperiment(const base::StompBasePlanner& planner,
                                         const BasePlanningExperimentOptions& options,
                                         std::vector<BasePlanningCase>* cases = nullptr);

}  // namespace ifab::experiments
