// Peer comparison (built only where OMPL is installed): the repositioning maneuvers of
// planner_bench planned by OMPL in a Reeds-Shepp state space (forwards and in reverse, minimum
// turning radius 0.5 m: Reeds-Shepp cannot turn on the spot as tracks can), with the same footprint
// clearance as validity check. Reports plan time and path length beside STOMP's.

#include <benchmark/benchmark.h>
#include <ompl/base/ScopedState.h>
#include <ompl/base/spaces/ReedsSheppStateSpace.h>
#include <ompl/geometric/SimpleSetup.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>

#include "ifab/base/planner/site_scene.h"
#include "ifab/base/planner/stomp_planner.h"
#include "ifab/core/angles.h"
#include "ifab/model/site.h"

namespace ifab::base {
namespace {

namespace ob = ompl::base;
namespace og = ompl::geometric;

PlanningScene Scene() { return PlanningSceneFromSite(LoadSite(IFAB_DATA_DIR "/sites/brick_stack.yaml")); }
BaseGeometry Robot() { return BaseGeometry::Load(IFAB_DATA_DIR "/robots/insitu_fabricator_base.yaml"); }

const Pose2 kStart(-1.6, 0.0, 0.0);
const Pose2 kGoal(1.6, 0.5, WrapAngle(std::atan2(-0.5, -1.6)));

void BM_OmplReedsShepp(benchmark::State& state) {
  ompl::msg::setLogLevel(ompl::msg::LOG_WARN);
  const PlanningScene scene = Scene();
  const FootprintChecker checker(scene, Robot());
  auto space = std::make_shared<ob::ReedsSheppStateSpace>(0.5);
  ob::RealVectorBounds bounds(2);
  bounds.setLow(0, -4.5);
  bounds.setHigh(0, 4.5);
  bounds.setLow(1, -3.5);
  bounds.setHigh(1, 3.5);
  space->setBounds(bounds);
  og::SimpleSetup ss(space);
  ss.setStateValidityChecker([&](const ob::State* s) {
    const auto* se2 = s->as<ob::SE2StateSpace::StateType>();
    return checker.Clearance(Pose2(se2->getX(), se2->getY(), se2->getYaw())) >= 0.0;
  });
  ss.getSpaceInformation()->setStateValidityCheckingResolution(0.005);
  ob::ScopedState<> start(space), goal(space);
  start[0] = kStart.x;
  start[1] = kStart.y;
  start[2] = kStart.theta;
  goal[0] = kGoal.x;
  goal[1] = kGoal.y;
  goal[2] = kGoal.theta;
  ss.setStartAndGoalStates(start, goal);
  ss.setPlanner(std::make_shared<og::RRTConnect>(ss.getSpaceInformation()));
  ss.setup();
  int ok = 0;
  double length = 0.0;
  for (auto _ : state) {
    ss.clear();
    const ob::PlannerStatus solved = ss.solve(1.0);
    if (solved == ob::PlannerStatus::EXACT_SOLUTION) {
      ss.simplifySolution();
      ++ok;
      length += ss.getSolutionPath().length();
    }
  }
  state.counters["success"] = benchmark::Counter(ok, benchmark::Counter::kAvgIterations);
  state.counters["length_m"] = ok > 0 ? length / ok : 0.0;
}
BENCHMARK(BM_OmplReedsShepp)->Unit(benchmark::kMillisecond);

void BM_StompSameCase(benchmark::State& state) {
  StompPlannerOptions o;
  o.num_threads = 1;
  const StompBasePlanner planner(Scene(), Robot(), o);
  std::uint64_t seed = 0;
  int ok = 0;
  double length = 0.0;
  for (auto _ : state) {
    const PlanResult r = planner.Plan(kStart, kGoal, RandomStream(seed++));
    if (r.IsUsable()) {
      ++ok;
      length += r.trajectory.Length();
    }
  }
  state.counters["success"] = benchmark::Counter(ok, benchmark::Counter::kAvgIterations);
  state.counters["length_m"] = ok > 0 ? length / ok : 0.0;
}
BENCHMARK(BM_StompSameCase)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace ifab::base
