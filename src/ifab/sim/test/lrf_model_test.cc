#include "ifab/sim/lrf_model.h"

#include <gtest/gtest.h>

#include <cmath>

#include "ifab/core/angles.h"
#include "ifab/core/config.h"
#include "ifab/core/data_path.h"

namespace ifab::sim {
namespace {

LrfOptions Utm30lx() {
  return LrfOptions::FromConfig(ConfigNode::LoadFile(DataPath("sensors/utm30lx.yaml"))["lrf"]);
}

// A wall 2 m ahead of the laser, facing it.
World WallAt2m() {
  Site site;
  site.ground_z = -100.0;  // keep the floor out of the way
  site.obstacles.push_back({"wall", PoseFromXyzRpy(2.05, 0, 0, 0, 0, 0), Box{{0.1, 20, 20}}});
  return World(site);
}

TEST(LrfModel, NoiseAlongAndAcrossTheRayMatchesTheConfiguration) {
  LrfOptions o = Utm30lx();
  o.bias_enabled = false;  // at 2 m the bias is small, but measure the noise alone
  o.no_return_probability = 0.0;
  const LrfModel lrf(o);
  const World world = WallAt2m();
  RandomStream rng(11);
  const int n = 20000;
  double s_along = 0, s2_along = 0, s2_across = 0;
  for (int i = 0; i < n; ++i) {
    const BeamSample b = lrf.Beam(world, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
                                  Eigen::Vector3d::UnitZ(), rng);
    ASSERT_TRUE(std::isfinite(b.range));
    const double e = b.range - b.true_range;
    s_along += e;
    s2_along += e * e;
    s2_across += b.across_offset * b.across_offset;
  }
  const double mean = s_along / n;
  const double sigma_along = std::sqrt(s2_along / n - mean * mean);
  const double sigma_across = std::sqrt(s2_across / n);
  EXPECT_NEAR(sigma_along, o.sigma_along, 0.05 * o.sigma_along);
  EXPECT_NEAR(sigma_across, o.SigmaAcross(2.0), 0.05 * o.SigmaAcross(2.0));
  EXPECT_NEAR(mean, 0.0, 4 * o.sigma_along / std::sqrt(n));
}

TEST(LrfModel, BiasCurveFollowsTheRealUnitAndFig7) {
  const LrfOptions o = Utm30lx();
  // The real unit reads long by ~20 mm at 0.10-0.115 m.
  EXPECT_NEAR(o.Bias(0.105, 0.0), 0.020, 0.003);
  // Fig. 7: about 3 cm towards the scanner at 0.4 m near normal incidence, shrinking with range.
  EXPECT_NEAR(o.Bias(0.4, 0.0), -0.030, 0.005);
  EXPECT_GT(std::abs(o.Bias(0.4, 0.0)), std::abs(o.Bias(1.1, 0.0)));
  EXPECT_GT(std::abs(o.Bias(1.1, 0.0)), std::abs(o.Bias(2.4, 0.0)));
  // ... and confined to near-normal incidence.
  EXPECT_LT(std::abs(o.Bias(0.4, DegToRad(45))), 0.1 * std::abs(o.Bias(0.4, 0.0)));
  LrfOptions off = o;
  off.bias_enabled = false;
  EXPECT_EQ(off.Bias(0.4, 0.0), 0.0);
}

// A board 1 m away covering y in [0, 1] in front of a wall 3 m away: one depth edge at y = 0.
Site NearBoardBeforeAWall() {
  Site site;
  site.ground_z = -100.0;
  site.obstacles.push_back({"near", PoseFromXyzRpy(1.05, 0.5, 0, 0, 0, 0), Box{{0.1, 1.0, 5}}});
  site.obstacles.push_back({"far", PoseFromXyzRpy(3.05, 0, 0, 0, 0, 0), Box{{0.1, 20, 20}}});
  return site;
}

TEST(LrfModel, MixedPixelsAppearOnlyAtDepthEdges) {
  const World world(NearBoardBeforeAWall());
  const LrfModel lrf(Utm30lx());
  RandomStream rng(5);
  int mixed_at_edge = 0, mixed_elsewhere = 0;
  for (int i = 0; i < 2000; ++i) {
    const double a = -0.3 + 0.6 * i / 2000.0;  // sweep across the near board's edge at y = 0
    const Eigen::Vector3d d(std::cos(a), std::sin(a), 0), u(-std::sin(a), std::cos(a), 0);
    const BeamSample b = lrf.Beam(world, Eigen::Vector3d::Zero(), d, u, Eigen::Vector3d::UnitZ(), rng);
    if (b.mixed) (std::abs(a) < 0.01 ? mixed_at_edge : mixed_elsewhere)++;
  }
  EXPECT_GT(mixed_at_edge, 0);
  EXPECT_EQ(mixed_elsewhere, 0);
}

// A beam straddles an edge where it passes it: one whose centre passes a near board's edge to a
// wall behind is as wide there as one ending on the board, so mixed pixels come as often from
// either side of the edge (otherwise the edge reads moved towards the far side).
TEST(LrfModel, MixedPixelsComeFromBothSidesOfAnEdgeAlike) {
  const World world(NearBoardBeforeAWall());
  LrfOptions o = Utm30lx();
  o.bias_enabled = false;
  o.no_return_probability = 0.0;
  const LrfModel lrf(o);
  RandomStream rng(7);
  int near_side = 0, far_side = 0;
  LaserScan scan;
  for (int k = 0; k < 1200; ++k) {
    const double yaw = rng.Uniform(0.0, o.AngleIncrement());  // the edge anywhere between two beams
    lrf.Scan(world, [&](double) { return PoseFromXyzRpy(0, 0, 0, 0, 0, yaw); }, rng, scan);
    for (std::size_t i = 0; i < scan.ranges.size(); ++i) {
      const double a = scan.Angle(i) + yaw, r = scan.ranges[i];
      if (std::abs(a) > 0.01 || !(r > 1.1 && r < 2.9)) continue;  // a return between the surfaces
      (a > 0.0 ? near_side : far_side)++;
    }
  }
  ASSERT_GT(near_side + far_side, 300);
  EXPECT_NEAR(static_cast<double>(far_side) / near_side, 1.0, 0.2) << near_side << " / " << far_side;
}

TEST(LrfModel, BadConfigNamesTheField) {
  const auto c = ConfigNode::FromString("lrf:\n  sigma_along: -0.1\n", "utm.yaml");
  try {
    LrfOptions::FromConfig(c["lrf"]);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("utm.yaml:2: lrf.sigma_along: expected a number >= 0"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace ifab::sim
