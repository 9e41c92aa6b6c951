// `ifab estimate LOG [--relations FILE] [--config FILE] --out DIR`: run the base state estimator
// (paper Sec. III-B) over a recorded CARMEN log; write DIR/trajectory.csv and DIR/metrics.json
// (errors against reference relations with the metric of Kuemmerle et al. 2009).

#include <iostream>

#include "ifab/app/commands.h"
#include "ifab/experiments/report.h"
#include "ifab/experiments/estimate_log.h"
#include "ifab/core/data_path.h"

namespace ifab::app {

void AddEstimateCommand(CLI::App& app, int& exit_code) {
  struct Args {
    std::string log, relations, out;
    std::string config{DataPath("estimator/carmen.yaml")};
  };
  auto args = std::make_shared<Args>();
  CLI::App* sub = app.add_subcommand(
      "estimate",
      "Run the base state estimator (scan matching, paper eq. 1-3) over a CARMEN log (FLASER /\n"
      "ROBOTLASER1 / ODOM lines). The laser's geometry comes from the log; the odometry is a factor\n"
      "of eq. 3 (log.odometry: factor) or, as in the paper's eq. 2, its heading stands in for the\n"
      "gyro (log.odometry: gyro). Writes DIR/trajectory.csv (one pose per scan, with its status and\n"
      "degenerate direction) and DIR/metrics.json (flagged_fraction, false_ok_rate, the log's\n"
      "geometry, the raw odometry's error and\n"
      "(errors against the reference relations, Kuemmerle et al. 2009; LOG with .relations is used\n"
      "if --relations is not given and it exists).");
  sub->add_option("LOG", args->log, "CARMEN log (.clf)")->required()->check(CLI::ExistingFile);
  sub->add_option("--relations", args->relations, "Reference relations: t1 t2 x y z roll pitch yaw")
      ->check(CLI::ExistingFile);
  sub->add_option("--config", args->config, "Estimator and log options (YAML)")->capture_default_str();
  sub->add_option("--out", args->out, "Output folder")->required();
  sub->callback([args, &exit_code] {
    const auto options = experiments::EstimateLogOptions::FromConfig(ConfigNode::LoadFile(args->config));
    const nlohmann::json m = experiments::RunEstimateOnLog(args->log, args->relations, options, args->out);
    std::cout << "scans " << m["scans"] << ", relations " << m["relations"];
    if (m["relations"].get<int>() > 0) {
      std::cout << ", translation error mean " << m["translation_error_m"]["mean"].get<double>()
                << " m, rotation error mean " << m["rotation_error_deg"]["mean"].get<double>()
                << " deg (short span: " << m["short_span"]["translation_error_m"]["mean"].get<double>()
                << " m)";
    }
    std::cout << ", flagged " << m["flagged_fraction"].get<double>() << ", false ok "
              << m["false_ok_rate"].get<double>() << ", " << m["ms_per_scan_median"].get<double>()
              << " ms per scan (median)\n"
              << "wrote " << args->out << "/trajectory.csv and " << args->out << "/metrics.json\n";
    experiments::WriteReportAfterRun(args->out, true);  // DIR/report.html: trajectory, relation errors
    exit_code = 0;
  });
}

}  // namespace ifab::app
