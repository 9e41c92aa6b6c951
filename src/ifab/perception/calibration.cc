#include "ifab/perception/calibration.h"

#include <Eigen/SVD>
#include <fmt/format.h>

#include <chrono>
#include <cmath>

#include "ifab/core/config.h"
#include "ifab/perception/pose_solver.h"

namespace ifab {

CalibrationOptions CalibrationOptions::FromConfig(const ConfigNode& c, CalibrationOptions o) {
  c.ExpectKeys({"registration", "laser_extent", "autodiff"});
  if (auto r = c.Find("registration")) o.registration = RegistrationOptions::FromConfig(*r, o.registration);
  c.ReadPositive("laser_extent", o.laser_extent);
  c.Read("autodiff", o.autodiff);
  return o;
}

std::string CalibrationSummary::BriefReport() const {
  const auto v = XyzRpyFromPose(T_tool0_laser);
  std::string s = fmt::format(
      "calibration {} ({}): T_tool0_laser [{:.4f} {:.4f} {:.4f}] m [{:.3f} {:.3f} {:.3f}] deg, std [{:.2f} {:.2f} "
      "{:.2f}] mm [{:.3f} {:.3f} {:.3f}] deg; {} points, {} inliers, {} shadow removed, rms {:.2f} sigma, {} steps, "
      "{:.2f} s; noise: {}; fit: {}",
      ToString(status), message, v[0], v[1], v[2], v[3] * 180 / M_PI, v[4] * 180 / M_PI, v[5] * 180 / M_PI,
      1e3 * std::sqrt(covariance(0, 0)), 1e3 * std::sqrt(covariance(1, 1)), 1e3 * std::sqrt(covariance(2, 2)),
      std::sqrt(covariance(3, 3)) * 180 / M_PI, std::sqrt(covariance(4, 4)) * 180 / M_PI,
      std::sqrt(covariance(5, 5)) * 180 / M_PI, num_points, num_inliers, num_shadow_removed, rms_whitened, iterations,
      seconds, fit.noise_source, fit.message);
  for (const auto& w : warnings) s += "\n  warning: " + w;
  return s;
}

CalibrationSummary CalibrateLaserMount(const std::vector<CalibrationSweep>& sweeps,
                                       const std::vector<RegistrationBody>& bodies, const Pose3& T_tool0_laser_guess,
                                       const CalibrationOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<SweepPoint> all;
  std::vector<std::size_t> sweep_of;
  for (std::size_t k = 0; k < sweeps.size(); ++k) {
    all.insert(all.end(), sweeps[k].points.begin(), sweeps[k].points.end());
    sweep_of.insert(sweep_of.end(), sweeps[k].points.size(), k);
  }
  internal::PoseProblemInput input;
  input.sweep = &all;
  input.T_tool0_laser = T_tool0_laser_guess;
  input.laser_extent = options.laser_extent;
  input.autodiff = options.autodiff;
  const internal::PoseProblemOutput r = internal::SolvePoseProblem(input, bodies, options.registration);

  CalibrationSummary s;
  s.status = r.summary.status;
  s.message = r.summary.message;
  s.iterations = r.summary.iterations;
  s.cost = r.summary.cost;
  s.seconds = r.summary.seconds;
  s.T_tool0_laser = r.T_tool0_laser;
  s.covariance = r.laser_covariance;
  s.unconstrained = r.laser_unconstrained;
  s.bodies = r.summary.bodies;
  s.num_points = r.summary.num_points;
  s.num_inliers = r.summary.num_inliers;
  s.num_shadow_removed = r.summary.num_shadow_removed;
  s.rms_whitened = r.summary.rms_whitened;
  s.fit = r.summary.fit;
  s.warnings = r.summary.warnings;
  s.sweep_inliers.assign(sweeps.size(), 0);
  for (std::size_t i = 0; i < r.summary.labels.size(); ++i)
    s.sweep_inliers[sweep_of[i]] += r.summary.labels[i] == PointLabel::kInlier;
  for (std::size_t k = 0; k < sweeps.size(); ++k)
    if (s.sweep_inliers[k] == 0)
      s.warnings.push_back(fmt::format("sweep '{}' has no point on the target", sweeps[k].name));
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return s;
}

std::vector<RegistrationBody> CubeOnGroundBodies(double size, const Pose3& T_base_cube, double ground_z) {
  Pose3 T_base_ground = Pose3::Identity();
  T_base_ground.translation().z() = ground_z;
  RigidObject ground{"ground", Pose3::Identity(), {Plane{Eigen::Vector3d::UnitZ(), 0.0}}};
  RigidObject cube{"cube", Pose3::Identity(), {Box{Eigen::Vector3d::Constant(size)}}};
  return {{"ground", T_base_ground, {ground}, true}, {"cube", T_base_cube, {cube}, true}};
}

Pose3 AveragePoses(const std::vector<Pose3>& poses) {
  IFAB_CHECK(!poses.empty());
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  for (const auto& p : poses) {
    t += p.translation();
    m += p.linear();
  }
  // Nearest rotation to the mean matrix (chordal L2 mean).
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d r = svd.matrixU() * svd.matrixV().transpose();
  if (r.determinant() < 0) {
    Eigen::Matrix3d u = svd.matrixU();
    u.col(2) *= -1;
    r = u * svd.matrixV().transpose();
  }
  Pose3 out = Pose3::Identity();
  out.linear() = r;
  out.translation() = t / static_cast<double>(poses.size());
  return out;
}

}  // namespace ifab
