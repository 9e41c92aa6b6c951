// The solve of eq. 3 alone: scan terms, the gyro term and the motion prior.
#include "ifab/base/estimator/eq3_solver.h"

#include <gtest/gtest.h>

#include "ifab/base/estimator/test/synthetic_scans.h"
#include "ifab/core/angles.h"

namespace ifab::base {
namespace {

// A keyframe of `world` at the origin and a measurement scan from T_true.
struct Eq3Setup {
  Eq3Setup(const testing::World& world, const Pose2& T_true, EstimatorOptions options)
      : o(std::move(options)), pre(o, Pose2()), map(o), scan(o), solver(o) {
    pre.Extract(testing::CastScan(world, Pose2(), 0.0));
    map.Add(Pose2(), 0.0, &pre);
    pre.Extract(testing::CastScan(world, T_true, 0.1));
    map.Select(T_true);
    residual_var.assign(static_cast<std::size_t>(NumLevels(o)), -1.0);
  }
  Eq3Result Solve(const Eq3Problem& p) { return solver.Solve(p, &pre, map, &scan, &residual_var); }
  EstimatorOptions o;
  ScanPreprocessor pre;
  KeyframeMap map;
  Association scan;
  Eq3Solver solver;
  std::vector<double> residual_var;
};

TEST(Eq3Solver, RecoversTheMotionFromAnOffsetStart) {
  EstimatorOptions o;
  o.coarse_sigmas = {0.15};
  const Pose2 T_true(0.12, -0.07, DegToRad(3.0));
  Eq3Setup s(testing::LRoom(), T_true, o);
  Eq3Problem p;  // predicted at the origin, no gyro
  const Eq3Result r = s.Solve(p);
  ASSERT_FALSE(r.failed);
  EXPECT_NEAR(r.x[0], T_true.x, 2e-3);
  EXPECT_NEAR(r.x[1], T_true.y, 2e-3);
  EXPECT_NEAR(r.x[2], T_true.theta, DegToRad(0.05));
  EXPECT_GT(r.iterations, 0);
}

TEST(Eq3Solver, TheGyroTermHoldsTheHeading) {
  // In a circular room the scan says nothing about the heading: the gyro decides it.
  EstimatorOptions o;
  const Pose2 T_true(0.02, 0.01, DegToRad(2.0));
  Eq3Setup s(testing::RegularRoom(720, 3.0), T_true, o);
  Eq3Problem p;
  p.x_pred = Eigen::Vector3d(0.0, 0.0, DegToRad(1.5));  // the gyro's heading
  p.use_gyro = true;
  const Eq3Result r = s.Solve(p);
  ASSERT_FALSE(r.failed);
  EXPECT_NEAR(r.x[2], DegToRad(1.5), DegToRad(0.01));
  EXPECT_NEAR(r.x[0], T_true.x, 2e-3);
  EXPECT_NEAR(r.x[1], T_true.y, 2e-3);
}

TEST(Eq3Solver, AnInformativePriorDecidesTheCorridorAxisTheWeakPullDoesNot) {
  EstimatorOptions o;
  const Pose2 T_true(0.3, 0.02, 0.0);
  Eq3Problem p;
  p.x_pred = Eigen::Vector3d(0.25, 0.0, 0.0);
  p.use_gyro = true;
  {
    Eq3Setup s(testing::Corridor(), T_true, o);
    const Eq3Result r = s.Solve(p);
    ASSERT_FALSE(r.failed);
    EXPECT_NEAR(r.x[1], T_true.y, 2e-3);  // across: the scan
    // Along: the weak pull (prior_weight 1) or the reference's ripple, never the truth.
    EXPECT_GT(std::abs(r.x[0] - T_true.x), 0.02);
  }
  {
    Eq3Setup s(testing::Corridor(), T_true, o);
    p.informative = true;
    p.info_prior = Eigen::Vector3d(1.0 / (0.002 * 0.002), 1.0, 1.0 / 1e-6).asDiagonal();  // 2 mm along, 1 m across
    p.x_pred = Eigen::Vector3d(0.29, 0.0, 0.0);
    const Eq3Result r = s.Solve(p);
    ASSERT_FALSE(r.failed);
    EXPECT_NEAR(r.x[0], 0.29, 3e-3);      // along: the prior
    EXPECT_NEAR(r.x[1], T_true.y, 2e-3);  // across: still the scan
  }
}

TEST(Eq3Cost, HandsTheSolverTheGradientAndHessianOfTheFullProblem) {
  EstimatorOptions o;
  Eq3Setup s(testing::LRoom(), Pose2(0.02, 0.01, 0.01), o);
  s.pre.Thin(o.min_point_spacing, 1e9, o.max_points, &s.scan.meas_base);
  s.scan.Associate(s.map, Pose2(), 0, o.search_radius_sigmas * std::sqrt(2.0) * o.sigma);
  Eq3Cost cost;
  cost.scan = &s.scan;
  cost.sigma = o.sigma;
  cost.use_gyro = true;
  cost.gyro_weight = 1e4;
  cost.theta_gyro = 0.01;
  cost.prior_weight = 1.0;
  const double x[3] = {0.004, -0.003, 0.002};
  double r[4], J[12];
  ASSERT_TRUE(cost(x, r, J));
  const Eigen::Map<const Eigen::Matrix<double, 4, 3>> Jm(J);
  const Eigen::Map<const Eigen::Vector4d> rm(r);
  NormalEquations ne = s.scan.Accumulate(Pose2(x[0], x[1], x[2]), o.sigma);
  const double e_g = x[2] - 0.01;
  ne.H(2, 2) += 1e4;
  ne.g(2) += 1e4 * e_g;
  ne.sum_sq += 1e4 * e_g * e_g;
  const Eigen::Vector3d dx(x[0], x[1], x[2]);
  ne.H.diagonal() += Eigen::Vector3d::Ones();
  ne.g += dx;
  ne.sum_sq += dx.squaredNorm();
  EXPECT_NEAR((Jm.transpose() * Jm - ne.H).norm(), 0.0, 1e-6 * ne.H.norm());
  EXPECT_NEAR((Jm.transpose() * rm - ne.g).norm(), 0.0, 1e-6 * ne.g.norm() + 1e-9);
  EXPECT_NEAR(rm.squaredNorm(), ne.sum_sq, 1e-9 * ne.sum_sq);
}

}  // namespace
}  // namespace ifab::base
