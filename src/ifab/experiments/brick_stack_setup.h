#pragma once
/// \file
/// What the brick-stack, base-maneuvers and faults experiments share (brick_stack.cc): the
/// simulated machine and the stack's components and options, read from one experiment YAML,
/// and the arm laser calibration before a mission.

#include <nlohmann/json.hpp>

#include <cstdint>

#include "ifab/core/config.h"
#include "ifab/experiments/experiment.h"
#include "ifab/sequencer/building_plan.h"
#include "ifab/sequencer/laser_sweeps.h"
#include "ifab/sequencer/mission.h"
#include "ifab/perception/range_bias.h"
#include "ifab/sim/as_built.h"
#include "ifab/sim/sim_robot.h"

namespace ifab::experiments {

// What the brick-stack, base-maneuvers and faults experiments share: the simulated machine, the
// stack's components and options, read from one experiment YAML.
struct Setup {
  sim::SimOptions sim_options;
  sequencer::MissionComponents parts;
  sequencer::MissionOptions mission_options;
  sequencer::BuildingPlan plan;
  Vector6d q0;
  bool calibrate_mount{true};                ///< calibrate the arm laser first (else the design mount)
  bool compensate_bias{true};                ///< identify the range bias with the mount if the plan says how
  sequencer::LaserCalibrationPlan calibration;  ///< how: sweeps of a cube on the floor (Sec. V-C)
  Pose3 T_base_feeder_design{Pose3::Identity()};  ///< the feeder as designed (robot YAML)
  bool as_built_world{true};                 ///< `world: as-built` (default) or `exact` (model = world)
  sim::AsBuiltTolerances tolerances;         ///< data/sim/as_built.yaml (simulator only)
};

/// Read the experiment YAML (and the files it names): the stack's side from design files only,
/// the simulator's side from its own.
Setup LoadSetup(const ConfigNode& c);
/// Draw this seed's as-built world and machine into `s.sim_options` (nothing for `world: exact`).
void DrawWorld(Setup& s, std::uint64_t seed);
/// Calibrate the arm laser's mount (and, if the plan says how, its range bias) on a cube before
/// the mission (Sec. V-C), into `setup.parts`: the mount, the identified bias model for scan
/// assembly and, when the plan fits the arm's kinematics and the fit is usable, the corrected arm
/// chain (the mount then goes with it). `info` gets a summary.
void CalibrateMount(Setup& setup, std::uint64_t seed, const RunContext& ctx, nlohmann::json* info);

}  // namespace ifab::experiments
