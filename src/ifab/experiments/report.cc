#include "ifab/experiments/report.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "ifab/core/error.h"
#include "ifab/experiments/results_table.h"
#include "ifab/perception/ply.h"

#ifndef IFAB_REPORT_BUNDLE
#define IFAB_REPORT_BUNDLE ""
#endif

namespace ifab::experiments {
namespace fs = std::filesystem;

namespace {

std::string ReadText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) ThrowInputError("{}: cannot read the file", path.string());
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

nlohmann::json ReadJson(const fs::path& path) {
  try {
    return nlohmann::json::parse(ReadText(path));
  } catch (const nlohmann::json::exception& e) {  // parse_error, or out_of_range for 1e405
    ThrowInputError("{}: not valid JSON ({})", path.string(), e.what());
  }
}

nlohmann::json TableJson(const ResultsTable& t) { return {{"header", t.header}, {"rows", t.rows}}; }

// A cloud for display: every n-th point (keeps the scan lines' structure), in mm as integers,
// with its labels when the PLY has them.
nlohmann::json DecimatedCloud(const fs::path& path, int max_points) {
  const PointCloud cloud = ReadPly(path.string());
  const std::size_t n = cloud.size();
  const std::size_t stride = std::max<std::size_t>(1, (n + static_cast<std::size_t>(max_points) - 1) /
                                                          static_cast<std::size_t>(std::max(1, max_points)));
  const PointCloud::Field* label = nullptr;
  for (const auto& f : cloud.fields)
    if (f.name == "label") label = &f;
  nlohmann::json xyz = nlohmann::json::array(), labels = nlohmann::json::array();
  for (std::size_t i = 0; i < n; i += stride) {
    for (int a = 0; a < 3; ++a) xyz.push_back(static_cast<int>(std::lround(1000.0 * cloud.points[i][a])));
    if (label) labels.push_back(static_cast<int>(label->values[i]));
  }
  nlohmann::json j = {{"file", path.filename().string()}, {"points", n}, {"stride", stride}, {"xyz_mm", xyz}};
  if (label) {
    j["label"] = labels;
    // Counts over the full cloud, so the page can state them without the decimation, and every
    // shadow point (label 1): few, and what Fig. 4 is about.
    nlohmann::json counts = nlohmann::json::object(), shadow = nlohmann::json::array();
    for (std::size_t i = 0; i < n; ++i) {
      const int l = static_cast<int>(label->values[i]);
      counts[std::to_string(l)] = counts.value(std::to_string(l), 0) + 1;
      if (l == 1)
        for (int a = 0; a < 3; ++a) shadow.push_back(static_cast<int>(std::lround(1000.0 * cloud.points[i][a])));
    }
    j["label_counts"] = counts;
    j["shadow_xyz_mm"] = shadow;
  }
  return j;
}

// Everything the page needs from one folder.
nlohmann::json Gather(const fs::path& dir, const ReportOptions& options, std::string* experiment) {
  nlohmann::json data;
  data["folder"] = fs::absolute(dir).lexically_normal().string();
  if (fs::exists(dir / "results.json")) {
    data["results"] = ReadJson(dir / "results.json");
    *experiment = data["results"].value("experiment", "");
    if (const ExperimentInfo* info = FindExperiment(*experiment))
      data["table"] = TableJson(MakeResultsTable(*info, data["results"]));
  } else if (fs::exists(dir / "metrics.json") && fs::exists(dir / "trajectory.csv")) {
    data["metrics"] = ReadJson(dir / "metrics.json");
    *experiment = "estimate";
  } else {
    ThrowInputError("{}: neither results.json (a folder of `ifab run`) nor metrics.json and trajectory.csv "
                    "(a folder of `ifab estimate`): nothing to draw", dir.string());
  }
  data["experiment"] = *experiment;
  if (fs::exists(dir / "metrics.json") && !data.contains("metrics")) data["metrics"] = ReadJson(dir / "metrics.json");
  if (fs::exists(dir / "scene.json")) data["scene"] = ReadJson(dir / "scene.json");

  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.is_regular_file()) files.push_back(e.path());
  std::sort(files.begin(), files.end());
  nlohmann::json csv = nlohmann::json::object(), clouds = nlohmann::json::array(), left_out = nlohmann::json::array();
  for (const fs::path& f : files) {
    if (f.extension() == ".csv") {
      if (fs::file_size(f) > options.max_csv_bytes) {
        left_out.push_back(f.filename().string());
        continue;
      }
      csv[f.filename().string()] = ReadText(f);
    } else if (f.extension() == ".ply") {
      clouds.push_back(DecimatedCloud(f, options.max_cloud_points));
    }
  }
  data["csv"] = csv;
  data["clouds"] = clouds;
  data["left_out"] = left_out;

