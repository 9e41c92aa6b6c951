// `ifab register CLOUD.ply --site SITE.yaml --guess "x y z roll pitch yaw" --out DIR`: register a
// laser cloud (robot base frame) to the site model (paper Sec. V-B, eq. 7) and write the robot's
// pose in the site with its covariance as JSON. The work is perception/commands.h.

#include <iostream>

#include "ifab/app/commands.h"
#include "ifab/core/data_path.h"
#include "ifab/perception/commands.h"

namespace ifab::app {

void AddRegisterCommand(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<RegisterCommandOptions>();
  o->site_path = DataPath("sites/brick_stack.yaml");
  CLI::App* sub = app.add_subcommand(
      "register",
      "Register a laser cloud to the site model (paper Sec. V-B) and write the robot's pose in the site.\n"
      "CLOUD.ply is in the robot base frame with per-point laser origins (origin_x/y/z, as ifab writes them)\n"
      "or one --origin. Writes DIR/registration.json (T_site_base, covariance, bodies, shadow points,\n"
      "warnings) and DIR/labelled.ply. Exit code 0 if the registration is usable, 1 if not.");
  sub->add_option("cloud", o->cloud_path, "PLY cloud in the robot base frame")->required();
  sub->add_option("--site", o->site_path, "Site YAML")->capture_default_str();
  sub->add_option("--guess", o->guess, "Robot pose guess in the site: \"x y z roll pitch yaw\" (m, deg)")->required();
  sub->add_option("--out", o->out_dir, "Output folder")->required();
  sub->add_option("--config", o->config_path, "Options YAML (registration: section; default data/perception/perception.yaml)");
  sub->add_option("--origin", o->origin, "\"x y z\": laser origin for clouds without per-point origins (base frame, m)");
  sub->add_flag("--one-body", o->one_body, "Register ground and site as one rigid body (else apart, as the paper)");
  sub->callback([o, &exit_code] {
    const nlohmann::json j = RegisterCommand(*o);
    const auto& xyz = j["T_site_base"]["xyz"];
    const auto& rpy = j["T_site_base"]["rpy_deg"];
    std::cout << "registration " << j["status"].get<std::string>() << " (" << j["message"].get<std::string>() << ")\n"
              << "T_site_base: xyz [" << xyz[0] << ", " << xyz[1] << ", " << xyz[2] << "] m, rpy [" << rpy[0] << ", "
              << rpy[1] << ", " << rpy[2] << "] deg\n"
              << j["inliers"] << " of " << j["points"] << " points inliers, " << j["shadow_points_removed"]
              << " shadow points removed\n";
    for (const auto& w : j["warnings"]) std::cout << "warning: " << w.get<std::string>() << "\n";
    std::cout << "wrote " << o->out_dir << "/registration.json\n";
    exit_code = j["usable"].get<bool>() ? 0 : 1;
  });
}

}  // namespace ifab::app
