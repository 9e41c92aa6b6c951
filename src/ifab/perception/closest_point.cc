#include "ifab/perception/closest_point.h"

#include <cmath>
#include <limits>

namespace ifab {
namespace {

Eigen::Matrix3d FaceJacobian(const Eigen::Vector3d& n) {
  return Eigen::Matrix3d::Identity() - n * n.transpose();
}

ClosestPointJacobian PolygonJacobian(const ConvexPolygon& poly, const Eigen::Vector3d& p) {
  ClosestPointJacobian out;
  out.closest = Closest(poly, p);
  switch (out.closest.feature) {
    case Feature::kFace:
      out.d_point_d_query = FaceJacobian(poly.normal());
      break;
    case Feature::kVertex:
      out.d_point_d_query.setZero();
      break;
    case Feature::kEdge: {
      // The edge the closest point lies on: the one nearest to it.
      const auto& v = poly.vertices();
      double best = std::numeric_limits<double>::infinity();
      Eigen::Vector3d direction = Eigen::Vector3d::UnitX();
      for (std::size_t i = 0; i < v.size(); ++i) {
        const Eigen::Vector3d a = v[i], b = v[(i + 1) % v.size()];
        const Eigen::Vector3d e = (b - a).normalized();
        const Eigen::Vector3d r = out.closest.point - a;
        const double d = (r - r.dot(e) * e).norm();
        if (d < best) {
          best = d;
          direction = e;
        }
      }
      out.d_point_d_query = direction * direction.transpose();
      break;
    }
  }
  return out;
}

ClosestPointJacobian BoxJacobian(const Box& box, const Eigen::Vector3d& p) {
  ClosestPointJacobian out;
  out.closest = Closest(box, p);
  const Eigen::Vector3d h = 0.5 * box.size;
  const bool inside = (p.cwiseAbs().array() <= h.array()).all();
  if (inside) {
    out.d_point_d_query = FaceJacobian(out.closest.normal);
  } else {
    for (int k = 0; k < 3; ++k) out.d_point_d_query(k, k) = std::abs(p[k]) <= h[k] ? 1.0 : 0.0;
  }
  return out;
}

}  // namespace

ClosestPointJacobian ClosestWithJacobian(const Primitive& primitive, const Eigen::Vector3d& p) {
  return std::visit(
      [&](const auto& g) -> ClosestPointJacobian {
        using G = std::decay_t<decltype(g)>;
        if constexpr (std::is_same_v<G, Plane>) {
          ClosestPointJacobian out;
          out.closest = Closest(g, p);
          out.d_point_d_query = FaceJacobian(g.normal);
          return out;
        } else if constexpr (std::is_same_v<G, ConvexPolygon>) {
          return PolygonJacobian(g, p);
        } else {
          return BoxJacobian(g, p);
        }
      },
      primitive);
}

}  // namespace ifab