  // --runs N: each run's own figures, for their distributions.
  if (data.contains("results") && data["results"].contains("over_runs")) {
    nlohmann::json runs = nlohmann::json::array();
    for (const auto& e : fs::directory_iterator(dir))
      if (e.is_directory() && fs::exists(e.path() / "results.json")) {
        nlohmann::json r = ReadJson(e.path() / "results.json");
        r["folder"] = e.path().filename().string();
        runs.push_back(std::move(r));
      }
    std::sort(runs.begin(), runs.end(),
              [](const nlohmann::json& a, const nlohmann::json& b) { return a.value("folder", "") < b.value("folder", ""); });
    data["runs"] = runs;
  }
  return data;
}

// JSON inside <script type="application/json">: "</" must not close the element.
std::string ScriptSafe(std::string s) {
  std::string out;
  out.reserve(s.size() + 64);
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '<' && i + 1 < s.size() && s[i + 1] == '/') {
      out += "<\\/";
      ++i;
    } else {
      out += s[i];
    }
  }
  return out;
}

}  // namespace

std::string DefaultReportBundle() {
  if (const char* env = std::getenv("IFAB_REPORT_BUNDLE"); env && *env) return env;
  return IFAB_REPORT_BUNDLE;
}

ReportSummary WriteReport(const std::string& dir_name, const ReportOptions& options) {
  const fs::path dir(dir_name);
  if (!fs::is_directory(dir)) ThrowInputError("{}: not a folder (expected a run folder)", dir_name);
  const std::string bundle_path = options.bundle_path.empty() ? DefaultReportBundle() : options.bundle_path;
  if (bundle_path.empty() || !fs::exists(bundle_path))
    ThrowInputError("the report page's script '{}' is missing (`make` builds it with esbuild; "
                    "scripts/install-deps installs node and the page's npm packages)", bundle_path);
  std::string bundle = ReadText(bundle_path);
  // The bundle sits inside <script>: a literal "</script" in a string of it would end the element.
  for (std::size_t p = bundle.find("</script"); p != std::string::npos; p = bundle.find("</script", p + 2))
    bundle.replace(p, 2, "<\\/");

  ReportSummary summary;
  const nlohmann::json data = Gather(dir, options, &summary.experiment);
  const fs::path path = dir / "report.html";
  const fs::path tmp = dir / "report.html.tmp";
  {
    std::ofstream out(tmp, std::ios::binary);
    IFAB_THROW_UNLESS(out.good(), "{}: cannot write the file", tmp.string());
    out << "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
        << "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">"
        << "<title>ifab: " << summary.experiment << "</title></head>\n<body><div id=\"app\"></div>\n"
        << "<script type=\"application/json\" id=\"ifab-data\">" << ScriptSafe(data.dump()) << "</script>\n"
        << "<script>" << bundle << "</script>\n</body></html>\n";
    IFAB_THROW_UNLESS(out.good(), "{}: cannot write the file", tmp.string());
  }
  fs::rename(tmp, path);  // a reader never sees half a page
  summary.path = path.string();
  summary.bytes = fs::file_size(path);
  return summary;
}

bool WriteReportAfterRun(const std::string& dir, bool print_path) {
  try {
    const ReportSummary s = WriteReport(dir);
    if (print_path) std::cout << fmt::format("report: {} ({:.1f} MB)\n", s.path, static_cast<double>(s.bytes) / 1e6);
    return true;
  } catch (const std::exception& e) {
    if (print_path) std::cerr << "report.html not written: " << e.what() << "\n";
    return false;
  }
}

}  // namespace ifab::experiments
