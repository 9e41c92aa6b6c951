// One simulated 1081-beam UTM-30LX scan of the brick-stacking site with a 26-brick stack,
// from the arm laser looking at the stack (aim: under 0.2 ms).
#include <benchmark/benchmark.h>

#include "ifab/core/data_path.h"
#include "ifab/sim/lrf_model.h"
#include "ifab/core/config.h"

namespace ifab::sim {
namespace {

World StackSite() {
  World world(LoadSite(DataPath("sites/brick_stack.yaml")));
  for (int k = 0; k < 26; ++k)
    world.AddBrick({"brick", world.site().DesignedBrickPose(k), world.site().brick});
  return world;
}

void BM_ScanOfBrickStackSite(benchmark::State& state) {
  const World world = StackSite();
  const LrfModel lrf(LrfOptions::FromConfig(ConfigNode::LoadFile(DataPath("sensors/utm30lx.yaml"))["lrf"]));
  RandomStream rng(1);
  // The arm laser 1.6 m from the stack at 1.5 m height, looking at it and down at 30 deg.
  const Pose3 T_site_laser = PoseFromXyzRpy(1.6, 0.2, 1.5, EIGEN_PI / 2, 0.5, EIGEN_PI);
  LaserScan scan;
  for (auto _ : state) {
    lrf.Scan(world, [&](double) { return T_site_laser; }, rng, scan);
    benchmark::DoNotOptimize(scan.ranges.data());
  }
  state.SetItemsProcessed(state.iterations() * 1081);
}
BENCHMARK(BM_ScanOfBrickStackSite)->Unit(benchmark::kMicrosecond);

void BM_BaseLaserScan(benchmark::State& state) {
  const World world = StackSite();
  const LrfModel lrf(LrfOptions::FromConfig(ConfigNode::LoadFile(DataPath("sensors/utm30lx.yaml"))["lrf"]));
  RandomStream rng(2);
  const Pose3 T_site_laser = PoseFromXyzRpy(-1.5, 0.3, 0.35, 0, 0, 0.1);
  LaserScan scan;
  for (auto _ : state) {
    lrf.Scan(world, [&](double) { return T_site_laser; }, rng, scan);
    benchmark::DoNotOptimize(scan.ranges.data());
  }
}
BENCHMARK(BM_BaseLaserScan)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace ifab::sim
