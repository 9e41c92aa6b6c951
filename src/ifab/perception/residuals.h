#pragma once
/// \file
/// The per-point error of registration (eq. 7) and calibration (eq. 6 inside eq. 7), templated on
/// the scalar so Ceres Jets pass through.
///
/// A body's pose is optimised as x = [t, w]: T_base_body = (Exp(w) R0, t), with R0 the rotation at
/// the start of the current correspondence step (so w stays small) and t the body origin in base.
///
/// Errors (PointMatch::Kind):
///  - kClosest (eq. 7 as written, Sigma read as the information matrix as the text intends):
///    r = S (p - cp(p, g*)), S^T S = Sigma_p^-1, Sigma_p the laser covariance rotated onto the ray;
///  - kRange (improvement): the measured range minus the range at which the point's ray meets the
///    plane of the face it hits, over sqrt(sigma_along^2 + sigma_across^2 tan^2(incidence)).
///    Unlike a point-to-plane distance, its expected square does not depend on the plane's tilt
///    (the noise is along the ray, not along the normal), so rotations come out unbiased; and
///    along-ray noise cannot push a point off a face's border or into a box onto the wrong face;
///  - kPlane: signed distance to a plane over sqrt(n^T Sigma_p n) (the fallback of kRange for a
///    ray that hits nothing: the tangent plane at the closest point).

#include <ceres/rotation.h>

#include <Eigen/Core>
#include <cstdint>

#include "ifab/perception/closest_point.h"
#include "ifab/perception/scene.h"

namespace ifab {

/// The frozen correspondence of one point for one correspondence step.
struct PointMatch {
  enum class Kind : std::uint8_t { kNone, kClosest, kRange, kPlane };
  Kind kind{Kind::kNone};
  int body{-1};
  int primitive{-1};  ///< Scene primitive index
  Eigen::Matrix3d sqrt_information{Eigen::Matrix3d::Zero()};  ///< S in base (kClosest)
  Eigen::Vector3d normal_body{Eigen::Vector3d::UnitZ()};      ///< plane n . x = offset in the body
  double offset_body{0.0};                                    ///< frame (kRange, kPlane)
  double inv_sigma{0.0};  ///< 1 / sigma of the range (kRange) or of the normal distance (kPlane)

  int NumResiduals() const { return kind == Kind::kClosest ? 3 : kind == Kind::kNone ? 0 : 1; }
};

template <typename T>
using Vector3T = Eigen::Matrix<T, 3, 1>;

/// R v for a double matrix and a T vector.
template <typename T>
Vector3T<T> Rotate(const Eigen::Matrix3d& r, const Vector3T<T>& v) {
  Vector3T<T> out;
  for (int i = 0; i < 3; ++i) out[i] = r(i, 0) * v[0] + r(i, 1) * v[1] + r(i, 2) * v[2];
  return out;
}

/// T p for a double pose and a T point.
template <typename T>
Vector3T<T> Transform(const Pose3& pose, const Vector3T<T>& p) {
  Vector3T<T> out = Rotate<T>(pose.linear(), p);
  for (int i = 0; i < 3; ++i) out[i] += pose.translation()[i];
  return out;
}

template <typename T>
T Dot(const Vector3T<T>& a, const Vector3T<T>& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/// A body pose T_base_body = (R, t) in scalar T, built once from x = [t, w] about R0 and used for
/// many points: R = Exp(w) R0. Written with plain loops: Eigen's generic product kernels do not
/// inline Jet arithmetic.
template <typename T>
struct PoseT {
  T R[3][3];
  T t[3];

  PoseT(const T* x, const Eigen::Matrix3d& R0) {
    T Rw[9];
    ceres::AngleAxisToRotationMatrix(x + 3, ceres::ColumnMajorAdapter3x3(Rw));
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) R[i][j] = Rw[i] * R0(0, j) + Rw[i + 3] * R0(1, j) + Rw[i + 6] * R0(2, j);
      t[i] = x[i];
    }
  }
  /// R v (v in T or double)
  template <typename S>
  Vector3T<T> Rotate(const Eigen::Matrix<S, 3, 1>& v) const {
    Vector3T<T> out;
    for (int i = 0; i < 3; ++i) out[i] = R[i][0] * v[0] + R[i][1] * v[1] + R[i][2] * v[2];
    return out;
  }
  /// R p + t
  Vector3T<T> Apply(const Vector3T<T>& p) const {
    Vector3T<T> out = Rotate(p);
    for (int i = 0; i < 3; ++i) out[i] += t[i];
    return out;
  }
  /// R^T (p - t)
  Vector3T<T> ApplyInverse(const Vector3T<T>& p) const {
    const T q[3] = {p[0] - t[0], p[1] - t[1], p[2] - t[2]};
    Vector3T<T> out;
    for (int i = 0; i < 3; ++i) out[i] = R[0][i] * q[0] + R[1][i] * q[1] + R[2][i] * q[2];
    return out;
  }
  Vector3T<T> Translation() const { return Vector3T<T>(t[0], t[1], t[2]); }
};

/// The pose x = [t, w] about R0 applied to a point: Exp(w) R0 p + t.
template <typename T>
Vector3T<T> BodyToBase(const T* x, const Eigen::Matrix3d& R0, const Vector3T<T>& p) {
  return PoseT<T>(x, R0).Apply(p);
}

/// Its inverse: R0^T Exp(-w) (p - t).
template <typename T>
Vector3T<T> BaseToBody(const T* x, const Eigen::Matrix3d& R0, const Vector3T<T>& p_base) {
  return PoseT<T>(x, R0).ApplyInverse(p_base);
}

