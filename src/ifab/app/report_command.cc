// `ifab report DIR`: draw DIR/report.html again from what a run folder holds (the paper's
// figures, the 3D replay, the results table beside the paper's), e.g. after the page's script
// changed or for a run folder of `ifab estimate`.

#include <fmt/format.h>

#include <iostream>

#include "ifab/app/commands.h"
#include "ifab/experiments/report.h"

namespace ifab::app {

void AddReportCommand(CLI::App& app, int& exit_code) {
  struct Args {
    std::string dir;
    experiments::ReportOptions options;
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand(
      "report",
      "Write DIR/report.html from a run folder of `ifab run` (results.json, CSVs, PLY clouds) or of\n"
      "`ifab estimate` (metrics.json, trajectory.csv): one self-contained page that opens from disk\n"
      "with no network (the paper's figures, a 3D replay of the mission, the results beside the paper's).");
  sub->add_option("dir", args->dir, "Run folder")->required();
  sub->add_option("--cloud-points", args->options.max_cloud_points,
                  "Points per cloud on the page (every n-th; the PLY files keep all)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  sub->add_option("--bundle", args->options.bundle_path, "The page's script (default: the one the build made)");
  sub->callback([args, &exit_code] {
    const auto s = experiments::WriteReport(args->dir, args->options);
    std::cout << fmt::format("report: {} ({:.1f} MB, {})\n", s.path, static_cast<double>(s.bytes) / 1e6, s.experiment);
    exit_code = 0;
  });
}

}  // namespace ifab::app
