#pragma once
/// \file
/// Spatial rigid transforms on Eigen::Isometry3d. T_a_b maps points in frame b into frame a:
/// p_a = T_a_b * p_b. Roll-pitch-yaw are the URDF convention: R = Rz(yaw) Ry(pitch) Rx(roll).

#include <Eigen/Geometry>
#include <array>

namespace ifab {

using Pose3 = Eigen::Isometry3d;

/// Rotation from URDF roll, pitch, yaw (fixed axes x, y, z).
Eigen::Matrix3d RotationFromRpy(double roll, double pitch, double yaw);

/// Roll, pitch, yaw of a rotation (pitch in [-pi/2, pi/2]).
Eigen::Vector3d RpyFromRotation(const Eigen::Matrix3d& r);

/// Pose from translation and URDF roll-pitch-yaw.
Pose3 PoseFromXyzRpy(double x, double y, double z, double roll, double pitch, double yaw);
Pose3 PoseFromXyzRpy(const std::array<double, 6>& xyzrpy);

/// (x, y, z, roll, pitch, yaw) of a pose.
std::array<double, 6> XyzRpyFromPose(const Pose3& pose);

/// The cross-product matrix [v]x: Skew(v) * u == v.cross(u).
inline Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

/// Rotation vector (axis * angle) of a rotation matrix, and back (SO(3) log/exp).
Eigen::Vector3d LogSO3(const Eigen::Matrix3d& r);
Eigen::Matrix3d ExpSO3(const Eigen::Vector3d& w);

/// Pose between a and b at s in [0, 1]: linear in translation, slerp in rotation.
Pose3 Interpolate(const Pose3& a, const Pose3& b, double s);

/// Translation distance [m] and rotation angle [rad] between two poses.
double TranslationDistance(const Pose3& a, const Pose3& b);
double RotationAngle(const Pose3& a, const Pose3& b);

}  // namespace ifab
