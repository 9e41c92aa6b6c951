#pragma once
/// \file The experiments ifab ships, one factory each (see registry.cc).

#include "ifab/experiments/experiment.h"

namespace ifab::experiments {

ExperimentInfo LrfBiasExperiment();  ///< paper Fig. 7: stationary floor scans from 3 heights
ExperimentInfo ArmPlanningExperiment();  ///< paper Sec. IV: iLQG on seeded brick and scan motions
ExperimentInfo RegistrationConsistencyExperiment();  ///< paper Table I (perception_experiments.cc)
ExperimentInfo CalibrationConsistencyExperiment();   ///< paper Table II (perception_experiments.cc)

}  // namespace ifab::experiments
