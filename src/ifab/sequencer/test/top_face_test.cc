// The workpiece as built (issue 12): the top face of the last brick is measured from the points
// that land on it, and nothing else in the sweep (its side faces, the brick below, the floor)
// moves the measurement.
#include "ifab/sequencer/top_face.h"

#include <gtest/gtest.h>

#include "ifab/core/angles.h"
#include "ifab/core/random.h"

namespace ifab::sequencer {
namespace {

SiteBox Brick(double z_centre) {
  SiteBox b;
  b.name = "brick";
  b.box.size = Eigen::Vector3d(0.240, 0.115, 0.052);
  b.T_site_box = PoseFromXyzRpy(0.3, -0.2, z_centre, 0, 0, 0.4);
  return b;
}

// A sweep over the top brick of a stack standing on a floor at z = 0 (tilted 0.2 deg): points on
// the top face, whose real height is the model's plus `offset`, on a side face, and on the floor
// around the stack, with 8 mm noise in height (the arm laser's at 40 deg incidence); in the base
// frame of the robot at its true pose.
std::vector<RayPoint> Sweep(const SiteBox& model, double offset, const Pose3& T_site_base, RandomStream& rng) {
  const Pose3 T_base_site = T_site_base.inverse(Eigen::Isometry);
  const Eigen::Vector3d h = 0.5 * model.box.size;
  const Eigen::Vector3d c = model.T_site_box.translation();
  const double slope = DegToRad(0.2);
  std::vector<RayPoint> cloud;
  auto add = [&](const Eigen::Vector3d& p_site) {
    RayPoint r;
    r.p = T_base_site * p_site;
    r.origin = T_base_site * Eigen::Vector3d(c.x(), c.y() - 0.6, c.z() + 0.6);
    cloud.push_back(r);
  };
  for (int i = 0; i < 400; ++i) {
    // Draws named, last coordinate first: gcc's order of a call's arguments (C++ leaves it open).
    const double top_z = rng.Normal(0.008), top_y = rng.Uniform(-h.y(), h.y()), top_x = rng.Uniform(-h.x(), h.x());
    add(model.T_site_box * Eigen::Vector3d(top_x, top_y, h.z() + offset + top_z));  // top
    const double side_z = rng.Uniform(-h.z(), h.z()), side_y = rng.Normal(0.008), side_x = rng.Uniform(-h.x(), h.x());
    add(model.T_site_box * Eigen::Vector3d(side_x, -h.y() + side_y, side_z));  // side
    const double a = rng.Uniform(0.0, 2.0 * M_PI), r = rng.Uniform(0.2, 0.6);
    const double x = c.x() + r * std::cos(a), y = c.y() + r * std::sin(a);
    add({x, y, slope * (x - c.x()) + rng.Normal(0.008)});  // floor
  }
  return cloud;
}

TEST(TopFaceTest, MeasuresTheHeightAboveTheFloorWithinItsReportedError) {
  const Pose3 T_site_base = PoseFromXyzRpy(-1.5, 0.4, 0.0, 0.001, -0.002, 0.3);
  const SiteBox model = Brick(0.30);
  const double designed_top = 0.30 + 0.026;
  int covered = 0;
  const int trials = 50;
  for (int t = 0; t < trials; ++t) {
    RandomStream rng(100 + static_cast<std::uint64_t>(t));
    const double offset = 0.004 * ((t % 5) - 2);  // -8 .. +8 mm
    const auto m = MeasureTopFace(Sweep(model, offset, T_site_base, rng), T_site_base, model, 0.0);
    ASSERT_TRUE(m.has_value());
    // The top face inside the 2 cm margin holds 54 % of its 400 points; no side or floor point.
    EXPECT_GT(m->points, 180);
    EXPECT_LT(m->points, 260);
    EXPECT_LT(m->std, 0.001);
    covered += std::abs(m->height - (designed_top + offset)) < 2.0 * m->std;
  }
  EXPECT_GE(covered, 0.9 * trials);  // a 2-sigma interval holds about 95 %
}

TEST(TopFaceTest, DoesNotDependOnTheRegisteredHeightOrTilt) {
  // Registered 6 mm high and pitched 0.3 deg (a small workpiece pins these loosely): the face and
  // the floor move alike.
  const Pose3 T_true = PoseFromXyzRpy(-1.5, 0.4, 0.0, 0.0, 0.0, 0.3);
  const Pose3 T_registered = PoseFromXyzRpy(-1.5, 0.4, 0.006, 0.0, DegToRad(0.3), 0.3);
  const SiteBox model = Brick(0.30);
  RandomStream rng(11);
  const auto cloud = Sweep(model, 0.005, T_true, rng);
  const auto m_true = MeasureTopFace(cloud, T_true, model, 0.0);
  const auto m_reg = MeasureTopFace(cloud, T_registered, model, 0.0);
  ASSERT_TRUE(m_true && m_reg);
  EXPECT_NEAR(m_reg->height, m_true->height, 0.0005);
}

TEST(TopFaceTest, NoMeasurementWithoutPointsOnTheFace) {
  const Pose3 T_site_base = Pose3::Identity();
  const SiteBox model = Brick(0.30);
  RandomStream rng(7);
  std::vector<RayPoint> cloud = Sweep(model, 0.0, T_site_base, rng);
  // Keep only the side face and the floor.
  std::vector<RayPoint> no_top;
  for (const auto& p : cloud)
    if (p.p.z() < 0.30) no_top.push_back(p);
  EXPECT_FALSE(MeasureTopFace(no_top, T_site_base, model, 0.0).has_value());
  EXPECT_TRUE(MeasureTopFace(cloud, T_site_base, model, 0.0).has_value());
}

}  // namespace
}  // namespace ifab::sequencer
