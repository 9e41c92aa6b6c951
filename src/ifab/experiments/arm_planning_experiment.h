#pragma once
/// \file
/// The `arm-planning` experiment's runner (issue 6; moved out of arm/ by issue 12: algorithm
/// modules write no files and do not link nlohmann_json): seeded point-to-point motions typical of the
/// brick stack (transfers between the feeder and the stack, approach/retreat above a brick, scan
/// sweeps of one joint and moves to scan poses, moves to and from the home configuration), each
/// planned with iLQG on one thread. The experiment wrapper only loads the config and writes the
/// JSON and CSV returned here.

#include <nlohmann/json.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "ifab/arm/ik.h"
#include "ifab/arm/ilqg.h"
#include "ifab/model/robot_model.h"

namespace ifab {
class ConfigNode;
}

namespace ifab::experiments {

struct ArmPlanningExperimentConfig {
  int cases{240};                      ///< number of motions
  double transfer_fraction{0.3};       ///< feeder <-> stack transfers (between approach poses)
  double approach_fraction{0.2};       ///< descents onto and lifts off a brick
  double scan_fraction{0.3};           ///< single-joint sweeps and moves to scan poses; the rest go home or leave it
  double radius_min{1.2};              ///< gripper distance from the arm axis J1 [m]
  double radius_max{2.0};
  double height_min{-0.70};            ///< gripper height in arm_base [m] (arm_base stands 0.75 m above the floor)
  double height_max{0.55};
  double approach_height{0.15};        ///< approach poses this far above the grip [m]
  double sweep_min_deg{15.0};          ///< scan sweep amplitude range [deg]
  double sweep_max_deg{60.0};
  /// The on-board feeder's brick (centre, base frame; robot YAML `feeder_in_base`). Without it,
  /// pick poses are drawn 50-120 deg to either side of the arm.
  std::optional<Pose3> T_base_feeder_brick;
  double brick_height{0.052};          ///< [m] (German DF brick)
  Vector6d q_home{(Vector6d() << 0.0, -0.5236, 0.5236, 0.0, 1.5708, 0.0).finished()};  ///< [rad]
  arm::IlqgOptions ilqg;                    ///< planner options
  arm::IkOptions ik;                        ///< IK options for generating the cases

  /// Read the experiment YAML (keys: cases, mix, workspace, sweep_deg, home_deg, brick_height,
  /// ilqg, ik; seed, robot, robot_yaml and arm are left to the wrapper) over `base` (whose ilqg
  /// options typically come from data/arm/arm.yaml and feeder from the robot YAML).
  static ArmPlanningExperimentConfig FromConfig(const ConfigNode& node, const ArmPlanningExperimentConfig& base);
};

struct ArmPlanningCase {
  int index{0};
  std::string kind;  ///< transfer, approach, sweep, scan_pose, home
  Vector6d q_from{Vector6d::Zero()};
  Vector6d q_to{Vector6d::Zero()};
  arm::PlanSummary summary;
};

struct ArmPlanningResult {
  /// results.json: cases, converged_rate, iterations_median, plan_ms_median, plan_ms_max,
  /// final_joint_error_deg_max, and more (usable_rate, iterations_max, duration stats, per kind).
  nlohmann::json results;
  std::vector<ArmPlanningCase> cases;
  /// One line per case (header first).
  std::string CasesCsv() const;
};

/// Generate the cases from `seed` and plan each one (single thread).
ArmPlanningResult RunArmPlanningExperiment(const RobotModel& robot, const ArmPlanningExperimentConfig& config,
                                           std::uint64_t seed);

}  // namespace ifab::experiments
