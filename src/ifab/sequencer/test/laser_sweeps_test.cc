#include "ifab/sequencer/laser_sweeps.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ifab/core/angles.h"
#include "ifab/core/config.h"
#include "ifab/core/data_path.h"
#include "ifab/core/testing/error_of.h"

namespace ifab::sequencer {
namespace {

using ::testing::HasSubstr;
using testing::ErrorOf;

TEST(ReadSweepSpecs, ReadsDegreesAsRadiansAndZeroBasedJoints) {
  const auto c = ConfigNode::FromString(
      "- {joint: 5, range_deg: [-12, 12], speed_deg_s: 8, aim_offset: [0.0, -0.6]}\n"
      "- {joint: 1, range_deg: [10, -10], offset_deg: [0, 0, 0, 0, 0, 90]}\n",
      "s.yaml");
  const auto s = ReadSweepSpecs(c);
  ASSERT_EQ(s.size(), 2u);
  EXPECT_EQ(s[0].joint, 4);
  EXPECT_DOUBLE_EQ(s[0].from, DegToRad(-12.0));
  EXPECT_DOUBLE_EQ(s[0].speed, DegToRad(8.0));
  EXPECT_EQ(s[0].aim_offset, Eigen::Vector2d(0.0, -0.6));
  EXPECT_EQ(s[1].joint, 0);
  EXPECT_DOUBLE_EQ(s[1].pose_offset[5], DegToRad(90.0));
}

TEST(ReadSweepSpecs, ErrorsNameTheEntryAndField) {
  auto error = [](const std::string& text) {
    return ErrorOf([&] { ReadSweepSpecs(ConfigNode::FromString(text, "s.yaml")); });
  };
  EXPECT_THAT(error("- {joint: 7, range_deg: [-1, 1]}\n"), HasSubstr("[0].joint: expected a joint number 1..6, got 7"));
  EXPECT_THAT(error("- {joint: 2, range_deg: [-1, 1]}\n- {joint: 2, range_deg: [1]}\n"),
              HasSubstr("[1].range_deg: expected a list of 2 numbers"));
  EXPECT_THAT(error("- {joint: 2, range_deg: [-1, 1], speed_deg_s: -3}\n"),
              HasSubstr("speed_deg_s: expected a positive number"));
  EXPECT_THAT(error("- {joint: 2, range_deg: [-1, 1], aim: [0, 1]}\n"), HasSubstr("aim"));
  EXPECT_THAT(error("- {joint: 2, range_deg: [3, 3]}\n"), HasSubstr("range_deg: expected two different angles"));
  EXPECT_THAT(error("- {joint: 2, range_deg: [-1, 1], view: {distance: 1, elevation_deg: 95}}\n"),
              HasSubstr("[0].view.elevation_deg: expected"));
  EXPECT_THAT(error("- {joint: 2, range_deg: [-1, 1], view: {range: 1}}\n"), HasSubstr("range"));
}

TEST(LaserCalibrationPlan, ReadsASectionWithDefaults) {
  const auto c = ConfigNode::FromString(
      "cube_in_base: [1.5, -0.4, 30]\n"
      "sweeps:\n  - {joint: 5, range_deg: [-15, 15]}\n"
      "beam_stride: 2\n",
      "plan.yaml");
  const auto plan = LaserCalibrationPlan::FromConfig(c);
  EXPECT_DOUBLE_EQ(plan.cube_in_base.z(), DegToRad(30.0));
  EXPECT_DOUBLE_EQ(plan.cube_size, 0.25);
  EXPECT_EQ(plan.beam_stride, 2);
  EXPECT_EQ(plan.sweeps.size(), 1u);
  EXPECT_NEAR(plan.T_base_cube().translation().z(), 0.125, 1e-12);
  EXPECT_THAT(ErrorOf([] { LaserCalibrationPlan::FromConfig(ConfigNode::FromString("cube_size: 0.2\n", "p.yaml")); }),
              HasSubstr("cube_in_base"));
}

TEST(AimAt, CentreBeamMeetsTheFloorAtTheTarget) {
  const RobotModel robot = LoadRobotModel(DataPath("robots/insitu_fabricator.urdf"));
  Vector6d posture;
  posture << 0.0, DegToRad(17.0), DegToRad(17.0), 0.0, DegToRad(69.0), 0.0;
  for (const Eigen::Vector2d& target : {Eigen::Vector2d(1.7, 0.0), Eigen::Vector2d(1.5, -0.4), Eigen::Vector2d(2.0, 0.4)}) {
    const Vector6d q = AimAt(robot, target, posture);
    const Pose3 T = robot.T_base_arm_base * robot.ArmForwardKinematics(q) * robot.T_tool0_arm_laser;
    const Eigen::Vector3d o = T.translation(), d = T.linear().col(0);
    ASSERT_LT(d.z(), 0.0);
    const Eigen::Vector3d hit = o - (o.z() / d.z()) * d;
    EXPECT_LT((hit.head<2>() - target).norm(), 0.02) << target.transpose();
  }
}

TEST(ViewPose, PutsTheLaserWhereTheViewSaysLookingAtTheTarget) {
  const RobotModel robot = LoadRobotModel(DataPath("robots/insitu_fabricator.urdf"));
  arm::IkSolver ik(robot);
  Vector6d posture;
  posture << 0.0, DegToRad(17.0), DegToRad(17.0), 0.0, DegToRad(69.0), 0.0;
  const Eigen::Vector2d look(1.75, 0.2);
  const auto specs = ReadSweepSpecs(ConfigNode::FromString(
      "- {joint: 5, range_deg: [-5, 5], view: {distance: 0.9, elevation_deg: 35, azimuth_deg: 60, roll_deg: 90}}\n",
      "v.yaml"));
  ASSERT_TRUE(specs[0].view.has_value());
  const LaserView& view = *specs[0].view;
  const auto q = ViewPose(ik, robot, look, view, posture);
  ASSERT_TRUE(q.has_value());
  const Pose3 T = robot.T_base_arm_base * robot.ArmForwardKinematics(*q) * robot.T_tool0_arm_laser;
  const Eigen::Vector3d target(look.x(), look.y(), 0.0);
  EXPECT_NEAR((T.translation() - target).norm(), 0.9, 1e-4);
  const Eigen::Vector3d beam = T.linear().col(0);
  EXPECT_NEAR(beam.dot((target - T.translation()).normalized()), 1.0, 1e-8);
  EXPECT_NEAR(std::asin(-beam.z()), DegToRad(35.0), 1e-4);
  // Azimuth 60 deg from the arm foot's side; roll 90 deg: the scan plane holds the vertical.
  const Eigen::Vector2d foot = robot.T_base_arm_base.translation().head<2>();
  const Eigen::Vector2d from_look = (T.translation().head<2>() - look).normalized();
  const Eigen::Vector2d to_foot = (foot - look).normalized();
  EXPECT_NEAR(std::atan2(to_foot.x() * from_look.y() - to_foot.y() * from_look.x(), to_foot.dot(from_look)),
              DegToRad(60.0), 1e-4);
  EXPECT_NEAR(std::abs(T.linear().col(2).z()), 0.0, 1e-4);
  // Out of reach: 3 m up.
  LaserView far = view;
  far.distance = 3.0;
  far.elevation = DegToRad(89.0);
  EXPECT_FALSE(ViewPose(ik, robot, look, far, posture).has_value());
}

// A robot whose arm arrives at once and whose sensors send nothing but a gyro sample per Wait:
// enough to see what the recorder asks of hal::Robot.
class FakeRobot : public hal::Robot {
 public:
  Seconds Now() const override { return t_; }
  void Wait(Seconds dt) override {
    t_ += dt;
    GyroSample g;
    g.stamp.t = t_;
    gyro_.push_back(g);
  }
  void CommandTracks(const TrackCommand&) override {}
  void SendJointTrajectory(const JointTrajectory&) override { ++trajectories; }
  bool ArmBusy() const override { return false; }
  void SetGripper(bool) override {}
  void SetLaserActive(DeviceId laser, bool active) override {
    if (laser == DeviceId::kArmLaser) arm_laser_switches.push_back(active);
  }
  std::vector<LaserScan> TakeLaserScans(DeviceId) override { return {}; }
  std::vector<GyroSample> TakeGyroSamples() override { return std::exchange(gyro_, {}); }
  std::vector<JointState> TakeJointStates() override { return {}; }
  std::vector<SyncPulse> TakeSyncPulses() override { return {}; }

