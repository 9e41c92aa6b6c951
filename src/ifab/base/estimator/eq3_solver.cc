#include "ifab/base/estimator/eq3_solver.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>

#include "ifab/core/angles.h"

namespace ifab::base {

bool Eq3Cost::operator()(const double* x, double* residuals, double* jacobian) const {
  const Pose2 T_world_base(x0[0] + x[0], x0[1] + x[1], x0[2] + x[2]);
  NormalEquations ne = scan->Accumulate(T_world_base, sigma);
  // Eq. 2: E_G = theta_k - (theta_{k-1} + sum omega_i dt), weighted by c_G.
  if (use_gyro) {
    const double e_g = WrapAngle(T_world_base.theta - theta_gyro);
    ne.H(2, 2) += gyro_weight;
    ne.g(2) += gyro_weight * e_g;
    ne.sum_sq += gyro_weight * e_g * e_g;
  }
  // A weak pull to the prediction keeps directions the scan does not observe (a corridor's
  // axis) at the prediction instead of letting the solver wander along them.
  if (prior_full) {
    Eigen::Vector3d dx(x0[0] + x[0] - x_pred[0], x0[1] + x[1] - x_pred[1], 0.0);
    dx[2] = WrapAngle(x0[2] + x[2] - x_pred[2]);
    const Eigen::Vector3d Wdx = prior_W * dx;
    ne.H += prior_W;
    ne.g += Wdx;
    ne.sum_sq += dx.dot(Wdx);
  } else if (prior_weight > 0.0) {
    const Eigen::Vector3d w(prior_weight, prior_weight, prior_weight * prior_lever * prior_lever);
    Eigen::Vector3d dx(x0[0] + x[0] - x_pred[0], x0[1] + x[1] - x_pred[1], 0.0);
    dx[2] = WrapAngle(x0[2] + x[2] - x_pred[2]);
    ne.H.diagonal() += w;
    ne.g += w.cwiseProduct(dx);
    ne.sum_sq += dx.dot(w.cwiseProduct(dx));
  }
  if (!std::isfinite(ne.sum_sq)) return false;
  if (!jacobian) {
    residuals[0] = std::sqrt(ne.sum_sq);
    residuals[1] = residuals[2] = residuals[3] = 0.0;
    return true;
  }
  // H = L L^T (a tiny ridge keeps it factorable when a direction is unobserved).
  const double ridge = 1e-12 * (ne.H.trace() + 1.0);
  const Eigen::LLT<Eigen::Matrix3d> llt(ne.H + ridge * Eigen::Matrix3d::Identity());
  if (llt.info() != Eigen::Success) return false;
  const Eigen::Matrix3d L = llt.matrixL();
  const Eigen::Vector3d r3 = L.triangularView<Eigen::Lower>().solve(ne.g);
  residuals[0] = r3[0];
  residuals[1] = r3[1];
  residuals[2] = r3[2];
  residuals[3] = std::sqrt(std::max(0.0, ne.sum_sq - r3.squaredNorm()));
  // Column-major 4 x 3: J~ = [L^T; 0].
  for (int c = 0; c < 3; ++c) {
    for (int r = 0; r < 3; ++r) jacobian[c * 4 + r] = L(c, r);
    jacobian[c * 4 + 3] = 0.0;
  }
  return true;
}

Eq3Solver::Eq3Solver(const EstimatorOptions& options) : o_(options) {
  solver_.options.max_num_iterations = o_.max_iterations + 1;  // TinySolver counts from 1
  // Stop when a step is below 1e-4 of the increment so far (the increment is relative to the
  // round's start pose: ~10 um for a 0.1 m motion).
  solver_.options.parameter_tolerance = 1e-3;
  solver_.options.gradient_tolerance = 1e-10;
}

Eq3Result Eq3Solver::Solve(const Eq3Problem& problem, ScanPreprocessor* points, const KeyframeMap& map,
                           Association* scan, std::vector<double>* residual_var) {
  Eq3Result result;
  Eigen::Vector3d& x = result.x;
  x = problem.x_pred;
  cost_.scan = scan;
  cost_.use_gyro = problem.use_gyro;
  cost_.gyro_weight = o_.gyro_weight;
  cost_.theta_gyro = problem.x_pred[2];
  cost_.x_pred = problem.x_pred;
  cost_.prior_weight = o_.prior_weight;
  cost_.prior_lever = 1.0;
  cost_.prior_full = problem.informative;
  const int num_levels = NumLevels(o_);
  for (int level = 0; level < num_levels; ++level) {
    const double sigma = LevelSigma(o_, level);
    const double radius = o_.search_radius_sigmas * std::sqrt(2.0) * sigma;
    points->Thin(MeasurementSpacing(o_, level), std::numeric_limits<double>::infinity(), o_.max_points,
                 &scan->meas_base);
    cost_.sigma = sigma;
    for (int round = 0; round < o_.max_associations; ++round) {
      scan->Associate(map, Pose2(x[0], x[1], x[2]), level, radius);
      if (scan->Empty()) break;
      if (problem.informative) {
        // The odometry factor in the scan's cost units: physical information times the scan
        // terms' residual variance per row (the same factor that turns the scan's Hessian into
        // its covariance), so each side weighs by what it knows.
        double& var = (*residual_var)[static_cast<std::size_t>(level)];
        if (var <= 0.0) {
          const NormalEquations ne0 = scan->Accumulate(Pose2(x[0], x[1], x[2]), sigma);
          var = std::max(ne0.sum_sq / std::max(1, ne0.rows - 3), 1e-12);
        }
        cost_.prior_W = var * problem.info_prior;
      }
      // TinySolver's function tolerance is absolute (on 2 * cost): scale it with the pairs.
      solver_.options.function_tolerance = 1e-8 * static_cast<double>(scan->pairs().size());
      cost_.x0 = x;
      Eigen::Vector3d increment = Eigen::Vector3d::Zero();
      const auto& summary = solver_.Solve(cost_, &increment);
      result.iterations += std::max(0, summary.iterations);
      if (!increment.allFinite()) {
        result.failed = true;
        return result;
      }
      x += increment;
      x[2] = WrapAngle(x[2]);
      result.pairs_current = std::max(increment.head<2>().norm(), std::abs(increment[2])) < o_.converged_step;
      if (result.pairs_current) break;
    }
  }
  return result;
}

}  // namespace ifab::base
