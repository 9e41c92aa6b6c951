#pragma once
/// \file
/// Internal: the alternating match-and-solve engine behind Register() and CalibrateLaserMount().
/// Not part of the module's interface.

#include <vector>

#include "ifab/perception/calibration.h"
#include "ifab/perception/registration.h"

namespace ifab::internal {

struct PoseProblemInput {
  const std::vector<RayPoint>* cloud{nullptr};      ///< registration: points in base
  const std::vector<SweepPoint>* sweep{nullptr};    ///< calibration: raw points, mount solved
  Pose3 T_tool0_laser{Pose3::Identity()};           ///< calibration: initial mount
  double laser_extent{1.0};
  bool autodiff{false};                             ///< calibration: Ceres autodiff (else analytic)
};

struct PoseProblemOutput {
  RegistrationSummary summary;
  Pose3 T_tool0_laser{Pose3::Identity()};
  Matrix6d laser_covariance{Matrix6d::Zero()};
  std::vector<std::string> laser_unconstrained;
};

PoseProblemOutput SolvePoseProblem(const PoseProblemInput& input, const std::vector<RegistrationBody>& bodies,
                                   const RegistrationOptions& options);

}  // namespace ifab::internal