  int trajectories{0};
  std::vector<bool> arm_laser_switches;

 private:
  Seconds t_{0.0};
  std::vector<GyroSample> gyro_;
};

TEST(SweepRecorder, SwitchesTheArmLaserOnForTheSweepAndHandsOnOtherData) {
  const RobotModel robot = LoadRobotModel(DataPath("robots/insitu_fabricator.urdf"));
  arm::ArmPrimitives arm(robot, arm::ArmOptions::Load(DataPath("arm/arm.yaml")));
  FakeRobot fake;
  Vector6d posture;
  posture << 0.0, DegToRad(17.0), DegToRad(17.0), 0.0, DegToRad(69.0), 0.0;
  SweepRecorderOptions options;
  options.laser_on_between_sweeps = false;  // as the mission keeps it
  SweepRecorder recorder(fake, arm, posture, options);
  std::size_t gyro = 0;
  recorder.on_other_data = [&](DrainedData&& d) { gyro += d.gyro_samples.size(); };
  SweepSpec spec;
  spec.joint = 4;
  spec.from = DegToRad(-5.0);
  spec.to = DegToRad(5.0);
  const SweepRecording rec = recorder.Record(Eigen::Vector2d(1.7, 0.0), posture, spec, false, "test");
  EXPECT_EQ(fake.arm_laser_switches, (std::vector<bool>{true, false}));
  EXPECT_GE(fake.trajectories, 1);
  EXPECT_GT(gyro, 0u);
  EXPECT_TRUE(rec.scans.empty());
  const Vector6d aimed = AimAt(robot, Eigen::Vector2d(1.7, 0.0), posture);
  EXPECT_NEAR(recorder.q()[4], aimed[4] + spec.to, 1e-9);
}

}  // namespace
}  // namespace ifab::sequencer
