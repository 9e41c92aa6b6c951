#pragma once
/// \file
/// The results table of a run, for the terminal and the report page: the experiment's own
/// figures beside the paper's. Over several runs each figure is named as in the single-run
/// table, with its mean, std, min and max over the runs that did not fail.

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "ifab/experiments/experiment.h"

namespace ifab::experiments {

struct ResultsTable {
  std::vector<std::string> header;             ///< e.g. {"figure", "ifab", "paper"}
  std::vector<std::vector<std::string>> rows;  ///< one cell per header entry
};

/// The table of `results` (a single run's results.json, or the summary of --runs N with
/// `over_runs`). Falls back to every numeric key when the experiment gives no table.
ResultsTable MakeResultsTable(const ExperimentInfo& info, const nlohmann::json& results);

/// The table as aligned text (first column left, the others right).
std::string FormatResultsTable(const ResultsTable& table);

/// For --runs N: one line for a finished run (its first figures, or why it failed), and the
/// live line's count of finished runs. Safe to call from parallel runs.
void ReportRunDone(const ExperimentInfo& info, std::size_t k, int runs, std::uint64_t seed,
                   const nlohmann::json& result, const std::string& error);

/// The experiment named `name`, or nullptr.
const ExperimentInfo* FindExperiment(const std::string& name);

}  // namespace ifab::experiments
