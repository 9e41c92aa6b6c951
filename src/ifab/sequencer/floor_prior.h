#pragma once
/// \file
/// The floor's prior on a registered base pose: the base stands on the floor (its origin at the
/// floor's height) and nearly level (a floor within DIN 18202's flatness limits under the tracks
/// tilts it by a few tenths of a degree at most). A small workpiece seen from a few metres pins
/// the base's height and its tilt only together (a tilt moves the far workpiece up or down), so
/// the prior decides that combination.

#include <Eigen/Core>

#include "ifab/core/se3.h"

namespace ifab::sequencer {

struct FloorPrior {
  double ground_z{0.0};      ///< [m] floor height in the site frame (the base origin's)
  double height_sigma{0.004};  ///< [m]
  double tilt_sigma{0.0017};   ///< [rad] of the base's up axis from the vertical
  /// false: the prior says nothing about the tilt (another sensor measured it: the IMU's roll
  /// and pitch include the chassis's lean under the arm, which a level floor does not describe).
  bool on_tilt{true};
};

/// A Kalman update of T_site_base, with covariance over [x y z rx ry rz] (perturbations in the
/// site frame, rotations left-multiplied: T = (Exp(w) R, t + d), as registration reports it), by
/// the prior. Through the registration's correlations every component moves, so what the scan
/// pinned (where the workpiece is relative to the base) stays.
Pose3 FuseFloorPrior(const Pose3& T_site_base, const Eigen::Matrix<double, 6, 6>& covariance, const FloorPrior& prior);

/// The earlier variant: height, roll and pitch each pulled towards the prior by its own variance
/// alone, the other components kept (it moves the workpiece off where the scan saw it when
/// height and tilt are correlated).
Pose3 FuseFloorPriorPerComponent(const Pose3& T_site_base, const Eigen::Matrix<double, 6, 6>& covariance,
                                 const FloorPrior& prior);

}  // namespace ifab::sequencer
