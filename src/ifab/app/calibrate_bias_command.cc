// `ifab calibrate-bias SWEEP.json... --out DIR`: the arm laser's range bias identified with its
// mount (perception/range_bias.h, sequencer/laser_sweeps.h IdentifyMountAndRangeBias) from
// recorded sweeps of a cube on the floor and, optionally, of the bare floor from several heights.

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "ifab/app/commands.h"
#include "ifab/core/config.h"
#include "ifab/core/data_path.h"
#include "ifab/core/error.h"
#include "ifab/app/perception_commands.h"
#include "ifab/experiments/perception_json.h"
#include "ifab/perception/scan_assembly.h"
#include "ifab/experiments/sweep_io.h"
#include "ifab/sequencer/laser_sweeps.h"

namespace ifab::app {
namespace {

using nlohmann::json;

struct Options {
  std::vector<std::string> cube_sweeps, floor_sweeps;
  std::string out_dir, target_path, robot_path, plan_path, mount_guess;
};

std::vector<CalibrationSweep> Load(const std::vector<std::string>& paths, const RobotModel& robot, int beam_stride,
                                   json* info) {
  ScanAssemblyOptions assembly;
  assembly.beam_stride = beam_stride;
  std::vector<CalibrationSweep> out;
  for (const auto& path : paths) {
    const SweepRecording rec = LoadSweep(path);
    const AssembledSweep a = AssembleSweep(rec.scans, rec.joint_states, robot, assembly);
    if (a.points.empty()) ThrowInputError("{}: no laser beam falls within the joint states' times", path);
    out.push_back({rec.name, a.points});
    info->push_back({{"file", path}, {"name", rec.name}, {"points", a.points.size()}, {"untimed_beams", a.untimed_beams}});
  }
  return out;
}

json Run(const Options& o) {
  if (o.cube_sweeps.empty()) ThrowInputError("calibrate-bias: give at least one sweep file of the cube");
  if (o.out_dir.empty()) ThrowInputError("--out: an output folder is required");
  const RobotModel robot = LoadRobotModel(o.robot_path.empty() ? DataPath("robots/insitu_fabricator.urdf") : o.robot_path);
  // The plan file gives the bias options (`range_bias:`) and the mount solver's (`calibration:`).
  const std::string plan_path = o.plan_path.empty() ? DataPath("perception/arm_laser_calibration.yaml") : o.plan_path;
  const sequencer::LaserCalibrationPlan plan = sequencer::LaserCalibrationPlan::FromConfig(ConfigNode::LoadFile(plan_path));
  if (!plan.range_bias) ThrowInputError("{}: range_bias: expected a section that says how to identify the bias", plan_path);
  const CubeTarget target = LoadCubeTarget(o.target_path);
  const double size = target.size;
  const Pose3 T_base_cube = target.T_base_cube;
  const double ground_z = target.ground_z;
  const Pose3 mount_guess = o.mount_guess.empty() ? robot.T_tool0_arm_laser : ParsePoseArgument(o.mount_guess, "--mount");

  json sweeps_info = json::array(), floor_info = json::array();
  const auto cube_sweeps = Load(o.cube_sweeps, robot, plan.beam_stride, &sweeps_info);
  const auto floor_sweeps = Load(o.floor_sweeps, robot, plan.beam_stride, &floor_info);
  std::error_code ec;
  std::filesystem::create_directories(o.out_dir, ec);
  if (ec) ThrowInputError("--out: cannot create '{}': {}", o.out_dir, ec.message());

  const sequencer::ArmLaserCalibration cal = sequencer::IdentifyMountAndRangeBias(
      cube_sweeps, floor_sweeps, CubeOnGroundBodies(size, T_base_cube, ground_z), mount_guess, plan.calibration,
      *plan.range_bias, [](const std::string& t) { std::cerr << t << "\n"; });
  const bool usable = cal.mount.IsUsable() && cal.bias && cal.bias->usable;
  json j = {{"usable", usable},
            {"mount_status", ToString(cal.mount.status)},
            {"mount_message", cal.mount.message},
            {"T_tool0_laser", PoseToJson(cal.mount.T_tool0_laser)},
            {"T_tool0_laser_uncompensated", PoseToJson(cal.mount_uncompensated.T_tool0_laser)},
            {"mount_guess", PoseToJson(mount_guess)},
            {"sweeps", sweeps_info},
            {"floor_sweeps", floor_info},
            {"warnings", cal.mount.warnings}};
  if (cal.ground_extent) j["ground_extent"] = GroundExtentToJson(*cal.ground_extent);
  if (cal.bias) {
    const RangeBiasSummary& b = *cal.bias;
    const double max_std = cal.compensation.max_std_fraction * cal.compensation.sigma_along;
    json curve = json::array();
    for (double r : b.model.range_knots)
      for (double a : b.model.incidence_knots)
        curve.push_back({{"range_m", r}, {"incidence_deg", a * 180 / M_PI}, {"bias_mm", 1e3 * b.model.Bias(r, a)},
                         {"std_mm", 1e3 * b.model.Std(r, a)}, {"used", b.model.Std(r, a) <= max_std}});
    j["range_bias"] = {{"usable", b.usable},
                       {"message", b.message},
                       {"points", b.num_points},
                       {"points_used", b.num_used},
                       {"rms_whitened", b.rms_whitened},
                       {"variance_factor", b.variance_factor},
                       {"iterations", b.iterations},
                       {"seconds", b.seconds},
                       {"guard_std_mm", 1e3 * max_std},
                       {"knots", curve},
                       {"warnings", b.warnings}};
  }
  {
    std::ofstream out(std::filesystem::path(o.out_dir) / "range_bias.json");
    if (!out) ThrowInputError("{}: cannot open for writing", (std::filesystem::path(o.out_dir) / "range_bias.json").string());
    out << j.dump(2) << "\n";
  }
  if (cal.bias && cal.bias->usable) {
    // A `range_bias:` section for a perception config's `scan_assembly:` (scan_assembly.h).
    std::ofstream yaml(std::filesystem::path(o.out_dir) / "range_bias.yaml");
    yaml << "# The arm laser's range bias from `ifab calibrate-bias` (perception/range_bias.h), for the\n"
         << "# `scan_assembly:` section of a perception config.\n"
         << "range_bias:\n"
         << fmt::format("  compensate: true\n  normal_radius: {}\n  min_neighbours: {}\n  max_std_fraction: {}\n"
                        "  sigma_along: {}\n  model:\n",
                        cal.compensation.normal_radius, cal.compensation.min_neighbours,
                        cal.compensation.max_std_fraction, cal.compensation.sigma_along)
         << cal.bias->model.ToYaml(4);
  }
  return j;
}

}  // namespace

void AddCalibrateBiasCommand(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<Options>();
  CLI::App* sub = app.add_subcommand(
      "calibrate-bias",
      "Identify the arm laser's range bias in range and incidence, with its uncertainty, together with the laser's\n"
      "mount (the paper's Sec. VII leaves this as future work), from recorded sweeps of a cube on the floor and of\n"
      "the bare floor from several heights (Fig. 7). Each SWEEP is a JSON file of arm laser scans and joint states\n"
      "(format: src/ifab/experiments/sweep_io.h). Writes DIR/range_bias.json (the model at its knots with std, the\n"
      "mount) and DIR/range_bias.yaml (a scan_assembly `range_bias:` section). Exit code 0 if usable, 1 if not,\n"
      "2 for bad input.");
  sub->add_option("sweeps", o->cube_sweeps, "Sweep files of the cube on the floor")->required();
  sub->add_option("--floor", o->floor_sweeps, "Sweep files of the bare floor seen from above (any number)");
  sub->add_option("--out", o->out_dir, "Output folder")->required();
  sub->add_option("--plan", o->plan_path,
                  "Calibration plan YAML with `range_bias:` and `calibration:` (default "
                  "data/perception/arm_laser_calibration.yaml)");
  sub->add_option("--target", o->target_path, "Target YAML: cube size and pose guess (default data/perception/cube_target.yaml)");
  sub->add_option("--robot", o->robot_path, "Robot URDF (default data/robots/insitu_fabricator.urdf)");
  sub->add_option("--mount", o->mount_guess, "Mount guess \"x y z roll pitch yaw\" (m, deg); default the URDF's");
  sub->callback([o, &exit_code] {
    const json j = Run(*o);
    const auto& xyz = j["T_tool0_laser"]["xyz"];
    const auto& rpy = j["T_tool0_laser"]["rpy_deg"];
    std::cout << "mount " << j["mount_status"].get<std::string>() << ": xyz [" << xyz[0] << ", " << xyz[1] << ", "
              << xyz[2] << "] m, rpy [" << rpy[0] << ", " << rpy[1] << ", " << rpy[2] << "] deg\n";
    if (j.contains("range_bias"))
      std::cout << "range bias " << j["range_bias"]["message"].get<std::string>() << ": "
                << j["range_bias"]["points_used"] << " points, rms " << j["range_bias"]["rms_whitened"] << " sigma\n";
    std::cout << "wrote " << o->out_dir << "/range_bias.json" << (j["usable"].get<bool>() ? " and range_bias.yaml" : "")
              << "\n";
    exit_code = j["usable"].get<bool>() ? 0 : 1;
  });
}

}  // namespace ifab::app
