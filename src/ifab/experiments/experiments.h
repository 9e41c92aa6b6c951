#pragma once
/// \file The experiments ifab ships, one factory each (see registry.cc).

#include "ifab/experiments/experiment.h"

namespace ifab::experiments {

ExperimentInfo BaseManeuversExperiment();  ///< issue 4: maneuvers on the estimator alone
ExperimentInfo BrickStackExperiment();  ///< paper Sec. VI-VII: the brick stack (the default)
ExperimentInfo LrfBiasExperiment();  ///< paper Fig. 7: stationary floor scans from 3 heights
ExperimentInfo ArmPlanningExperiment();  ///< paper Sec. IV: iLQG on seeded brick and scan motions
ExperimentInfo BasePlanningExperiment();  ///< paper Sec. III-A: STOMP on seeded start/goal poses
ExperimentInfo RegistrationConsistencyExperiment();  ///< paper Table I (perception_experiments.cc)
ExperimentInfo CalibrationConsistencyExperiment();   ///< paper Table II (perception_experiments.cc)
ExperimentInfo FaultsExperiment();  ///< issue 14: missions with injected faults (faults.cc)

}  // namespace ifab::experiments
