#include "ifab/experiments/results_table.h"

#include <fmt/format.h>

#include <algorithm>

#include "ifab/experiments/progress.h"

namespace ifab::experiments {

namespace {

std::vector<std::vector<std::string>> GenericRows(const nlohmann::json& src) {
  std::vector<std::vector<std::string>> rows;
  for (const auto& [key, value] : src.items())
    if (value.is_number() && key != "seed") rows.push_back({key, fmt::format("{:.4g}", value.get<double>()), ""});
  return rows;
}

// The experiment's own rows for a results object, or none if its table cannot read it.
std::vector<std::vector<std::string>> OwnRows(const ExperimentInfo& info, const nlohmann::json& r) {
  if (!info.table) return {};
  try {
    return info.table(r);
  } catch (const std::exception&) {
    return {};
  }
}

}  // namespace

const ExperimentInfo* FindExperiment(const std::string& name) {
  for (const auto& e : Registry())
    if (e.name == name) return &e;
  return nullptr;
}

ResultsTable MakeResultsTable(const ExperimentInfo& info, const nlohmann::json& results) {
  ResultsTable t;
  if (!results.contains("over_runs")) {
    t.header = {"figure", "ifab", "paper"};
    t.rows = OwnRows(info, results);
    if (t.rows.empty()) t.rows = GenericRows(results);
    return t;
  }
  // Over runs: the experiment's table applied to the mean, std, min and max of every key gives
  // the same names, units and paper column as a single run (its formatting is linear per key).
  const nlohmann::json& over = results["over_runs"];
  nlohmann::json stat[4];
  const char* names[4] = {"mean", "std", "min", "max"};
  for (const auto& [key, value] : over.items())
    for (int s = 0; s < 4; ++s)
      if (value.is_object() && value.contains(names[s])) stat[s][key] = value[names[s]];
  std::vector<std::vector<std::string>> per[4];
  for (int s = 0; s < 4; ++s) per[s] = OwnRows(info, stat[s]);
  bool own = !per[0].empty();
  for (int s = 1; s < 4; ++s) own = own && per[s].size() == per[0].size();
  if (!own)
    for (int s = 0; s < 4; ++s) per[s] = GenericRows(stat[s]);
  t.header = {"figure", "mean", "std", "min", "max", "paper"};
  for (std::size_t i = 0; i < per[0].size(); ++i)
    t.rows.push_back({per[0][i][0], per[0][i][1], per[1][i][1], per[2][i][1], per[3][i][1],
                      per[0][i].size() > 2 ? per[0][i][2] : ""});
  t.rows.push_back({"failed runs", results.value("failed_runs", nlohmann::json(0)).dump(), "", "", "", ""});
  return t;
}

std::string FormatResultsTable(const ResultsTable& table) {
  std::vector<std::size_t> w(table.header.size(), 0);
  auto widen = [&](const std::vector<std::string>& r) {
    for (std::size_t c = 0; c < r.size() && c < w.size(); ++c) w[c] = std::max(w[c], r[c].size());
  };
  widen(table.header);
  for (const auto& r : table.rows) widen(r);
  auto line = [&](const std::vector<std::string>& r) {
    std::string s;
    for (std::size_t c = 0; c < w.size(); ++c) {
      const std::string cell = c < r.size() ? r[c] : "";
      const bool last = c + 1 == w.size();
      if (c == 0) s += fmt::format("{:<{}}", cell, w[c]);
      else if (last) s += "  " + cell;  // the paper's column: free text
      else s += fmt::format("  {:>{}}", cell, w[c]);
    }
    return s + "\n";
  };
  std::size_t total = 0;
  for (std::size_t x : w) total += x + 2;
  std::string out = line(table.header) + std::string(total, '-') + "\n";
  for (const auto& r : table.rows) out += line(r);
  return out;
}

void ReportRunDone(const ExperimentInfo& info, std::size_t k, int runs, std::uint64_t seed,
                   const nlohmann::json& result, const std::string& error) {
  ProgressLine& line = ProgressLine::Global();
  const int n = line.FinishedOne();
  std::string what;
  if (!error.empty()) {
    what = "failed: " + error;
  } else if (result.value("failed", false)) {
    what = "failed: " + result.value("failure", std::string("(no reason given)"));
  } else {
    const auto rows = OwnRows(info, result);
    for (std::size_t i = 0; i < rows.size() && i < 4; ++i) what += (i ? ", " : "") + rows[i][0] + " " + rows[i][1];
  }
  line.Print(fmt::format("run {:>3} (seed {}) {:>3}/{}: {}", k, seed, n, runs, what));
  line.Update(fmt::format("{} of {} runs done", n, runs), static_cast<double>(n) / runs);
}

}  // namespace ifab::experiments
