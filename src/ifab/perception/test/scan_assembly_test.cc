#include "ifab/perception/scan_assembly.h"

#include <gtest/gtest.h>

#include "ifab/core/random.h"
#include "ifab/perception/testing/synthetic.h"

namespace ifab {
namespace {

std::vector<RegistrationBody> Floor() {
  RigidObject ground{"ground", Pose3::Identity(), {Plane{Eigen::Vector3d::UnitZ(), 0.0}}};
  return {{"ground", Pose3::Identity(), {ground}, true}};
}

const Vector6d kLookDown = (Vector6d() << 0.0, 0.3, 0.3, 0.0, 1.2, 0.0).finished();

TEST(ScanAssembly, PutsEveryBeamAtTheArmPoseOfItsOwnTime) {
  const RobotModel robot = testing::DesignRobot();
  const Scene world(Floor());
  testing::SyntheticLaser laser;
  laser.noisy = false;
  RandomStream rng(1);
  Vector6d q1 = kLookDown;
  q1[4] += 0.5;  // a fast tilt with joint 5: 0.5 rad in 0.5 s, so beam times matter
  const auto sweep = testing::SynthesizeArmSweep(world, robot, robot.T_tool0_arm_laser, kLookDown, q1, 0.5, laser, rng);
  const AssembledSweep joint = AssembleSweep(sweep.scans, sweep.joints, robot);
  ASSERT_GT(joint.points.size(), 5000u);
  EXPECT_EQ(joint.untimed_beams, 0);
  // The arm moves linearly in joint space, so joint interpolation is exact: every point lies on
  // the floor.
  double worst_joint = 0.0;
  for (const auto& p : ToBaseFrame(joint.points, robot.T_tool0_arm_laser)) worst_joint = std::max(worst_joint, std::abs(p.p.z()));
  EXPECT_LT(worst_joint, 1e-9);

  // Interpolating flange poses between samples at 250 Hz instead is close but not exact.
  ScanAssemblyOptions pose_options;
  pose_options.interpolation = ArmInterpolation::kPose;
  const AssembledSweep pose = AssembleSweep(sweep.scans, sweep.joints, robot, pose_options);
  double worst_pose = 0.0;
  for (const auto& p : ToBaseFrame(pose.points, robot.T_tool0_arm_laser)) worst_pose = std::max(worst_pose, std::abs(p.p.z()));
  EXPECT_LT(worst_pose, 1e-4);

  // Ignoring the beams' own times (the whole scan at its start time) smears the cloud.
  std::vector<LaserScan> untimed = sweep.scans;
  for (auto& s : untimed) s.time_increment = 0.0;
  double worst_untimed = 0.0;
  for (const auto& p : AssembleCloud(untimed, sweep.joints, robot, robot.T_tool0_arm_laser))
    worst_untimed = std::max(worst_untimed, std::abs(p.p.z()));
  EXPECT_GT(worst_untimed, 0.005);
}

TEST(ScanAssembly, DropsBeamsOutsideTheJointSamplesAndInvalidRanges) {
  const RobotModel robot = testing::DesignRobot();
  LaserScan scan;
  scan.stamp.t = 1.0;
  scan.angle_min = -0.1;
  scan.angle_increment = 0.1;
  scan.time_increment = 0.01;
  scan.ranges = {1.0, LaserScan::kNoReturn, 0.05, 2.0, 1.5};
  std::vector<JointState> joints(2);
  joints[0].stamp.t = 0.95;
  joints[1].stamp.t = 1.025;  // covers beams 0..2 only
  const AssembledSweep s = AssembleSweep({scan}, joints, robot);
  EXPECT_EQ(s.points.size(), 1u);
  EXPECT_EQ(s.invalid_beams, 2);
  EXPECT_EQ(s.untimed_beams, 2);
  EXPECT_NEAR(s.points[0].t, 1.0, 1e-12);
  // A gap between joint samples longer than max_sample_gap drops the beams inside it.
  ScanAssemblyOptions options;
  options.max_sample_gap = 0.05;
  EXPECT_EQ(AssembleSweep({scan}, joints, robot, options).points.size(), 0u);
}

}  // namespace
}  // namespace ifab
