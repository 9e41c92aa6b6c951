#include "ifab/core/se2.h"

#include <gtest/gtest.h>

namespace ifab {
namespace {

TEST(Pose2, ComposeAndInverse) {
  const Pose2 a(1.0, 2.0, 0.5), b(-0.3, 0.7, -1.2);
  const Pose2 id = a * a.inverse();
  EXPECT_NEAR(id.x, 0.0, 1e-12);
  EXPECT_NEAR(id.y, 0.0, 1e-12);
  EXPECT_NEAR(id.theta, 0.0, 1e-12);
  const Eigen::Vector2d p(0.4, -1.1);
  const Eigen::Vector2d lhs = (a * b) * p, rhs = a * (b * p);
  EXPECT_NEAR((lhs - rhs).norm(), 0.0, 1e-12);
  EXPECT_NEAR(((a.matrix() * b.matrix()) - (a * b).matrix()).norm(), 0.0, 1e-12);
}

TEST(Pose2, RotatesPointsCounterClockwise) {
  const Pose2 t(0.0, 0.0, kPi / 2);
  const Eigen::Vector2d p = t * Eigen::Vector2d(1.0, 0.0);
  EXPECT_NEAR(p.x(), 0.0, 1e-12);
  EXPECT_NEAR(p.y(), 1.0, 1e-12);
}

TEST(Pose2, InterpolateTakesShortestWayAroundPi) {
  const Pose2 a(0, 0, kPi - 0.1), b(2, 0, -kPi + 0.1);
  const Pose2 m = Interpolate(a, b, 0.5);
  EXPECT_NEAR(m.x, 1.0, 1e-12);
  EXPECT_NEAR(std::abs(m.theta), kPi, 1e-12);
}

TEST(Angles, WrapAngle) {
  EXPECT_NEAR(WrapAngle(3 * kPi / 2), -kPi / 2, 1e-12);
  EXPECT_NEAR(WrapAngle(-3 * kPi / 2), kPi / 2, 1e-12);
  EXPECT_NEAR(RadToDeg(DegToRad(33.0)), 33.0, 1e-12);
}

}  // namespace
}  // namespace ifab
