#include "ifab/model/site.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ifab/core/config.h"
#include "ifab/core/data_path.h"

namespace ifab {
namespace {

TEST(Site, LoadsTheBrickStackSite) {
  const Site site = LoadSite(DataPath("sites/brick_stack.yaml"));
  EXPECT_GE(site.boundary.size(), 3u);
  EXPECT_EQ(site.walls.size(), site.boundary.size());
  EXPECT_FALSE(site.obstacles.empty());
  EXPECT_NEAR(site.brick.size.x(), 0.240, 1e-12);
  const auto objects = site.Objects();
  EXPECT_EQ(objects.front().name, "ground");
  EXPECT_EQ(site.ObstacleFootprints().size(), site.walls.size() + site.obstacles.size());
  EXPECT_TRUE(site.bricks.empty());
  EXPECT_NEAR(site.DesignedBrickPose(2).translation().z(), 2.5 * 0.052, 1e-12);
}

TEST(Site, ErrorsNameTheField) {
  const char* text = "boundary: [[0,0],[1,0],[1,1]]\nbricks:\n  - pose: [0, 0, 0.026, 0, 0, 0]\n    size: [0.24, -0.1, 0.05]\n";
  try {
    SiteFromConfig(ConfigNode::FromString(text, "site.yaml"));
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("site.yaml:4: bricks[0].size: expected 3 positive numbers"));
  }
  EXPECT_THROW(SiteFromConfig(ConfigNode::FromString("boundary: [[0,0],[1,0]]\n", "s.yaml")), InputError);
  EXPECT_THROW(SiteFromConfig(ConfigNode::FromString("boundary: [[0,0],[1,0],[1,1]]\ncolour: red\n", "s.yaml")),
               InputError);
}

TEST(Site, WallsStandOutsideTheBoundary) {
  const Site site = SiteFromConfig(ConfigNode::FromString(
      "boundary: [[-2,-1],[2,-1],[2,1],[-2,1]]\nwalls: {height: 2, thickness: 0.2}\n", "s.yaml"));
  ASSERT_EQ(site.walls.size(), 4u);
  // The first wall runs along y = -1 and lies below it.
  EXPECT_NEAR(site.walls[0].T_site_box.translation().y(), -1.1, 1e-12);
}

}  // namespace
}  // namespace ifab
