// `ifab calibrate SWEEP.json... --out DIR`: extrinsic calibration of the arm laser (paper Sec. V-C)
// from recorded sweeps of a cube on the floor. The sweep file format is in experiments/sweep_io.h;
// the work is app/perception_commands.h.

#include <iostream>

#include "ifab/app/commands.h"
#include "ifab/app/perception_commands.h"

namespace ifab::app {

void AddCalibrateCommand(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<CalibrateCommandOptions>();
  CLI::App* sub = app.add_subcommand(
      "calibrate",
      "Calibrate the arm laser's mount T_tool0_laser (paper Sec. V-C) from sweeps of a cube on the floor.\n"
      "Each SWEEP is a JSON file of arm laser scans and joint states (format: src/ifab/experiments/sweep_io.h).\n"
      "The noise model as for `ifab register` (--sensor; default: estimated from the residuals).\n"
      "Writes DIR/calibration.json and DIR/arm_laser_mount.yaml. Exit code 0 if usable (converged, the fit agrees\n"
      "with the noise model, every direction of the mount fixed by the sweeps), 1 if not, 2 for bad input.");
  sub->add_option("sweeps", o->sweep_paths, "Sweep files (6 to 8 sweeps of different joints)")->required();
  sub->add_option("--out", o->out_dir, "Output folder")->required();
  sub->add_option("--target", o->target_path, "Target YAML: cube size and pose guess (default data/perception/cube_target.yaml)");
  sub->add_option("--robot", o->robot_path, "Robot URDF (default data/robots/insitu_fabricator.urdf)");
  sub->add_option("--mount", o->mount_guess, "Mount guess \"x y z roll pitch yaw\" (m, deg); default the URDF's");
  sub->add_option("--config", o->config_path,
                  "Options YAML overlaid on data/perception/perception.yaml (calibration:, scan_assembly: sections)");
  sub->add_option("--sensor", o->sensor,
                  "Noise profile: a name in data/sensors/ or a YAML file; 'config' keeps the config's noise; default: "
                  "estimated from the residuals");
  sub->callback([o, &exit_code] { exit_code = ReportCalibration(CalibrateCommand(*o), o->out_dir, std::cout); });
}

}  // namespace ifab::app
