#include "ifab/base/planner/stomp_planner.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "brick_stacking_scene.h"
#include "ifab/core/angles.h"
#include "ifab/core/data_path.h"
#include "ifab/core/error.h"
#include "ifab/core/random.h"

namespace ifab::base {
namespace {

StompBasePlanner MakePlanner(StompPlannerOptions options = {}) {
  return StompBasePlanner(testing::BrickStackingScene(), testing::InsituFabricatorBase(), options);
}

// Bound on the worst sideways speed implied by consecutive poses, computed here independently of
// the planner: lateral chord displacement in the mean heading's frame over the shortest time a
// segment may take (the estimated duration spread evenly; slow segments only take longer).
double MaxLateralVelocity(const StompBasePlanner& planner, const BaseTrajectory& t) {
  const double dt = planner.EstimateDuration(t.points.front().pose, t.points.back().pose) /
                    static_cast<double>(t.size() - 1);
  double worst = 0.0;
  for (std::size_t i = 0; i + 1 < t.size(); ++i) {
    const Pose2& a = t.points[i].pose;
    const Pose2& b = t.points[i + 1].pose;
    const double mean = a.theta + 0.5 * WrapAngle(b.theta - a.theta);
    const double lateral = -std::sin(mean) * (b.x - a.x) + std::cos(mean) * (b.y - a.y);
    worst = std::max(worst, std::abs(lateral) / dt);
  }
  return worst;
}

// Footprint clearance along the trajectory, interpolated finely here (not by the planner).
double MinClearance(const FootprintChecker& checker, const BaseTrajectory& t) {
  double worst = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i + 1 < t.size(); ++i) {
    for (int s = 0; s < 20; ++s) {
      worst = std::min(worst, checker.Clearance(Interpolate(t.points[i].pose, t.points[i + 1].pose, s / 20.0)));
    }
  }
  return std::min(worst, checker.Clearance(t.points.back().pose));
}

TEST(StompPlannerOptions, ReadsYamlAndRejectsNonsense) {
  const auto c = ConfigNode::FromString(
      "num_time_steps: 30\nnum_rollouts: 8\nphase2_initialization: tangent\nphase2: {max_iterations: 20}\n", "p.yaml");
  const StompPlannerOptions o = StompPlannerOptions::FromConfig(c);
  EXPECT_EQ(o.num_time_steps, 30);
  EXPECT_EQ(o.num_rollouts, 8);
  EXPECT_EQ(o.phase2_initialization, "tangent");
  EXPECT_EQ(o.phase2.max_iterations, 20);
  EXPECT_EQ(o.phase1.max_iterations, StompPlannerOptions{}.phase1.max_iterations);
  EXPECT_THROW(StompPlannerOptions::FromConfig(ConfigNode::FromString("num_rolouts: 3\n")), InputError);
  EXPECT_THROW(StompPlannerOptions::FromConfig(ConfigNode::FromString("phase2_initialization: magic\n")),
               InputError);
  EXPECT_THROW(StompPlannerOptions::FromConfig(ConfigNode::FromString("num_time_steps: -2\n")), InputError);
  StompPlannerOptions bad;
  bad.required_clearance = 0.5;  // beyond the obstacle margin: never costed, never reached
  std::string why;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_THROW(MakePlanner(bad), InputError);
}

// data/base/planner.yaml documents the defaults: it must parse and agree with them.
TEST(StompPlannerOptions, ShippedYamlHoldsTheDefaults) {
  const StompPlannerOptions o =
      StompPlannerOptions::FromConfig(ConfigNode::LoadFile(DataPath("base/planner.yaml"))["base_planner"]);
  const StompPlannerOptions d;
  EXPECT_EQ(o.num_time_steps, d.num_time_steps);
  EXPECT_EQ(o.num_rollouts, d.num_rollouts);
  EXPECT_EQ(o.num_reused_rollouts, d.num_reused_rollouts);
  EXPECT_EQ(o.exponent_h, d.exponent_h);
  EXPECT_EQ(o.smoothness.acceleration, d.smoothness.acceleration);
  EXPECT_EQ(o.smoothness.jerk, d.smoothness.jerk);
  EXPECT_EQ(o.smoothness.heading_scale, d.smoothness.heading_scale);
  EXPECT_EQ(o.obstacle_weight, d.obstacle_weight);
  EXPECT_EQ(o.obstacle_margin, d.obstacle_margin);
  EXPECT_EQ(o.collision_penalty, d.collision_penalty);
  EXPECT_EQ(o.obstacle_substeps, d.obstacle_substeps);
  EXPECT_EQ(o.obstacle_substep_length, d.obstacle_substep_length);
  EXPECT_EQ(o.required_clearance, d.required_clearance);
  EXPECT_EQ(o.phase1_clearance, d.phase1_clearance);
  EXPECT_EQ(o.collision_check_step, d.collision_check_step);
  EXPECT_EQ(o.duration_slack, d.duration_slack);
  EXPECT_EQ(o.track_speed_fraction, d.track_speed_fraction);
  EXPECT_EQ(o.per_segment_timing, d.per_segment_timing);
  EXPECT_EQ(o.constraint_tolerance, d.constraint_tolerance);
  EXPECT_EQ(o.constraint_projection_steps, d.constraint_projection_steps);
  EXPECT_EQ(o.constraint_damping, d.constraint_damping);
  EXPECT_EQ(o.phase2_initialization, d.phase2_initialization);
  EXPECT_EQ(o.phase2_attempts, d.phase2_attempts);
  EXPECT_EQ(o.check_reachability, d.check_reachability);
  EXPECT_EQ(o.reachability_cell, d.reachability_cell);
  EXPECT_EQ(o.num_threads, d.num_threads);
  for (const auto& [p, q] : {std::pair{o.phase1, d.phase1}, std::pair{o.phase2, d.phase2}}) {
    EXPECT_EQ(p.max_iterations, q.max_iterations);
    EXPECT_EQ(p.min_iterations, q.min_iterations);
    EXPECT_EQ(p.noise_stddev_xy, q.noise_stddev_xy);
    EXPECT_EQ(p.noise_stddev_theta, q.noise_stddev_theta);
    EXPECT_EQ(p.noise_decay, q.noise_decay);
    EXPECT_EQ(p.min_noise_fraction, q.min_noise_fraction);
    EXPECT_EQ(p.hold_noise_until_valid, q.hold_noise_until_valid);
    EXPECT_EQ(p.cost_window, q.cost_window);
    EXPECT_EQ(p.convergence_tolerance, q.convergence_tolerance);
  }
}

// The point-clearance field only skips poses whose obstacle cost is zero: per-point costs are the
// same as without it (check_reachability off builds no field).
TEST(StompBasePlanner, ClearanceFieldLeavesPointCostsUnchanged) {
  const StompBasePlanner with = MakePlanner();
  StompPlannerOptions o;
  o.check_reachability = false;
  const StompBasePlanner without = MakePlanner(o);
  RandomStream rng(5);
  const int rows = o.num_time_steps + 2;
  int zero_points = 0, costly_points = 0;
  for (int t = 0; t < 200; ++t) {
    TrajectoryMatrix q(rows, 3);
    // Draws named, last coordinate first: gcc's order of a call's arguments (C++ leaves it open).
    const double a_t = rng.Uniform(-kPi, kPi), a_y = rng.Uniform(-3, 3), a_x = rng.Uniform(-4, 4);
    const Eigen::Vector3d a(a_x, a_y, a_t);
    const double b_t = rng.Uniform(-kPi, kPi), b_y = rng.Uniform(-3, 3), b_x = rng.Uniform(-4, 4);
    const Eigen::Vector3d b(b_x, b_y, b_t);
    for (int i = 0; i < rows; ++i) {
      const double f = static_cast<double>(i) / (rows - 1);
      const double n_t = rng.Normal(), n_y = rng.Normal(), n_x = rng.Normal();
      q.row(i) = (a + f * (b - a)).transpose() + 0.05 * Eigen::RowVector3d(n_x, n_y, n_t);
    }
    Eigen::VectorXd c1, c2, smooth = Eigen::VectorXd::Zero(rows);
    with.PointCosts(q, &c1);
    without.PointCosts(q, &c2);
    ASSERT_EQ(c1.size(), c2.size());
    for (int i = 0; i < rows; ++i) ASSERT_DOUBLE_EQ(c1[i], c2[i]) << "trajectory " << t << " point " << i;
    AddSmoothnessCosts(q, o.smoothness, &smooth);
    for (int i = 0; i < rows; ++i) (c1[i] - smooth[i] > 1e-9 ? costly_points : zero_points)++;
    ASSERT_EQ(with.DenseCollisionFree(q, 0.05), without.DenseCollisionFree(q, 0.05)) << "trajectory " << t;
  }
  EXPECT_GT(zero_points, 500);    // poses clear of everything, where the field skips the checker
  EXPECT_GT(costly_points, 500);  // and poses near the objects
}

TEST(StompBasePlanner, EstimatesDurationFromDistanceTurnAndTrackSpeed) {
  StompPlannerOptions o;
  o.duration_slack = 1.5;
  o.track_speed_fraction = 0.5;
  const StompBasePlanner planner = MakePlanner(o);
  // 3 m straight plus a half turn (each track travels B/2 * pi = 1.571 m) at 0.15 m/s, times 1.5.
  EXPECT_NEAR(planner.EstimateDuration(Pose2(0, 1, 0), Pose2(3, 1, kPi)), 1.5 * (3.0 + 0.5 * kPi) / 0.15, 1e-9);
}

// The paper's maneuvers: around the stack between the four building positions, in a loop.
TEST(StompBasePlanner, PlansTheBuildingPositionLoopWithoutSidewaysMotion) {
  const StompBasePlanner planner = MakePlanner();
  const auto positions = testing::BuildingPositions();
  for (std::size_t k = 0; k < positions.size(); ++k) {
    const Pose2& start = positions[k];
    const Pose2& goal = positions[(k + 1) % positions.size()];
    const PlanResult r = planner.Plan(start, goal, RandomStream(k));
    SCOPED_TRACE(r.BriefReport());
    ASSERT_TRUE(r.IsUsable());
    const BaseTrajectory& t = r.trajectory;
    ASSERT_EQ(static_cast<int>(t.size()), planner.options().num_time_steps + 2);
    EXPECT_NEAR(TranslationDistance(t.points.front().pose, start), 0.0, 1e-12);
    EXPECT_NEAR(AngleDistance(t.points.front().pose, start), 0.0, 1e-12);
    EXPECT_NEAR(TranslationDistance(t.points.back().pose, goal), 0.0, 1e-12);
    EXPECT_NEAR(AngleDistance(t.points.back().pose, goal), 0.0, 1e-9);
    // Phase 2's constraint: negligible sideways motion (the tracks cannot slide sideways).
    EXPECT_LT(MaxLateralVelocity(planner, t), 1e-3);
    EXPECT_LT(r.max_lateral_velocity, 1e-3);
    EXPECT_GE(MinClearance(planner.checker(), t), -1e-3);
    EXPECT_GE(r.min_clearance, 0.0);
    // Nominal velocities keep both tracks within the planning speed.
    const double limit = planner.options().track_speed_fraction * planner.checker().robot().max_track_speed;
    for (const auto& p : t.points) {
      EXPECT_LE(std::abs(p.v) + 0.5 * planner.checker().robot().track_gauge * std::abs(p.omega), limit + 1e-9);
    }
    EXPECT_GT(t.duration, 0.0);
    EXPECT_GE(t.Length(), TranslationDistance(start, goal) - 1e-9);
  }
}

TEST(StompBasePlanner, ReproducibleFromTheSeedWithAnyNumberOfThreads) {
  StompPlannerOptions serial;
  serial.num_threads = 1;
  StompPlannerOptions parallel;
  parallel.num_threads = 2;
  const Pose2 start(-1.6, 0.0, 0.0), goal(1.6, 0.5, kPi);
  const PlanResult a = MakePlanner(serial).Plan(start, goal, RandomStream(42));
  const PlanResult b = MakePlanner(parallel).Plan(start, goal, RandomStream(42));
  const PlanResult c = MakePlanner(serial).Plan(start, goal, RandomStream(43));
  ASSERT_TRUE(a.IsUsable());
  ASSERT_EQ(a.trajectory.size(), b.trajectory.size());
  EXPECT_EQ(a.iterations, b.iterations);
  for (std::size_t i = 0; i < a.trajectory.size(); ++i) {
    EXPECT_EQ(a.trajectory.points[i].pose.x, b.trajectory.points[i].pose.x);
    EXPECT_EQ(a.trajectory.points[i].pose.y, b.trajectory.points[i].pose.y);
    EXPECT_EQ(a.trajectory.points[i].pose.theta, b.trajectory.points[i].pose.theta);
  }
  // Another seed explores differently.
  double diff = 0.0;
  for (std::size_t i = 0; i < a.trajectory.size(); ++i) {
    diff += TranslationDistance(a.trajectory.points[i].pose, c.trajectory.points[i].pose);
  }
  EXPECT_GT(diff, 0.0);
}

TEST(StompBasePlanner, ReportsImpossibleRequestsAsStatus) {
  const StompBasePlanner planner = MakePlanner();
  const Pose2 start(-1.6, 0.0, 0.0);
  const RandomStream rng(1);
  const PlanResult in_stack = planner.Plan(start, Pose2(0.5, 0.0, 0.0), rng);
  EXPECT_EQ(in_stack.status, PlanStatus::kGoalInCollision);
  EXPECT_THAT(in_stack.message, ::testing::HasSubstr("brick stack"));
  EXPECT_TRUE(in_stack.trajectory.empty());
  EXPECT_EQ(planner.Plan(start, Pose2(4.3, 0.0, 0.0), rng).status, PlanStatus::kGoalOutsideBoundary);
  EXPECT_EQ(planner.Plan(start, Pose2(9.0, 0.0, 0.0), rng).status, PlanStatus::kGoalOutsideBoundary);
  EXPECT_EQ(planner.Plan(Pose2(0.5, 0.0, 0.0), start, rng).status, PlanStatus::kStartInCollision);
  EXPECT_FALSE(planner.Plan(start, Pose2(0.5, 0.0, 0.0), rng).IsUsable());

  // A wall across the site with a gap narrower than the robot: the far side is unreachable.
  PlanningScene split = testing::BrickStackingScene();
  split.obstacles.push_back(testing::Rectangle(2.5, -1.0, 0.2, 5.0));
  split.obstacles.push_back(testing::Rectangle(2.5, 3.0, 0.2, 1.0));  // gap: y in [1.5, 2.5]
  split.obstacle_names.clear();
  const StompBasePlanner walled(split, testing::InsituFabricatorBase());
  const PlanResult r = walled.Plan(start, Pose2(3.6, 0.0, kPi / 2), rng);
  EXPECT_EQ(r.status, PlanStatus::kUnreachable) << r.BriefReport();
  EXPECT_LT(r.seconds, 1.0);  // decided by the grid, not by running STOMP out of iterations
}

}  // namespace
}  // namespace ifab::base
