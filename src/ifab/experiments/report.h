#pragma once
/// \file
/// The report page of a run folder: one self-contained HTML file (DIR/report.html) that opens
/// from disk with no server and no network. It holds the page's script (three.js, plotly.js and
/// web/src, bundled by esbuild at build time: an installed data file) and the run's data: its
/// results.json and results table, its CSVs, its scene.json and its clouds decimated for display
/// (the full clouds stay in the PLY files). Which figures the page draws depends on the files it
/// finds; the page itself is web/src/main.js.

#include <cstdint>
#include <string>

namespace ifab::experiments {

struct ReportOptions {
  std::string bundle_path;           ///< the page's script; empty: DefaultReportBundle()
  int max_cloud_points{3000};        ///< per cloud on the page (every n-th point is kept)
  std::uintmax_t max_csv_bytes{8u << 20};  ///< larger CSVs are left out of the page (named on it)
};

struct ReportSummary {
  std::string path;         ///< DIR/report.html
  std::uintmax_t bytes{0};  ///< its size
  std::string experiment;   ///< what it shows
};

/// The bundle's path: $IFAB_REPORT_BUNDLE, else the one the build made.
std::string DefaultReportBundle();

/// Write DIR/report.html from what DIR holds (results.json of `ifab run`, or metrics.json and
/// trajectory.csv of `ifab estimate`). Throws InputError naming the folder or file when there is
/// nothing to draw or a file cannot be read, and when the bundle is missing.
ReportSummary WriteReport(const std::string& dir, const ReportOptions& options = {});

/// WriteReport for the end of `ifab run`: the run's results are already written, so a page that
/// cannot be drawn returns false (and says why on stderr when `print_path`) instead of failing
/// the run. Prints the page's path and size when `print_path`.
bool WriteReportAfterRun(const std::string& dir, bool print_path);

}  // namespace ifab::experiments
