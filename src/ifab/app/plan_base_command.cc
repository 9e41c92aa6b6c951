// `ifab plan-base --start "x y theta" --goal "x y theta"`: plan one base repositioning maneuver
// in a site with the two-phase STOMP planner (paper Sec. III-A), print the summary, and write the
// trajectory (poses with nominal v and omega) as CSV with --trajectory.

#include <nlohmann/json.hpp>

#include <cmath>
#include <iostream>

#include "ifab/app/commands.h"
#include "ifab/base/planner/site_scene.h"
#include "ifab/base/planner/stomp_planner.h"
#include "ifab/core/angles.h"
#include "ifab/core/data_path.h"
#include "ifab/core/error.h"
#include "ifab/core/parse.h"
#include "ifab/experiments/atomic_file.h"
#include "ifab/model/site.h"

namespace ifab::app {
namespace {

// "x y theta" (spaces and/or commas); x, y in m, theta in degrees unless radians.
Pose2 ParsePose(const std::string& text, const char* option, bool radians) {
  const std::vector<double> v = ParseNumbers(text, option, 3);
  return Pose2(v[0], v[1], WrapAngle(radians ? v[2] : DegToRad(v[2])));
}

}  // namespace

void AddPlanBaseCommand(CLI::App& app, int& exit_code) {
  struct Args {
    std::string start, goal;
    bool radians{false};
    std::string site{DataPath("sites/brick_stack.yaml")};
    std::string robot{DataPath("robots/insitu_fabricator_base.yaml")};
    std::string config{DataPath("base/planner.yaml")};
    std::uint64_t seed{1};
    std::string trajectory;
    bool json{false};
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand(
      "plan-base",
      "Plan a base repositioning maneuver in a site with two-phase STOMP (paper Sec. III-A) and print the summary.\n"
      "Poses are \"x y theta\" in the site frame: metres and DEGREES (use --radians for radians).\n"
      "Exit code 0 if the plan is usable (collision-free, no sideways motion), 1 if not.");
  sub->add_option("--start", args->start, "Start pose of the base, e.g. \"-1.6 0 0\"")->required();
  sub->add_option("--goal", args->goal, "Goal pose of the base, e.g. \"1.6 0.5 -163\"")->required();
  sub->add_flag("--radians", args->radians, "Read the headings in radians instead of degrees");
  sub->add_option("--site", args->site, "Site YAML (boundary, obstacles, stack)")->capture_default_str();
  sub->add_option("--robot", args->robot, "Base footprint and tracks (its base: section)")->capture_default_str();
  sub->add_option("--config", args->config, "Planner options (the file's base_planner: section)")
      ->capture_default_str();
  sub->add_option("--seed", args->seed, "Seed of the rollouts")->capture_default_str();
  sub->add_option("--trajectory", args->trajectory,
                  "Write the trajectory as CSV (index, x, y, theta, v, omega; m, rad, m/s, rad/s)");
  sub->add_flag("--json", args->json, "Print the summary as JSON");
  sub->callback([args, &exit_code] {
    const Pose2 start = ParsePose(args->start, "--start", args->radians);
    const Pose2 goal = ParsePose(args->goal, "--goal", args->radians);
    const Site site = LoadSite(args->site);
    site.RequireBoundary(args->site, "ifab plan-base");
    const base::BaseGeometry robot = base::BaseGeometry::Load(args->robot);
    const base::StompPlannerOptions options =
        base::StompPlannerOptions::FromConfig(ConfigNode::LoadSection(args->config, "base_planner"));
    const base::StompBasePlanner planner(base::PlanningSceneFromSite(site), robot, options);
    const base::PlanResult r = planner.Plan(start, goal, RandomStream(args->seed));
    if (args->json) {
      const nlohmann::json j = {{"status", base::PlanStatusName(r.status)},
                                {"message", r.message},
                                {"iterations", r.iterations},
                                {"phase1_iterations", r.phase1_iterations},
                                {"phase2_iterations", r.phase2_iterations},
                                {"cost", r.cost},
                                {"seconds", r.seconds},
                                {"min_clearance_m", r.min_clearance},
                                {"max_lateral_velocity_mps", r.max_lateral_velocity},
                                {"max_track_speed_mps", r.max_track_speed},
                                {"poses", r.trajectory.size()},
                                {"length_m", r.trajectory.Length()},
                                {"duration_s", r.trajectory.duration},
                                {"usable", r.IsUsable()}};
      std::cout << j.dump(2) << "\n";
    } else {
      std::cout << r.BriefReport() << "\n";
    }
    if (!args->trajectory.empty()) {
      if (!r.IsUsable()) {
        std::cerr << "ifab: plan-base: the plan is not usable; writing the best attempt for inspection\n";
      }
      experiments::AtomicOfstream out(args->trajectory);
      r.trajectory.WriteCsv(out);
      out.Commit();
    }
    exit_code = r.IsUsable() ? 0 : 1;
  });
}

}  // namespace ifab::app
