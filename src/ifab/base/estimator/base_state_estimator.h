#pragma once
/// \file
/// Base state estimator of the paper's section III-B (eq. 1-3). Each laser scan (the
/// measurement scan, rigid at its middle time) is matched against a few earlier reference scans
/// (keyframes spaced in distance and angle, kept over a receding time horizon), fused with the
/// gyro's integrated rotation, and the pose is the Ceres solution of eq. 3 (Ceres' TinySolver,
/// a dense Levenberg-Marquardt that keeps all of its memory between solves).
///
/// Eq. 1 as least squares (kernel_residual.h): each pair contributes 1 - G_ij / G(0) (the
/// Gaussian kernel G(p_M - p_R, 2 sigma^2 I) normalised to peak 1, subtracted from 1); the
/// total over a fixed set of pairs is (pairs - sum of eq. 1's kernels), so minimising it is
/// maximising the paper's score exactly. Eq. 2 adds c_G (theta - theta_gyro)^2. The solver is
/// given the cost's exact gradient and, per measurement point, the exact Hessian of its kernel
/// sum projected to be positive semi-definite (see PointKernelSum): that converges in a few
/// steps and shows a corridor as degenerate.
///
/// Usage:
///   BaseStateEstimator estimator(options, T_base_laser);
///   estimator.Reset(T_site_base_from_localization, t);
///   for each gyro sample: estimator.AddGyro(sample);     // before the scan it precedes
///   for each scan: const BaseEstimate& e = estimator.AddScan(scan);  // e.IsUsable()?
///
/// The pose is T_world_base where "world" is whatever frame Reset() was given (the site, on
/// the robot). No allocation per scan in the steady state: buffers are sized at construction
/// (from Options::max_beams) and reused (a test counts allocations); adding a keyframe builds
/// that keyframe's neighbour grid (point_grid.h; it allocates only to grow), once per keyframe.
///
/// The parts, one file each with its own tests (KISS-ICP style): scan_preprocessing.h (range
/// filter, deskew, thinning, reference sampling), keyframe_map.h (the reference set),
/// association.h (pairs and eq. 1's sums), eq3_solver.h (the solve of eq. 3 with its gyro and
/// prior terms), match_quality.h and degeneracy.h (the quality check: coverage, score,
/// degeneracy, gates), gyro_buffer.h (eq. 2's integration), motion_prior.h (odometry noise).
/// This class holds the state and strings them together per scan.
///
/// The paper treats each scan as rigid at its middle time; Options::deskew (an improvement, off by
/// default) moves every beam to that time with the gyro rate and the last velocity instead.
///
/// Options marked "improvement" below are off by default (the paper's method as written); the
/// configs in data/estimator/ say which they switch on and why. Three safeguards are on by
/// default and can be set to 0 for eq. 1-3 literally: the reference-point filters
/// max_reference_gap_sigmas and end_margin_sigmas, and the weak prior_weight.

#include <Eigen/Core>
#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "ifab/base/estimator/estimate.h"
#include "ifab/base/estimator/estimator_options.h"
#include "ifab/base/estimator/motion_prior.h"
#include "ifab/core/config.h"
#include "ifab/core/se2.h"
#include "ifab/msgs/msgs.h"

namespace ifab::base {

class BaseStateEstimator {
 public:
  /// T_base_laser: the laser's planar mount on the base.
  BaseStateEstimator(const EstimatorOptions& options, const Pose2& T_base_laser);
  ~BaseStateEstimator();
  BaseStateEstimator(const BaseStateEstimator&) = delete;
  BaseStateEstimator& operator=(const BaseStateEstimator&) = delete;

  /// Set the pose (e.g. from the last localization) at time t. With keep_references the
  /// reference scans are moved rigidly with the correction and matching goes on; otherwise they
  /// are cleared and the next scan becomes the first reference.
  void Reset(const Pose2& T_world_base, Seconds t, bool keep_references = false);

  /// A gyro sample; rate.z() is the yaw rate of the base [rad/s]. Samples must arrive in time
  /// order; the sample at time t_i holds the rate over (t_{i-1}, t_i].
  void AddGyro(const GyroSample& sample);

  /// Match one scan; returns the estimate (valid until the next call). Throws InputError if the
  /// scan has more beams than Options::max_beams or goes back in time.
  /// motion, if given, is the base's motion since the previous scan (T_prev_current, e.g. from
  /// wheel odometry or commanded track speeds). With a covariance it is a factor of eq. 3 (the
  /// odometry factor, see motion_prior.h) and the prior of the Mahalanobis gate and of the
  /// degenerate directions; without, it only seeds the initial guess (its rotation too when no
  /// gyro covers the interval).
  const BaseEstimate& AddScan(const LaserScan& scan,
                              const std::optional<MotionMeasurement>& motion = {});
  /// The motion as an initial guess only (no covariance).
  const BaseEstimate& AddScan(const LaserScan& scan, const Pose2& motion_hint) {
    return AddScan(scan, MotionMeasurement{motion_hint, Eigen::Matrix3d::Zero()});
  }

  /// The latest estimate.
  const BaseEstimate& Latest() const { return latest_; }
  const EstimatorOptions& options() const { return options_; }
  /// Keyframes kept (the candidates of the reference set).
  int NumReferenceScans() const;

 private:
  struct Impl;
  EstimatorOptions options_;
  Pose2 T_base_laser_;
  BaseEstimate latest_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ifab::base
