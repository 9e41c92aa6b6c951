// `ifab run arm-planning`: iLQG arm planning on seeded point-to-point motions typical of picking
// and placing bricks and of scan sweeps (paper Sec. IV: "typically converges in less than 5
// iterations ... in less than 2 seconds"). Pure planning: no simulator involved.

#include <fmt/format.h>

#include <filesystem>
#include <fstream>

#include "ifab/experiments/arm_planning_experiment.h"
#include "ifab/experiments/atomic_file.h"
#include "ifab/core/error.h"
#include "ifab/experiments/experiments.h"
#include "ifab/model/robot_model.h"

namespace ifab::experiments {
namespace {

namespace fs = std::filesystem;

nlohmann::json RunArmPlanning(const RunContext& ctx) {
  const ConfigNode& c = *ctx.config;
  const fs::path dir = fs::path(c.file()).parent_path();
  const RobotModel robot = LoadRobotModel((dir / c.Get<std::string>("robot")).string());
  ArmPlanningExperimentConfig base;
  base.ilqg = arm::LoadIlqgOptions((dir / c.Get<std::string>("arm")).string());
  if (auto robot_yaml = c.Find("robot_yaml")) {
    // The on-board feeder's brick pose (base frame), as the algorithms know it.
    const ConfigNode r = ConfigNode::LoadFile((dir / robot_yaml->As<std::string>()).string());
    r.ExpectKeys({"feeder_in_base", "sim"});
    const auto v = r["feeder_in_base"].AsNumbers(6);
    base.T_base_feeder_brick = PoseFromXyzRpy(v[0], v[1], v[2], v[3], v[4], v[5]);
  }
  const ArmPlanningExperimentConfig config = ArmPlanningExperimentConfig::FromConfig(c, base);
  ctx.Progress(fmt::format("arm-planning: {} seeded motions, iLQG on one thread", config.cases));
  const ArmPlanningResult r = RunArmPlanningExperiment(robot, config, ctx.seed);
  AtomicOfstream csv(fs::path(ctx.out_dir) / "arm_planning_cases.csv");
  IFAB_THROW_UNLESS(csv.good(), "{}: cannot write arm_planning_cases.csv", ctx.out_dir);
  csv << r.CasesCsv();
  return r.results;
}

std::vector<std::vector<std::string>> ArmPlanningTable(const nlohmann::json& r) {
  return {{"motions planned", fmt::format("{}", r["cases"].get<int>()), ""},
          {"converged rate", fmt::format("{:.3f}", r["converged_rate"].get<double>()), ""},
          {"iterations (median)", fmt::format("{:.1f}", r["iterations_median"].get<double>()), "< 5"},
          {"plan time median [ms]", fmt::format("{:.1f}", r["plan_ms_median"].get<double>()), "< 2000"},
          {"plan time max [ms]", fmt::format("{:.1f}", r["plan_ms_max"].get<double>()), ""},
          {"final joint error max [deg]", fmt::format("{:.5f}", r["final_joint_error_deg_max"].get<double>()), ""}};
}

}  // namespace

ExperimentInfo ArmPlanningExperiment() {
  return {"arm-planning", "paper Sec. IV: iLQG arm plans for brick picking, placing and scan sweeps", RunArmPlanning, ArmPlanningTable};
}

}  // namespace ifab::experiments
