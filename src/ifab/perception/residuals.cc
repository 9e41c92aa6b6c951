#include "ifab/perception/residuals.h"

#include <cmath>

namespace ifab {
PoseJacobianData::PoseJacobianData(const double* x, const Eigen::Matrix3d& R0) {
  const Eigen::Vector3d w(x[3], x[4], x[5]);
  R = ExpSO3(w) * R0;
  t = Eigen::Vector3d(x[0], x[1], x[2]);
  const double th2 = w.squaredNorm();
  double a, b;  // (1 - cos th) / th^2, (th - sin th) / th^3
  if (th2 < 1e-8) {
    a = 0.5 - th2 / 24.0;
    b = 1.0 / 6.0 - th2 / 120.0;
  } else {
    const double th = std::sqrt(th2);
    a = (1.0 - std::cos(th)) / th2;
    b = (th - std::sin(th)) / (th2 * th);
  }
  const Eigen::Matrix3d W = Skew(w);
  left_jacobian = Eigen::Matrix3d::Identity() + a * W + b * W * W;
}


LaserRayJacobian LaserRayWithJacobian(const PoseJacobianData& X, const Pose3& T_base_tool0,
                                      const Eigen::Vector3d& p_laser) {
  LaserRayJacobian out;
  const double range = p_laser.norm();
  const Eigen::Vector3d u_tool0 = X.R * (p_laser / range);
  const Eigen::Matrix3d& R_bt = T_base_tool0.linear();
  out.ray.origin = T_base_tool0 * X.t;
  out.ray.direction = R_bt * u_tool0;
  out.ray.range = range;
  out.d_origin.setZero();
  out.d_origin.leftCols<3>() = R_bt;
  out.d_direction.setZero();
  out.d_direction.rightCols<3>() = -R_bt * Skew(u_tool0) * X.left_jacobian;
  return out;
}


}  // namespace ifab
