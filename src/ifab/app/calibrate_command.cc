// `ifab calibrate SWEEP.json... --out DIR`: extrinsic calibration of the arm laser (paper Sec. V-C)
// from recorded sweeps of a cube on the floor. The sweep file format is in perception/sweep_io.h;
// the work is perception/commands.h.

#include <iostream>

#include "ifab/app/commands.h"
#include "ifab/perception/commands.h"

namespace ifab::app {

void AddCalibrateCommand(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<CalibrateCommandOptions>();
  CLI::App* sub = app.add_subcommand(
      "calibrate",
      "Calibrate the arm laser's mount T_tool0_laser (paper Sec. V-C) from sweeps of a cube on the floor.\n"
      "Each SWEEP is a JSON file of arm laser scans and joint states (format: src/ifab/perception/sweep_io.h).\n"
      "Writes DIR/calibration.json and DIR/arm_laser_mount.yaml. Exit code 0 if usable, 1 if not.");
  sub->add_option("sweeps", o->sweep_paths, "Sweep files (6 to 8 sweeps of different joints)")->required();
  sub->add_option("--out", o->out_dir, "Output folder")->required();
  sub->add_option("--target", o->target_path, "Target YAML: cube size and pose guess (default data/perception/cube_target.yaml)");
  sub->add_option("--robot", o->robot_path, "Robot URDF (default data/robots/insitu_fabricator.urdf)");
  sub->add_option("--mount", o->mount_guess, "Mount guess \"x y z roll pitch yaw\" (m, deg); default the URDF's");
  sub->add_option("--config", o->config_path, "Options YAML (calibration:, scan_assembly: sections)");
  sub->callback([o, &exit_code] {
    const nlohmann::json j = CalibrateCommand(*o);
    const auto& xyz = j["T_tool0_laser"]["xyz"];
    const auto& rpy = j["T_tool0_laser"]["rpy_deg"];
    std::cout << "calibration " << j["status"].get<std::string>() << " (" << j["message"].get<std::string>() << ")\n"
              << "T_tool0_laser: xyz [" << xyz[0] << ", " << xyz[1] << ", " << xyz[2] << "] m, rpy [" << rpy[0]
              << ", " << rpy[1] << ", " << rpy[2] << "] deg\n";
    for (const auto& w : j["warnings"]) std::cout << "warning: " << w.get<std::string>() << "\n";
    std::cout << "wrote " << o->out_dir << "/calibration.json and arm_laser_mount.yaml\n";
    exit_code = j["usable"].get<bool>() ? 0 : 1;
  });
}

}  // namespace ifab::app
