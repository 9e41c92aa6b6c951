// Base planner and controller benchmarks (issue 3). Scene: data/sites/brick_stack.yaml.

#include <benchmark/benchmark.h>

#include "ifab/base/controller/trajectory_controller.h"
#include "ifab/base/planner/site_scene.h"
#include "ifab/base/planner/stomp_planner.h"
#include "ifab/core/angles.h"
#include "ifab/model/site.h"

namespace ifab::base {
namespace {

PlanningScene Scene() { return PlanningSceneFromSite(LoadSite(IFAB_DATA_DIR "/sites/brick_stack.yaml")); }
BaseGeometry Robot() { return BaseGeometry::Load(IFAB_DATA_DIR "/robots/insitu_fabricator_base.yaml"); }

// A typical repositioning: from the building position west of the stack, facing it, round the
// stack to the one east of it (heading reversed), as in the paper's hysteresis loop (Fig. 6).
const Pose2 kStart(-1.6, 0.0, 0.0);
const Pose2 kGoal(1.6, 0.5, WrapAngle(std::atan2(-0.5, -1.6)));

void BM_PlanRepositioning(benchmark::State& state) {
  StompPlannerOptions o;
  o.num_threads = static_cast<int>(state.range(0));
  const StompBasePlanner planner(Scene(), Robot(), o);
  std::uint64_t seed = 0;
  int ok = 0, iterations = 0;
  for (auto _ : state) {
    const PlanResult r = planner.Plan(kStart, kGoal, RandomStream(seed++));
    ok += r.IsUsable();
    iterations += r.iterations;
    benchmark::DoNotOptimize(r.cost);
  }
  state.counters["success"] = benchmark::Counter(ok, benchmark::Counter::kAvgIterations);
  state.counters["iterations"] = benchmark::Counter(iterations, benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_PlanRepositioning)->Arg(1)->Arg(0)->ArgName("threads")->Unit(benchmark::kMillisecond);

void BM_FootprintCost(benchmark::State& state) {
  const FootprintChecker checker(Scene(), Robot());
  RandomStream rng(1);
  std::vector<Pose2> poses;
  for (int i = 0; i < 1024; ++i) {  // last argument first: gcc's order (a call's is unspecified)
    const double theta = rng.Uniform(-kPi, kPi), y = rng.Uniform(-1.5, 1.5), x = rng.Uniform(-2, 2);
    poses.emplace_back(x, y, theta);
  }
  std::size_t i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(checker.Cost(poses[i++ % poses.size()], 0.15, 1.0));
}
BENCHMARK(BM_FootprintCost);

void BM_ControllerUpdate(benchmark::State& state) {
  StompPlannerOptions o;
  o.num_threads = 1;
  const PlanResult plan = StompBasePlanner(Scene(), Robot(), o).Plan(kStart, kGoal, RandomStream(1));
  BaseTrajectoryController controller(BaseControllerOptions{}.SetTracks(Robot()));
  controller.SetTrajectory(plan.trajectory);
  // Poses a little off the trajectory, walked along it as the robot would.
  std::vector<Pose2> poses;
  for (const auto& p : plan.trajectory.points) poses.push_back(Pose2(p.pose.x + 0.02, p.pose.y - 0.01, p.pose.theta + 0.01));
  std::size_t i = 0;
  for (auto _ : state) {
    if (i == poses.size() - 1) {
      controller.SetTrajectory(plan.trajectory);
      i = 0;
    }
    benchmark::DoNotOptimize(controller.Update(poses[i++], 0.0));
  }
}
BENCHMARK(BM_ControllerUpdate);

}  // namespace
}  // namespace ifab::base