/// A measured laser point as its ray: p = origin + range * direction (all in base).
template <typename T>
struct RayT {
  Vector3T<T> origin;
  Vector3T<T> direction;  ///< unit
  T range;
  Vector3T<T> Point() const { return origin + direction * range; }
};

/// Residual of one point against its match under the body pose X; writes NumResiduals() values to
/// r and returns that number. `primitive` is the matched scene primitive (kClosest).
template <typename T>
int PointResidual(const PointMatch& m, const ScenePrimitive* primitive, const RayT<T>& ray, const PoseT<T>& X,
                  T* r) {
  switch (m.kind) {
    case PointMatch::Kind::kNone:
      return 0;
    case PointMatch::Kind::kRange: {
      // Plane in base: n . x = offset + n . t. The ray meets it at range (offset + n.(t - o)) / n.u.
      const Vector3T<T> n = X.Rotate(m.normal_body);
      const Vector3T<T> t = X.Translation();
      const T predicted = (T(m.offset_body) + Dot<T>(n, t - ray.origin)) / Dot<T>(n, ray.direction);
      r[0] = (ray.range - predicted) * m.inv_sigma;
      return 1;
    }
    case PointMatch::Kind::kPlane: {
      const Vector3T<T> p_body = X.ApplyInverse(ray.Point());
      r[0] = (Dot<T>(Vector3T<T>(m.normal_body.cast<T>()), p_body) - m.offset_body) * m.inv_sigma;
      return 1;
    }
    case PointMatch::Kind::kClosest: {
      const Vector3T<T> p_body = X.ApplyInverse(ray.Point());
      const Vector3T<T> p_primitive = Transform<T>(primitive->T_primitive_body, p_body);
      const Vector3T<T> e_primitive = OffsetFromPrimitive(primitive->primitive, p_primitive);
      const Vector3T<T> e_base = X.Rotate(Rotate<T>(primitive->T_body_primitive.linear(), e_primitive));
      const Vector3T<T> w = Rotate<T>(m.sqrt_information, e_base);
      for (int i = 0; i < 3; ++i) r[i] = w[i];
      return 3;
    }
  }
  return 0;
}

/// Same, with the body pose given as x = [t, w] about R0.
template <typename T>
int PointResidual(const PointMatch& m, const ScenePrimitive* primitive, const RayT<T>& ray, const T* x,
                  const Eigen::Matrix3d& R0, T* r) {
  return PointResidual<T>(m, primitive, ray, PoseT<T>(x, R0), r);
}

/// The ray of a raw laser point through the mount X_laser (eq. 6): origin T_base_tool0 t_laser,
/// direction T_base_tool0 R_laser p_laser / |p_laser|, range |p_laser|.
template <typename T>
RayT<T> LaserRay(const PoseT<T>& X_laser, const Pose3& T_base_tool0, const Eigen::Vector3d& p_laser) {
  const double range = p_laser.norm();
  RayT<T> ray;
  ray.origin = Transform<T>(T_base_tool0, X_laser.Translation());
  ray.direction = Rotate<T>(T_base_tool0.linear(), X_laser.Rotate(Eigen::Vector3d(p_laser / range)));
  ray.range = T(range);
  return ray;
}

/// A body pose for analytic derivatives: R = Exp(w) R0, t, and the left Jacobian J_l(w) of SO(3)
/// (Exp(w + d) ~ Exp(J_l(w) d) Exp(w)).
struct PoseJacobianData {
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  Eigen::Matrix3d left_jacobian;
  PoseJacobianData(const double* x, const Eigen::Matrix3d& R0);
};

/// Derivatives of a point's residual with respect to its ray (n x 3 each, row-major), for the
/// analytic calibration path: d r / d origin and d r / d direction (range held fixed).
struct RayJacobian {
  double d_origin[9];
  double d_direction[9];
};

/// PointResidual for a fixed ray (registration) with its Jacobian with respect to x = [t, w]
/// computed analytically (row-major, NumResiduals() x 6; null to skip), and with ray_jacobian the
/// derivatives with respect to the ray. The same values as the autodiff path, several times
/// faster. Defined at the end of this header, so the solvers' loops over ~20k points inline it.
inline int PointResidualAnalytic(const PointMatch& m, const ScenePrimitive* primitive, const RayT<double>& ray,
                                 const PoseJacobianData& X, double* r, double* jacobian,
                                 RayJacobian* ray_jacobian = nullptr);

/// The ray of a raw laser point through the mount (eq. 6) with its derivatives with respect to
/// the mount parameters x = [t, w] (3 x 6 each): d origin / dx and d direction / dx.
struct LaserRayJacobian {
  RayT<double> ray;
  Eigen::Matrix<double, 3, 6> d_origin;
  Eigen::Matrix<double, 3, 6> d_direction;
};
LaserRayJacobian LaserRayWithJacobian(const PoseJacobianData& X_laser, const Pose3& T_base_tool0,
                                      const Eigen::Vector3d& p_laser);

namespace internal {
inline Eigen::Matrix3d SkewOf(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}
}  // namespace internal

inline int PointResidualAnalytic(const PointMatch& m, const ScenePrimitive* primitive, const RayT<double>& ray,
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
        J.tail<3>() = m.inv_sigma / c * (X.t - x_predicted).transpose() * internal::SkewOf(n) * X.left_jacobian;
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
        J.tail<3>() = m.inv_sigma * n.transpose() * internal::SkewOf(q) * X.left_jacobian;
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
          J.rightCols<3>() = m.sqrt_information * (A * internal::SkewOf(q) - internal::SkewOf(e_base)) * X.left_jacobian;
        }
        point_jacobian(Row3(m.sqrt_information * A));
      }
      return 3;
    }
  }
  return 0;
}

}  // namespace ifab
