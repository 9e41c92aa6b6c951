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
#include "ifab/sim/sim_robot.h"

namespace ifab::experiments {

struct Setup {
  sim::SimOptions sim_options;
  sequencer::MissionComponents parts;
  sequencer::MissionOptions mission_options;
  sequencer::BuildingPlan plan;
  Vector6d q0;
  bool calibrate_mount{true};                ///< calibrate the arm laser first (else the design mount)
  sequencer::LaserCalibrationPlan calibration;  ///< how: sweeps of a cube on the floor (Sec. V-C)
};

/// Read the experiment YAML (and the files it names).
Setup LoadSetup(const ConfigNode& c);
/// Calibrate the arm laser's mount on a cube before the mission (Sec. V-C); `info` gets a summary.
Pose3 CalibrateMount(const Setup& setup, std::uint64_t seed, const RunContext& ctx, nlohmann::json* info);

}  // namespace ifab::experiments
