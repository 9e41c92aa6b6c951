#include "ifab/base/planner/trajectory_cost.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>

#include "ifab/core/angles.h"
#include "ifab/core/random.h"
#include "ifab/core/testing/numeric_jacobian.h"

namespace ifab::base {
namespace {

TrajectoryMatrix RandomTrajectory(int n_free, std::uint64_t seed, double scale = 1.0) {
  RandomStream rng(seed);
  TrajectoryMatrix q(n_free + 2, 3);
  for (int i = 0; i < q.rows(); ++i) {
    const double t = static_cast<double>(i) / (n_free + 1);
    q.row(i) << 3.0 * t + scale * rng.Normal(0.1), -1.0 + 2.0 * t * t + scale * rng.Normal(0.1),
        0.5 + t + scale * rng.Normal(0.2);
  }
  return q;
}

// Free points stacked as [x_1..x_N, y_1..y_N, theta_1..theta_N].
Eigen::VectorXd Stack(const TrajectoryMatrix& q) {
  const int n = static_cast<int>(q.rows()) - 2;
  Eigen::VectorXd v(3 * n);
  for (int d = 0; d < 3; ++d) v.segment(d * n, n) = q.col(d).segment(1, n);
  return v;
}
TrajectoryMatrix Unstack(const TrajectoryMatrix& q, const Eigen::VectorXd& v) {
  const int n = static_cast<int>(q.rows()) - 2;
  TrajectoryMatrix out = q;
  for (int d = 0; d < 3; ++d) out.col(d).segment(1, n) = v.segment(d * n, n);
  return out;
}

TEST(AccelerationMatrix, GivesRestPaddedSecondDifferences) {
  const int n = 6;
  const TrajectoryMatrix q = RandomTrajectory(n, 1);
  const Eigen::MatrixXd A = AccelerationMatrix(n);
  ASSERT_EQ(A.rows(), n + 2);
  ASSERT_EQ(A.cols(), n);
  // With the fixed start and goal set to zero, A * free = second differences of the padded path.
  TrajectoryMatrix z = q;
  z.row(0).setZero();
  z.row(n + 1).setZero();
  const Eigen::VectorXd a = A * z.col(0).segment(1, n);
  for (int i = 0; i < n + 2; ++i) {
    const double prev = i == 0 ? z(0, 0) : z(i - 1, 0);
    const double next = i == n + 1 ? z(n + 1, 0) : z(i + 1, 0);
    EXPECT_NEAR(a[i], prev - 2 * z(i, 0) + next, 1e-12) << i;
  }
  // R = A^T A is positive definite, so STOMP's noise covariance R^-1 exists.
  const Eigen::MatrixXd R = A.transpose() * A;
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(R).eigenvalues().minCoeff(), 1e-6);
}

TEST(SmoothnessCosts, MatchIntegralsOfSquaredAccelerationAndJerk) {
  const int n = 10;
  const TrajectoryMatrix q = RandomTrajectory(n, 2);
  SmoothnessWeights w;
  w.acceleration = 2.0;
  w.jerk = 0.1;
  w.heading_scale = 0.7;
  Eigen::VectorXd per_point = Eigen::VectorXd::Zero(n + 2);
  AddSmoothnessCosts(q, w, &per_point);
  // Independent computation: pad, difference, sum.
  const double inv = n + 1;
  std::vector<Eigen::Vector3d> p;
  p.push_back(q.row(0).transpose());  // q[-1]
  for (int i = 0; i < n + 2; ++i) p.push_back(q.row(i).transpose());
  p.push_back(q.row(n + 1).transpose());  // q[N+2]
  const Eigen::Vector3d s(1, 1, w.heading_scale);
  double acc = 0.0, jerk = 0.0;
  std::vector<Eigen::Vector3d> a(n + 4, Eigen::Vector3d::Zero());  // a[-1] .. a[N+2]
  for (int i = 0; i < n + 2; ++i) a[i + 1] = (p[i] - 2 * p[i + 1] + p[i + 2]).cwiseProduct(s) * inv * inv;
  for (int i = 0; i < n + 2; ++i) acc += a[i + 1].squaredNorm() / inv;
  for (int i = 0; i < n + 3; ++i) jerk += ((a[i + 1] - a[i]) * inv).squaredNorm() / inv;
  EXPECT_NEAR(per_point.sum(), w.acceleration * acc + w.jerk * jerk, 1e-9 * per_point.sum());
  EXPECT_TRUE((per_point.array() >= 0).all());
}

TEST(SmoothnessCosts, StraightUniformMotionCostsOnlyStartingAndStopping) {
  const int n = 20;
  TrajectoryMatrix q(n + 2, 3);
  for (int i = 0; i < n + 2; ++i) q.row(i) << i * 0.1, 0.0, 0.0;
  Eigen::VectorXd c = Eigen::VectorXd::Zero(n + 2);
  AddSmoothnessCosts(q, SmoothnessWeights{1.0, 0.0, 1.0}, &c);
  for (int i = 2; i < n; ++i) EXPECT_NEAR(c[i], 0.0, 1e-12) << i;
  EXPECT_GT(c[0], 0.0);
  EXPECT_GT(c[n + 1], 0.0);
}

TEST(LateralResiduals, ZeroOnArcsAndStraightLinesFullOnSidewaysMotion) {
  // Poses on a circle of radius 2 with the heading along it: chords point along the mean heading.
  const int n = 8;
  TrajectoryMatrix arc(n + 2, 3);
  for (int i = 0; i < n + 2; ++i) {
    const double a = 0.2 * i;
    arc.row(i) << 2 * std::sin(a), 2 - 2 * std::cos(a), a;
  }
  EXPECT_LT(LateralResiduals(arc).cwiseAbs().maxCoeff(), 1e-12);
  // Reversing along the same arc (heading + pi) is also allowed.
  TrajectoryMatrix reverse = arc;
  reverse.col(2).array() += kPi;
  EXPECT_LT(LateralResiduals(reverse).cwiseAbs().maxCoeff(), 1e-12);
  // Sliding sideways by 0.1 m per step: every residual is the full displacement.
  TrajectoryMatrix sideways(n + 2, 3);
  for (int i = 0; i < n + 2; ++i) sideways.row(i) << 0.0, 0.1 * i, 0.0;
  for (int j = 0; j <= n; ++j) EXPECT_NEAR(LateralResiduals(sideways)[j], 0.1, 1e-12);
}

TEST(LateralJacobian, MatchesFiniteDifferences) {
  for (std::uint64_t seed : {3u, 4u, 5u}) {
    const int n = 7;
    const TrajectoryMatrix q = RandomTrajectory(n, seed);
    const LateralJacobian J = LinearizeLateral(q);
    const auto f = [&](const Eigen::VectorXd& x) { return LateralResiduals(Unstack(q, x)); };
    ifab::testing::ExpectJacobianMatchesNumeric(f, Stack(q), J.Dense(), 1e-7);
    // The sparse product agrees with the dense matrix.
    const TrajectoryMatrix v = RandomTrajectory(n, seed + 10).middleRows(1, n);
    TrajectoryMatrix vq = q;
    vq.middleRows(1, n) = v;
    EXPECT_LT((J.Apply(v) - J.Dense() * Stack(vq)).cwiseAbs().maxCoeff(), 1e-12);
  }
}

class ProjectorTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const Eigen::MatrixXd A = AccelerationMatrix(n);
    const Eigen::MatrixXd Rinv = (A.transpose() * A).inverse();
    S = Rinv / Rinv.maxCoeff();
    projector.Reset(S, Eigen::Vector3d(0.3, 0.3, 0.5), 1e-12);
    q = RandomTrajectory(n, 11, 0.3);
    projector.Linearize(q);
  }
  const int n = 12;
  Eigen::MatrixXd S;
  ConstraintProjector projector;
  TrajectoryMatrix q;
};

