#pragma once
/// \file
/// Test helper used by every module with analytic or autodiff derivatives (STYLE.md):
/// compare a Jacobian against central finite differences.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <functional>

namespace ifab::testing {

/// Central-difference Jacobian of f at x.
inline Eigen::MatrixXd NumericJacobian(
    const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& f, const Eigen::VectorXd& x,
    double step = 1e-6) {
  const Eigen::VectorXd f0 = f(x);
  Eigen::MatrixXd j(f0.size(), x.size());
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    Eigen::VectorXd xp = x, xm = x;
    xp[k] += step;
    xm[k] -= step;
    j.col(k) = (f(xp) - f(xm)) / (2.0 * step);
  }
  return j;
}

/// EXPECT that `jacobian` matches the numeric Jacobian of f at x, entry by entry, within
/// tol * max(1, |entry|).
inline void ExpectJacobianMatchesNumeric(
    const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& f, const Eigen::VectorXd& x,
    const Eigen::MatrixXd& jacobian, double tol = 1e-6, double step = 1e-6) {
  const Eigen::MatrixXd numeric = NumericJacobian(f, x, step);
  ASSERT_EQ(numeric.rows(), jacobian.rows());
  ASSERT_EQ(numeric.cols(), jacobian.cols());
  for (Eigen::Index r = 0; r < numeric.rows(); ++r) {
    for (Eigen::Index c = 0; c < numeric.cols(); ++c) {
      const double scale = std::max(1.0, std::abs(numeric(r, c)));
      EXPECT_NEAR(jacobian(r, c), numeric(r, c), tol * scale) << "entry (" << r << ", " << c << ")";
    }
  }
}

}  // namespace ifab::testing
