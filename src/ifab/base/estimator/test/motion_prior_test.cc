#include "ifab/base/estimator/motion_prior.h"

#include <gtest/gtest.h>

#include "ifab/core/angles.h"

namespace ifab::base {
namespace {

TEST(OdometryNoise, CovarianceGrowsWithDistanceAndTurn) {
  const OdometryNoise n;
  const Eigen::Matrix3d still = StepCovariance(Pose2(), n);
  EXPECT_NEAR(still(0, 0), n.translation_floor * n.translation_floor, 1e-15);
  EXPECT_NEAR(still(2, 2), n.rotation_floor * n.rotation_floor, 1e-15);
  const Eigen::Matrix3d short_step = StepCovariance(Pose2(0.1, 0.0, 0.0), n);
  const Eigen::Matrix3d long_step = StepCovariance(Pose2(1.0, 0.0, 0.0), n);
  EXPECT_GT(long_step(0, 0), short_step(0, 0));
  EXPECT_GT(long_step(2, 2), short_step(2, 2));
  // Along the motion it is less certain than across (10 % vs 5 % of the distance).
  EXPECT_NEAR(std::sqrt(long_step(0, 0)), 0.10 + n.translation_floor, 1e-12);
  EXPECT_NEAR(std::sqrt(long_step(1, 1)), 0.05 + n.translation_floor, 1e-12);
  // Turning on the spot grows the heading's variance.
  const Eigen::Matrix3d turn = StepCovariance(Pose2(0.0, 0.0, DegToRad(90.0)), n);
  EXPECT_NEAR(std::sqrt(turn(2, 2)), 0.10 * kPi / 2 + n.rotation_floor, 1e-12);
}

TEST(OdometryNoise, AlongTheMotionWhenMovingSideways) {
  const OdometryNoise n;
  const Eigen::Matrix3d c = StepCovariance(Pose2(0.0, 1.0, 0.0), n);
  EXPECT_GT(c(1, 1), c(0, 0));  // the step is along y: y is the uncertain one
}

TEST(OdometryNoise, WorldFrameRotatesTheTranslationBlock) {
  const OdometryNoise n;
  const Eigen::Matrix3d c = StepCovariance(Pose2(1.0, 0.0, 0.0), n);
  const Eigen::Matrix3d w = StepCovarianceInWorld(Pose2(0.0, 0.0, kPi / 2), c);
  EXPECT_NEAR(w(1, 1), c(0, 0), 1e-12);  // heading +90 deg: the step's x is the world's y
  EXPECT_NEAR(w(0, 0), c(1, 1), 1e-12);
  EXPECT_NEAR(w(2, 2), c(2, 2), 1e-15);
}

TEST(OdometryNoise, ReadsYamlAndRejectsBadValues) {
  const auto ok = OdometryNoise::FromConfig(ConfigNode::FromString("translation_per_m: 0.2\n", "t.yaml"));
  EXPECT_DOUBLE_EQ(ok.translation_per_m, 0.2);
  EXPECT_THROW(OdometryNoise::FromConfig(ConfigNode::FromString("translation_floor: 0\n", "t.yaml")),
               InputError);
  EXPECT_THROW(OdometryNoise::FromConfig(ConfigNode::FromString("translaton_per_m: 0.2\n", "t.yaml")),
               InputError);
}

}  // namespace
}  // namespace ifab::base
