// The workpiece as built (issue 12): the top face of the last brick is measured from the points
// that land on it, and nothing else in the sweep (its side faces, the brick below, the floor)
// moves the measurement.
#include "ifab/sequencer/top_face.h"

#include <gtest/gtest.h>

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

// A sweep over a brick whose real top face lies `offset` above the modelled one: points on the
// top face, on a side face, and on the floor around it, with 8 mm noise in height (the arm
// laser's range noise at a 40 degree incidence), all in the base frame.
std::vector<RayPoint> Sweep(const SiteBox& model, double offset, const Pose3& T_site_base, RandomStream& rng) {
  const Pose3 T_base_box = T_site_base.inverse(Eigen::Isometry) * model.T_site_box;
  const Eigen::Vector3d h = 0.5 * model.box.size;
  std::vector<RayPoint> cloud;
  auto add = [&](const Eigen::Vector3d& p_box) {
    RayPoint r;
    r.p = T_base_box * p_box;
    r.origin = T_base_box * Eigen::Vector3d(0.0, -0.6, 0.6);
    cloud.push_back(r);
  };
  for (int i = 0; i < 400; ++i) {
    add({rng.Uniform(-h.x(), h.x()), rng.Uniform(-h.y(), h.y()), h.z() + offset + rng.Normal(0.008)});  // top
    add({rng.Uniform(-h.x(), h.x()), -h.y() + rng.Normal(0.008), rng.Uniform(-h.z(), h.z() + offset)});  // side
    add({rng.Uniform(-0.5, 0.5), rng.Uniform(-0.5, -0.1), -h.z() - 0.3 + rng.Normal(0.008)});            // floor
  }
  return cloud;
}

TEST(TopFaceTest, MeasuresTheTopFaceWithinItsReportedError) {
  const Pose3 T_site_base = PoseFromXyzRpy(-1.5, 0.4, 0.0, 0.001, -0.002, 0.3);
  const SiteBox model = Brick(0.30);
  int covered = 0;
  const int trials = 50;
  for (int t = 0; t < trials; ++t) {
    RandomStream rng(100 + static_cast<std::uint64_t>(t));
    const double offset = 0.004 * ((t % 5) - 2);  // -8 .. +8 mm
    const auto m = MeasureTopFace(Sweep(model, offset, T_site_base, rng), T_site_base, model);
    ASSERT_TRUE(m.has_value());
    // The top face inside the 2 cm margin holds 54 % of its 400 points; no side or floor point.
    EXPECT_GT(m->points, 180);
    EXPECT_LT(m->points, 260);
    EXPECT_LT(m->std, 0.001);
    covered += std::abs(m->offset - offset) < 2.0 * m->std;
  }
  EXPECT_GE(covered, 0.9 * trials);  // a 2-sigma interval holds about 95 %
}

TEST(TopFaceTest, NoMeasurementWithoutPointsOnTheFace) {
  const Pose3 T_site_base = Pose3::Identity();
  const SiteBox model = Brick(0.30);
  RandomStream rng(7);
  std::vector<RayPoint> cloud = Sweep(model, 0.0, T_site_base, rng);
  // Keep only the side face and the floor.
  std::vector<RayPoint> no_top;
  const Pose3 T_box_base = model.T_site_box.inverse(Eigen::Isometry) * T_site_base;
  for (const auto& p : cloud)
    if ((T_box_base * p.p).z() < 0.5 * model.box.size.z() - 0.03) no_top.push_back(p);
  EXPECT_FALSE(MeasureTopFace(no_top, T_site_base, model).has_value());
}

}  // namespace
}  // namespace ifab::sequencer