TEST_F(ProjectorTest, NoiseLandsInTheConstraintNullSpace) {
  const TrajectoryMatrix noise = RandomTrajectory(n, 12).middleRows(1, n);
  TrajectoryMatrix v = noise;
  projector.Project(&v);
  EXPECT_LT(projector.jacobian().Apply(v).cwiseAbs().maxCoeff(), 1e-9);
  // Projecting again changes nothing.
  TrajectoryMatrix w = v;
  projector.Project(&w);
  EXPECT_LT((w - v).cwiseAbs().maxCoeff(), 1e-9);
  // The correction lies in the range of Sigma C^T: Sigma^-1 (noise - v) is a combination of the
  // constraint gradients, i.e. orthogonal to the null space (checked against v itself).
  const int m = 3 * n;
  Eigen::MatrixXd Sigma = Eigen::MatrixXd::Zero(m, m);
  const double var[3] = {0.09, 0.09, 0.25};
  for (int d = 0; d < 3; ++d) Sigma.block(d * n, d * n, n, n) = var[d] * S;
  const auto stack = [&](const TrajectoryMatrix& t) {
    Eigen::VectorXd s(m);
    for (int d = 0; d < 3; ++d) s.segment(d * n, n) = t.col(d);
    return s;
  };
  const Eigen::VectorXd corr = Sigma.ldlt().solve(stack(noise) - stack(v));
  EXPECT_NEAR(corr.dot(stack(v)), 0.0, 1e-6 * corr.norm() * stack(v).norm());
}

TEST_F(ProjectorTest, WithResidualTheStepSatisfiesTheLinearisedConstraints) {
  const Eigen::VectorXd r = LateralResiduals(q);
  TrajectoryMatrix step = TrajectoryMatrix::Zero(n, 3);
  projector.Project(&step, &r);
  EXPECT_LT((projector.jacobian().Apply(step) + r).cwiseAbs().maxCoeff(), 1e-9);
}

TEST_F(ProjectorTest, GaussNewtonStepsConvergeNearAFeasibleTrajectory) {
  // An arc (feasible) disturbed by 1 cm and 0.01 rad: each step shrinks the residual many times.
  TrajectoryMatrix near(n + 2, 3);
  RandomStream rng(13);
  for (int i = 0; i < n + 2; ++i) {
    const double a = 0.1 * i;
    near.row(i) << 3 * std::sin(a), 3 - 3 * std::cos(a), a;
    if (i > 0 && i < n + 1) {  // last coordinate first: gcc's order of a call's arguments
      const double dt = rng.Normal(0.01), dy = rng.Normal(0.01), dx = rng.Normal(0.01);
      near.row(i) += Eigen::RowVector3d(dx, dy, dt);
    }
  }
  double before = LateralResiduals(near).norm();
  for (int it = 0; it < 3; ++it) {
    projector.Linearize(near);
    const Eigen::VectorXd r = LateralResiduals(near);
    TrajectoryMatrix step = TrajectoryMatrix::Zero(n, 3);
    projector.Project(&step, &r);
    near.middleRows(1, n) += step;
    const double after = LateralResiduals(near).norm();
    EXPECT_LT(after, 0.1 * before) << "step " << it;
    before = after;
  }
  EXPECT_LT(before, 1e-9);
}

}  // namespace
}  // namespace ifab::base
