// Registration of one sweep of the brick stack on the floor, ~20k points synthesised by ray
// casting (perception_scene.h), from a guess 2 cm and 2 deg off; counters give the final error
// of the workpiece pose (perception_open3d_bench: the same with Open3D, where installed). And one
// extrinsic calibration from six sweeps of a cube.
#include <benchmark/benchmark.h>

#include "ifab/core/random.h"
#include "ifab/perception/calibration.h"
#include "ifab/perception/registration.h"
#include "ifab/perception/scan_assembly.h"
#include "ifab/perception/testing/synthetic.h"
#include "perception_scene.h"

namespace ifab {
namespace {

void BM_RegisterStackSweep(benchmark::State& state) {
  const bench::StackScene& s = bench::Scene20k();
  RegistrationOptions options;
  options.residual = state.range(0) == 0 ? RegistrationResidual::kClosest : RegistrationResidual::kRay;
  auto guess = s.truth;
  for (auto& b : guess) b.T_base_body = b.T_base_body * bench::GuessOffset();
  RegistrationSummary summary;
  for (auto _ : state) {
    summary = Register(s.cloud, guess, options);
    benchmark::DoNotOptimize(summary.cost);
  }
  const Pose3& est = summary.bodies[1].T_base_body;
  const Pose3& truth = s.truth[1].T_base_body;
  state.counters["points"] = static_cast<double>(s.cloud.size());
  state.counters["steps"] = summary.iterations;
  state.counters["error_mm"] = 1e3 * TranslationDistance(est, truth);
  state.counters["error_deg"] = RotationAngle(est, truth) * 180.0 / M_PI;
  state.SetLabel(options.residual == RegistrationResidual::kClosest ? "eq. 7 closest point (paper)" : "ray residual");
}
BENCHMARK(BM_RegisterStackSweep)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(3);

void BM_CalibrateSixSweeps(benchmark::State& state) {
  static const RobotModel robot = LoadRobotModel(std::string(IFAB_DATA_DIR) + "/robots/insitu_fabricator.urdf");
  const Pose3 T_cube = PoseFromXyzRpy(1.75, 0.08, 0.125, 0.0, 0.0, 0.3);
  const Pose3 T_true = robot.T_tool0_arm_laser * PoseFromXyzRpy(0.006, -0.004, 0.008, 0.01, -0.01, 0.02);
  static const std::vector<CalibrationSweep> sweeps = [&] {
    const Scene world(CubeOnGroundBodies(0.25, T_cube));
    testing::SyntheticLaser laser;
    RandomStream rng(3);
    const Vector6d down = (Vector6d() << 0.0, 0.3, 0.3, 0.0, 1.2, 0.0).finished();
    Vector6d turned = down;
    turned[5] = M_PI / 2;
    std::vector<CalibrationSweep> out;
    ScanAssemblyOptions assembly;
    assembly.beam_stride = 2;
    for (auto [joint, from, to, base] : {std::tuple{4, 1.0, 1.45, down}, {5, -0.7, 0.7, down}, {3, -0.5, 0.5, down},
                                         {0, -0.2, 0.25, turned}, {1, 0.15, 0.45, down}, {2, 0.15, 0.45, down}}) {
      Vector6d q0 = base, q1 = base;
      q0[joint] = from;
      q1[joint] = to;
      const auto sweep = testing::SynthesizeArmSweep(world, robot, T_true, q0, q1, 1.5, laser, rng);
      out.push_back({"sweep", AssembleSweep(sweep.scans, sweep.joints, robot, assembly).points});
    }
    return out;
  }();
  CalibrationOptions options;
  options.autodiff = state.range(0) == 1;
  const auto bodies = CubeOnGroundBodies(0.25, T_cube * PoseFromXyzRpy(0.01, -0.01, 0.0, 0.0, 0.0, 0.03), 0.005);
  CalibrationSummary summary;
  for (auto _ : state) {
    summary = CalibrateLaserMount(sweeps, bodies, robot.T_tool0_arm_laser, options);
    benchmark::DoNotOptimize(summary.cost);
  }
  state.counters["points"] = summary.num_points;
  state.counters["error_mm"] = 1e3 * TranslationDistance(summary.T_tool0_laser, T_true);
  state.counters["error_deg"] = RotationAngle(summary.T_tool0_laser, T_true) * 180.0 / M_PI;
  state.SetLabel(options.autodiff ? "Ceres autodiff (paper)" : "analytic Jacobians");
}
BENCHMARK(BM_CalibrateSixSweeps)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace
}  // namespace ifab
