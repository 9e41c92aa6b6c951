#include "ifab/sim/sim_robot.h"

#include <gtest/gtest.h>

#include "ifab/sim/test/default_options.h"
#include <cstring>

#include "ifab/core/angles.h"
#include "ifab/core/data_path.h"

namespace ifab::sim {
namespace {

TEST(SimRobot, SameSeedGivesByteIdenticalScans) {
  const SimOptions o = DefaultOptions();
  auto scans = [&](std::uint64_t seed) {
    SimRobot robot(o, Pose2(1.5, 0.3, 2.8), Vector6d::Zero(), seed);
    robot.CommandTracks({0.0, 0.2, 0.25});
    robot.Wait(0.5);
    return robot.TakeLaserScans(DeviceId::kBaseLaser);
  };
  const auto a = scans(7), b = scans(7), c = scans(8);
  ASSERT_GE(a.size(), 15u);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    ASSERT_EQ(a[k].ranges.size(), b[k].ranges.size());
    EXPECT_EQ(0, std::memcmp(a[k].ranges.data(), b[k].ranges.data(), a[k].ranges.size() * sizeof(double)));
    EXPECT_EQ(a[k].stamp.t_device, b[k].stamp.t_device);
  }
  EXPECT_NE(0, std::memcmp(a[0].ranges.data(), c[0].ranges.data(), a[0].ranges.size() * sizeof(double)));
}

TEST(SimRobot, SlipMakesDrivingDifferFromIdealKinematics) {
  const SimOptions o = DefaultOptions();
  SimRobot robot(o, Pose2(0, 0, 0), Vector6d::Zero(), 3);
  // Ideal differential drive: a left turn of (v_r - v_l) / B for 10 s after the lag.
  const double vl = 0.1, vr = 0.2, B = o.tracks.track_gauge;
  robot.CommandTracks({0.0, vl, vr});
  robot.Wait(10.0);
  const double ideal_heading = (vr - vl) / B * 10.0;
  const double true_heading = robot.true_base_pose().theta;
  // Steering efficiency 0.70-0.76 and the lag make the robot turn clearly less than ideal.
  EXPECT_LT(true_heading, 0.8 * ideal_heading);
  EXPECT_GT(true_heading, 0.6 * ideal_heading);
  // Straight driving covers less ground than commanded (speed factor 0.90-0.95).
  SimRobot straight(o, Pose2(0, 0, 0), Vector6d::Zero(), 3);
  straight.CommandTracks({0.0, 0.2, 0.2});
  straight.Wait(10.0);
  EXPECT_LT(straight.true_base_pose().x, 0.96 * 0.2 * 10.0);
  EXPECT_GT(straight.true_base_pose().x, 0.80 * 0.2 * 10.0);
}

TEST(SimRobot, GyroMeasuresTheYawRateWithNoise) {
  SimRobot robot(DefaultOptions(), Pose2(0, 0, 0), Vector6d::Zero(), 4);
  robot.CommandTracks({0.0, -0.1, 0.1});
  robot.Wait(3.0);
  robot.TakeGyroSamples();
  const double omega = 0.0;
  (void)omega;
  robot.Wait(2.0);
  const auto samples = robot.TakeGyroSamples();
  ASSERT_NEAR(static_cast<double>(samples.size()), 800.0, 2.0);
  double mean = 0;
  for (const auto& s : samples) mean += s.rate.z();
  mean /= static_cast<double>(samples.size());
  // chi in [0.70, 0.76]: omega = chi * 0.2 / 1.0.
  EXPECT_GT(mean, 0.69 * 0.2);
  EXPECT_LT(mean, 0.77 * 0.2);
}

TEST(SimRobot, ArmFollowsATrajectoryAndReportsJointStates) {
  SimRobot robot(DefaultOptions(), Pose2(0, 0, 0), Vector6d::Zero(), 5);
  JointTrajectory traj;
  Vector6d goal = Vector6d::Zero();
  goal[0] = 0.5;
  goal[1] = 0.3;
  traj.points.push_back({0.0, Vector6d::Zero(), Vector6d::Zero()});
  traj.points.push_back({2.0, goal, Vector6d::Zero()});
  robot.SendJointTrajectory(traj);
  EXPECT_TRUE(robot.ArmBusy());
  robot.Wait(4.0);
  EXPECT_FALSE(robot.ArmBusy());
  const auto states = robot.TakeJointStates();
  ASSERT_NEAR(static_cast<double>(states.size()), 1000.0, 3.0);
  EXPECT_NEAR((states.back().q - goal).norm(), 0.0, 1e-4);
  const auto pulses = robot.TakeSyncPulses();
  EXPECT_GT(pulses.size(), states.size());
}

TEST(SimRobot, PickAndReleaseABrickSettlesItOnTheGround) {
  SimRobot robot(DefaultOptions(), Pose2(0, 0, 0), Vector6d::Zero(), 6);
  EXPECT_FALSE(robot.holding_brick());
  robot.SetGripper(true);  // far from the feeder: nothing to grip
  EXPECT_FALSE(robot.holding_brick());
  EXPECT_TRUE(robot.world().bricks().empty());
}

}  // namespace
}  // namespace ifab::sim
