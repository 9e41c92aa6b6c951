// Peer comparison (built only where Open3D >= 0.10 is installed; bench/perception.cmake): the
// sweep of perception_bench (about 20k points of the brick stack and the floor) registered with
// Open3D's point-to-plane ICP against the model sampled densely at the guessed poses, from the
// same guess (2 cm, 2 deg off). Time and the stack's final error read beside BM_RegisterStackSweep.
// ICP moves the cloud as one rigid body onto the model: T p_true = p_guess, so the stack is at
// T^-1 T_base_guess.
#include <benchmark/benchmark.h>
#include <open3d/Open3D.h>

#include "perception_scene.h"

namespace ifab {
namespace {

namespace reg = open3d::pipelines::registration;

void BM_Open3dPointToPlaneIcp(benchmark::State& state) {
  const bench::StackScene& s = bench::Scene20k();
  auto guess = s.truth;
  for (auto& b : guess) b.T_base_body = b.T_base_body * bench::GuessOffset();
  const double spacing = 1e-3 * static_cast<double>(state.range(0));
  const bench::OrientedPoints model =
      bench::SampleSurfaces(guess, spacing, guess[1].T_base_body.translation(), 1.5);
  open3d::geometry::PointCloud source, target;
  target.points_ = model.points;
  target.normals_ = model.normals;
  for (const auto& p : s.cloud) source.points_.push_back(p.p);
  reg::RegistrationResult result;
  for (auto _ : state) {
    result = reg::RegistrationICP(source, target, 0.05, Eigen::Matrix4d::Identity(),
                                  reg::TransformationEstimationPointToPlane(),
                                  reg::ICPConvergenceCriteria(1e-8, 1e-8, 100));
    benchmark::DoNotOptimize(result.fitness_);
  }
  Pose3 T = Pose3::Identity();
  T.matrix() = result.transformation_;
  const Pose3 est = T.inverse() * guess[1].T_base_body;
  const Pose3& truth = s.truth[1].T_base_body;
  state.counters["points"] = static_cast<double>(s.cloud.size());
  state.counters["model_points"] = static_cast<double>(model.points.size());
  state.counters["fitness"] = result.fitness_;
  state.counters["error_mm"] = 1e3 * TranslationDistance(est, truth);
  state.counters["error_deg"] = RotationAngle(est, truth) * 180.0 / M_PI;
  state.SetLabel("Open3D point-to-plane ICP, model every " + std::to_string(state.range(0)) + " mm");
}
BENCHMARK(BM_Open3dPointToPlaneIcp)->Arg(10)->Arg(5)->Arg(2)->Unit(benchmark::kMillisecond)->Iterations(3);

}  // namespace
}  // namespace ifab
