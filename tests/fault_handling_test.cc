// Issue 14: the arm's step runner notices what a real arm shows of two faults: the controller
// refusing a trajectory (the arm does not move) and the vacuum losing the brick. Before, both
// went unnoticed: the next steps ran as if the arm had moved, and "placed" nothing.
#include <gtest/gtest.h>

#include "ifab/arm/primitives.h"
#include "ifab/core/angles.h"
#include "ifab/core/config.h"
#include "ifab/core/data_path.h"
#include "ifab/sim/faults.h"
#include "ifab/sim/sim_robot.h"

namespace ifab {
namespace {

struct PickPlace {
  sim::SimOptions sim_options;
  RobotModel robot;
  Pose3 T_base_feeder;
  Vector6d q0 = Vector6d::Zero();
  Pose2 base{-1.9, -0.2, DegToRad(6)};
  arm::PrimitiveResult steps;

  PickPlace() {
    const ConfigNode robot_yaml = ConfigNode::LoadFile(DataPath("robots/insitu_fabricator.yaml"));
    sim_options = sim::SimOptions::Load(DataPath("sim/insitu_fabricator.yaml"));
    robot = LoadRobotModel(DataPath("robots/insitu_fabricator.urdf"));
    const auto f = robot_yaml["feeder_in_base"].AsNumbers(6);
    T_base_feeder = PoseFromXyzRpy(f[0], f[1], f[2], f[3], f[4], f[5]);
    q0[1] = DegToRad(-30);
    q0[2] = DegToRad(60);
    q0[4] = DegToRad(60);
    const Box brick{{0.240, 0.115, 0.052}};
    arm::ArmPrimitives arm(robot, arm::ArmOptions::Load(DataPath("arm/arm.yaml")));
    steps = arm.PickBrickFromFeeder(q0, T_base_feeder, brick);
    steps.Append(arm.PlaceBrick(steps.q_end, PoseFromXyzRpy(base.x, base.y, 0, 0, 0, base.theta),
                                PoseFromXyzRpy(0, 0, 0.026, 0, 0, 0), brick));
  }
};

TEST(FaultHandling, ARejectedTrajectoryStopsTheStepsAndSaysSo) {
  PickPlace p;
  ASSERT_TRUE(p.steps.ok) << p.steps.message;
  sim::FaultSpec f;
  f.kind = sim::FaultKind::kArmTrajectoryRejected;
  f.index = 2;
  sim::FaultInjector faults({f});
  sim::SimRobot sim(p.sim_options, p.base, p.q0, 21);
  sim.SetFaults(&faults);
  const arm::ExecuteResult r = arm::ExecuteSteps(sim, p.steps.steps);
  EXPECT_FALSE(r.ok);
  EXPECT_TRUE(r.rejected);
  EXPECT_NE(r.message.find("rejected the trajectory"), std::string::npos) << r.message;
  EXPECT_TRUE(sim.world().bricks().empty());
}

TEST(FaultHandling, ALostBrickStopsTheStepsBeforeTheRelease) {
  PickPlace p;
  ASSERT_TRUE(p.steps.ok) << p.steps.message;
  sim::FaultSpec f;
  f.kind = sim::FaultKind::kBrickDropped;
  f.index = 1;
  f.duration = 0.5;
  sim::FaultInjector faults({f});
  sim::SimRobot sim(p.sim_options, p.base, p.q0, 21);
  sim.SetFaults(&faults);
  const arm::ExecuteResult r = arm::ExecuteSteps(sim, p.steps.steps);
  EXPECT_FALSE(r.ok);
  EXPECT_TRUE(r.lost_grip) << r.message;
  EXPECT_LT(r.steps_done, static_cast<int>(p.steps.steps.size()));
  EXPECT_FALSE(sim.holding_brick());
  EXPECT_TRUE(sim.world().bricks().empty());
  ASSERT_TRUE(faults.records()[0].injected);
}

TEST(FaultHandling, WithoutFaultsTheStepsRunThrough) {
  PickPlace p;
  sim::SimRobot sim(p.sim_options, p.base, p.q0, 21);
  const arm::ExecuteResult r = arm::ExecuteSteps(sim, p.steps.steps);
  EXPECT_TRUE(r.ok) << r.message;
  EXPECT_EQ(sim.world().bricks().size(), 1u);
}

}  // namespace
}  // namespace ifab
