#pragma once
/// \file
/// Internal: Levenberg-Marquardt for problems with few parameters and many residuals, on the
/// normal equations. The caller accumulates J^T J and J^T r point by point, so the Jacobian is
/// never stored (a registration has ~20k residuals and 6-18 parameters: a dense Jacobian costs
/// more to build and reduce than the residuals cost to evaluate). The iteration follows Ceres's
/// trust-region LM (Jacobi scaling, diagonal damping, the same radius updates and tolerances), so
/// it takes the same steps Ceres took on the same problem. Not part of the module's interface.

#include <Eigen/Core>
#include <functional>
#include <string>

namespace ifab::internal {

struct DenseLmOptions {
  int max_iterations{25};                 ///< LM iterations, accepted and rejected steps alike
  double function_tolerance{1e-10};       ///< stop when |cost change| <= this * cost
  double gradient_tolerance{1e-14};       ///< stop when max |J^T r| <= this
  double parameter_tolerance{1e-10};      ///< stop when |step| <= this * (|x| + this)
  double initial_trust_region_radius{1e4};  ///< Ceres's default
  double min_relative_decrease{1e-3};     ///< a step is accepted if it achieves this share of the model's decrease
  double min_diagonal{1e-6};              ///< clamp of the damping diagonal (Ceres's min_lm_diagonal)
  double max_diagonal{1e32};              ///< ... and max_lm_diagonal
};

struct DenseLmSummary {
  bool usable{false};      ///< x holds a valid point at least as good as the start
  std::string message;
  int iterations{0};
  int evaluations{0};      ///< evaluations of the residuals and normal equations
  double initial_cost{0.0};
  double final_cost{0.0};
};

/// Evaluates cost = 0.5 |r(x)|^2 at x; when H and g are non-null, also H = J^T J and g = J^T r
/// there (H and g arrive sized n x n and n, zeroed). Returns false if r cannot be evaluated at x.
using DenseLmEvaluate = std::function<bool(const Eigen::VectorXd& x, double* cost, Eigen::MatrixXd* H,
                                           Eigen::VectorXd* g)>;

/// Minimises the cost from x (updated in place).
DenseLmSummary SolveDenseLm(const DenseLmEvaluate& evaluate, Eigen::VectorXd& x, const DenseLmOptions& options = {});

}  // namespace ifab::internal
