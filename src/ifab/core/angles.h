#pragma once
/// \file Angle helpers (radians).

#include <cmath>
#include <numbers>

namespace ifab {

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kDeg = kPi / 180.0;  ///< one degree [rad]

/// Wrap an angle to (-pi, pi]. Templated so Ceres Jets pass through.
template <typename T>
T WrapAngle(const T& a) {
  using std::atan2;
  using std::cos;
  using std::sin;
  return atan2(sin(a), cos(a));
}

constexpr double DegToRad(double deg) { return deg * kPi / 180.0; }
constexpr double RadToDeg(double rad) { return rad * 180.0 / kPi; }

}  // namespace ifab
