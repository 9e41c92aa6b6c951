#include "ifab/base/planner/planning_scene.h"

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

using testing::Rectangle;

double Distance(const std::vector<Eigen::Vector2d>& a, const std::vector<Eigen::Vector2d>& b) {
  return SignedDistanceConvex(a.data(), static_cast<int>(a.size()), b.data(), static_cast<int>(b.size()));
}

TEST(SignedDistanceConvex, ApartTouchingAndOverlapping) {
  const auto a = Rectangle(0, 0, 1, 1);
  EXPECT_NEAR(Distance(a, Rectangle(2, 0, 1, 1)), 1.0, 1e-12);        // faces 1 m apart
  EXPECT_NEAR(Distance(a, Rectangle(2, 2, 1, 1)), std::sqrt(2.0), 1e-12);  // corner to corner
  EXPECT_NEAR(Distance(a, Rectangle(1, 0, 1, 1)), 0.0, 1e-12);        // touching
  EXPECT_NEAR(Distance(a, Rectangle(0.75, 0, 1, 1)), -0.25, 1e-12);   // 0.25 m overlap
  EXPECT_NEAR(Distance(a, Rectangle(0, 0, 0.2, 0.2)), -0.6, 1e-12);   // small box at the centre
  // A segment (two vertices) is a convex polygon too.
  const std::vector<Eigen::Vector2d> seg = {{-1, 2}, {1, 2}};
  EXPECT_NEAR(Distance(a, seg), 1.5, 1e-12);
  EXPECT_NEAR(Distance(seg, a), 1.5, 1e-12);
}

TEST(PointInPolygon, ConvexAndNonConvex) {
  const std::vector<Eigen::Vector2d> l_shape = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  EXPECT_TRUE(PointInPolygon(l_shape, {0.5, 0.5}));
  EXPECT_TRUE(PointInPolygon(l_shape, {0.5, 1.5}));
  EXPECT_FALSE(PointInPolygon(l_shape, {1.5, 1.5}));
  EXPECT_FALSE(PointInPolygon(l_shape, {3, 0.5}));
}

TEST(PlanningScene, ValidateRejectsBadPolygons) {
  PlanningScene s = testing::BrickStackingScene();
  EXPECT_NO_THROW(s.Validate());
  PlanningScene nonconvex = s;
  nonconvex.obstacles.push_back({{0, 0}, {2, 0}, {2, 1}, {1, 0.2}, {0, 1}});
  EXPECT_THROW(nonconvex.Validate(), InputError);
  PlanningScene degenerate = s;
  degenerate.boundary = {{0, 0}, {1, 1}};
  EXPECT_THROW(degenerate.Validate(), InputError);
  PlanningScene names = s;
  names.obstacle_names.pop_back();
  EXPECT_THROW(names.Validate(), InputError);
}

TEST(BaseGeometry, ReadsTheRobotFile) {
  const BaseGeometry g = BaseGeometry::Load(DataPath("robots/insitu_fabricator_base.yaml"));
  EXPECT_DOUBLE_EQ(g.length, 1.8);
  EXPECT_DOUBLE_EQ(g.width, 1.2);
  EXPECT_DOUBLE_EQ(g.track_gauge, 1.0);
  EXPECT_DOUBLE_EQ(g.max_track_speed, 0.3);
  const auto bad = ConfigNode::FromString("base:\n  footprint: {length: -1, width: 1}\n  tracks: {gauge: 1}\n", "r.yaml");
  try {
    BaseGeometry::FromConfig(bad["base"]);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("r.yaml:2: base.footprint.length: expected a positive number"));
  }
}

TEST(BaseGeometry, CornersFollowThePose) {
  BaseGeometry g = testing::InsituFabricatorBase();
  g.footprint_offset = {0.1, 0.0};
  const auto c = g.Corners(Pose2(1.0, 2.0, kPi / 2));
  // Footprint centre at (1, 2.1); rear-right corner (-0.8, -0.6) in the base frame.
  EXPECT_NEAR(c[0].x(), 1.0 + 0.6, 1e-12);
  EXPECT_NEAR(c[0].y(), 2.0 - 0.8, 1e-12);
  EXPECT_NEAR(g.CircumRadius(), std::hypot(0.9, 0.6), 1e-12);
}

// The checker's box-frame distance must agree with the generic convex distance (one conformance
// check over many random poses, near and far, for every obstacle).
TEST(FootprintChecker, ClearanceMatchesGenericConvexDistance) {
  const PlanningScene scene = testing::BrickStackingScene();
  BaseGeometry robot = testing::InsituFabricatorBase();
  robot.footprint_offset = {0.15, -0.05};
  const FootprintChecker checker(scene, robot);
  RandomStream rng(7);
  for (int i = 0; i < 2000; ++i) {
    const double theta = rng.Uniform(-kPi, kPi), y = rng.Uniform(-3, 3);  // last first: gcc's order of the arguments
    const Pose2 pose(rng.Uniform(-4, 4), y, theta);
    const auto corners = robot.Corners(pose);
    const std::vector<Eigen::Vector2d> box(corners.begin(), corners.end());
    double expected = std::numeric_limits<double>::infinity();
    for (const auto& o : scene.obstacles) expected = std::min(expected, Distance(box, o));
    const auto& b = scene.boundary;
    for (std::size_t e = 0; e < b.size(); ++e) {
      expected = std::min(expected, Distance(box, {b[e], b[(e + 1) % b.size()]}));
    }
    ASSERT_NEAR(checker.Clearance(pose), expected, 1e-9) << "pose " << pose;
  }
}

