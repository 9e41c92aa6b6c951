#pragma once
/// \file
/// The motion prior of eq. 3: where the base should be at this scan, and how sure that is.
///
/// The paper's eq. 3 has the scan (eq. 1) and the gyro (eq. 2). A robot with wheel odometry
/// (the CARMEN logs) adds an odometry factor: the step since the previous scan with a covariance
/// that grows with the distance travelled and the angle turned (OdometryNoise, the classic
/// odometry motion model of Thrun, Burgard, Fox, "Probabilistic Robotics", sec. 5.4: each
/// variance is a sum of squares of terms proportional to the motion). A robot without usable
/// odometry (the IF: its tracks slip) may use its commanded track speeds the same way, with a
/// far larger noise (a weak prior). The estimator weighs the prior against the scan match by
/// the match's own information matrix (see degeneracy.h and match_quality.h).

#include <Eigen/Core>
#include <string>

#include "ifab/core/config.h"
#include "ifab/core/se2.h"

namespace ifab::base {

/// Noise of a relative motion measurement (odometry or commanded speeds), standard deviations
/// that grow linearly with the motion (variances add up over steps like a random walk in the
/// motion, not in time).
///
/// Defaults: wheel odometry of an indoor differential-drive robot on a floor. UMBmark
/// (Borenstein, Feng 1996) reports systematic odometry errors of a few percent of the distance
/// and about 1-2 deg per metre before calibration; the defaults take the pessimistic end (10 %
/// of the distance along, 5 % across, 2 deg per metre plus 10 % of the turn) so that a slipping
/// wheel still lies inside the prior, and the scan, far more precise, decides every direction
/// it observes. Nothing here is tuned on a log.
struct OdometryNoise {
  double translation_per_m{0.10};    ///< [m/m] sigma along the motion per metre travelled
  double lateral_per_m{0.05};        ///< [m/m] sigma across the motion per metre travelled
  double translation_per_rad{0.02};  ///< [m/rad] sigma of the position per radian turned
  double rotation_per_m{0.035};      ///< [rad/m] sigma of the heading per metre (2 deg/m)
  double rotation_per_rad{0.10};     ///< [rad/rad] sigma of the heading per radian turned
  double translation_floor{0.005};   ///< [m] sigma of a step with no motion (quantisation)
  double rotation_floor{0.002};      ///< [rad] sigma of a step with no turn (0.1 deg)

  /// The keys the map names on top of `defaults` (unknown keys are rejected).
  static OdometryNoise FromConfig(const ConfigNode& node, const OdometryNoise& defaults);
  static OdometryNoise FromConfig(const ConfigNode& node) { return FromConfig(node, OdometryNoise{}); }
  std::string Validate() const;
};

/// Covariance of the step T_prev_current (x, y, theta, in the frame of the previous pose) by
/// the noise model.
Eigen::Matrix3d StepCovariance(const Pose2& step, const OdometryNoise& noise);

/// The same covariance expressed for the world-frame pose parameters (x, y, theta) of
/// T_world_current = T_world_prev * step, when T_world_prev is known exactly: the step's
/// translation block rotated by the previous heading.
Eigen::Matrix3d StepCovarianceInWorld(const Pose2& T_world_prev, const Eigen::Matrix3d& cov_step);

/// A relative motion measurement handed to the estimator with a scan.
struct MotionMeasurement {
  Pose2 step;  ///< T_prev_current: the motion since the previous scan
  /// Covariance of step (x, y, theta in the previous pose's frame). Zero: the step only seeds the
  /// initial guess (the behaviour before the odometry factor) and is not part of eq. 3.
  Eigen::Matrix3d covariance{Eigen::Matrix3d::Zero()};
  bool HasCovariance() const { return covariance.trace() > 0.0; }
};

/// A pose prior for eq. 3: the predicted pose and its covariance (world frame). An empty
/// covariance (all zero) means no informative prior.
struct PosePrior {
  Pose2 T_world_base;
  Eigen::Matrix3d covariance{Eigen::Matrix3d::Zero()};
  bool informative{false};  ///< covariance is set and positive definite
};

}  // namespace ifab::base
