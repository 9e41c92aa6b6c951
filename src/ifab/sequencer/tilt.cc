#include "ifab/sequencer/tilt.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "ifab/perception/registration.h"

namespace ifab::sequencer {

std::optional<Eigen::Vector3d> MeanUp(const std::vector<AccelSample>& samples, Seconds t0, Seconds t1,
                                      int min_samples) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int n = 0;
  for (const AccelSample& s : samples) {
    if (s.stamp.t < t0 || s.stamp.t > t1) continue;
    sum += s.specific_force;
    ++n;
  }
  if (n < min_samples || sum.norm() < 1e-9) return std::nullopt;
  return Eigen::Vector3d(sum.normalized());
}

Eigen::Matrix3d TiltChange(const Eigen::Vector3d& up_ref, const Eigen::Vector3d& up_now) {
  // up_now = R^T up_ref (the same world up seen from the turned base), so R maps up_now to up_ref.
  return Eigen::Quaterniond::FromTwoVectors(up_now.normalized(), up_ref.normalized()).toRotationMatrix();
}

Pose3 CompensateTilt(const Pose3& T_site_base_ref, const Eigen::Vector3d& up_ref, const Eigen::Vector3d& up_now) {
  Pose3 delta = Pose3::Identity();
  delta.linear() = TiltChange(up_ref, up_now);
  return T_site_base_ref * delta;
}

bool LevelSweepPoints(std::vector<SweepPoint>& points, const std::vector<AccelSample>& accel,
                      const Eigen::Vector3d& up_ref, double half_window) {
  if (points.empty()) return true;
  // One attitude per scan (a scan lasts 25 ms; the base rocks over seconds).
  std::vector<std::pair<int, Eigen::Matrix3d>> per_scan;
  for (const SweepPoint& p : points) {
    if (!per_scan.empty() && per_scan.back().first == p.scan) continue;
    const auto up = MeanUp(accel, p.t - half_window, p.t + half_window, 5);
    if (!up) return false;
    per_scan.emplace_back(p.scan, TiltChange(up_ref, *up));
  }
  std::size_t k = 0;
  for (SweepPoint& p : points) {
    while (per_scan[k].first != p.scan) ++k;
    p.T_base_tool0.linear() = per_scan[k].second * p.T_base_tool0.linear();
    p.T_base_tool0.translation() = per_scan[k].second * p.T_base_tool0.translation();
  }
  return true;
}

double TiltAngle(const Eigen::Vector3d& up_a, const Eigen::Vector3d& up_b) {
  return std::acos(std::clamp(up_a.normalized().dot(up_b.normalized()), -1.0, 1.0));
}

Pose3 LevelledPose(const Pose3& T_site_base, const Eigen::Vector3d& up_base) {
  const double heading = XyzRpyFromPose(T_site_base)[5];
  Pose3 out = Pose3::Identity();
  // R up_base = e_z; the smallest such tilt, then the heading about the vertical.
  out.linear() = Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                 Eigen::Quaterniond::FromTwoVectors(up_base.normalized(), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  out.translation() = T_site_base.translation();
  return out;
}

Eigen::Matrix<double, 6, 6> WithHeldTiltCovariance(const Pose3& T_base_site, Eigen::Matrix<double, 6, 6> covariance,
                                                   double tilt_sigma) {
  for (int k : {3, 4}) {
    covariance.row(k).setZero();
    covariance.col(k).setZero();
    covariance(k, k) = tilt_sigma * tilt_sigma;
  }
  return InverseCovariance(T_base_site, covariance);
}

}  // namespace ifab::sequencer
