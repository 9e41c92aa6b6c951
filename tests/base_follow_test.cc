// Issue 3: the base trajectory controller (eq. 4) follows planned maneuvers in the simulator
// (tracked base with slip that wanders, hydraulic lag) to the goal tolerance. Test-only wiring: the
// controller is fed the simulator's true pose here; on the robot it gets the estimator's pose.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "ifab/base/controller/trajectory_controller.h"
#include "ifab/base/planner/site_scene.h"
#include "ifab/base/planner/stomp_planner.h"
#include "ifab/core/angles.h"
#include "ifab/core/config.h"
#include "ifab/core/data_path.h"
#include "ifab/model/site.h"
#include "ifab/sim/sim_robot.h"

namespace ifab {
namespace {

Pose2 FacingStack(double x, double y) { return Pose2(x, y, std::atan2(-y, -x)); }

TEST(BaseFollow, ControllerBringsTheSimulatedBaseAlongPlannedManeuversToTheGoal) {
  const ConfigNode robot_yaml = ConfigNode::LoadFile(DataPath("sim/insitu_fabricator.yaml"));
  const sim::SimOptions sim_options = sim::SimOptions::FromConfig(robot_yaml["sim"]);
  const base::BaseGeometry robot = base::BaseGeometry::Load(DataPath("robots/insitu_fabricator_base.yaml"));
  const base::StompBasePlanner planner(base::PlanningSceneFromSite(LoadSite(DataPath("sites/brick_stack.yaml"))),
                                       robot);
  const base::BaseControllerOptions options =
      base::BaseControllerOptions::FromConfig(
          ConfigNode::LoadFile(DataPath("base/controller.yaml"))["base_controller"])
          .SetTracks(robot);
  const int maneuvers = 4;

  // The paper's hysteresis loop around the stack (Fig. 6).
  const std::vector<Pose2> positions = {FacingStack(-1.6, 0.0), FacingStack(-0.6, 1.45), FacingStack(1.6, 0.5),
                                        FacingStack(1.2, -1.0)};
  sim::SimRobot sim(sim_options, positions[0], Vector6d::Zero(), 5);
  double worst_along = 0.0, worst_lateral = 0.0, worst_heading = 0.0;
  for (int k = 0; k < maneuvers; ++k) {
    const Pose2 goal = positions[(k + 1) % positions.size()];
    const base::PlanResult plan = planner.Plan(sim.true_base_pose(), goal, RandomStream(k));
    ASSERT_TRUE(plan.IsUsable()) << plan.BriefReport();
    base::BaseTrajectoryController controller(options);
    controller.SetTrajectory(plan.trajectory);
    bool done = false;
    const double timeout = 3.0 * plan.trajectory.duration + 30.0;
    for (double t = 0.0; t < timeout; t += 0.025) {  // 40 Hz, the base laser's rate
      const base::BaseControllerOutput out = controller.Update(sim.true_base_pose(), sim.Now());
      sim.CommandTracks(out.command);
      if (out.done) {
        done = true;
        break;
      }
      sim.Wait(0.025);
    }
    ASSERT_TRUE(done) << "maneuver " << k << " not finished: " << plan.BriefReport();
    const Pose2 goal_base = goal.inverse() * sim.true_base_pose();
    EXPECT_LE(std::abs(goal_base.x), options.goal_tolerance_xy) << "maneuver " << k;
    EXPECT_LE(std::abs(goal_base.theta), options.goal_tolerance_theta) << "maneuver " << k;
    EXPECT_LE(std::abs(goal_base.y), 0.05) << "maneuver " << k;  // sideways: what tracking leaves
    worst_along = std::max(worst_along, std::abs(goal_base.x));
    worst_lateral = std::max(worst_lateral, std::abs(goal_base.y));
    worst_heading = std::max(worst_heading, std::abs(goal_base.theta));
  }
  std::printf("worst end error over %d maneuvers: along %.1f mm, sideways %.1f mm, heading %.2f deg\n", maneuvers,
              worst_along * 1e3, worst_lateral * 1e3, RadToDeg(worst_heading));
}

}  // namespace
}  // namespace ifab