// Cost is culled (bounding circles, boundary edges by the centre's distance): it must equal the
// hinge computed from every object's exact distance.
TEST(FootprintChecker, CostMatchesTheHingeOverEveryObject) {
  const PlanningScene scene = testing::BrickStackingScene();
  const BaseGeometry robot = testing::InsituFabricatorBase();
  const FootprintChecker checker(scene, robot);
  const double margin = 0.15, penalty = 1.0;
  RandomStream rng(11);
  int costly = 0;
  for (int i = 0; i < 2000; ++i) {
    const double theta = rng.Uniform(-kPi, kPi), y = rng.Uniform(-3, 3);  // last first: gcc's order of the arguments
    const Pose2 pose(rng.Uniform(-4, 4), y, theta);
    const auto corners = robot.Corners(pose);
    const std::vector<Eigen::Vector2d> box(corners.begin(), corners.end());
    const auto hinge = [&](double d) { return std::max(0.0, margin - d) + (d < 0.0 ? penalty : 0.0); };
    double expected = 0.0;
    for (const auto& o : scene.obstacles) expected += hinge(Distance(box, o));
    const auto& b = scene.boundary;
    double d_boundary = std::numeric_limits<double>::infinity();
    for (std::size_t e = 0; e < b.size(); ++e) {
      d_boundary = std::min(d_boundary, Distance(box, {b[e], b[(e + 1) % b.size()]}));
    }
    const bool all_outside = d_boundary > 0.0 && !PointInPolygon(b, pose * robot.footprint_offset);
    if (!all_outside) expected += hinge(d_boundary);
    const double cost = checker.Cost(pose, margin, penalty);
    if (!all_outside) {
      ASSERT_NEAR(cost, expected, 1e-9) << "pose " << pose;
    } else {
      ASSERT_GT(cost, expected - 1e-9) << "pose " << pose;  // outside: penalised, by how far out
    }
    ASSERT_EQ(checker.Cost(pose, std::cos(pose.theta), std::sin(pose.theta), margin, penalty), cost);
    costly += cost > 0.0;
  }
  EXPECT_GT(costly, 200);  // the samples do come near the objects
}

TEST(FootprintChecker, BoundaryInsideCrossingOutside) {
  PlanningScene scene;
  scene.boundary = Rectangle(0, 0, 10, 10);
  const FootprintChecker checker(scene, testing::InsituFabricatorBase());
  EXPECT_NEAR(checker.Clearance(Pose2(0, 0, 0)), 5.0 - 0.9, 1e-12);
  EXPECT_NEAR(checker.Clearance(Pose2(4.5, 0, 0)), -0.4, 1e-12);  // sticks out 0.4 m
  EXPECT_LT(checker.Clearance(Pose2(8, 0, 0)), -2.9);             // entirely outside
  EXPECT_FALSE(checker.CentreInsideBoundary(Pose2(8, 0, 0)));
  std::string closest;
  checker.Clearance(Pose2(4.5, 0, 0), &closest);
  EXPECT_EQ(closest, "boundary");
}

TEST(FootprintChecker, CostIsZeroBeyondTheMarginAndPenalisesCollisions) {
  const FootprintChecker checker(testing::BrickStackingScene(), testing::InsituFabricatorBase());
  const double margin = 0.15, penalty = 1.0;
  // Facing the stack, front 0.5 m away: beyond the margin.
  EXPECT_EQ(checker.Cost(Pose2(-1.52, 0, 0), margin, penalty), 0.0);
  // 0.1 m away: inside the margin by 0.05 m.
  EXPECT_NEAR(checker.Cost(Pose2(-1.12, 0, 0), margin, penalty), 0.05, 1e-12);
  // 0.1 m into the stack: hinge 0.25 plus the penalty.
  EXPECT_NEAR(checker.Cost(Pose2(-0.92, 0, 0), margin, penalty), 1.25, 1e-12);
  EXPECT_EQ(checker.OverlappingObstacle(Pose2(-0.92, 0, 0)), 4);
  std::string closest;
  EXPECT_NEAR(checker.Clearance(Pose2(-0.92, 0, 0), &closest), -0.1, 1e-12);
  EXPECT_EQ(closest, "brick stack");
}

TEST(FootprintChecker, PointClearance) {
  const FootprintChecker checker(testing::BrickStackingScene(), testing::InsituFabricatorBase());
  EXPECT_NEAR(checker.PointClearance({1.12, 0.0}), 1.0, 1e-12);
  EXPECT_NEAR(checker.PointClearance({0.0, 0.0}), -0.0575, 1e-12);
  EXPECT_NEAR(checker.PointClearance({0.0, 3.4}), 0.1, 1e-12);
  EXPECT_NEAR(checker.PointClearance({0.0, 3.6}), -0.1, 1e-12);
}

}  // namespace
}  // namespace ifab::base
