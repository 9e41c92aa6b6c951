// The planning experiments' runners (issue 6 and the base planner's issue), moved to
// experiments/ by issue 12: statistics over fixed seeds.
#include <gtest/gtest.h>

#include <cmath>

#include "ifab/core/angles.h"
#include "ifab/core/config.h"
#include "ifab/core/data_path.h"
#include "ifab/core/error.h"
#include "ifab/core/random.h"
#include "ifab/experiments/arm_planning_experiment.h"
#include "ifab/experiments/base_planning_experiment.h"
#include "../../base/planner/test/brick_stacking_scene.h"

namespace ifab::experiments {
namespace {

base::StompBasePlanner MakePlanner(base::StompPlannerOptions options = {}) {
  return base::StompBasePlanner(base::testing::BrickStackingScene(), base::testing::InsituFabricatorBase(), options);
}

// The bar on seeded point-to-point motions (speed is measured in bench/, not here).
TEST(ArmPlanningExperiment, SeededBrickMotionsAllConvergeInFewIterations) {
  const RobotModel robot = LoadRobotModel(DataPath("robots/insitu_fabricator.urdf"));
  ArmPlanningExperimentConfig config;
  config.ilqg = arm::LoadIlqgOptions(DataPath("arm/arm.yaml"));
  config.cases = 40;
  const ArmPlanningResult r = RunArmPlanningExperiment(robot, config, 7);
  EXPECT_EQ(r.results["cases"].get<int>(), 40);
  EXPECT_EQ(r.results["converged_rate"].get<double>(), 1.0) << r.CasesCsv();
  EXPECT_LE(r.results["iterations_median"].get<double>(), 5.0);
  EXPECT_LE(r.results["final_joint_error_deg_max"].get<double>(), 0.01);
}

// Stochastic planner, statistical test over fixed seeds: the experiment's random start/goal pairs
// (building positions around the stack and free poses anywhere in the site).
TEST(BasePlanningExperiment, SucceedsOnRandomStartGoalPairs) {
  base::StompPlannerOptions o;
  o.num_threads = 1;
  const base::StompBasePlanner planner = MakePlanner(o);
  BasePlanningExperimentOptions e;
  e.cases = 150;
  e.seed = 5;
  std::vector<BasePlanningCase> cases;
  const nlohmann::json j = RunBasePlanningExperiment(planner, e, &cases);
  ASSERT_EQ(cases.size(), 150u);
  EXPECT_EQ(j["cases"], 150);
  EXPECT_GE(j["success_rate"].get<double>(), 0.97) << j.dump(2);
  EXPECT_LT(j["max_lateral_velocity_mps"].get<double>(), 1e-3);
  EXPECT_GE(j["min_clearance_m"].get<double>(), 0.0);
  for (const char* key : {"plan_ms_median", "plan_ms_p95", "status_counts", "failures"}) EXPECT_TRUE(j.contains(key));
}

TEST(BasePlanningExperiment, SamplesCollisionFreePosesInTheSite) {
  const base::StompBasePlanner planner = MakePlanner();
  BasePlanningExperimentOptions e;
  RandomStream rng(3);
  int building = 0;
  for (int i = 0; i < 300; ++i) {
    const Pose2 p = SampleExperimentPose(planner.checker(), e, rng);
    EXPECT_GE(planner.checker().Clearance(p), e.pose_min_clearance);
    const double r = std::hypot(p.x, p.y);
    if (r >= e.building_radius_min - 1e-9 && r <= e.building_radius_max + 1e-9 &&
        AngleDistance(p, Pose2(p.x, p.y, std::atan2(-p.y, -p.x))) <= e.building_heading_noise + 1e-9) {
      ++building;
    }
  }
  EXPECT_GT(building, 100);  // about half are building positions facing the stack
  const auto c = ConfigNode::FromString("cases: 7\nbuilding_region: [-1, 1, -1, 1]\n", "e.yaml");
  const auto o = BasePlanningExperimentOptions::FromConfig(c);
  EXPECT_EQ(o.cases, 7);
  EXPECT_EQ(o.building_region, Eigen::Vector4d(-1, 1, -1, 1));
  EXPECT_THROW(BasePlanningExperimentOptions::FromConfig(ConfigNode::FromString("building_region: [1, -1, 0, 1]\n")),
               InputError);
}

}  // namespace
}  // namespace ifab::experiments
