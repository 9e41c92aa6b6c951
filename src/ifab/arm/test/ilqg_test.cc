#include "ifab/arm/ilqg.h"

#include <gtest/gtest.h>

#include "ifab/arm/test/joint_degrees.h"
#include "ifab/core/angles.h"
#include "ifab/core/config.h"
#include "ifab/core/data_path.h"
#include "ifab/core/random.h"
#include "ifab/core/testing/numeric_jacobian.h"

namespace ifab::arm {
namespace {

class IlqgTest : public ::testing::Test {
 protected:
  IlqgTest()
      : robot_(LoadRobotModel(DataPath("robots/insitu_fabricator.urdf"))),
        model_(ArmModel::FromRobotModel(robot_)),
        options_(LoadIlqgOptions(DataPath("arm/arm.yaml"))) {}
  RobotModel robot_;
  ArmModel model_;
  IlqgOptions options_;
};

TEST_F(IlqgTest, PlansATransferToTheGoalAtRest) {
  IlqgPlanner planner(model_, options_);
  const Vector6d from = Deg(52, 23, 25, 0, 43, -98);
  const Vector6d to = Deg(-26, 40, 10, 0, 40, 20);
  const ArmPlan plan = planner.Plan(from, to);
  const PlanSummary& s = plan.summary;
  EXPECT_EQ(s.status, PlanStatus::kConverged) << s.BriefReport();
  EXPECT_TRUE(s.IsUsable());
  EXPECT_LE(s.iterations, 6);
  EXPECT_LT(s.cost, s.initial_cost);
  EXPECT_LT(RadToDeg(s.final_position_error), 0.01);
  // Duration proportional to the norm of the joint change.
  EXPECT_NEAR(s.duration, options_.duration_per_rad * (to - from).norm(), 1e-9);
  const auto& pts = plan.trajectory.points;
  ASSERT_EQ(static_cast<int>(pts.size()), s.steps + 1);
  EXPECT_EQ(pts.front().q, from);
  EXPECT_NEAR(pts.back().t, s.duration, 1e-9);
  for (std::size_t k = 1; k < pts.size(); ++k) EXPECT_GT(pts[k].t, pts[k - 1].t);
  EXPECT_LT((pts.back().q - to).cwiseAbs().maxCoeff(), options_.goal_tolerance);
  EXPECT_EQ(plan.torques.size(), pts.size() - 1);
  EXPECT_EQ(plan.feedback_gains.size(), pts.size() - 1);
  // Torques include gravity compensation: joint 2 carries the arm.
  EXPECT_GT(plan.torques.front().cwiseAbs()[1], 500.0);
}

TEST_F(IlqgTest, DiscreteDynamicsJacobiansMatchFiniteDifferences) {
  for (const bool relative : {true, false}) {
    IlqgOptions o = options_;
    o.effort_relative_to_gravity = relative;
    IlqgPlanner planner(model_, o);
    RandomStream rng(21);
    for (int trial = 0; trial < 5; ++trial) {
      Eigen::VectorXd xu(18);
      for (int i = 0; i < 6; ++i) {
        xu[i] = rng.Uniform(model_.q_min[i], model_.q_max[i]);
        xu[6 + i] = rng.Uniform(-1.0, 1.0);
        xu[12 + i] = rng.Uniform(-50.0, 50.0);
      }
      const double dt = 0.04;
      IlqgPlanner::Matrix12d fx;
      IlqgPlanner::Matrix12x6d fu;
      ASSERT_TRUE(planner.Linearize(xu.head<12>(), xu.tail<6>(), dt, fx, fu));
      auto step = [&](const Eigen::VectorXd& v) -> Eigen::VectorXd {
        IlqgPlanner::Vector12d next;
        planner.Step(v.head<12>(), v.tail<6>(), dt, next);
        return next;
      };
      Eigen::MatrixXd jac(12, 18);
      jac << fx, fu;
      testing::ExpectJacobianMatchesNumeric(step, xu, jac, 1e-6, 1e-6);
    }
  }
}

TEST_F(IlqgTest, RespectsSpeedLimitsWhenAskedForAFastMove) {
  IlqgOptions o = options_;
  o.duration_per_rad = 0.05;  // far too fast: the warm-start check lengthens the move
  o.min_duration = 0.2;
  IlqgPlanner planner(model_, o);
  const Vector6d from = Deg(-90, 10, 10, 0, 60, 0);
  const Vector6d to = Deg(90, 30, 0, 0, 40, 0);
  const ArmPlan plan = planner.Plan(from, to);
  EXPECT_TRUE(plan.summary.IsUsable()) << plan.summary.BriefReport();
  EXPECT_GT(plan.summary.duration, 0.05 * (to - from).norm());
  for (const auto& p : plan.trajectory.points) {
    EXPECT_TRUE((p.qd.cwiseAbs().array() <= model_.qd_max.array()).all()) << p.qd.transpose();
  }
}

TEST_F(IlqgTest, KeepsInsidePositionLimitsWhenRushingTowardsOne) {
  // Joint 3 moves up at 2 rad/s towards a goal just under its upper limit: the quintic warm start
  // overshoots the limit by far; the limit penalty must keep the plan inside, whichever warm start.
  Vector6d from = Deg(0, 20, 0, 0, 45, 0);
  from[2] = model_.q_max[2] - 0.3;
  Vector6d qd = Vector6d::Zero();
  qd[2] = 2.0;
  Vector6d to = from;
  to[2] = model_.q_max[2] - 0.001;
  for (const auto warm_start : {IlqgOptions::WarmStart::kQuintic, IlqgOptions::WarmStart::kLq}) {
    IlqgOptions o = options_;
    o.warm_start = warm_start;
    IlqgPlanner planner(model_, o);
    const ArmPlan plan = planner.Plan(from, to, qd);
    EXPECT_TRUE(plan.summary.IsUsable()) << plan.summary.BriefReport();
    double highest = -1e9;
    for (const auto& p : plan.trajectory.points) highest = std::max(highest, p.q[2]);
    EXPECT_LE(highest, model_.q_max[2]);
    if (warm_start == IlqgOptions::WarmStart::kQuintic) {
      EXPECT_GT(plan.summary.initial_cost, 2.0 * plan.summary.cost) << plan.summary.BriefReport();
    }
  }
}

TEST_F(IlqgTest, BothWarmStartsReachTheSameOptimum) {
  IlqgOptions quintic = options_;
  quintic.warm_start = IlqgOptions::WarmStart::kQuintic;
  IlqgOptions lq = options_;
  lq.warm_start = IlqgOptions::WarmStart::kLq;
  const Vector6d from = Deg(52, 23, 25, 0, 43, -98), to = Deg(-26, 40, 10, 0, 40, 20);
  IlqgPlanner a(model_, quintic), b(model_, lq);
  const ArmPlan pa = a.Plan(from, to), pb = b.Plan(from, to);
  ASSERT_TRUE(pa.summary.IsUsable()) << pa.summary.BriefReport();
  ASSERT_TRUE(pb.summary.IsUsable()) << pb.summary.BriefReport();
  EXPECT_NEAR(pa.summary.cost, pb.summary.cost, 1e-4 * pb.summary.cost);
  EXPECT_LT(pb.summary.initial_cost, pa.summary.initial_cost);  // the decoupled optimum starts closer
  double gap = 0.0;
  for (std::size_t k = 0; k < pa.trajectory.points.size(); ++k)
    gap = std::max(gap, (pa.trajectory.points[k].q - pb.trajectory.points[k].q).cwiseAbs().maxCoeff());
  EXPECT_LT(RadToDeg(gap), 0.1);
}

TEST_F(IlqgTest, LiteralTorqueEffortAlsoConverges) {
  IlqgOptions o = options_;
  o.effort_relative_to_gravity = false;
  IlqgPlanner planner(model_, o);
  const ArmPlan plan = planner.Plan(Deg(52, 23, 25, 0, 43, -98), Deg(-26, 40, 10, 0, 40, 20));
  EXPECT_TRUE(plan.summary.IsUsable()) << plan.summary.BriefReport();
}

TEST_F(IlqgTest, HandlesAZeroLengthMotionAndGoalsOnTheLimits) {
  IlqgPlanner planner(model_, options_);
  const Vector6d q = Deg(10, 20, 30, 40, 50, 60);
  const ArmPlan still = planner.Plan(q, q);
  EXPECT_EQ(still.summary.status, PlanStatus::kConverged) << still.summary.BriefReport();
  EXPECT_LT(still.summary.cost, 1e-12);
  // 180 deg lies a rounding error beyond the URDF's 3.14159265: accepted, moved onto the limit.
  const ArmPlan edge = planner.Plan(Vector6d::Zero(), Deg(180, 150, -180, 400, 120, 400));
  EXPECT_TRUE(edge.summary.IsUsable()) << edge.summary.BriefReport();
}

TEST_F(IlqgTest, RejectsAGoalOutsideTheLimits) {
  IlqgPlanner planner(model_, options_);
  Vector6d to = Vector6d::Zero();
  to[1] = model_.q_min[1] - 0.1;
  EXPECT_THROW(planner.Plan(Vector6d::Zero(), to), InputError);
}

TEST_F(IlqgTest, OptionsFromYamlRejectTypos) {
  EXPECT_THROW(IlqgOptions::FromConfig(ConfigNode::FromString("dtt: 0.1")), InputError);
  EXPECT_THROW(IlqgOptions::FromConfig(ConfigNode::FromString("dt: -0.1")), InputError);
  EXPECT_THROW(IlqgOptions::FromConfig(ConfigNode::FromString("effort_scale: [1, 2, 3]")), InputError);
  EXPECT_THROW(IlqgOptions::FromConfig(ConfigNode::FromString("warm_start: spline")), InputError);
  const IlqgOptions o = IlqgOptions::FromConfig(ConfigNode::FromString("dt: 0.05\nmax_iterations: 7"));
  EXPECT_EQ(o.dt, 0.05);
  EXPECT_EQ(o.max_iterations, 7);
}

}  // namespace
}  // namespace ifab::arm
