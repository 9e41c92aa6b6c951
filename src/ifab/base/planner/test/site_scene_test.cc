#include "ifab/base/planner/site_scene.h"

#include <gtest/gtest.h>

#include "brick_stacking_scene.h"
#include "ifab/core/data_path.h"

namespace ifab::base {
namespace {

// The hand-written fixture of the planner tests must describe the shipped site.
TEST(SiteScene, BrickStackSiteMatchesTheTestFixture) {
  const PlanningScene scene = PlanningSceneFromSite(LoadSite(DataPath("sites/brick_stack.yaml")));
  const PlanningScene fixture = testing::BrickStackingScene();
  ASSERT_EQ(scene.boundary.size(), fixture.boundary.size());
  for (std::size_t i = 0; i < scene.boundary.size(); ++i) {
    EXPECT_LT((scene.boundary[i] - fixture.boundary[i]).norm(), 1e-9);
  }
  ASSERT_EQ(scene.obstacles.size(), fixture.obstacles.size());
  for (std::size_t k = 0; k < scene.obstacles.size(); ++k) {
    SCOPED_TRACE(scene.obstacle_names[k]);
    EXPECT_EQ(scene.obstacle_names[k], fixture.obstacle_names[k]);
    ASSERT_EQ(scene.obstacles[k].size(), fixture.obstacles[k].size());
    for (std::size_t i = 0; i < scene.obstacles[k].size(); ++i) {
      EXPECT_LT((scene.obstacles[k][i] - fixture.obstacles[k][i]).norm(), 1e-9);
    }
  }
}

TEST(SiteScene, PlacedBricksCountOnceAndWallsOnRequest) {
  Site site = LoadSite(DataPath("sites/brick_stack.yaml"));
  for (int k = 0; k < 3; ++k) {
    SiteBox b;
    b.name = "brick";
    b.box = site.brick;
    b.T_site_box = site.DesignedBrickPose(k);
    site.bricks.push_back(b);
  }
  const std::size_t n_obstacles = site.obstacles.size();
  // The stack's footprint and its three bricks' footprints coincide.
  EXPECT_EQ(PlanningSceneFromSite(site).obstacles.size(), n_obstacles + 1);
  SiteSceneOptions o;
  o.include_stack = false;
  o.include_walls = true;
  EXPECT_EQ(PlanningSceneFromSite(site, o).obstacles.size(), n_obstacles + 1 + site.walls.size());
}

}  // namespace
}  // namespace ifab::base
