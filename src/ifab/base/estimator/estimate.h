#pragma once
/// \file
/// What the base state estimator returns for one scan: the pose, its covariance, the status a
/// user can act on, and the directions the scan left to the prior.

#include <Eigen/Core>

#include "ifab/core/se2.h"
#include "ifab/core/time.h"

namespace ifab::base {

/// Outcome of one scan. Only kOk, kDegenerate and kReference come from a match; every other
/// status is a flagged scan: its pose is the prior's (the prediction), and it never becomes a
/// reference keyframe.
enum class EstimateStatus {
  kOk,                ///< matched; pose and covariance usable
  kDegenerate,        ///< matched; the prior decided the directions the scan leaves unconstrained
  kReference,         ///< first scan after Reset: taken as reference, pose = the reset pose
  kTooFewPoints,      ///< too few valid points (or matched points: poor coverage): prediction
  kPoorScore,         ///< most matched points disagree with the reference (kernel): prediction
  kUnexplainedJump,   ///< the match disagrees with the prior beyond their uncertainty: prediction
  kSolverFailed,      ///< the solver returned no usable answer: prediction
};
const char* StatusName(EstimateStatus status);

/// The estimate for one scan.
struct BaseEstimate {
  Seconds t{0.0};                  ///< the scan's middle time
  Pose2 T_world_base;              ///< estimated pose (the prediction when the match failed)
  Eigen::Matrix3d covariance{Eigen::Matrix3d::Identity()};  ///< of (x, y, theta) [m^2, rad^2]
  EstimateStatus status{EstimateStatus::kReference};
  int num_points{0};               ///< measurement points used
  double matched_fraction{0.0};    ///< of those, with a reference point within the radius
  double inlier_fraction{0.0};     ///< of the matched, with the nearest reference within 2 sigma
  double score{0.0};               ///< mean over points of eq. 1's e_mi (kernels of peak 1)
  double gyro_error_rad{0.0};      ///< E_G of eq. 2 at the solution (0 if no gyro)
  bool gyro_used{false};           ///< gyro samples covered the interval since the last scan
  bool prior_used{false};          ///< an informative motion prior (odometry factor) was in eq. 3
  double degeneracy{0.0};          ///< min/max eigenvalue of the (scaled) scan information
  /// Directions the scan constrains poorly (decided by the prior when there is one): unit
  /// vectors over (x [m], y [m], lever * theta [m]), the first num_degenerate columns.
  int num_degenerate{0};
  Eigen::Matrix3d degenerate_directions{Eigen::Matrix3d::Zero()};
  double mahalanobis_sq{0.0};      ///< the match's innovation against the prior (0: no prior)
  double window_mahalanobis_sq{0.0};  ///< the match's translation against the odometry chained since the last keyframe (0: off)
  int gate_dof{0};                 ///< directions the gate tested
  int iterations{0};               ///< LM iterations, summed over rounds and sigma levels
  double cost{0.0};                ///< final cost of eq. 3 (sum of squares / 2)
  bool keyframe_added{false};      ///< this scan joined the reference set

  /// Ok or degenerate: the pose came from a match.
  bool IsUsable() const {
    return status == EstimateStatus::kOk || status == EstimateStatus::kDegenerate ||
           status == EstimateStatus::kReference;
  }
  /// The status says the match was not used (the pose is the prior's).
  bool IsFlagged() const { return !IsUsable(); }
};

}  // namespace ifab::base
