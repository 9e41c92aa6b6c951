#include "ifab/arm/primitives.h"

#include <gtest/gtest.h>

#include "ifab/arm/test/joint_degrees.h"
#include "ifab/arm/dynamics.h"
#include "ifab/core/angles.h"
#include "ifab/core/data_path.h"

namespace ifab::arm {
namespace {

// A kinematic stand-in for the robot: the arm jumps to a trajectory's last point when it ends,
// and the vacuum gripper carries a brick rigidly from the moment it grips.
class FakeArmRobot : public hal::Robot {
 public:
  FakeArmRobot(const RobotModel& robot, const Pose3& T_site_base, const Vector6d& q, const Pose3& T_site_brick)
      : robot_(robot), T_site_base_(T_site_base), q_(q), T_site_brick_(T_site_brick) {}

  Seconds Now() const override { return t_; }
  void Wait(Seconds dt) override {
    t_ += dt;
    if (busy_ && t_ >= end_) {
      busy_ = false;
      q_ = trajectory_.points.back().q;
    }
  }
  void CommandTracks(const TrackCommand&) override {}
  void SendJointTrajectory(const JointTrajectory& trajectory) override {
    max_start_jump_ = std::max(max_start_jump_, (trajectory.points.front().q - q_).cwiseAbs().maxCoeff());
    trajectory_ = trajectory;
    end_ = t_ + trajectory.Duration();
    busy_ = true;
    ++trajectories_;
  }
  bool ArmBusy() const override { return busy_; }
  void SetGripper(bool grip) override {
    const Pose3 T_site_gripper = GripperPose();
    if (grip) {
      // Only a gripper touching the top face's centre picks the brick up.
      const Eigen::Vector3d top = T_site_brick_ * Eigen::Vector3d(0, 0, 0.026);
      holding_ = (T_site_gripper.translation() - top).norm() < 1e-3;
      T_gripper_brick_ = T_site_gripper.inverse() * T_site_brick_;
    } else if (holding_) {
      T_site_brick_ = T_site_gripper * T_gripper_brick_;
      holding_ = false;
    }
  }
  std::vector<LaserScan> TakeLaserScans(DeviceId) override { return {}; }
  std::vector<GyroSample> TakeGyroSamples() override { return {}; }
  std::vector<JointState> TakeJointStates() override { return {}; }
  std::vector<SyncPulse> TakeSyncPulses() override { return {}; }

  Pose3 GripperPose() const {
    return T_site_base_ * robot_.T_base_arm_base * robot_.ArmForwardKinematics(q_) * robot_.T_tool0_gripper;
  }
  const Vector6d& q() const { return q_; }
  const Pose3& brick() const { return T_site_brick_; }
  bool holding() const { return holding_; }
  double max_start_jump() const { return max_start_jump_; }
  int trajectories() const { return trajectories_; }

