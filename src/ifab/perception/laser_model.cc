#include "ifab/perception/laser_model.h"

#include <Eigen/Geometry>
#include <cmath>

#include "ifab/core/config.h"

namespace ifab {

Eigen::Vector3d AnyPerpendicular(const Eigen::Vector3d& u) {
  // Cross with the axis least aligned with u.
  Eigen::Index k = 0;
  u.cwiseAbs().minCoeff(&k);
  return u.cross(Eigen::Vector3d::Unit(k)).normalized();
}

Eigen::Matrix3d LaserNoiseModel::SqrtInformation(const Eigen::Vector3d& ray, double range) const {
  const Eigen::Vector3d v1 = AnyPerpendicular(ray);
  const Eigen::Vector3d v2 = ray.cross(v1);
  const double across = SigmaAcross(range);
  Eigen::Matrix3d s;
  s.row(0) = ray.transpose() / SigmaAlong(range);
  s.row(1) = v1.transpose() / across;
  s.row(2) = v2.transpose() / across;
  return s;
}

double LaserNoiseModel::NormalVariance(const Eigen::Vector3d& ray, double range,
                                       const Eigen::Vector3d& n) const {
  const double c2 = std::min(1.0, std::pow(ray.dot(n), 2));
  const double across = SigmaAcross(range);
  const double along = SigmaAlong(range);
  return along * along * c2 + across * across * (1.0 - c2);
}

LaserNoiseModel LaserNoiseModel::Scaled(double k) const {
  LaserNoiseModel m = *this;
  m.sigma_along *= k;
  m.sigma_along_slope *= k;
  m.sigma_along_offset *= k;
  m.sigma_across_slope *= k;
  m.sigma_across_offset *= k;
  return m;
}

LaserNoiseModel LaserNoiseModel::FromConfig(const ConfigNode& c, LaserNoiseModel m) {
  c.ExpectKeys({"sigma_along", "sigma_along_slope", "sigma_along_offset", "sigma_across_slope", "sigma_across_offset"});
  c.ReadPositive("sigma_along", m.sigma_along);
  c.ReadNonNegative("sigma_along_slope", m.sigma_along_slope);
  c.Read("sigma_along_offset", m.sigma_along_offset);
  c.ReadNonNegative("sigma_across_slope", m.sigma_across_slope);
  c.ReadPositive("sigma_across_offset", m.sigma_across_offset);
  return m;
}

}  // namespace ifab
