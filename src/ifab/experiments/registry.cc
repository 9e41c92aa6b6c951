#include "ifab/experiments/experiment.h"
#include "ifab/experiments/experiments.h"

namespace ifab::experiments {

// Every experiment, in the order `ifab run --help` lists them. One line each.
const std::vector<ExperimentInfo>& Registry() {
  static const std::vector<ExperimentInfo> registry = {
      BrickStackExperiment(),
      BaseManeuversExperiment(),
      LrfBiasExperiment(),
      ArmPlanningExperiment(),
      BasePlanningExperiment(),
      RegistrationConsistencyExperiment(),
      CalibrationConsistencyExperiment(),
      FaultsExperiment(),
  };
  return registry;
}

}  // namespace ifab::experiments