 private:
  const RobotModel& robot_;
  Pose3 T_site_base_;
  Vector6d q_;
  Pose3 T_site_brick_;
  Pose3 T_gripper_brick_{Pose3::Identity()};
  bool holding_{false};
  bool busy_{false};
  Seconds t_{0.0}, end_{0.0};
  JointTrajectory trajectory_;
  double max_start_jump_{0.0};
  int trajectories_{0};
};

class PrimitivesTest : public ::testing::Test {
 protected:
  PrimitivesTest()
      : robot_(LoadRobotModel(DataPath("robots/insitu_fabricator.urdf"))),
        arm_(robot_, ArmOptions::Load(DataPath("arm/arm.yaml"))) {
    brick_.size = Eigen::Vector3d(0.240, 0.115, 0.052);
    T_site_base_ = PoseFromXyzRpy(-1.6, 0.3, 0.0, 0, 0, 0.2);
  }
  RobotModel robot_;
  ArmPrimitives arm_;
  Box brick_;
  Pose3 T_site_base_;
  Vector6d q_home_{Deg(0, -30, 30, 0, 90, 0)};
};

TEST_F(PrimitivesTest, SweepMovesOneJointAtConstantSpeedAfterGettingToItsStart) {
  const double from = DegToRad(-20), to = DegToRad(25), speed = DegToRad(15);
  const PrimitiveResult r = arm_.SweepJoint(q_home_, 3, from, to, speed);
  ASSERT_TRUE(r.ok) << r.message;
  ASSERT_EQ(r.steps.size(), 2u);  // iLQG move to the start, then the sweep
  const JointTrajectory& sweep = r.steps[1].trajectory;
  EXPECT_NEAR(sweep.Duration(), std::abs(to - sweep.points.front().q[3]) / speed, 1e-9);
  for (std::size_t k = 1; k < sweep.points.size(); ++k) {
    const auto& a = sweep.points[k - 1];
    const auto& b = sweep.points[k];
    EXPECT_NEAR((b.q[3] - a.q[3]) / (b.t - a.t), speed, 1e-9);
    for (int j : {0, 1, 2, 4, 5}) EXPECT_EQ(b.q[j], a.q[j]);
  }
  EXPECT_NEAR(sweep.points.front().q[3], from, 1e-4);
  EXPECT_DOUBLE_EQ(r.q_end[3], to);
  // Already at the start: no move first.
  EXPECT_EQ(arm_.SweepJoint(r.q_end, 3, to, from, speed).steps.size(), 1u);
  EXPECT_THROW(arm_.SweepJoint(q_home_, 6, 0, 1, 1), InputError);
  EXPECT_THROW(arm_.SweepJoint(q_home_, 1, 0, 3.0, 1), InputError);
  EXPECT_THROW(arm_.SweepJoint(q_home_, 1, 0, 1, 0), InputError);
}

TEST_F(PrimitivesTest, LinearMoveKeepsTheGripperOnTheLine) {
  const Vector6d q0 = Deg(10, 30, 20, 0, 40, 0);
  const Pose3 start = robot_.ArmForwardKinematics(q0) * robot_.T_tool0_gripper;
  Pose3 goal = start;
  goal.translation() += Eigen::Vector3d(0.05, -0.1, -0.15);
  const PrimitiveResult r = arm_.MoveGripperLinear(q0, goal);
  ASSERT_TRUE(r.ok) << r.message;
  const Eigen::Vector3d dir = (goal.translation() - start.translation()).normalized();
  for (const auto& p : r.steps[0].trajectory.points) {
    const Pose3 g = robot_.ArmForwardKinematics(p.q) * robot_.T_tool0_gripper;
    const Eigen::Vector3d d = g.translation() - start.translation();
    EXPECT_LT((d - d.dot(dir) * dir).norm(), 1e-5);
    EXPECT_LT(RotationAngle(g, start), 1e-5);
  }
  const Pose3 end = robot_.ArmForwardKinematics(r.q_end) * robot_.T_tool0_gripper;
  EXPECT_LT(TranslationDistance(end, goal), 1e-5);
}

TEST_F(PrimitivesTest, PickAndPlaceLandsTheBrickWhereAsked) {
  const Pose3 T_site_feeder_brick = T_site_base_ * PoseFromXyzRpy(1.2, 1.1, 0.776, 0, 0, 0.4);
  const Pose3 T_site_goal = PoseFromXyzRpy(0.0, 0.0, 0.026 + 3 * 0.052, 0, 0, 0.3);
  FakeArmRobot robot(robot_, T_site_base_, q_home_, T_site_feeder_brick);

  PrimitiveResult seq = arm_.PickBrick(q_home_, T_site_base_, T_site_feeder_brick, brick_);
  ASSERT_TRUE(seq.ok) << seq.message;
  seq.Append(arm_.PlaceBrick(seq.q_end, T_site_base_, T_site_goal, brick_));
  ASSERT_TRUE(seq.ok) << seq.message;
  seq.Append(arm_.MoveToJoints(seq.q_end, q_home_));
  ASSERT_TRUE(seq.ok) << seq.message;
  ASSERT_EQ(seq.steps.size(), 7u);
  EXPECT_EQ(seq.steps[1].gripper, GripperAction::kGrip);
  EXPECT_EQ(seq.steps[4].gripper, GripperAction::kRelease);
  EXPECT_EQ(seq.plans.size(), 3u);

  const ExecuteResult done = ExecuteSteps(robot, seq.steps);
  ASSERT_TRUE(done.ok) << done.message;
  EXPECT_EQ(done.steps_done, 7);
  EXPECT_EQ(robot.trajectories(), 7);
  EXPECT_NEAR(done.elapsed, seq.Duration(), 0.2);
  EXPECT_LT(robot.max_start_jump(), 1e-3);  // each trajectory starts where the arm is
  EXPECT_FALSE(robot.holding());
  EXPECT_LT((robot.brick().translation() - T_site_goal.translation()).norm(), 1e-5);
  // Yaw up to the brick's symmetry (turned by 180 deg is the same brick).
  const Eigen::Vector3d x_brick = robot.brick().linear().col(0), x_goal = T_site_goal.linear().col(0);
  EXPECT_LT(std::acos(std::min(1.0, std::abs(x_brick.dot(x_goal)))), 1e-5);
  EXPECT_LT(RotationAngle(robot.brick(), T_site_goal) < 1e-5 ? 0.0 : std::abs(RotationAngle(robot.brick(), T_site_goal) - kPi), 1e-5);
}

TEST_F(PrimitivesTest, ReportsABrickOutOfReach) {
  const Pose3 far = PoseFromXyzRpy(6.0, 0.0, 0.026, 0, 0, 0);
  const PrimitiveResult r = arm_.PickBrick(q_home_, T_site_base_, far, brick_);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.message.find("out of reach"), std::string::npos) << r.message;
  EXPECT_TRUE(r.steps.empty());
}

}  // namespace
}  // namespace ifab::arm
