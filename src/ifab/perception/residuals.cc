#include "ifab/perception/residuals.h"

#include <cmath>

namespace ifab {
namespace {

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

}  // namespace

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

int PointResidualAnalytic(const PointMatch& m, const ScenePrimitive* primitive, const RayT<double>& ray,
                          const PoseJacobianData& X, double* r, double* jacobian) {
  return PointResidualAnalytic(m, primitive, ray, X, r, jacobian, nullptr);
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

int PointResidualAnalytic(const PointMatch& m, const ScenePrimitive* primitive, const RayT<double>& ray,
                          const PoseJacobianData& X, double* r, double* jacobian, RayJacobian* ray_jacobian) {
  using RowJ = Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor>;
  using Row3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
  // For the point-based errors: d r / d origin = d r / d p, d r / d direction = range d r / d p.
  auto point_jacobian = [&](const Row3& dr_dp) {
    if (!ray_jacobian) return;
    const Eigen::Index n = dr_dp.rows();
    Eigen::Map<Row3>(ray_jacobian->d_origin, n, 3) = dr_dp;
    Eigen::Map<Row3>(ray_jacobian->d_direction, n, 3) = ray.range * dr_dp;
  };
  // Derivatives with R = Exp(w) R0: d(R a)/dw = -[R a]x J_l, d(R^T b)/dw = R^T [b]x J_l.
  switch (m.kind) {
    case PointMatch::Kind::kNone:
      return 0;
    case PointMatch::Kind::kRange: {
      const Eigen::Vector3d n = X.R * m.normal_body;
      const double c = n.dot(ray.direction);
      const double predicted = (m.offset_body + n.dot(X.t - ray.origin)) / c;
      r[0] = (ray.range - predicted) * m.inv_sigma;
      if (jacobian) {
        // d predicted/dt = n / c; d predicted/dn = (t - x_predicted) / c; dn/dw = -[n]x J_l.
        const Eigen::Vector3d x_predicted = ray.origin + predicted * ray.direction;
        Eigen::Map<Eigen::Matrix<double, 1, 6>> J(jacobian);
        J.head<3>() = -m.inv_sigma / c * n.transpose();
        J.tail<3>() = m.inv_sigma / c * (X.t - x_predicted).transpose() * Skew(n) * X.left_jacobian;
      }
      if (ray_jacobian) {
        // d predicted/d origin = -n / c; d predicted/d direction = -predicted n / c.
        Eigen::Map<Eigen::Vector3d>(ray_jacobian->d_origin) = m.inv_sigma / c * n;
        Eigen::Map<Eigen::Vector3d>(ray_jacobian->d_direction) = m.inv_sigma * predicted / c * n;
      }
      return 1;
    }
    case PointMatch::Kind::kPlane: {
      const Eigen::Vector3d q = ray.Point() - X.t;
      r[0] = (m.normal_body.dot(X.R.transpose() * q) - m.offset_body) * m.inv_sigma;
      if (jacobian) {
        const Eigen::Vector3d n = X.R * m.normal_body;
        Eigen::Map<Eigen::Matrix<double, 1, 6>> J(jacobian);
        J.head<3>() = -m.inv_sigma * n.transpose();
        J.tail<3>() = m.inv_sigma * n.transpose() * Skew(q) * X.left_jacobian;
      }
      if (ray_jacobian) point_jacobian(Row3(m.inv_sigma * (X.R * m.normal_body).transpose()));
      return 1;
    }
    case PointMatch::Kind::kClosest: {
      const Eigen::Vector3d q = ray.Point() - X.t;
      const Eigen::Vector3d p_body = X.R.transpose() * q;
      const Pose3& T_pb = primitive->T_primitive_body;
      const Eigen::Matrix3d& R_bp = primitive->T_body_primitive.linear();
      const ClosestPointJacobian cj = ClosestWithJacobian(primitive->primitive, T_pb * p_body);
      const Eigen::Vector3d e_base = X.R * (R_bp * (T_pb * p_body - cj.closest.point));
      Eigen::Map<Eigen::Vector3d> residual(r);
      residual = m.sqrt_information * e_base;
      if (jacobian || ray_jacobian) {
        // de/dp in base: A = R R_bp (I - dcp/dp) R_pb R^T.
        const Eigen::Matrix3d A =
            X.R * R_bp * (Eigen::Matrix3d::Identity() - cj.d_point_d_query) * T_pb.linear() * X.R.transpose();
        if (jacobian) {
          Eigen::Map<RowJ> J(jacobian, 3, 6);
          J.leftCols<3>() = -m.sqrt_information * A;
          J.rightCols<3>() = m.sqrt_information * (A * Skew(q) - Skew(e_base)) * X.left_jacobian;
        }
        point_jacobian(Row3(m.sqrt_information * A));
      }
      return 3;
    }
  }
  return 0;
}

}  // namespace ifab
