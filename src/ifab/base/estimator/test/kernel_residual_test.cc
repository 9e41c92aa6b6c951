#include "ifab/base/estimator/kernel_residual.h"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace ifab::base
