#include "ifab/base/estimator/kernel_residual.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <vector>

#include "ifab/core/testing/numeric_jacobian.h"

namespace ifab::base {
namespace {

// |r|^2 = 1 - G / G(0): squares sum to (pairs - sum of eq. 1's kernels), the paper's score.
TEST(KernelResidual, SquaredNormIsOneMinusNormalisedKernel) {
  const double sigma = 0.05;
  for (double dist : {0.0, 1e-6, 0.003, 0.05, 0.12, 0.4, 3.0}) {
    const Eigen::Vector2d d(dist * 0.6, -dist * 0.8);
    Eigen::Vector2d r;
    KernelResidualOfDifference(d, sigma, &r, nullptr);
    EXPECT_NEAR(r.squaredNorm(), 1.0 - KernelScore(d, sigma), 1e-12) << dist;
    // G(mu, 2 sigma^2 I) has variance 2 sigma^2: exp(-|d|^2 / (2 * 2 sigma^2)).
    EXPECT_NEAR(KernelScore(d, sigma), std::exp(-dist * dist / (4 * sigma * sigma)), 1e-15);
  }
}

TEST(KernelResidual, JacobianMatchesFiniteDifferences) {
  const Eigen::Vector2d q_base(2.0, -0.7);
  for (double sigma : {0.03, 0.2}) {
    for (const Eigen::Vector2d& offset :
         {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(1e-5, -2e-5), Eigen::Vector2d(0.01, 0.02),
          Eigen::Vector2d(-0.08, 0.05), Eigen::Vector2d(0.3, -0.2)}) {
      const Pose2 T(0.4, -1.1, 0.7);
      const Eigen::Vector2d p_ref = T * q_base + offset;
      const KernelPairResidual kp = KernelPair(T, q_base, p_ref, sigma);
      auto f = [&](const Eigen::VectorXd& x) -> Eigen::VectorXd {
        return KernelPair(Pose2(x[0], x[1], x[2]), q_base, p_ref, sigma).r;
      };
      SCOPED_TRACE(::testing::Message() << "sigma " << sigma << " offset " << offset.transpose());
      ifab::testing::ExpectJacobianMatchesNumeric(f, Eigen::Vector3d(T.x, T.y, T.theta), kp.J, 1e-5);
    }
  }
}

TEST(KernelResidual, PointToLineJacobianMatchesFiniteDifferences) {
  const Eigen::Vector2d q_base(1.5, 0.9);
  const Eigen::Vector2d n = Eigen::Vector2d(0.3, 1.0).normalized();
  for (double along : {0.0, 0.01, 0.07, 0.5}) {
    const Pose2 T(-0.2, 0.3, -2.0);
    const Eigen::Vector2d p_ref = T * q_base + along * n + 0.2 * Eigen::Vector2d(-n.y(), n.x());
    double r = 0;
    Eigen::Matrix<double, 1, 3> J;
    KernelLinePair(T, q_base, p_ref, n, 0.05, &r, &J);
    auto f = [&](const Eigen::VectorXd& x) -> Eigen::VectorXd {
      double v = 0;
      KernelLinePair(Pose2(x[0], x[1], x[2]), q_base, p_ref, n, 0.05, &v, nullptr);
      return Eigen::VectorXd::Constant(1, v);
    };
    ifab::testing::ExpectJacobianMatchesNumeric(f, Eigen::Vector3d(T.x, T.y, T.theta), J, 1e-5);
    EXPECT_NEAR(r * r, 1.0 - std::exp(-along * along / (4 * 0.05 * 0.05)), 1e-12);
  }
}

// What the solver uses: a measurement point's share of the cost, (1/2) sum_j (1 - G_ij), with
// its gradient and Hessian with respect to the point, and through the point to the pose.
PointKernelSum SumAt(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& refs, double sigma,
                     bool line) {
  PointKernelSum sum;
  const Eigen::Vector2d n = Eigen::Vector2d(0.2, 1.0).normalized();
  for (std::size_t j = 0; j < refs.size(); ++j) {
    if (line) {
      sum.AddLine(p - refs[j], n, sigma, 0.5 + 0.25 * static_cast<double>(j));
    } else {
      sum.AddPoint(p - refs[j], sigma, 0.5 + 0.25 * static_cast<double>(j));
    }
  }
  return sum;
}

TEST(PointKernelSum, GradientAndHessianMatchFiniteDifferences) {
  const std::vector<Eigen::Vector2d> refs{{0.0, 0.0}, {0.04, 0.01}, {0.09, -0.02}, {-0.05, 0.03}};
  for (bool line : {false, true}) {
    for (const Eigen::Vector2d& p : {Eigen::Vector2d(0.01, 0.02), Eigen::Vector2d(0.1, -0.07),
                                     Eigen::Vector2d(-0.12, 0.15)}) {
      SCOPED_TRACE(::testing::Message() << "line " << line << " p " << p.transpose());
      const PointKernelSum sum = SumAt(p, refs, 0.05, line);
      auto cost = [&](const Eigen::VectorXd& x) -> Eigen::VectorXd {
        return Eigen::VectorXd::Constant(1, SumAt(x, refs, 0.05, line).cost);
      };
      auto gradient = [&](const Eigen::VectorXd& x) -> Eigen::VectorXd {
        return SumAt(x, refs, 0.05, line).gradient;
      };
      ifab::testing::ExpectJacobianMatchesNumeric(cost, p, sum.gradient.transpose(), 1e-6);
      ifab::testing::ExpectJacobianMatchesNumeric(gradient, p, sum.hessian, 1e-5);
      // The projected Hessian is positive semi-definite and equal to the Hessian where that is.
      const Eigen::Matrix2d psd = sum.PsdHessian();
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(psd);
      EXPECT_GE(es.eigenvalues().minCoeff(), -1e-9);
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es_full(sum.hessian);
      if (es_full.eigenvalues().minCoeff() >= 0.0) {
        EXPECT_LT((psd - sum.hessian).norm(), 1e-9);
      }
    }
  }
}

// The cost as a function of the pose: its gradient is J_p^T (d cost / d p).
TEST(PointKernelSum, PoseGradientMatchesFiniteDifferences) {
  const Eigen::Vector2d q_base(2.0, -0.6);
  const std::vector<Eigen::Vector2d> refs{{1.9, 0.5}, {1.95, 0.47}, {2.05, 0.52}};
  const Pose2 T(0.3, 1.0, 0.4);
  auto cost = [&](const Eigen::VectorXd& x) -> Eigen::VectorXd {
    const Pose2 pose(x[0], x[1], x[2]);
    return Eigen::VectorXd::Constant(1, SumAt(pose * q_base, refs, 0.05, false).cost);
  };
  const Eigen::Vector2d p = T * q_base;
  const Eigen::Vector3d g = PointJacobian(T.translation(), p).transpose() * SumAt(p, refs, 0.05, false).gradient;
  ifab::testing::ExpectJacobianMatchesNumeric(cost, Eigen::Vector3d(T.x, T.y, T.theta), g.transpose(), 1e-6);
  // And the cost is eq. 1's: (1/2) sum_j w_j (1 - exp(-|d|^2 / (4 sigma^2))).
  double expected = 0.0;
  for (std::size_t j = 0; j < refs.size(); ++j) {
    expected += 0.5 * (0.5 + 0.25 * static_cast<double>(j)) * (1.0 - KernelScore(p - refs[j], 0.05));
  }
  EXPECT_NEAR(SumAt(p, refs, 0.05, false).cost, expected, 1e-12);
}

}  // namespace
}  // namespace ifab::base
