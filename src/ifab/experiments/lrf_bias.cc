// `ifab run lrf-bias`: the paper's Fig. 7 in simulation. The UTM-30LX looks straight down at the
// floor from three heights; the short-range bias makes the floor seem to rise below the scanner.

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "ifab/experiments/atomic_file.h"
#include "ifab/core/angles.h"
#include "ifab/core/data_path.h"
#include "ifab/core/random.h"
#include "ifab/experiments/experiments.h"
#include "ifab/sim/as_built.h"
#include "ifab/sim/lrf_model.h"

namespace ifab::experiments {
namespace {

nlohmann::json RunLrfBias(const RunContext& ctx) {
  const ConfigNode& c = *ctx.config;
  c.ExpectKeys({"seed", "laser", "unit", "as_built", "minutes_since_power_on", "heights_m", "scans_per_height",
                "centre_deg", "reference_deg"});
  const auto dir = std::filesystem::path(c.file()).parent_path();
  const std::string laser_path = (dir / c.Get<std::string>("laser")).string();
  const sim::LrfOptions nominal = sim::LrfOptions::FromConfig(ConfigNode::LoadFile(laser_path)["lrf"]);
  const std::vector<double> heights = c["heights_m"].AsNumbers();
  for (std::size_t i = 0; i < heights.size(); ++i)
    if (!(heights[i] > 0)) c["heights_m"][i].Fail("a positive height");
  int scans = 40;
  c.ReadPositive("scans_per_height", scans);
  double centre_deg = 3.0;
  c.ReadPositive("centre_deg", centre_deg);
  const auto ref = c["reference_deg"].AsNumbers(2);
  if (!(ref[0] < ref[1])) c["reference_deg"].Fail("[low, high] with low < high");
  // A unit drawn for this seed around the nominal model (its own bias curve, noise, warm-up), as
  // the as-built world draws its lasers; `unit: nominal` scans with the nominal model itself.
  const std::string unit = c.Get<std::string>("unit", "drawn");
  if (unit != "drawn" && unit != "nominal") c["unit"].Fail("drawn or nominal");
  sim::LrfOptions options = nominal;
  if (unit == "drawn") {
    const auto tolerances = sim::AsBuiltTolerances::Load(
        c.Has("as_built") ? (dir / c.Get<std::string>("as_built")).string() : DataPath("sim/as_built.yaml"));
    RandomStream unit_rng = RandomStream(ctx.seed).Derive("lrf-bias unit");
    options = sim::DrawLrfUnit(nominal, tolerances.laser, unit_rng);
  }
  sim::LrfModel lrf(options);
  double minutes_on = 60.0;  // Fig. 7 was measured on a warm unit
  c.ReadNonNegative("minutes_since_power_on", minutes_on);
  lrf.SetTimeSincePowerOn(60.0 * minutes_on);

  Site floor_only;  // an empty lab floor
  floor_only.ground_z = 0.0;
  const sim::World world(floor_only);
  RandomStream rng(ctx.seed);

  AtomicOfstream csv(std::filesystem::path(ctx.out_dir) / "lrf_bias_points.csv");
  csv << "height_m,scan,beam,angle_from_vertical_deg,x_m,z_m\n";
  nlohmann::json bumps = nlohmann::json::array();
  for (const double h : heights) {
    ctx.Progress(fmt::format("lrf-bias: {} scans of the floor from {:.1f} m", scans, h));
    // Laser x straight down, scan plane vertical along the site's x axis.
    Pose3 T_site_laser = Pose3::Identity();
    T_site_laser.linear() << 0, 1, 0,  //
        0, 0, -1,                      //
        -1, 0, 0;
    T_site_laser.translation() = Eigen::Vector3d(0, 0, h);
    double centre_sum = 0, ref_sum = 0;
    int centre_n = 0, ref_n = 0;
    LaserScan scan;
    for (int k = 0; k < scans; ++k) {
      lrf.Scan(world, [&](double) { return T_site_laser; }, rng, scan);
      for (std::size_t i = 0; i < scan.size(); ++i) {
        if (!scan.IsValid(i)) continue;
        const Eigen::Vector3d p = T_site_laser * scan.Point(i);
        const double from_vertical = RadToDeg(std::abs(scan.Angle(i)));
        csv << fmt::format("{},{},{},{:.3f},{:.5f},{:.5f}\n", h, k, i, RadToDeg(scan.Angle(i)), p.x(), p.z());
        if (from_vertical <= centre_deg) {
          centre_sum += p.z();
          ++centre_n;
        } else if (from_vertical >= ref[0] && from_vertical <= ref[1]) {
          ref_sum += p.z();
          ++ref_n;
        }
      }
    }
    if (centre_n == 0 || ref_n == 0) ThrowInputError("{}: no floor points in the centre or reference band at {} m", c.file(), h);
    bumps.push_back(1000.0 * (centre_sum / centre_n - ref_sum / ref_n));
  }
  // The unit's own walk bias at normal incidence (what the bump shows, beside the nominal model's).
  nlohmann::json unit_info = {{"unit", unit}};
  for (const double h : heights) {
    unit_info["walk_bias_mm"].push_back(1e3 * (options.Bias(h, 0.0) - options.Bias(10.0, 0.0)));
    unit_info["nominal_walk_bias_mm"].push_back(1e3 * (nominal.Bias(h, 0.0) - nominal.Bias(10.0, 0.0)));
  }
  unit_info["warmup_drift_mm"] = 1e3 * lrf.drift();
  return {{"heights_m", heights}, {"bump_height_mm", bumps}, {"scans_per_height", scans}, {"laser_unit", unit_info}};
}

std::vector<std::vector<std::string>> LrfBiasTable(const nlohmann::json& r) {
  std::vector<std::vector<std::string>> rows;
  const char* paper[] = {"about 30 (Fig. 7)", "smaller", "smaller still"};
  for (std::size_t i = 0; i < r["heights_m"].size(); ++i)
    rows.push_back({fmt::format("bump at {:.1f} m [mm]", r["heights_m"][i].get<double>()),
                    fmt::format("{:.1f}", r["bump_height_mm"][i].get<double>()), i < 3 ? paper[i] : ""});
  return rows;
}

}  // namespace

ExperimentInfo LrfBiasExperiment() {
  return {"lrf-bias", "paper Fig. 7: floor scans from 0.4, 1.1, 2.4 m show the short-range bias", RunLrfBias, LrfBiasTable};
}

}  // namespace ifab::experiments
