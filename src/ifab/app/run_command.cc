// `ifab run [EXPERIMENT]`: run an experiment in simulation and write DIR/results.json.

#include <fmt/format.h>

#include "ifab/app/commands.h"
#include "ifab/experiments/experiment.h"

namespace ifab::app {

void AddRunCommand(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<experiments::RunOptions>();
  std::string list;
  for (const auto& e : experiments::Registry())
    list += fmt::format("\n  {:<26} {}", e.name, e.description);
  CLI::App* sub = app.add_subcommand(
      "run", "Run an experiment in simulation (default: brick-stack) and write DIR/results.json."
             "\nExperiments:" + list);
  sub->add_option("experiment", options->experiment, "Experiment name (data/experiments/NAME.yaml)")
      ->capture_default_str();
  sub->add_option("--config", options->config_path, "Experiment YAML (default: data/experiments/NAME.yaml)");
  sub->add_option("--seed", options->seed, "Seed of the first run (default: the config's seed)");
  sub->add_option("--runs", options->runs, "Number of seeded runs")->check(CLI::PositiveNumber);
  sub->add_option("--jobs", options->jobs, "Runs in parallel")->check(CLI::PositiveNumber);
  sub->add_option("--out", options->out_dir, "Output folder (default: runs/NAME)");
  sub->add_option("--set", options->settings,
                  "KEY=VALUE over the config, dotted keys (repeatable), e.g. --set mission.tilt_compensation=none");
  sub->add_flag("--force", options->force, "Overwrite the output folder if it already holds a run");
  sub->add_flag("!--quiet", options->progress, "No progress or table on the terminal");
  sub->callback([options, &exit_code] {
    const auto results = experiments::RunExperiment(*options);
    exit_code = results.value("failed_runs", 0) > 0 || results.value("failed", false) ? 1 : 0;
    if (results.value("interrupted", false)) exit_code = 130;  // the shell's code for SIGINT
  });
}

}  // namespace ifab::app
