// `ifab register CLOUD.ply --site SITE.yaml ...`: register a laser cloud to the site model (paper
// Sec. V-B, eq. 7), in the robot base frame (the robot's pose in the site) or in the cloud's own
// frame (each object's pose and plane). The work is app/perception_commands.h.

#include <iostream>

#include "ifab/app/commands.h"
#include "ifab/app/perception_commands.h"
#include "ifab/core/data_path.h"

namespace ifab::app {

void AddRegisterCommand(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<RegisterCommandOptions>();
  o->site_path = DataPath("sites/brick_stack.yaml");
  CLI::App* sub = app.add_subcommand(
      "register",
      "Register a laser cloud to a site model (paper Sec. V-B).\n"
      "--frame site (default): CLOUD.ply is in the robot base frame, --guess is the robot's pose in the site;\n"
      "  writes T_site_base. --frame sensor: the site YAML gives each object's pose guess in the cloud's own\n"
      "  frame (planes:, polygons:, boxes:, objects:); each object is solved apart and each plane's normal and\n"
      "  offset written. Points carry laser origins (origin_x/y/z) or one --origin (sensor frame: 0 0 0).\n"
      "The noise model: --sensor NAME (data/sensors/NAME.yaml: utm30lx, urg04lx, sick_lms1xx, sick_lms2xx) or\n"
      "  FILE; without it the noise scale is estimated from the residuals. Points beyond 3 sigmas are outliers.\n"
      "Writes DIR/registration.json and DIR/labelled.ply. Exit code 0 if usable (converged, the fit agrees with\n"
      "the noise model, every pose reported fixed by the data), 1 if not, 2 for bad input.");
  sub->add_option("cloud", o->cloud_path, "PLY cloud")->required();
  sub->add_option("--site", o->site_path, "Site YAML")->capture_default_str();
  sub->add_option("--frame", o->frame, "site (cloud in the robot base frame) or sensor (objects in the cloud's frame)")
      ->capture_default_str();
  sub->add_option("--guess", o->guess, "--frame site: robot pose guess in the site, \"x y z roll pitch yaw\" (m, deg)");
  sub->add_option("--out", o->out_dir, "Output folder")->required();
  sub->add_option("--config", o->config_path,
                  "Options YAML overlaid on data/perception/perception.yaml (registration: section; only the keys it "
                  "names change)");
  sub->add_option("--sensor", o->sensor,
                  "Noise profile: a name in data/sensors/ or a YAML file with a noise: section; 'config' keeps the "
                  "config's noise; default: estimated from the residuals");
  sub->add_option("--origin", o->origin, "\"x y z\": laser origin for clouds without per-point origins (m)");
  sub->add_option("--crop", o->crop, "Keep only points in \"box x0 y0 z0 x1 y1 z1\" or \"radius R [x y z]\" (cloud frame, m)");
  sub->add_option("--fix", o->fix,
                  "BODY:COMPONENTS held at the guess, e.g. board:z,tilt (x, y, z, rx, ry, rz about the cloud frame's "
                  "axes through the body origin; tilt = rx, ry); repeatable");
  sub->add_flag("--one-body", o->one_body, "--frame site: register ground and site as one rigid body (else apart, as the paper)");
  sub->callback([o, &exit_code] { exit_code = ReportRegistration(RegisterCommand(*o), o->out_dir, std::cout); });
}

}  // namespace ifab::app
