// `ifab run base-planning`: the two-phase STOMP base planner (paper Sec. III-A) on seeded random
// start/goal pairs in the brick-stacking site: building positions around the stack and free poses
// anywhere in the site. Pure planning: no simulator involved. results.json: cases, success_rate
// (collision-free and without sideways motion), plan_ms_median, plan_ms_p95,
// max_lateral_velocity_mps, min_clearance_m; base_planning_cases.csv has every case.

#include <fmt/format.h>

#include <filesystem>
#include <fstream>

#include "ifab/experiments/base_planning_experiment.h"
#include "ifab/experiments/atomic_file.h"
#include "ifab/base/planner/site_scene.h"
#include "ifab/core/error.h"
#include "ifab/experiments/experiments.h"
#include "ifab/experiments/report_data.h"
#include "ifab/model/site.h"

namespace ifab::experiments {
namespace {

namespace fs = std::filesystem;

nlohmann::json RunBasePlanning(const RunContext& ctx) {
  const ConfigNode& c = *ctx.config;
  c.ExpectKeys({"seed", "site", "robot", "planner", "cases", "rollout_threads", "sampling"});
  const fs::path dir = fs::path(c.file()).parent_path();
  const Site site = LoadSite((dir / c.Get<std::string>("site")).string());
  const base::BaseGeometry robot = base::BaseGeometry::Load((dir / c.Get<std::string>("robot")).string());
  base::StompPlannerOptions options;
  if (auto p = c.Find("planner")) {
    options = base::StompPlannerOptions::FromConfig(
        ConfigNode::LoadSection((dir / p->As<std::string>()).string(), "base_planner"));
  }
  options.num_threads = 1;  // plan times are single-core wall times
  c.ReadPositive("rollout_threads", options.num_threads);
  BasePlanningExperimentOptions sampling;
  if (auto s = c.Find("sampling")) sampling = BasePlanningExperimentOptions::FromConfig(*s);
  c.ReadPositive("cases", sampling.cases);
  sampling.seed = ctx.seed;

  const base::StompBasePlanner planner(base::PlanningSceneFromSite(site), robot, options);
  ctx.Progress(fmt::format("base-planning: {} seeded start/goal pairs, STOMP rollouts on {} thread(s)",
                           sampling.cases, options.num_threads));
  std::vector<BasePlanningCase> cases;
  nlohmann::json results = RunBasePlanningExperiment(planner, sampling, &cases);

  AtomicOfstream csv(fs::path(ctx.out_dir) / "base_planning_cases.csv");
  IFAB_THROW_UNLESS(csv.good(), "{}: cannot write base_planning_cases.csv", ctx.out_dir);
  csv << "case,start_x,start_y,start_theta,goal_x,goal_y,goal_theta,status,plan_ms,iterations,phase1_iterations,"
         "phase2_iterations,min_clearance_m,max_lateral_velocity_mps,length_m,duration_s\n";
  for (std::size_t k = 0; k < cases.size(); ++k) {
    const auto& cs = cases[k];
    const auto& r = cs.result;
    csv << fmt::format("{},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{},{:.3f},{},{},{},{:.4f},{:.3e},{:.3f},{:.2f}\n", k,
                       cs.start.x, cs.start.y, cs.start.theta, cs.goal.x, cs.goal.y, cs.goal.theta,
                       base::PlanStatusName(r.status), r.seconds * 1e3, r.iterations, r.phase1_iterations,
                       r.phase2_iterations, r.min_clearance, r.max_lateral_velocity, r.trajectory.Length(),
                       r.trajectory.duration);
  }
  // For the report page: the site and the first few plans' poses, drawn in the site.
  WriteSiteSceneJson(ctx.out_dir, site);
  std::ofstream plans(fs::path(ctx.out_dir) / "base_planning_plans.csv");
  plans << "case,index,x,y,theta\n";
  for (std::size_t k = 0; k < cases.size() && k < 8; ++k)
    for (std::size_t i = 0; i < cases[k].result.trajectory.points.size(); ++i) {
      const Pose2& p = cases[k].result.trajectory.points[i].pose;
      plans << fmt::format("{},{},{:.4f},{:.4f},{:.5f}\n", k, i, p.x, p.y, p.theta);
    }
  return results;
}

std::vector<std::vector<std::string>> BasePlanningTable(const nlohmann::json& r) {
  return {{"start/goal pairs", fmt::format("{}", r["cases"].get<int>()), ""},
          {"success rate", fmt::format("{:.3f}", r["success_rate"].get<double>()), ""},
          {"plan time median [ms]", fmt::format("{:.1f}", r["plan_ms_median"].get<double>()), "not given"},
          {"plan time p95 [ms]", fmt::format("{:.1f}", r["plan_ms_p95"].get<double>()), ""},
          {"max lateral velocity [m/s]", fmt::format("{:.2e}", r["max_lateral_velocity_mps"].get<double>()), "0"},
          {"min clearance [m]", fmt::format("{:.4f}", r["min_clearance_m"].get<double>()), ">= 0"}};
}

}  // namespace

ExperimentInfo BasePlanningExperiment() {
  return {"base-planning", "paper Sec. III-A: two-phase STOMP base plans between seeded start/goal poses", RunBasePlanning, BasePlanningTable};
}

}  // namespace ifab::experiments
