#include "ifab/sequencer/floor_prior.h"

#include <Eigen/Cholesky>
#include <Eigen/Dense>
#include <algorithm>

namespace ifab::sequencer {

Pose3 FuseFloorPrior(const Pose3& T_site_base, const Eigen::Matrix<double, 6, 6>& covariance, const FloorPrior& prior) {
  // Measurement: the base's height and the horizontal part of its up axis, both zero-mean
  // around the floor; H is their Jacobian in the perturbation.
  const Eigen::Vector3d up = T_site_base.linear().col(2);
  Eigen::Matrix<double, 3, 6> H = Eigen::Matrix<double, 3, 6>::Zero();
  H(0, 2) = 1.0;
  // d up_xy / d w: Exp(w) up = up + w x up, and w x up = -[up]x w.
  H.block<1, 3>(1, 3) << 0.0, up.z(), -up.y();
  H.block<1, 3>(2, 3) << -up.z(), 0.0, up.x();
  const Eigen::Vector3d innovation(prior.ground_z - T_site_base.translation().z(), -up.x(), -up.y());
  const Eigen::Matrix3d R =
      Eigen::Vector3d(prior.height_sigma * prior.height_sigma, prior.tilt_sigma * prior.tilt_sigma,
                      prior.tilt_sigma * prior.tilt_sigma)
          .asDiagonal();
  const Eigen::Matrix<double, 6, 6> P = 0.5 * (covariance + covariance.transpose());
  const int rows = prior.on_tilt ? 3 : 1;  // the height alone when the prior leaves the tilt be
  const Eigen::MatrixXd Hr = H.topRows(rows);
  const Eigen::MatrixXd S = Hr * P * Hr.transpose() + R.topLeftCorner(rows, rows);
  const Eigen::Matrix<double, 6, 1> delta = P * Hr.transpose() * S.ldlt().solve(innovation.head(rows));
  Pose3 out = T_site_base;
  out.translation() += delta.head<3>();
  out.linear() = ExpSO3(delta.tail<3>()) * T_site_base.linear();
  return out;
}

Pose3 FuseFloorPriorPerComponent(const Pose3& T_site_base, const Eigen::Matrix<double, 6, 6>& covariance,
                                 const FloorPrior& prior) {
  const auto v = XyzRpyFromPose(T_site_base);
  auto fuse = [](double measured, double variance, double prior_mean, double prior_sigma) {
    const double w = prior_sigma * prior_sigma / (prior_sigma * prior_sigma + std::max(0.0, variance));
    return prior_mean + w * (measured - prior_mean);
  };
  const double var_tilt = 0.5 * (covariance(3, 3) + covariance(4, 4));  // about horizontal axes
  const double roll = prior.on_tilt ? fuse(v[3], var_tilt, 0.0, prior.tilt_sigma) : v[3];
  const double pitch = prior.on_tilt ? fuse(v[4], var_tilt, 0.0, prior.tilt_sigma) : v[4];
  return PoseFromXyzRpy(v[0], v[1], fuse(v[2], covariance(2, 2), prior.ground_z, prior.height_sigma), roll, pitch,
                        v[5]);
}

}  // namespace ifab::sequencer
