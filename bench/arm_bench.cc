// Arm dynamics and iLQG planning speed (single thread).
#include <benchmark/benchmark.h>

#include "ifab/arm/dynamics.h"
#include "ifab/arm/ilqg.h"
#include "ifab/core/angles.h"
#include "ifab/core/data_path.h"

namespace ifab::arm {
namespace {

const RobotModel& Robot() {
  static const RobotModel robot = LoadRobotModel(DataPath("robots/insitu_fabricator.urdf"));
  return robot;
}
const ArmModel& Model() {
  static const ArmModel model = ArmModel::FromRobotModel(Robot());
  return model;
}
Vector6d Deg(double a, double b, double c, double d, double e, double f) {
  return (Vector6d() << a, b, c, d, e, f).finished() * (kPi / 180.0);
}
const Vector6d kQ = Deg(30, 20, 10, 40, 50, 60);
const Vector6d kQd = Deg(20, -30, 40, -50, 60, -70);
const Vector6d kQdd = Deg(100, 200, -300, 400, -500, 600);

void BM_InverseDynamics(benchmark::State& state) {
  ArmData data;
  for (auto _ : state) {
    benchmark::DoNotOptimize(InverseDynamics<double>(Model(), data, kQ, kQd, kQdd, Model().gravity));
  }
}
BENCHMARK(BM_InverseDynamics);

void BM_ForwardDynamics(benchmark::State& state) {
  ArmData data;
  const Vector6d tau = Vector6d::Constant(100.0);
  for (auto _ : state) {
    benchmark::DoNotOptimize(ForwardDynamics<double>(Model(), data, kQ, kQd, tau, Model().gravity));
    benchmark::DoNotOptimize(data.qdd);
  }
}
BENCHMARK(BM_ForwardDynamics);

// What iLQG evaluates at every knot and iteration: qdd and d qdd / d (q, qd, tau).
void BM_ForwardDynamicsDerivatives(benchmark::State& state) {
  DerivativeData work;
  DynamicsDerivatives d;
  const Vector6d tau = Vector6d::Constant(100.0);
  for (auto _ : state) {
    benchmark::DoNotOptimize(ForwardDynamicsDerivatives(Model(), work, kQ, kQd, tau, Model().gravity, d));
    benchmark::DoNotOptimize(d.dqdd_dq);
  }
}
BENCHMARK(BM_ForwardDynamicsDerivatives);

// A feeder-to-stack transfer (about 2 s of motion, ~50 knots).
void BM_IlqgPlanTransfer(benchmark::State& state) {
  IlqgPlanner planner(Model(), LoadIlqgOptions(DataPath("arm/arm.yaml")));
  const Vector6d from = Deg(52, 23, 25, 0, 43, -98);
  const Vector6d to = Deg(-26, 40, 10, 0, 40, 20);
  int iterations = 0;
  for (auto _ : state) {
    const ArmPlan plan = planner.Plan(from, to);
    iterations = plan.summary.iterations;
    benchmark::DoNotOptimize(plan.trajectory.points.data());
  }
  state.counters["ilqg_iterations"] = iterations;
}
BENCHMARK(BM_IlqgPlanTransfer)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace ifab::arm
