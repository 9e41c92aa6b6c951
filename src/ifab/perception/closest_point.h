#pragma once
/// \file
/// Closest points on primitives with their derivative with respect to the query point, and the
/// offset p - cp(p, g) of eq. 7 for plain doubles and for Ceres Jets. The Jet version evaluates
/// the closest point in double and carries the derivative part through the analytic Jacobian,
/// so autodiff through eq. 6 and 7 is exact without templating the geometry code.

#include <ceres/jet.h>

#include <Eigen/Core>

#include "ifab/model/geometry.h"

namespace ifab {

struct ClosestPointJacobian {
  ClosestPoint closest;
  /// d cp / d p (3x3): I - n n^T on a face, e e^T on an edge of direction e, 0 at a vertex; for a
  /// box seen from outside, the identity on the axes that are not clamped.
  Eigen::Matrix3d d_point_d_query{Eigen::Matrix3d::Zero()};
};

/// Closest point on a primitive (primitive frame) and its derivative.
ClosestPointJacobian ClosestWithJacobian(const Primitive& primitive, const Eigen::Vector3d& p);

/// p - cp(p, g) for a double query.
inline Eigen::Vector3d OffsetFromPrimitive(const Primitive& primitive, const Eigen::Vector3d& p) {
  return p - Closest(primitive, p).point;
}

/// p - cp(p, g) for a Jet query: value from Closest(), derivative (I - d cp/d p) times p's.
template <int N>
Eigen::Matrix<ceres::Jet<double, N>, 3, 1> OffsetFromPrimitive(
    const Primitive& primitive, const Eigen::Matrix<ceres::Jet<double, N>, 3, 1>& p) {
  const Eigen::Vector3d p0(p[0].a, p[1].a, p[2].a);
  const ClosestPointJacobian cj = ClosestWithJacobian(primitive, p0);
  const Eigen::Matrix3d projector = Eigen::Matrix3d::Identity() - cj.d_point_d_query;
  Eigen::Matrix<ceres::Jet<double, N>, 3, 1> e;
  for (int k = 0; k < 3; ++k) {
    e[k].a = p0[k] - cj.closest.point[k];
    e[k].v = projector(k, 0) * p[0].v + projector(k, 1) * p[1].v + projector(k, 2) * p[2].v;
  }
  return e;
}

}  // namespace ifab
