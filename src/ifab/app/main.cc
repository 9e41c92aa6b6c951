// ifab: the command line. `ifab --help` lists the commands; `ifab run` runs the brick
// stacking experiment in simulation.

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <iostream>

#include "ifab/app/commands.h"
#include "ifab/core/error.h"
#include "ifab/core/log.h"

int main(int argc, char** argv) {
  CLI::App app{
      "ifab: repositioning and localization of a mobile construction robot\n"
      "(after the In situ Fabricator, Sandy et al., ICRA 2016). The simulated robot is the default."};
  app.require_subcommand(1);
  std::string log_level = "warn";
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error or off")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "off"}));
  app.parse_complete_callback([&] { ifab::SetLogLevel(log_level); });

  int exit_code = 0;
  ifab::app::AddRunCommand(app, exit_code);
  ifab::app::AddReportCommand(app, exit_code);
  ifab::app::AddRobotCommand(app, exit_code);
  ifab::app::AddPlanArmCommand(app, exit_code);
  ifab::app::AddPlanBaseCommand(app, exit_code);
  ifab::app::AddRegisterCommand(app, exit_code);
  ifab::app::AddCalibrateCommand(app, exit_code);
  ifab::app::AddCalibrateBiasCommand(app, exit_code);
  ifab::app::AddEstimateCommand(app, exit_code);

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return 2;
  } catch (const ifab::InputError& e) {
    std::cerr << "ifab: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "ifab: failed: " << e.what() << "\n";
    return 1;
  }
  return exit_code;
}
