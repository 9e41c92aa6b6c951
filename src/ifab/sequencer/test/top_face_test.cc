// The workpiece as built (issue 12): the top face of the last brick is measured from the points
// that land on it, and nothing else in the sweep (its side faces, the brick below, the floor)
// moves the measurement.
#include "ifab/sequencer/top_face.h"

#include <gtest/gtest.h>

#include "ifab/core/angles.h"
#include "ifab/core/random.h"
#include "ifab/perception/registration.h"
#include "ifab/perception/testing/synthetic.h"

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

// A stack of three bricks, each `grown` longer and wider than designed, on the floor at the
// site origin, swept by a laser 0.8 m from the top at 50 deg elevation (the mission's scan) whose
// vertical scan plane yaws across it; ray-cast with the arm laser's noise (18 mm along the ray,
// beam jitter) and mixed pixels at depth edges. The model's top brick has the designed size and
// sits where a registration puts it: its near faces (towards the laser) on the real ones.
struct StackSweep {
  std::vector<RayPoint> cloud;
  SiteBox registered_top;
};
StackSweep SweepGrownStack(const Eigen::Vector2d& grown, std::uint64_t seed) {
  const Eigen::Vector3d design(0.240, 0.115, 0.052);
  Site world;
  world.has_ground = true;
  for (int k = 0; k < 3; ++k) {
    SiteBox b;
    b.name = "brick_" + std::to_string(k);
    b.box.size = design + Eigen::Vector3d(grown.x(), grown.y(), 0.0);
    b.T_site_box = PoseFromXyzRpy(0.0, 0.0, design.z() * (k + 0.5), 0, 0, 0);
    world.bricks.push_back(b);
  }
  const Scene scene(SiteBodies(world, Pose3::Identity(), true));
  const double top = 3 * design.z(), el = DegToRad(50.0), from = DegToRad(-135.0);  // from the -x, -y side
  const Eigen::Vector3d origin(0.8 * std::cos(el) * std::cos(from), 0.8 * std::cos(el) * std::sin(from),
                               top + 0.8 * std::sin(el));
  const double yaw_centre = std::atan2(-origin.y(), -origin.x());
  auto at = [&](double t) {
    Pose3 T = Pose3::Identity();
    T.translation() = origin;
    T.linear() = RotationFromRpy(M_PI / 2, 0.0, yaw_centre - 0.2 + 0.2 * t);
    return T;
  };
  testing::SyntheticLaser laser;
  laser.mixed_pixels = true;
  RandomStream rng(seed);
  StackSweep out;
  out.cloud = testing::SynthesizeCloud(scene, at, 0.0, 2.0, laser, rng);
  out.registered_top = world.bricks.back();
  out.registered_top.box.size = design;
  out.registered_top.T_site_box.translation().head<2>() = -0.5 * grown;  // near faces on the real ones
  return out;
}

TEST(TopFootprintTest, MeasuresALongerOrShorterBrickWithinItsReportedError) {
  // Bricks from 8 mm short to 8 mm long and 4 mm narrow to 4 mm wide (EN 771-1 T1 and R1).
  int covered = 0, trials = 0;
  for (int t = 0; t < 10; ++t) {
    const Eigen::Vector2d grown(0.002 * ((t % 5) * 2 - 4), 0.001 * (((t + 2) % 5) * 2 - 4));
    const StackSweep sweep = SweepGrownStack(grown, 300 + static_cast<std::uint64_t>(t));
    const auto m = MeasureTopFootprint(sweep.cloud, Pose3::Identity(), sweep.registered_top, 0.0);
    ASSERT_TRUE(m.has_value());
    for (int a = 0; a < 2; ++a) {
      ASSERT_TRUE(m->measured[static_cast<std::size_t>(a)]) << "axis " << a;
      const double truth = sweep.registered_top.box.size[a] + grown[a];
      EXPECT_LT(m->std[a], 0.0015);  // 18 mm of range noise: about 1 mm
      EXPECT_NEAR(m->size[a], truth, 3.0 * m->std[a]) << "trial " << t << " axis " << a;
      covered += std::abs(m->size[a] - truth) < 2.0 * m->std[a];
      ++trials;
    }
  }
  EXPECT_GE(covered, 0.8 * trials);  // a 2-sigma interval holds about 95 %
}

TEST(TopFootprintTest, ReadsTheSizeWithoutBiasForAPhysicalBeam) {
  // The edge is where the weight missing before it balances the weight past it: unbiased when a
  // beam straddling the far edge mixes as often on the floor's side as on the face's (the test
  // laser's footprint width is taken where it meets the edge). Mean error over 40 sweeps within
  // three standard errors of zero, per axis.
  constexpr int kSweeps = 40;
  Eigen::Vector2d sum = Eigen::Vector2d::Zero(), sum2 = Eigen::Vector2d::Zero();
  for (int t = 0; t < kSweeps; ++t) {
    const StackSweep sweep = SweepGrownStack(Eigen::Vector2d::Zero(), 500 + static_cast<std::uint64_t>(t));
    const auto m = MeasureTopFootprint(sweep.cloud, Pose3::Identity(), sweep.registered_top, 0.0);
    ASSERT_TRUE(m.has_value());
    const Eigen::Vector2d e = m->size - sweep.registered_top.box.size.head<2>();
    sum += e;
    sum2 += e.cwiseProduct(e);
  }
  const Eigen::Vector2d mean = sum / kSweeps;
  const Eigen::Vector2d se = ((sum2 / kSweeps - mean.cwiseProduct(mean)) / (kSweeps - 1)).cwiseSqrt();
  for (int a = 0; a < 2; ++a)
    EXPECT_LT(std::abs(mean[a]), 3.0 * se[a]) << "axis " << a << ": " << 1e3 * mean[a] << " +- " << 1e3 * se[a] << " mm";
}

TEST(TopFootprintTest, NothingWithoutAFarEdge) {
  // Only the points on the top face (no ray passes its far edges to the floor): no edge to find.
  const StackSweep sweep = SweepGrownStack(Eigen::Vector2d::Zero(), 7);
  std::vector<RayPoint> top_only;
  for (const auto& p : sweep.cloud)
    if (p.p.z() > 0.15) top_only.push_back(p);
  EXPECT_FALSE(MeasureTopFootprint(top_only, Pose3::Identity(), sweep.registered_top, 0.0).has_value());
  EXPECT_TRUE(MeasureTopFootprint(sweep.cloud, Pose3::Identity(), sweep.registered_top, 0.0).has_value());
}

}  // namespace
}  // namespace ifab::sequencer
