// `ifab robot [--urdf FILE]`: load and check a robot description; print its joints, limits,
// mounts and the flange at the zero pose (as JSON with --json).

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <iostream>

#include "ifab/app/commands.h"
#include "ifab/core/angles.h"
#include "ifab/core/data_path.h"
#include "ifab/model/robot_model.h"

namespace ifab::app {

void AddRobotCommand(CLI::App& app, int& exit_code) {
  auto urdf = std::make_shared<std::string>(DataPath("robots/insitu_fabricator.urdf"));
  auto json = std::make_shared<bool>(false);
  CLI::App* sub = app.add_subcommand("robot", "Check a robot URDF and print its arm chain, limits and mounts.");
  sub->add_option("--urdf", *urdf, "Robot description")->capture_default_str();
  sub->add_flag("--json", *json, "Print JSON instead of text");
  sub->callback([urdf, json, &exit_code] {
    const RobotModel robot = LoadRobotModel(*urdf);
    auto xyzrpy = [](const Pose3& p) { return XyzRpyFromPose(p); };
    nlohmann::json j;
    j["urdf"] = *urdf;
    for (int i = 0; i < 6; ++i) {
      j["joints"].push_back({{"name", robot.joint_names[static_cast<std::size_t>(i)]},
                             {"min_deg", RadToDeg(robot.q_min[i])},
                             {"max_deg", RadToDeg(robot.q_max[i])},
                             {"max_speed_deg_s", RadToDeg(robot.qd_max[i])}});
    }
    j["flange_at_zero_in_arm_base_m"] = xyzrpy(robot.ArmForwardKinematics(Vector6d::Zero()));
    j["T_base_arm_base"] = xyzrpy(robot.T_base_arm_base);
    j["T_base_base_laser"] = xyzrpy(robot.T_base_base_laser);
    j["T_tool0_arm_laser"] = xyzrpy(robot.T_tool0_arm_laser);
    j["T_tool0_gripper"] = xyzrpy(robot.T_tool0_gripper);
    if (*json) {
      std::cout << j.dump(2) << "\n";
    } else {
      std::cout << fmt::format("{}: arm chain arm_base -> tool0\n", *urdf);
      for (int i = 0; i < 6; ++i) {
        const std::string& name = robot.joint_names[static_cast<std::size_t>(i)];
        const double lo = RadToDeg(robot.q_min[i]), hi = RadToDeg(robot.q_max[i]), v = RadToDeg(robot.qd_max[i]);
        std::cout << fmt::format("  {:<8} [{:7.1f}, {:6.1f}] deg, {:5.0f} deg/s\n", name, lo, hi, v);
      }
      const Eigen::Vector3d f = robot.ArmForwardKinematics(Vector6d::Zero()).translation();
      const double fx = f.x(), fy = f.y(), fz = f.z();
      std::cout << fmt::format("  flange at the zero pose: ({:.3f}, {:.3f}, {:.3f}) m in arm_base\n", fx, fy, fz);
    }
    exit_code = 0;
  });
}

}  // namespace ifab::app
