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
  /// Restart trials: the poses of the result being tried against. Once a full step leaves every
  /// body within 10x the tolerances of these, the trial has come back to that minimum and stops
  /// (PoseProblemOutput::returned).
  const std::vector<Pose3>* return_to{nullptr};
};

struct PoseProblemOutput {
  RegistrationSummary summary;
  Pose3 T_tool0_laser{Pose3::Identity()};
  Matrix6d laser_covariance{Matrix6d::Zero()};
  std::vector<std::string> laser_unconstrained;
  bool returned{false};  ///< stopped back at input.return_to (summary not finished: no covariance)
};

PoseProblemOutput SolvePoseProblem(const PoseProblemInput& input, const std::vector<RegistrationBody>& bodies,
                                   const RegistrationOptions& options);

}  // namespace ifab::internal
