#pragma once
/// \file
/// The `ifab` subcommands, one file each. Each Add*Command registers a subcommand whose
/// callback sets `exit_code`. Bad input is thrown as ifab::InputError and reported by main().

#include <CLI/CLI.hpp>

namespace ifab::app {

void AddRunCommand(CLI::App& app, int& exit_code);
void AddReportCommand(CLI::App& app, int& exit_code);  // report page
void AddRobotCommand(CLI::App& app, int& exit_code);
void AddPlanArmCommand(CLI::App& app, int& exit_code);
void AddPlanBaseCommand(CLI::App& app, int& exit_code);
void AddRegisterCommand(CLI::App& app, int& exit_code);  // perception
void AddCalibrateCommand(CLI::App& app, int& exit_code);  // perception
void AddCalibrateBiasCommand(CLI::App& app, int& exit_code);  // perception + sequencer: range bias
void AddEstimateCommand(CLI::App& app, int& exit_code);  // base estimator

}  // namespace ifab::app
