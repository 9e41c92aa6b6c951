#include "ifab/base/estimator/motion_prior.h"

#include <fmt/format.h>

#include <cmath>

#include "ifab/core/error.h"

namespace ifab::base {

OdometryNoise OdometryNoise::FromConfig(const ConfigNode& node, const OdometryNoise& defaults) {
  OdometryNoise n = defaults;
  node.ExpectKeys({"translation_per_m", "lateral_per_m", "translation_per_rad", "rotation_per_m",
                   "rotation_per_rad", "translation_floor", "rotation_floor"});
  node.ReadNonNegative("translation_per_m", n.translation_per_m);
  node.ReadNonNegative("lateral_per_m", n.lateral_per_m);
  node.ReadNonNegative("translation_per_rad", n.translation_per_rad);
  node.ReadNonNegative("rotation_per_m", n.rotation_per_m);
  node.ReadNonNegative("rotation_per_rad", n.rotation_per_rad);
  node.ReadPositive("translation_floor", n.translation_floor);
  node.ReadPositive("rotation_floor", n.rotation_floor);
  const std::string problem = n.Validate();
  if (!problem.empty()) ThrowInputError("{}: {}", node.Where(), problem);
  return n;
}

std::string OdometryNoise::Validate() const {
  if (!(translation_floor > 0.0) || !(rotation_floor > 0.0)) {
    return "translation_floor and rotation_floor must be positive (a step is never exact)";
  }
  if (translation_per_m < 0.0 || lateral_per_m < 0.0 || translation_per_rad < 0.0 ||
      rotation_per_m < 0.0 || rotation_per_rad < 0.0) {
    return "the odometry noise coefficients must be >= 0";
  }
  return {};
}

Eigen::Matrix3d StepCovariance(const Pose2& step, const OdometryNoise& n) {
  const double d = std::hypot(step.x, step.y);
  const double a = std::abs(WrapAngle(step.theta));
  const double s_along = n.translation_per_m * d + n.translation_per_rad * a + n.translation_floor;
  const double s_across = n.lateral_per_m * d + n.translation_per_rad * a + n.translation_floor;
  const double s_rot = n.rotation_per_m * d + n.rotation_per_rad * a + n.rotation_floor;
  // Along / across the direction of travel (the x axis when not moving).
  Eigen::Matrix2d R = Eigen::Matrix2d::Identity();
  if (d > 1e-9) {
    const double c = step.x / d, s = step.y / d;
    R << c, -s, s, c;
  }
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  cov.topLeftCorner<2, 2>() =
      R * Eigen::Vector2d(s_along * s_along, s_across * s_across).asDiagonal() * R.transpose();
  cov(2, 2) = s_rot * s_rot;
  return cov;
}

Eigen::Matrix3d StepCovarianceInWorld(const Pose2& T_world_prev, const Eigen::Matrix3d& cov_step) {
  Eigen::Matrix3d J = Eigen::Matrix3d::Identity();
  J.topLeftCorner<2, 2>() = T_world_prev.rotation();
  return J * cov_step * J.transpose();
}

}  // namespace ifab::base
