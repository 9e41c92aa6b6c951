#include "ifab/experiments/experiment.h"

#include <fmt/format.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <csignal>
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
#include "ifab/experiments/atomic_file.h"

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

void WriteJson(const fs::path& path, const nlohmann::json& j) { WriteFileAtomically(path, j.dump(2) + "\n"); }

// Ctrl-C: the first SIGINT asks the runs to stop (they check at their next progress report) and
// the results so far are written, marked interrupted; a second one ends the program at once.
std::atomic<bool> g_interrupted{false};
extern "C" void OnSigint(int) {
  g_interrupted.store(true);
  std::signal(SIGINT, SIG_DFL);
}

// Installs the handler for the duration of a RunExperiment call.
class SigintScope {
 public:
  SigintScope() : previous_(std::signal(SIGINT, OnSigint)) { g_interrupted.store(false); }
  ~SigintScope() { std::signal(SIGINT, previous_ == SIG_ERR ? SIG_DFL : previous_); }
  SigintScope(const SigintScope&) = delete;
  SigintScope& operator=(const SigintScope&) = delete;

 private:
  void (*previous_)(int);
};

// A folder holds a run if it has results.json or per-run folders.
bool HoldsARun(const fs::path& dir) {
  std::error_code ec;
  if (fs::exists(dir / "results.json", ec)) return true;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.is_directory() && e.path().filename().string().rfind("run_", 0) == 0) return true;
  return false;
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

bool Interrupted() { return g_interrupted.load(); }

void RunContext::Progress(const std::string& text, double fraction) const {
  if (Interrupted()) throw RunInterrupted();
  if (progress) ProgressLine::Global().Update(text, fraction);
}

nlohmann::json RunExperiment(const RunOptions& options) {
  const ExperimentInfo& info = Find(options.experiment);
  IFAB_THROW_UNLESS(options.runs >= 1, "--runs: expected a positive number, got {}", options.runs);
  IFAB_THROW_UNLESS(options.jobs >= 1, "--jobs: expected a positive number, got {}", options.jobs);

  const std::string config_path = options.config_path.empty()
                                      ? DataPath("experiments/" + options.experiment + ".yaml")
                                      : options.config_path;
  ConfigNode config = ConfigNode::LoadFile(config_path);
  config.ApplySettings(options.settings);
  const std::uint64_t seed = options.seed ? *options.seed : config.Get<std::uint64_t>("seed", 1);

  const fs::path out = options.out_dir.empty() ? fs::path("runs") / options.experiment
                                               : fs::path(options.out_dir);
  std::error_code ec;
  // Nothing a user has is overwritten: an earlier run's folder is kept unless --force.
  IFAB_THROW_UNLESS(options.force || !fs::is_directory(out, ec) || !HoldsARun(out),
                    "--out {}: the folder already holds a run (results.json); choose another folder or pass --force "
                    "to overwrite it", out.string());
  fs::create_directories(out, ec);
  IFAB_THROW_UNLESS(!ec, "--out {}: cannot create the folder: {}", out.string(), ec.message());
  // A stale summary of an overwritten run must not stand beside new per-run results.
  if (options.force) fs::remove(out / "results.json", ec);
  // Keep the config that produced the results beside them (never over the user's own file).
  const fs::path config_copy = out / "config.yaml";
  if (fs::absolute(config_copy) != fs::absolute(config_path)) {
    if (options.settings.empty()) {
      fs::copy_file(config_path, config_copy, fs::copy_options::overwrite_existing, ec);
    } else {  // what ran: the file with the settings applied (its paths relative to the original)
      AtomicOfstream copy(config_copy);
      copy << "# " << config_path << " with --set";
      for (const auto& s : options.settings) copy << " " << s;
      copy << "\n" << config.Dump() << "\n";
      copy.Commit();
    }
  }

  const SigintScope sigint;
  const auto start = std::chrono::steady_clock::now();
  std::vector<nlohmann::json> results(static_cast<std::size_t>(options.runs));
  std::vector<std::string> errors(results.size());
  std::vector<char> finished(results.size(), 0);
  auto run_one = [&](std::size_t k) {
    if (Interrupted()) return;  // not started
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
      finished[k] = 1;
    } catch (const RunInterrupted&) {
      // stopped part-way: listed as not finished, its folder has no results.json
    } catch (const InputError&) {
      throw;  // a bad config is the same for every run: report it once
    } catch (const std::exception& e) {
      errors[k] = e.what();
      finished[k] = 1;
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

  const bool interrupted = Interrupted();
  nlohmann::json summary;
  if (options.runs == 1 && !finished[0]) {
    summary = {{"runs", 1}, {"runs_finished", 0}};
  } else if (options.runs == 1) {
    if (!errors[0].empty()) throw std::runtime_error(errors[0]);
    summary = results[0];
  } else {
    std::vector<nlohmann::json> ok;
    nlohmann::json failed = nlohmann::json::array();
    for (std::size_t k = 0; k < results.size(); ++k) {
      if (!finished[k]) continue;
      const bool run_failed = !errors[k].empty() || results[k].value("failed", false);
      if (run_failed) {
        failed.push_back({{"seed", seed + k}, {"error", errors[k].empty() ? results[k].value("failure", "") : errors[k]}});
      } else {
        ok.push_back(results[k]);
      }
    }
    summary = {{"experiment", options.experiment}, {"runs", options.runs},
               {"runs_finished", std::count(finished.begin(), finished.end(), 1)},
               {"failed_runs", failed.size()}, {"failures", failed},
               {"over_runs", Aggregate(ok)}};
    summary["wall_seconds_total"] = wall;
    if (info.summarize) {
      std::vector<nlohmann::json> done;
      for (std::size_t k = 0; k < results.size(); ++k)
        if (finished[k] && errors[k].empty()) done.push_back(results[k]);
      summary["campaign"] = info.summarize(done);
    }
  }
  summary["experiment"] = options.experiment;
  summary["interrupted"] = interrupted;
  WriteJson(out / "results.json", summary);
  if (interrupted) {
    std::cerr << "interrupted: results so far in " << (out / "results.json").string() << "\n";
    return summary;
  }
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
