#include "ifab/perception/dense_lm.h"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>

namespace ifab::internal {

DenseLmSummary SolveDenseLm(const DenseLmEvaluate& evaluate, Eigen::VectorXd& x, const DenseLmOptions& options) {
  DenseLmSummary s;
  const Eigen::Index n = x.size();
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(n);
  double cost = 0.0;
  ++s.evaluations;
  if (!evaluate(x, &cost, &H, &g) || !std::isfinite(cost)) {
    s.message = "the residuals cannot be evaluated at the initial point";
    return s;
  }
  s.usable = true;
  s.initial_cost = s.final_cost = cost;
  if (n == 0) {
    s.message = "no parameters";
    return s;
  }
  double radius = options.initial_trust_region_radius;
  double decrease_factor = 2.0;
  int invalid_steps = 0;
  Eigen::VectorXd scale(n), x_new(n), g_new(n);
  Eigen::MatrixXd H_new(n, n), A(n, n);
  Eigen::LLT<Eigen::MatrixXd> llt(n);
  auto gradient_small = [&] { return g.lpNorm<Eigen::Infinity>() <= options.gradient_tolerance; };
  if (gradient_small()) {
    s.message = "gradient tolerance reached at the initial point";
    return s;
  }
  // Jacobi scaling, as Ceres: columns of J scaled by 1 / (1 + |J_j|), fixed from the first
  // Jacobian on, so the damping treats translations and rotations alike.
  for (Eigen::Index j = 0; j < n; ++j) scale[j] = 1.0 / (1.0 + std::sqrt(std::max(H(j, j), 0.0)));
  auto reject = [&] {
    radius /= decrease_factor;
    decrease_factor *= 2.0;
  };
  s.message = fmt::format("maximum of {} iterations reached", options.max_iterations);
  while (s.iterations < options.max_iterations) {
    ++s.iterations;
    // Scaled system: (S H S + D) d = -S g with D the clamped diagonal of S H S over the radius.
    A = scale.asDiagonal() * H * scale.asDiagonal();
    for (Eigen::Index j = 0; j < n; ++j)
      A(j, j) += std::clamp(A(j, j), options.min_diagonal, options.max_diagonal) / radius;
    llt.compute(A);
    Eigen::VectorXd step;
    double model_change = -1.0;
    if (llt.info() == Eigen::Success) {
      step = scale.asDiagonal() * llt.solve(-(scale.asDiagonal() * g));
      model_change = -(step.dot(g) + 0.5 * step.dot(H * step));
    }
    if (!(model_change > 0.0) || !step.allFinite()) {
      // Cholesky failed or the model promises no decrease: shrink the region and try again.
      if (++invalid_steps > 5) {
        s.usable = true;  // x is the last accepted point
        s.message = "too many consecutive invalid steps";
        return s;
      }
      reject();
      continue;
    }
    invalid_steps = 0;
    x_new = x + step;
    if (step.norm() <= options.parameter_tolerance * (x.norm() + options.parameter_tolerance)) {
      s.message = "parameter tolerance reached";
      return s;
    }
    // The candidate is evaluated with its normal equations: most steps are accepted, and one pass
    // over the points then serves both the test and the next step.
    double cost_new = std::numeric_limits<double>::max();
    H_new.setZero();
    g_new.setZero();
    ++s.evaluations;
    if (!evaluate(x_new, &cost_new, &H_new, &g_new) || !std::isfinite(cost_new))
      cost_new = std::numeric_limits<double>::max();
    const double change = cost - cost_new;
    if (std::abs(change) <= options.function_tolerance * cost) {
      s.message = "function tolerance reached";
      return s;
    }
    const double quality = change / model_change;
    if (quality > options.min_relative_decrease) {
      x = x_new;
      cost = cost_new;
      H.swap(H_new);
      g.swap(g_new);
      s.final_cost = cost;
      radius = std::min(1e16, radius / std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * quality - 1.0, 3)));
      decrease_factor = 2.0;
      if (gradient_small()) {
        s.message = "gradient tolerance reached";
        return s;
      }
    } else {
      reject();
    }
    if (radius < 1e-32) {
      s.message = "trust region radius below its minimum";
      return s;
    }
  }
  return s;
}

}  // namespace ifab::internal
