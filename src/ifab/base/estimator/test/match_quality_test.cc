// The quality check's parts alone: structure trust, gate thresholds, window gate, prior scale.
#include "ifab/base/estimator/match_quality.h"

#include <gtest/gtest.h>

namespace ifab::base {
namespace {

TEST(MatchQuality, StructureTrustRemovesTheDirectionTheSceneLeavesOpen) {
  // Kernel information with a little curvature along x (a corridor's ripple); structure with
  // none along x.
  const Eigen::Matrix3d info = Eigen::Vector3d(50.0, 1e6, 1e5).asDiagonal();
  const Eigen::Matrix3d S = Eigen::Vector3d(0.0, 300.0, 900.0).asDiagonal();
  const Eigen::Matrix3d trusted = StructureTrustedInformation(info, S, 2.0, 0.01);
  EXPECT_NEAR(trusted(0, 0), 0.0, 1e-9);
  EXPECT_NEAR(trusted(1, 1), 1e6, 1e-3);
  EXPECT_NEAR(trusted(2, 2), 1e5, 1e-3);
  // A room: nothing is removed.
  const Eigen::Matrix3d S_room = Eigen::Vector3d(200.0, 300.0, 900.0).asDiagonal();
  EXPECT_NEAR((StructureTrustedInformation(info, S_room, 2.0, 0.01) - info).norm(), 0.0, 1e-6);
}

TEST(MatchQuality, GateThresholdsAreChiSquareQuantiles) {
  const GateTable g(0.999);
  EXPECT_NEAR(g.quantile[1], 10.828, 1e-3);
  EXPECT_NEAR(g.quantile[2], 13.816, 1e-3);
  EXPECT_NEAR(g.quantile[3], 16.266, 1e-3);
  EXPECT_NEAR(g.median[2], 1.386, 1e-3);
  const GateTable off(0.0);
  EXPECT_TRUE(std::isinf(off.quantile[2]));
}

TEST(MatchQuality, WindowGateTellsAMatchThatFallsBehindTheChainFromOneThatFollowsIt) {
  EstimatorOptions o;
  o.window_gate_probability = 0.999;
  o.window_gate_distance = 1.0;
  WindowGate gate(o);
  ASSERT_TRUE(gate.enabled());
  MotionMeasurement step;
  step.step = Pose2(0.05, 0.0, 0.0);
  step.covariance = Eigen::Vector3d(1e-6, 1e-6, 1e-8).asDiagonal();  // 1 mm per 5 cm step
  const Eigen::Matrix3d cov = Eigen::Vector3d(1e-6, 1e-6, 1e-8).asDiagonal();
  Pose2 pose;
  gate.Push(pose, cov, true, true, &step);
  for (int k = 1; k <= 40; ++k) {  // 2 m of travel along x, the estimate following
    pose = pose * step.step;
    gate.Push(pose, cov, true, true, &step);
  }
  const Pose2 expected = pose * step.step;
  EXPECT_LT(gate.MahalanobisSq(expected, cov), 1.0);
  EXPECT_LT(gate.MahalanobisSq(expected, cov), gate.threshold());
  // Clinging to where the robot was a metre ago.
  const Pose2 clinging = expected * Pose2(-0.3, 0.0, 0.0);
  EXPECT_GT(gate.MahalanobisSq(clinging, cov), gate.threshold());
  // A scan without an informative step breaks the chain.
  gate.Push(pose, cov, true, false, nullptr);
  EXPECT_LT(gate.MahalanobisSq(clinging, cov), 0.0);
  gate.Clear();
  EXPECT_LT(gate.MahalanobisSq(clinging, cov), 0.0);
}

TEST(MatchQuality, PriorScaleFollowsTheInnovationsButNeverShrinksTheModel) {
  EstimatorOptions o;
  o.prior_scale_window = 50;
  const GateTable g(0.999);
  PriorScale scale(o);
  // Innovations four times the chi-square median against the model: it was four times too
  // small. Each innovation is computed against the scaled covariance, as the estimator does.
  for (int k = 0; k < 50; ++k) scale.Add(4.0 * g.median[2] / scale.scale(), 2, g.median);
  EXPECT_NEAR(scale.scale(), 4.0, 1e-9);
  PriorScale small(o);
  for (int k = 0; k < 50; ++k) small.Add(0.1 * g.median[2], 2, g.median);
  EXPECT_DOUBLE_EQ(small.scale(), 1.0);
  EstimatorOptions off;
  PriorScale none(off);
  none.Add(100.0, 2, g.median);
  EXPECT_DOUBLE_EQ(none.scale(), 1.0);
}

}  // namespace
}  // namespace ifab::base
