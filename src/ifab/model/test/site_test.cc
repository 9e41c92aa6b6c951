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

TEST(Site, PlanesPolygonsBoxesAndObjectsInAnyOrientation) {
  const Site site = SiteFromConfig(ConfigNode::FromString(R"(
planes:
  - {name: wall, normal: [0, 2, 0], offset: 3.0}
  - {name: slope, normal: [1, 0, 1], point: [1, 0, 0]}
polygons:
  - name: board
    vertices: [[0, -0.3, -0.2], [0, -0.3, 0.2], [0, 0.3, 0.2], [0, 0.3, -0.2]]
    xyz: [1.5, 0, 0.1]
    rpy_deg: [0, 10, 0]
boxes:
  - {name: crate, size: [0.4, 0.4, 0.4], pose: [2, 1, 0.2, 0, 0, 0.5]}
objects:
  - name: stand
    xyz: [1.6, 0, 0]
    parts:
      - {polygon: {vertices: [[0, 0, 0], [0.1, 0, 0], [0.1, 0.1, 0]]}}
      - {box: {size: [0.05, 0.05, 0.5], xyz: [0, 0, -0.25]}}
)", "s.yaml"));
  EXPECT_FALSE(site.has_ground);  // no ground_z: no floor
  EXPECT_TRUE(site.boundary.empty());
  ASSERT_EQ(site.objects.size(), 5u);
  const auto& wall = std::get<Plane>(site.objects[0].parts[0].primitives[0]);
  EXPECT_NEAR(wall.normal.y(), 1.0, 1e-12);
  EXPECT_NEAR(wall.offset, 1.5, 1e-12);  // 3.0 along a normal of length 2
  const auto& slope = std::get<Plane>(site.objects[1].parts[0].primitives[0]);
  EXPECT_NEAR(slope.offset, std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(XyzRpyFromPose(site.objects[2].T_site_object)[4], 10 * M_PI / 180, 1e-12);
  EXPECT_EQ(site.objects[4].parts.size(), 2u);
  EXPECT_NEAR(site.objects[4].parts[1].T_site_object.translation().z(), -0.25, 1e-12);
  EXPECT_EQ(site.Objects().size(), 6u);
  EXPECT_EQ(site.Bodies().size(), 5u);
  EXPECT_THROW(site.RequireBoundary("s.yaml", "ifab plan-base"), InputError);
}

TEST(Site, APoseInDegreesIsRejected) {
  try {
    SiteFromConfig(ConfigNode::FromString("boxes:\n  - {name: b, size: [1, 1, 1], pose: [1, 0, 0, 0, 0, 20]}\n", "s.yaml"));
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("s.yaml:2: boxes[0].pose"));
    EXPECT_THAT(e.what(), ::testing::HasSubstr("looks like degrees"));
  }
  EXPECT_THROW(SiteFromConfig(ConfigNode::FromString(
                   "boundary: [[0,0],[1,0],[1,1]]\nobstacles:\n  - {size: [1, 1, 1], pose: [0, 0, 0, 0, 90, 0]}\n", "s.yaml")),
               InputError);
  // Radians within a half-turn are read as before.
  EXPECT_NO_THROW(SiteFromConfig(ConfigNode::FromString("boxes:\n  - {size: [1, 1, 1], pose: [0, 0, 0, 0, 0, 3.1]}\n", "s.yaml")));
  // Both forms at once is ambiguous.
  EXPECT_THROW(SiteFromConfig(ConfigNode::FromString(
                   "boxes:\n  - {size: [1, 1, 1], pose: [0, 0, 0, 0, 0, 0], rpy_deg: [0, 0, 5]}\n", "s.yaml")),
               InputError);
  // A non-convex polygon names its field.
  EXPECT_THROW(SiteFromConfig(ConfigNode::FromString(
                   "polygons:\n  - {vertices: [[0,0,0],[1,0,0],[0.2,0.2,0],[0,1,0]]}\n", "s.yaml")),
               InputError);
}

TEST(Site, TheGroundIsAnOrdinaryOptionalObject) {
  const Site with = SiteFromConfig(ConfigNode::FromString("ground_z: -0.4\n", "s.yaml"));
  ASSERT_TRUE(with.has_ground);
  ASSERT_EQ(with.Objects().size(), 1u);
  EXPECT_NEAR(std::get<Plane>(with.Objects()[0].primitives[0]).offset, -0.4, 1e-12);
  EXPECT_TRUE(SiteFromConfig(ConfigNode::FromString("{}", "s.yaml")).Objects().empty());
}

}  // namespace
}  // namespace ifab
