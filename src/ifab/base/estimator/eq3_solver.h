#pragma once
/// \file
/// The solve of eq. 3: the scan terms of eq. 1 (association.h), eq. 2's gyro term
/// c_G (theta - theta_gyro)^2, and the motion prior (the weak pull prior_weight to the
/// prediction, or the odometry factor: an informative prior with its own information), minimised
/// with Ceres' TinySolver (dense Levenberg-Marquardt, all memory kept between solves) by sigma
/// levels (coarse to fine when configured), re-associating in each.
///
/// The functor sums the Hessian H (PointKernelSum's, projected to be positive semi-definite),
/// the gradient g and the cost |r|^2 over all pairs and the other terms, and hands the solver an
/// equivalent 4-row system:
///   J~ = [L^T; 0],  r~ = [L^-1 g; sqrt(|r|^2 - |L^-1 g|^2)],  H = L L^T,
/// so that J~^T J~ = H, J~^T r~ = g and |r~|^2 = |r|^2: the solver takes exactly the
/// Levenberg-Marquardt steps and cost decisions it would take on the full problem, without
/// storing a residual per pair (fixed size: no allocation, no padding).

#include <ceres/tiny_solver.h>

#include <Eigen/Core>
#include <vector>

#include "ifab/base/estimator/association.h"
#include "ifab/base/estimator/estimator_options.h"
#include "ifab/base/estimator/keyframe_map.h"
#include "ifab/base/estimator/scan_preprocessing.h"

namespace ifab::base {

/// Eq. 3 at one pose for TinySolver (see the file comment). x is the increment about x0.
struct Eq3Cost {
  using Scalar = double;
  enum { NUM_RESIDUALS = 4, NUM_PARAMETERS = 3 };
  const Association* scan{nullptr};
  double sigma{0.05};
  bool use_gyro{false};
  double gyro_weight{0.0};
  double theta_gyro{0.0};
  Eigen::Vector3d x0{Eigen::Vector3d::Zero()};
  Eigen::Vector3d x_pred{Eigen::Vector3d::Zero()};  ///< the predicted pose (the prior's anchor)
  double prior_weight{0.0};                         ///< the weak pull [1/m^2, 1/rad^2]
  double prior_lever{1.0};
  /// The odometry factor (an informative prior): the weight matrix in cost units, replacing
  /// the weak prior_weight pull.
  bool prior_full{false};
  Eigen::Matrix3d prior_W{Eigen::Matrix3d::Zero()};
  bool operator()(const double* x, double* residuals, double* jacobian) const;
};

/// What the solve is given besides the scan.
struct Eq3Problem {
  Eigen::Vector3d x_pred{Eigen::Vector3d::Zero()};  ///< predicted pose (x, y, theta)
  bool use_gyro{false};        ///< eq. 2's term is in (theta_gyro = x_pred's theta)
  bool informative{false};     ///< an informative motion prior (the odometry factor)
  Eigen::Matrix3d info_prior{Eigen::Matrix3d::Zero()};  ///< its information [1/m^2, 1/rad^2]
};

struct Eq3Result {
  Eigen::Vector3d x{Eigen::Vector3d::Zero()};  ///< the solution
  int iterations{0};        ///< LM iterations, summed over rounds and sigma levels
  bool failed{false};       ///< the solver returned a non-finite step
  bool pairs_current{false};  ///< the last association was made at (about) the solution
};

class Eq3Solver {
 public:
  explicit Eq3Solver(const EstimatorOptions& options);

  /// Solve from the prediction over the sigma levels: each level thins the measurement points
  /// (at the level's spacing) into scan->meas_base, then re-associates and solves up to
  /// max_associations times. The odometry factor enters in the scan's cost units: physical
  /// information times the scan terms' residual variance per row, per level
  /// (residual_var[level], measured at the first solve of a level when negative).
  Eq3Result Solve(const Eq3Problem& problem, ScanPreprocessor* points, const KeyframeMap& map,
                  Association* scan, std::vector<double>* residual_var);

 private:
  const EstimatorOptions& o_;
  Eq3Cost cost_;
  ceres::TinySolver<Eq3Cost> solver_;
};

}  // namespace ifab::base
