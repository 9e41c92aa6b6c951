#pragma once
/// \file
/// Planar rigid transforms for the base (x forward, y left, theta about z; REP-103).
/// Pose2 T_a_b maps points in frame b into frame a: p_a = T_a_b * p_b.

#include <Eigen/Core>
#include <cmath>
#include <ostream>

#include "ifab/core/angles.h"

namespace ifab {

/// SE(2) element, templated on the scalar so Ceres Jets can pass through.
template <typename T>
struct Pose2T {
  T x{0};      ///< translation along x [m]
  T y{0};      ///< translation along y [m]
  T theta{0};  ///< heading [rad]

  Pose2T() = default;
  Pose2T(T x_in, T y_in, T theta_in) : x(x_in), y(y_in), theta(theta_in) {}

  Eigen::Matrix<T, 2, 1> translation() const { return {x, y}; }

  Eigen::Matrix<T, 2, 2> rotation() const {
    using std::cos;
    using std::sin;
    Eigen::Matrix<T, 2, 2> r;
    r << cos(theta), -sin(theta), sin(theta), cos(theta);
    return r;
  }

  /// this * p: a point of the child frame expressed in the parent frame.
  Eigen::Matrix<T, 2, 1> operator*(const Eigen::Matrix<T, 2, 1>& p) const {
    using std::cos;
    using std::sin;
    const T c = cos(theta), s = sin(theta);
    return {c * p.x() - s * p.y() + x, s * p.x() + c * p.y() + y};
  }

  /// Composition: (T_a_b * T_b_c) = T_a_c.
  Pose2T operator*(const Pose2T& o) const {
    const Eigen::Matrix<T, 2, 1> t = (*this) * o.translation();
    return {t.x(), t.y(), WrapAngle(theta + o.theta)};
  }

  Pose2T inverse() const {
    using std::cos;
    using std::sin;
    const T c = cos(theta), s = sin(theta);
    return {-(c * x + s * y), -(-s * x + c * y), WrapAngle(-theta)};
  }

  template <typename U>
  Pose2T<U> cast() const {
    return {U(x), U(y), U(theta)};
  }

  /// Homogeneous 3x3 matrix.
  Eigen::Matrix<T, 3, 3> matrix() const {
    Eigen::Matrix<T, 3, 3> m = Eigen::Matrix<T, 3, 3>::Identity();
    m.template topLeftCorner<2, 2>() = rotation();
    m(0, 2) = x;
    m(1, 2) = y;
    return m;
  }
};

using Pose2 = Pose2T<double>;

inline std::ostream& operator<<(std::ostream& os, const Pose2& p) {
  return os << "(" << p.x << ", " << p.y << ", " << p.theta << ")";
}

/// Pose between a and b at fraction s in [0, 1]: linear in translation, shortest way in angle.
inline Pose2 Interpolate(const Pose2& a, const Pose2& b, double s) {
  const double dtheta = WrapAngle(b.theta - a.theta);
  return {a.x + s * (b.x - a.x), a.y + s * (b.y - a.y), WrapAngle(a.theta + s * dtheta)};
}

/// Distance in translation [m] and |heading difference| [rad].
inline double TranslationDistance(const Pose2& a, const Pose2& b) {
  return std::hypot(a.x - b.x, a.y - b.y);
}
inline double AngleDistance(const Pose2& a, const Pose2& b) {
  return std::abs(WrapAngle(a.theta - b.theta));
}

}  // namespace ifab
