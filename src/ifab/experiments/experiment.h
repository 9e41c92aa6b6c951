#pragma once
/// \file
/// Experiments wire the stack to the simulator, score against ground truth and write results.
/// This is the only module that sees both sides. Each experiment is a YAML file in
/// data/experiments/NAME.yaml and a function registered in registry.cc.

#include <nlohmann/json.hpp>

#include <cstdint>
#include <exception>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "ifab/core/config.h"

namespace ifab::experiments {

/// What one run of an experiment gets.
struct RunContext {
  const ConfigNode* config{nullptr};  ///< the experiment's YAML (validated by the experiment)
  std::uint64_t seed{0};              ///< this run's seed
  std::string out_dir;                ///< where this run writes its files (exists)
  bool progress{true};                ///< print progress to the terminal
  /// Report progress (phase text; `fraction` of the run done in [0, 1], negative when unknown);
  /// no-op when progress is off. A terminal shows one live line (progress.h). Throws
  /// RunInterrupted once Ctrl-C was pressed (so every experiment stops at its next report).
  void Progress(const std::string& text, double fraction = -1.0) const;
};

/// Thrown by RunContext::Progress after SIGINT; RunExperiment catches it.
struct RunInterrupted : std::exception {
  const char* what() const noexcept override { return "interrupted (SIGINT)"; }
};
/// True once SIGINT arrived during RunExperiment.
bool Interrupted();

/// One run returns its results as JSON (numbers in SI units unless the key says _mm / _deg).
using ExperimentFn = std::function<nlohmann::json(const RunContext&)>;

struct ExperimentInfo {
  std::string name;         ///< e.g. "brick-stack"
  std::string description;  ///< one line for --help
  ExperimentFn run;
  /// Optional: rows (label, ours, paper) for the terminal table; may be empty.
  std::function<std::vector<std::vector<std::string>>(const nlohmann::json&)> table;
  /// Optional: with --runs > 1, what the experiment adds over all its runs (results.json's "campaign").
  std::function<nlohmann::json(const std::vector<nlohmann::json>&)> summarize{};
};

/// Every experiment ifab knows.
const std::vector<ExperimentInfo>& Registry();

/// Options of `ifab run`.
struct RunOptions {
  std::string experiment{"brick-stack"};
  std::string config_path;             ///< default: data/experiments/<experiment>.yaml
  std::optional<std::uint64_t> seed;   ///< default: the config's `seed`, else 1
  int runs{1};                         ///< seeds seed, seed+1, ...
  int jobs{1};                         ///< runs in parallel
  std::string out_dir;                 ///< default: runs/<experiment>
  bool force{false};                   ///< overwrite a folder that already holds a run
  bool progress{true};
  std::vector<std::string> settings;   ///< --set KEY=VALUE over the config (dotted keys)
};

/// Run an experiment: N seeded runs (in parallel with jobs > 1), results.json in out_dir
/// (with mean/std/worst over runs when runs > 1), the config copied beside it.
/// Returns the results written. Throws InputError on bad options or config.
nlohmann::json RunExperiment(const RunOptions& options);

/// Print results as a table (ours beside the paper's where the experiment gives one).
void PrintResultsTable(const ExperimentInfo& info, const nlohmann::json& results);

}  // namespace ifab::experiments
