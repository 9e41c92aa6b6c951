// `ifab plan-arm --from "q1 .. q6" --to "q1 .. q6"`: plan one point-to-point arm motion with
// iLQG (paper Sec. IV) and print the summary; --trajectory writes the joint trajectory as CSV.

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <iostream>

#include "ifab/app/commands.h"
#include "ifab/arm/ilqg.h"
#include "ifab/core/angles.h"
#include "ifab/core/data_path.h"
#include "ifab/core/error.h"
#include "ifab/core/parse.h"
#include "ifab/experiments/atomic_file.h"
#include "ifab/model/robot_model.h"

namespace ifab::app {
namespace {

// Six numbers separated by spaces and/or commas.
Vector6d ParseJoints(const std::string& text, const char* option, bool radians) {
  const std::vector<double> v = ParseNumbers(text, option, 6);
  Vector6d q;
  for (int i = 0; i < 6; ++i) q[i] = radians ? v[static_cast<std::size_t>(i)] : DegToRad(v[static_cast<std::size_t>(i)]);
  return q;
}

}  // namespace

void AddPlanArmCommand(CLI::App& app, int& exit_code) {
  struct Args {
    std::string from, to;
    bool radians{false};
    std::string urdf{DataPath("robots/insitu_fabricator.urdf")};
    std::string config{DataPath("arm/arm.yaml")};
    std::string trajectory;
    bool json{false};
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand(
      "plan-arm",
      "Plan an arm motion between two joint configurations with iLQG (paper Sec. IV) and print the summary.\n"
      "Joint angles are in DEGREES (use --radians for radians), six numbers for joints 1-6.\n"
      "Exit code 0 if the plan is usable (converged, within limits, at the goal), 1 if not.");
  sub->add_option("--from", args->from, "Start configuration, e.g. \"0 -30 30 0 90 0\" (deg)")->required();
  sub->add_option("--to", args->to, "Goal configuration, e.g. \"45 20 10 0 60 0\" (deg)")->required();
  sub->add_flag("--radians", args->radians, "Read --from and --to in radians instead of degrees");
  sub->add_option("--urdf", args->urdf, "Robot description")->capture_default_str();
  sub->add_option("--config", args->config, "Planner options (the file's ilqg: section)")->capture_default_str();
  sub->add_option("--trajectory", args->trajectory, "Write the planned trajectory as CSV (t, q, qd, tau; rad, N m)");
  sub->add_flag("--json", args->json, "Print the summary as JSON");
  sub->callback([args, &exit_code] {
    const Vector6d from = ParseJoints(args->from, "--from", args->radians);
    const Vector6d to = ParseJoints(args->to, "--to", args->radians);
    const RobotModel robot = LoadRobotModel(args->urdf);
    for (int i = 0; i < 6; ++i) {
      if (to[i] < robot.q_min[i] - arm::IlqgPlanner::kGoalLimitSlack ||
          to[i] > robot.q_max[i] + arm::IlqgPlanner::kGoalLimitSlack)
        ThrowInputError("--to: joint {} = {:.3f} deg lies outside its limits [{:.1f}, {:.1f}] deg", i + 1,
                        RadToDeg(to[i]), RadToDeg(robot.q_min[i]), RadToDeg(robot.q_max[i]));
    }
    arm::IlqgPlanner planner(arm::ArmModel::FromRobotModel(robot), arm::LoadIlqgOptions(args->config));
    const arm::ArmPlan plan = planner.Plan(from, to);
    const arm::PlanSummary& s = plan.summary;
    if (args->json) {
      const nlohmann::json j = {{"status", arm::ToString(s.status)},
                                {"message", s.message},
                                {"iterations", s.iterations},
                                {"cost", s.cost},
                                {"initial_cost", s.initial_cost},
                                {"seconds", s.seconds},
                                {"duration", s.duration},
                                {"steps", s.steps},
                                {"final_joint_error_deg", RadToDeg(s.final_position_error)},
                                {"final_speed_deg_s", RadToDeg(s.final_speed)},
                                {"within_limits", s.within_limits},
                                {"usable", s.IsUsable()}};
      std::cout << j.dump(2) << "\n";
    } else {
      std::cout << s.BriefReport() << "\n";
    }
    if (!args->trajectory.empty()) {
      experiments::AtomicOfstream out(args->trajectory);
      out << "t,q1,q2,q3,q4,q5,q6,qd1,qd2,qd3,qd4,qd5,qd6,tau1,tau2,tau3,tau4,tau5,tau6\n";
      for (std::size_t k = 0; k < plan.trajectory.points.size(); ++k) {
        const auto& p = plan.trajectory.points[k];
        const Vector6d tau = k < plan.torques.size() ? plan.torques[k] : Vector6d::Constant(NAN);
        out << fmt::format("{:.4f}", p.t);
        for (int i = 0; i < 6; ++i) out << fmt::format(",{:.9f}", p.q[i]);
        for (int i = 0; i < 6; ++i) out << fmt::format(",{:.9f}", p.qd[i]);
        for (int i = 0; i < 6; ++i) out << fmt::format(",{:.4f}", tau[i]);
        out << "\n";
      }
      out.Commit();
    }
    exit_code = s.IsUsable() ? 0 : 1;
  });
}

}  // namespace ifab::app
