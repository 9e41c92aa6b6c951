#include "ifab/experiments/perception_json.h"

#include <cmath>

#include "ifab/experiments/atomic_file.h"

namespace ifab {

using nlohmann::json;

json MatrixToJson(const Eigen::MatrixXd& m) {
  json rows = json::array();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    std::vector<double> row(static_cast<std::size_t>(m.cols()));
    for (Eigen::Index c = 0; c < m.cols(); ++c) row[static_cast<std::size_t>(c)] = m(r, c);
    rows.push_back(row);
  }
  return rows;
}

json GroundExtentToJson(const GroundExtent& g) {
  json rings = json::array();
  for (const auto& r : g.rings)
    rings.push_back({{"outer_m", r.outer},
                     {"points", r.points},
                     {"mean_mm", r.mean_mm},
                     {"se_mm", r.se_mm},
                     {"sectors", r.sectors},
                     {"chi2", r.chi2},
                     {"chi2_bound", r.bound},
                     {"worst_sector_mm", r.worst_sector_mm}});
  return {{"radius_m", g.radius}, {"limited", g.limited}, {"message", g.message}, {"rings", rings}};
}

json PoseToJson(const Pose3& pose) {
  const auto v = XyzRpyFromPose(pose);
  return {{"xyz", {v[0], v[1], v[2]}},
          {"rpy_deg", {v[3] * 180 / M_PI, v[4] * 180 / M_PI, v[5] * 180 / M_PI}},
          {"matrix", MatrixToJson(pose.matrix())}};
}

json StdToJson(const Matrix6d& cov) {
  return {{"xyz_mm", {1e3 * std::sqrt(cov(0, 0)), 1e3 * std::sqrt(cov(1, 1)), 1e3 * std::sqrt(cov(2, 2))}},
          {"rotation_deg",
           {std::sqrt(cov(3, 3)) * 180 / M_PI, std::sqrt(cov(4, 4)) * 180 / M_PI, std::sqrt(cov(5, 5)) * 180 / M_PI}}};
}

json BodyToJson(const RegisteredBody& b, bool usable) {
  return {{"name", b.name},
          {"free", b.free},
          {"usable", usable},
          {"T_base_body", PoseToJson(b.T_base_body)},
          {"covariance", MatrixToJson(b.covariance)},
          {"std", StdToJson(b.covariance)},
          {"inliers", b.inliers},
          {"unconstrained", b.unconstrained},
          {"fixed", b.fixed}};
}

json FitToJson(const FitQuality& f) {
  return {{"noise_model", f.noise_source},
          {"noise",
           {{"sigma_along", f.noise.sigma_along},
            {"sigma_along_slope", f.noise.sigma_along_slope},
            {"sigma_along_offset", f.noise.sigma_along_offset},
            {"sigma_across_slope", f.noise.sigma_across_slope},
            {"sigma_across_offset", f.noise.sigma_across_offset}}},
          {"noise_scale", f.noise_scale},
          {"variance_factor", f.variance_factor},
          {"degrees_of_freedom", f.degrees_of_freedom},
          {"chi2_z", f.chi2_z},
          {"robust_scale", f.robust_scale},
          {"within_1sigma", f.within_1sigma},
          {"consistent", f.consistent},
          {"message", f.message}};
}

void SaveSweep(const std::string& path, const SweepRecording& sweep, bool raw_stamps) {
  experiments::AtomicOfstream out(path);
  WriteSweep(out, sweep, raw_stamps);
  out.Commit();
}

}  // namespace ifab
