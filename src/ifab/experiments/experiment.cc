#include "ifab/experiments/experiment.h"

#include <fmt/format.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "ifab/core/data_path.h"
#include "ifab/core/error.h"
#include "ifab/experiments/progress.h"
#include "ifab/experiments/report.h"
#include "ifab/experiments/results_table.h"

namespace ifab::experiments {
namespace fs = std::filesystem;

namespace {
const ExperimentInfo& Find(const std::string& name) {
  for (const auto& e : Registry())
    if (e.name == name) return e;
  std::string names;
  for (const auto& e : Registry()) names += (names.empty() ? "" : ", ") + e.name;
  ThrowInputError("unknown experiment '{}' (expected one of: {})", name, names);
}

void WriteJson(const fs::path& path, const nlohmann::json& j) {
  std::ofstream out(path);
  IFAB_THROW_UNLESS(out.good(), "{}: cannot write the file", path.string());
  out << j.dump(2) << "\n";
}

// mean, std, min, max and worst (largest magnitude: errors) of every numeric top-level key over runs.
nlohmann::json Aggregate(const std::vector<nlohmann::json>& runs) {
  nlohmann::json agg = nlohmann::json::object();
  if (runs.empty()) return agg;
  for (const auto& [key, value] : runs.front().items()) {
    if (!value.is_number()) continue;
    std::vector<double> v;
    for (const auto& r : runs)
      if (r.contains(key) && r[key].is_number()) v.push_back(r[key].get<double>());
    double mean = 0, worst = v.front();
    for (double x : v) {
      mean += x;
      if (std::abs(x) > std::abs(worst)) worst = x;
    }
    mean /= static_cast<double>(v.size());
    double var = 0;
    for (double x : v) var += (x - mean) * (x - mean);
    const double std = v.size() > 1 ? std::sqrt(var / static_cast<double>(v.size() - 1)) : 0.0;
    agg[key] = {{"mean", mean},
                {"std", std},
                {"min", *std::min_element(v.begin(), v.end())},
                {"max", *std::max_element(v.begin(), v.end())},
                {"worst", worst}};
  }
  return agg;
}
}  // namespace

void RunContext::Progress(const std::string& text, double fraction) const {
  if (progress) ProgressLine::Global().Update(text, fraction);
}

nlohmann::json RunExperiment(const RunOptions& options) {
  const ExperimentInfo& info = Find(options.experiment);
  IFAB_THROW_UNLESS(options.runs >= 1, "--runs: expected a positive number, got {}", options.runs);
  IFAB_THROW_UNLESS(options.jobs >= 1, "--jobs: expected a positive number, got {}", options.jobs);

  const std::string config_path = options.config_path.empty()
                                      ? DataPath("experiments/" + options.experiment + ".yaml")
                                      : options.config_path;
  const ConfigNode config = ConfigNode::LoadFile(config_path);
  const std::uint64_t seed = options.seed ? *options.seed : config.Get<std::uint64_t>("seed", 1);

  const fs::path out = options.out_dir.empty() ? fs::path("runs") / options.experiment
                                               : fs::path(options.out_dir);
  std::error_code ec;
  fs::create_directories(out, ec);
  IFAB_THROW_UNLESS(!ec, "--out {}: cannot create the folder: {}", out.string(), ec.message());
  // Keep the config that produced the results beside them (never over the user's own file).
  const fs::path config_copy = out / "config.yaml";
  if (fs::absolute(config_copy) != fs::absolute(config_path)) {
    fs::copy_file(config_path, config_copy, fs::copy_options::overwrite_existing, ec);
  }

  const auto start = std::chrono::steady_clock::now();
  std::vector<nlohmann::json> results(static_cast<std::size_t>(options.runs));
  std::vector<std::string> errors(results.size());
  auto run_one = [&](std::size_t k) {
    RunContext ctx;
    ctx.config = &config;
    ctx.seed = seed + k;
    ctx.progress = options.progress && options.runs == 1;  // --runs N: one line per finished run
    fs::path dir = out;
    if (options.runs > 1) dir = out / fmt::format("run_{:03d}", k);
    fs::create_directories(dir);
    ctx.out_dir = dir.string();
    try {
      results[k] = info.run(ctx);
      results[k]["seed"] = ctx.seed;
      if (options.runs > 1) WriteJson(dir / "results.json", results[k]);
    } catch (const InputError&) {
      throw;  // a bad config is the same for every run: report it once
    } catch (const std::exception& e) {
      errors[k] = e.what();
    }
    if (options.progress && options.runs > 1) ReportRunDone(info, k, options.runs, ctx.seed, results[k], errors[k]);
  };
  ProgressLine::Global().Restart();
  if (options.progress && options.runs > 1)
    ProgressLine::Global().Update(fmt::format("{} runs, {} at a time", options.runs, options.jobs), 0.0);
  if (options.runs == 1) {
    run_one(0);
  } else {
    tbb::task_arena arena(options.jobs);
    arena.execute([&] {
      tbb::parallel_for(std::size_t{0}, results.size(), [&](std::size_t k) { run_one(k); });
    });
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  nlohmann::json summary;
  if (options.runs == 1) {
    if (!errors[0].empty()) throw std::runtime_error(errors[0]);
    summary = results[0];
  } else {
    std::vector<nlohmann::json> ok;
    nlohmann::json failed = nlohmann::json::array();
    for (std::size_t k = 0; k < results.size(); ++k) {
      const bool run_failed = !errors[k].empty() || results[k].value("failed", false);
      if (run_failed) {
        failed.push_back({{"seed", seed + k}, {"error", errors[k].empty() ? results[k].value("failure", "") : errors[k]}});
      } else {
        ok.push_back(results[k]);
      }
    }
    summary = {{"experiment", options.experiment}, {"runs", options.runs},
               {"failed_runs", failed.size()}, {"failures", failed},
               {"over_runs", Aggregate(ok)}};
    summary["wall_seconds_total"] = wall;
  }
  summary["experiment"] = options.experiment;
  WriteJson(out / "results.json", summary);
  if (options.progress) {
    ProgressLine::Global().Finish();
    PrintResultsTable(info, summary);
    std::cerr << "results: " << (out / "results.json").string() << "\n";
  }
  WriteReportAfterRun(out.string(), options.progress);
  return summary;
}

void PrintResultsTable(const ExperimentInfo& info, const nlohmann::json& results) {
  std::cout << "\n" << FormatResultsTable(MakeResultsTable(info, results)) << std::flush;
}

}  // namespace ifab::experiments
