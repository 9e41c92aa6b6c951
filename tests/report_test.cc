// Issue 13: the report page's writer (what it gathers from a run folder and how it inlines it),
// the results table over runs, and the progress line's text. The page itself is tested in a
// browser (tests/browser).
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "ifab/core/error.h"
#include "ifab/experiments/progress.h"
#include "ifab/experiments/report.h"
#include "ifab/experiments/results_table.h"
#include "ifab/experiments/ply_file.h"
#include "ifab/perception/ply.h"

namespace ifab::experiments {
namespace {
namespace fs = std::filesystem;

fs::path TempDir(const std::string& name) {
  const auto dir = fs::path(::testing::TempDir()) / ("ifab_report_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

void Write(const fs::path& path, const std::string& text) { std::ofstream(path) << text; }

std::string Read(const fs::path& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The data element of a written page, parsed back.
nlohmann::json PageData(const std::string& html) {
  const std::string open = "<script type=\"application/json\" id=\"ifab-data\">";
  const auto a = html.find(open) + open.size();
  const auto b = html.find("</script>", a);
  return nlohmann::json::parse(html.substr(a, b - a));
}

TEST(Report, InlinesTheBundleAndTheRunsDataAndKeepsScriptsClosed) {
  const fs::path dir = TempDir("inline");
  Write(dir / "results.json", R"({"experiment": "lrf-bias", "heights_m": [0.4], "bump_height_mm": [30.0], "scans_per_height": 2})");
  Write(dir / "notes.csv", "a,b\n1,</script><b>x</b>\n");
  PointCloud cloud;
  PointCloud::Field label{"label", {}};
  for (int i = 0; i < 10; ++i) {
    cloud.points.emplace_back(0.001 * i, 0.5, -0.25);
    label.values.push_back(i % 2);
  }
  cloud.fields.push_back(label);
  SavePly((dir / "cloud_visit_01.ply").string(), cloud);
  const fs::path bundle = dir / "bundle.js";
  Write(bundle, "window.x = '</script>';");
  ReportOptions o;
  o.bundle_path = bundle.string();
  o.max_cloud_points = 4;
  const ReportSummary s = WriteReport(dir.string(), o);
  EXPECT_EQ(s.experiment, "lrf-bias");
  EXPECT_EQ(s.path, (dir / "report.html").string());
  const std::string html = Read(dir / "report.html");
  EXPECT_EQ(s.bytes, html.size());
  // Nothing of the data or the bundle closes a script element early.
  EXPECT_EQ(html.find("</script><b>"), std::string::npos);
  EXPECT_NE(html.find("window.x = '<\\/script>';"), std::string::npos);
  const nlohmann::json data = PageData(html);
  EXPECT_EQ(data["experiment"], "lrf-bias");
  EXPECT_EQ(data["csv"]["notes.csv"], "a,b\n1,</script><b>x</b>\n");
  // The experiment's own table, named as on the terminal, with the paper's column.
  ASSERT_EQ(data["table"]["rows"].size(), 1u);
  EXPECT_EQ(data["table"]["rows"][0][0], "bump at 0.4 m [mm]");
  EXPECT_EQ(data["table"]["rows"][0][2], "about 30 (Fig. 7)");
  // Every 3rd point (10 -> 4), in mm, with its label; the counts over the full cloud.
  ASSERT_EQ(data["clouds"].size(), 1u);
  const auto& c = data["clouds"][0];
  EXPECT_EQ(c["points"], 10);
  EXPECT_EQ(c["stride"], 3);
  EXPECT_EQ(c["xyz_mm"], nlohmann::json({0, 500, -250, 3, 500, -250, 6, 500, -250, 9, 500, -250}));
  EXPECT_EQ(c["label"], nlohmann::json({0, 1, 0, 1}));
  EXPECT_EQ(c["label_counts"]["1"], 5);
  EXPECT_EQ(c["shadow_xyz_mm"].size(), 15u);  // every shadow point, not decimated (Fig. 4)
  EXPECT_FALSE(fs::exists(dir / "report.html.tmp"));
}

TEST(Report, SaysWhatIsMissing) {
  const fs::path dir = TempDir("missing");
  const fs::path bundle = dir / "bundle.js";
  Write(bundle, "1;");
  ReportOptions o;
  o.bundle_path = bundle.string();
  try {
    WriteReport(dir.string(), o);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("nothing to draw"), std::string::npos) << e.what();
  }
  Write(dir / "results.json", R"({"experiment": "lrf-bias")");  // broken JSON
  try {
    WriteReport(dir.string(), o);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("results.json: not valid JSON"), std::string::npos) << e.what();
  }
  o.bundle_path = (dir / "none.js").string();
  EXPECT_THROW(WriteReport(dir.string(), o), InputError);
  EXPECT_THROW(WriteReport((dir / "no_such_folder").string(), o), InputError);
}

TEST(ResultsTable, OverRunsNamesFiguresAsOneRunDoesWithThePapersColumn) {
  const ExperimentInfo* info = FindExperiment("brick-stack");
  ASSERT_NE(info, nullptr);
  nlohmann::json over;
  for (const char* key : {"bricks_placed", "repositionings", "brick_error_long_mm_mean", "brick_error_short_mm_mean",
                          "brick_error_mm_max", "brick_error_away_from_robot_mm_mean", "base_end_error_vs_desired_m_mean",
                          "base_end_error_vs_desired_deg_mean", "localization_correction_m_mean",
                          "localization_correction_deg_mean", "after_localization_vs_desired_m_max",
                          "after_localization_vs_desired_deg_max", "sim_seconds", "wall_seconds"})
    over[key] = {{"mean", 2.0}, {"std", 0.5}, {"min", 1.0}, {"max", 3.0}, {"worst", 3.0}};
  const nlohmann::json summary = {{"experiment", "brick-stack"}, {"runs", 3}, {"failed_runs", 0}, {"over_runs", over}};
  const ResultsTable t = MakeResultsTable(*info, summary);
  ASSERT_EQ(t.header, (std::vector<std::string>{"figure", "mean", "std", "min", "max", "paper"}));
  ASSERT_GE(t.rows.size(), 3u);
  EXPECT_EQ(t.rows[2], (std::vector<std::string>{"brick error, long face [mm]", "2.00", "0.50", "1.00", "3.00", "4.6 (target 1)"}));
  // Metres shown in cm, as in the single-run table.
  bool found = false;
  for (const auto& r : t.rows)
    if (r[0] == "end of maneuver vs desired [cm]") {
      found = true;
      EXPECT_EQ(r[1], "200.0");
      EXPECT_EQ(r[5], "3");
    }
  EXPECT_TRUE(found);
  EXPECT_EQ(t.rows.back()[0], "failed runs");
}

TEST(Progress, OneLineWithPercentAndTimeLeft) {
  EXPECT_EQ(ProgressLine::Format("east: placing brick 3", 0.5, 60.0, 80), "[ 50%] east: placing brick 3 · 1:00 left");
  // No time left before 2 % are done (too little to go by), none once done; no percent if unknown.
  EXPECT_EQ(ProgressLine::Format("start", 0.01, 5.0, 80), "[  1%] start");
  EXPECT_EQ(ProgressLine::Format("calibrating", -1.0, 5.0, 80), "calibrating");
  EXPECT_EQ(ProgressLine::Format("a long phase text", 0.25, 30.0, 12).size(), 11u);
}

}  // namespace
}  // namespace ifab::experiments
