// Issue 14: the simulator injects each fault as specified, and only then.
#include "ifab/sim/faults.h"

#include <gtest/gtest.h>

#include "ifab/sim/test/default_options.h"
#include <set>

#include "ifab/core/data_path.h"
#include "ifab/sim/sim_robot.h"

namespace ifab::sim {
namespace {

FaultSpec Spec(FaultKind kind, double drive_time, double duration = 0.0, double magnitude = 0.0) {
  FaultSpec f;
  f.kind = kind;
  f.drive_time = drive_time;
  f.duration = duration;
  f.magnitude = magnitude;
  return f;
}

TEST(Faults, ABaseLaserBlackoutSilencesTheLaserWhileDriving) {
  FaultInjector faults({Spec(FaultKind::kBaseLaserBlackout, 0.5, 2.0)});
  SimRobot robot(DefaultOptions(), Pose2(0, 0, 0), Vector6d::Zero(), 1);
  robot.SetFaults(&faults);
  robot.Wait(1.0);  // standing: no driving time, no blackout
  EXPECT_GE(robot.TakeLaserScans(DeviceId::kBaseLaser).size(), 35u);
  robot.CommandTracks({robot.Now(), 0.1, 0.1});
  robot.Wait(0.7);
  robot.TakeLaserScans(DeviceId::kBaseLaser);
  robot.Wait(1.5);  // inside the 2 s blackout
  EXPECT_TRUE(robot.TakeLaserScans(DeviceId::kBaseLaser).empty());
  robot.Wait(1.0);
  EXPECT_GE(robot.TakeLaserScans(DeviceId::kBaseLaser).size(), 20u);
  ASSERT_TRUE(faults.records()[0].injected);
  EXPECT_NEAR(faults.records()[0].t_end - faults.records()[0].t_start, 2.0, 1e-9);
}

TEST(Faults, AClockJumpShiftsOnlyThatDevicesStamps) {
  FaultSpec f = Spec(FaultKind::kClockJump, 0.2, 0.0, 1.5);
  f.device = DeviceId::kGyro;
  auto run = [&](bool with) {
    FaultInjector faults({f});
    SimRobot robot(DefaultOptions(), Pose2(0, 0, 0), Vector6d::Zero(), 2);
    if (with) robot.SetFaults(&faults);
    robot.CommandTracks({0.0, 0.1, 0.1});
    robot.Wait(0.5);
    return std::pair{robot.TakeGyroSamples().back().stamp.t_device, robot.TakeLaserScans(DeviceId::kBaseLaser).back().stamp.t_device};
  };
  const auto plain = run(false), jumped = run(true);
  EXPECT_NEAR(jumped.first - plain.first, 1.5, 1e-9);
  EXPECT_EQ(jumped.second, plain.second);
}

TEST(Faults, TheArmControllerRejectsTheChosenTrajectoryOnly) {
  FaultSpec f = Spec(FaultKind::kArmTrajectoryRejected, 0.0);
  f.index = 2;
  FaultInjector faults({f});
  SimRobot robot(DefaultOptions(), Pose2(0, 0, 0), Vector6d::Zero(), 3);
  robot.SetFaults(&faults);
  JointTrajectory t;
  t.points.resize(2);
  t.points[1].t = 0.5;
  t.points[1].q[0] = 0.1;
  robot.SendJointTrajectory(t);
  EXPECT_EQ(robot.ArmRejection(), "");
  robot.Wait(1.0);
  robot.SendJointTrajectory(t);
  EXPECT_NE(robot.ArmRejection(), "");
  EXPECT_FALSE(robot.ArmBusy());
  robot.SendJointTrajectory(t);
  EXPECT_EQ(robot.ArmRejection(), "");
}

TEST(Faults, ABumpMovesEveryBrickOfTheStack) {
  FaultSpec f = Spec(FaultKind::kStackBumped, 0.1, 0.0, 0.02);
  f.angle = 0.0;
  FaultInjector faults({f});
  SimRobot robot(DefaultOptions(), Pose2(0, 0, 0), Vector6d::Zero(), 4);
  SiteBox b;
  b.box.size = {0.24, 0.115, 0.052};
  b.T_site_box = PoseFromXyzRpy(1, 2, 0.026, 0, 0, 0);
  robot.mutable_world().AddBrick(b);
  robot.SetFaults(&faults);
  robot.CommandTracks({0.0, 0.1, 0.1});
  robot.Wait(0.3);
  EXPECT_NEAR(robot.world().bricks()[0].T_site_box.translation().x(), 1.02, 1e-12);
  EXPECT_NEAR(faults.T_site_stack_moved().translation().x(), 0.02, 1e-12);
}

TEST(Faults, DrawsDistinctKindsWithinTheCataloguesRanges) {
  RandomStream rng(5);
  FaultDrawOptions o;
  o.faults_per_run = 13;
  const auto specs = FaultInjector::Draw(rng, o);
  std::set<int> kinds;
  for (const auto& s : specs) {
    kinds.insert(static_cast<int>(s.kind));
    if (s.kind == FaultKind::kBaseLaserBlackout || s.kind == FaultKind::kArmLaserBlackout) {
      EXPECT_GE(s.duration, 0.5);
      EXPECT_LE(s.duration, 5.0);
    }
    if (s.kind == FaultKind::kStackBumped) {
      EXPECT_GE(s.magnitude, 0.01);
      EXPECT_LE(s.magnitude, 0.03);
    }
  }
  EXPECT_EQ(kinds.size(), 13u);
}

}  // namespace
}  // namespace ifab::sim
