#include "ifab/arm/ik.h"

#include <gtest/gtest.h>

#include "ifab/core/data_path.h"
#include "ifab/core/random.h"

namespace ifab::arm {
namespace {

class IkTest : public ::testing::Test {
 protected:
  IkTest() : robot_(LoadRobotModel(DataPath("robots/insitu_fabricator.urdf"))), ik_(robot_) {}
  // Random configuration away from the limits and from the wrist singularity (q5 = 0).
  Vector6d RandomQ(RandomStream& rng) const {
    Vector6d q;
    for (int i = 0; i < 6; ++i) {
      const double lo = std::max(robot_.q_min[i], -3.0), hi = std::min(robot_.q_max[i], 3.0);
      q[i] = rng.Uniform(lo + 0.1, hi - 0.1);
    }
    if (std::abs(q[4]) < 0.2) q[4] = 0.2;
    return q;
  }
  RobotModel robot_;
  IkSolver ik_;
};

TEST_F(IkTest, FindsTheConfigurationWeStartNear) {
  RandomStream rng(11);
  for (int trial = 0; trial < 50; ++trial) {
    const Vector6d q = RandomQ(rng);
    const Pose3 target = robot_.ArmForwardKinematics(q);
    Vector6d near = q;
    for (int i = 0; i < 6; ++i) near[i] += rng.Uniform(-0.05, 0.05);
    const IkResult r = ik_.Solve(target, near);
    ASSERT_TRUE(r.ok()) << r.message;
    EXPECT_LT(r.position_error, 1e-6);
    EXPECT_LT(r.orientation_error, 1e-6);
    // The nearest of the solutions is the one we came from.
    EXPECT_LT((r.q - q).cwiseAbs().maxCoeff(), 1e-4) << "trial " << trial;
    EXPECT_TRUE(robot_.WithinLimits(r.q));
  }
}

TEST_F(IkTest, SolvesFromFarStartsWithinLimits) {
  RandomStream rng(12);
  int solved = 0;
  for (int trial = 0; trial < 30; ++trial) {
    const Pose3 target = robot_.ArmForwardKinematics(RandomQ(rng));
    const IkResult r = ik_.Solve(target, RandomQ(rng));
    if (!r.ok()) continue;
    ++solved;
    EXPECT_TRUE(robot_.WithinLimits(r.q));
    const Pose3 reached = robot_.ArmForwardKinematics(r.q);
    EXPECT_LT(TranslationDistance(reached, target), 1e-6);
    EXPECT_LT(RotationAngle(reached, target), 1e-6);
  }
  EXPECT_GE(solved, 29);  // reachable by construction; random starts may rarely all miss
}

TEST_F(IkTest, ReportsAPoseOutOfReach) {
  Pose3 far = Pose3::Identity();
  far.translation() = Eigen::Vector3d(4.0, 0.0, 1.0);  // the arm reaches 2.55 m
  const IkResult r = ik_.Solve(far, Vector6d::Zero());
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(r.status, IkStatus::kOutOfReach);
  EXPECT_NE(r.message.find("out of reach"), std::string::npos) << r.message;
  EXPECT_GT(r.position_error, 1.0);
}

TEST_F(IkTest, IsDeterministic) {
  RandomStream rng(13);
  const Pose3 target = robot_.ArmForwardKinematics(RandomQ(rng));
  const Vector6d start = RandomQ(rng);
  const IkResult a = ik_.Solve(target, start);
  const IkResult b = ik_.Solve(target, start);
  EXPECT_EQ(a.status, b.status);
  EXPECT_EQ(a.q, b.q);
}

}  // namespace
}  // namespace ifab::arm
