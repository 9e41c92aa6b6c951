// The world's ray cast (issue 15): objects first, then the uneven floor only where the ray can
// reach it; every hit must be the first surface along the ray, found here by marching.
#include "ifab/sim/world.h"

#include <gtest/gtest.h>

#include <cmath>

#include "ifab/core/data_path.h"
#include "ifab/core/random.h"
#include "ifab/sim/as_built.h"
#include "ifab/sim/sim_robot.h"

namespace ifab::sim {
namespace {

// The first t in (0, t_max) where the ray is below the floor, by 1 mm steps and bisection; inf
// if none.
double MarchToFloor(const World& w, const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_max) {
  auto below = [&](double t) {
    const Eigen::Vector3d p = o + t * d;
    return p.z() < w.FloorHeight(p.x(), p.y());
  };
  for (double t = 1e-3; t < t_max; t += 1e-3) {
    if (!below(t)) continue;
    double lo = t - 1e-3, hi = t;
    for (int k = 0; k < 60; ++k) (below(0.5 * (lo + hi)) ? hi : lo) = 0.5 * (lo + hi);
    return hi;
  }
  return std::numeric_limits<double>::infinity();
}

TEST(World, RaysOverTheUnevenFloorHitTheFirstSurface) {
  const SimOptions options = SimOptions::Load(DataPath("sim/insitu_fabricator.yaml"));
  const RobotModel robot = LoadRobotModel(DataPath("robots/insitu_fabricator.urdf"));
  const Site site = LoadSite(DataPath("sites/brick_stack.yaml"));
  const AsBuiltTolerances tol = AsBuiltTolerances::Load(DataPath("sim/as_built.yaml"));
  const AsBuilt a = DrawAsBuilt(tol, robot, site, options.arm_laser, 1);
  ASSERT_FALSE(a.floor.flat());
  const World world(site, a.floor);
  Site no_floor = site;  // the objects alone: a flat floor far below
  no_floor.ground_z = -1e3;
  const World walls_only(no_floor);
  RandomStream rng(3);
  int floor_hits = 0, object_hits = 0;
  for (int k = 0; k < 400; ++k) {
    // Base-laser-like beams: 0.3 m up, tilted down by 0 to 2 deg (shallow ones are as steep as
    // the floor's slopes), and arm-laser-like beams steeply down.
    const bool steep = k % 4 == 0;
    const double oy = rng.Uniform(-2.0, 2.0), ox = rng.Uniform(-2.0, 2.0);  // y first: gcc's order of the arguments
    const Eigen::Vector3d o(ox, oy, steep ? 1.2 : 0.3);
    const double az = rng.Uniform(-M_PI, M_PI);
    const double el = steep ? rng.Uniform(-1.4, -0.4) : -rng.Uniform(0.0, 0.035);
    const Eigen::Vector3d d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    const double t_max = 31.0;
    const auto hit = world.CastRay(o, d, 1e-6, t_max);
    const auto obj = walls_only.CastRay(o, d, 1e-6, t_max);
    const double t_obj = obj ? obj->range : std::numeric_limits<double>::infinity();
    const double t_floor = MarchToFloor(world, o, d, std::min(t_max, t_obj));
    if (t_floor < t_obj) {
      ASSERT_TRUE(hit.has_value()) << "ray " << k;
      EXPECT_EQ(hit->object, -1) << "ray " << k;
      EXPECT_NEAR(hit->range, t_floor, 1e-6) << "ray " << k;
      ++floor_hits;
    } else if (std::isfinite(t_obj)) {
      ASSERT_TRUE(hit.has_value()) << "ray " << k;
      EXPECT_EQ(hit->object, obj->object) << "ray " << k;
      EXPECT_DOUBLE_EQ(hit->range, t_obj) << "ray " << k;
      ++object_hits;
    } else {
      EXPECT_FALSE(hit.has_value()) << "ray " << k;
    }
  }
  EXPECT_GT(floor_hits, 50);
  EXPECT_GT(object_hits, 50);
}

// Beams as shallow as the floor's slopes (a base laser tilted down a tenth of a degree on its
// tracks): Newton on the height field wanders there; whatever it returns must be on the floor.
TEST(World, ShallowRaysHitTheFloorOnlyOnTheFloor) {
  const SimOptions options = SimOptions::Load(DataPath("sim/insitu_fabricator.yaml"));
  const RobotModel robot = LoadRobotModel(DataPath("robots/insitu_fabricator.urdf"));
  const Site site = LoadSite(DataPath("sites/brick_stack.yaml"));
  const AsBuiltTolerances tol = AsBuiltTolerances::Load(DataPath("sim/as_built.yaml"));
  RandomStream rng(4);
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const World world(site, DrawAsBuilt(tol, robot, site, options.arm_laser, seed).floor);
    for (int k = 0; k < 100000; ++k) {
      const double oy = rng.Uniform(-2.0, 2.0), ox = rng.Uniform(-2.0, 2.0);  // y first, as above
      const Eigen::Vector3d o(ox, oy, 0.3);
      const double az = rng.Uniform(-M_PI, M_PI), el = -rng.Uniform(0.0, 0.004);
      const Eigen::Vector3d d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      const auto hit = world.CastRay(o, d, 1e-6, 31.0);
      if (!hit || hit->object != -1) continue;
      const Eigen::Vector3d p = o + hit->range * d;
      ASSERT_NEAR(p.z(), world.FloorHeight(p.x(), p.y()), 1e-6) << "seed " << seed << " ray " << k;
    }
  }
}

}  // namespace
}  // namespace ifab::sim
