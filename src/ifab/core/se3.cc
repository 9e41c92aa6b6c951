#include "ifab/core/se3.h"

#include <cmath>

namespace ifab {

Eigen::Matrix3d RotationFromRpy(double roll, double pitch, double yaw) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Vector3d RpyFromRotation(const Eigen::Matrix3d& r) {
  const double pitch = std::asin(std::clamp(-r(2, 0), -1.0, 1.0));
  double roll, yaw;
  if (std::abs(std::cos(pitch)) > 1e-9) {
    roll = std::atan2(r(2, 1), r(2, 2));
    yaw = std::atan2(r(1, 0), r(0, 0));
  } else {  // gimbal lock: put everything into yaw
    roll = 0.0;
    yaw = std::atan2(-r(0, 1), r(1, 1));
  }
  return {roll, pitch, yaw};
}

Pose3 PoseFromXyzRpy(double x, double y, double z, double roll, double pitch, double yaw) {
  Pose3 pose = Pose3::Identity();
  pose.linear() = RotationFromRpy(roll, pitch, yaw);
  pose.translation() = Eigen::Vector3d(x, y, z);
  return pose;
}

Pose3 PoseFromXyzRpy(const std::array<double, 6>& v) {
  return PoseFromXyzRpy(v[0], v[1], v[2], v[3], v[4], v[5]);
}

std::array<double, 6> XyzRpyFromPose(const Pose3& pose) {
  const Eigen::Vector3d t = pose.translation();
  const Eigen::Vector3d rpy = RpyFromRotation(pose.linear());
  return {t.x(), t.y(), t.z(), rpy.x(), rpy.y(), rpy.z()};
}

Eigen::Vector3d LogSO3(const Eigen::Matrix3d& r) {
  const Eigen::AngleAxisd aa(r);
  return aa.axis() * aa.angle();
}

Eigen::Matrix3d ExpSO3(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  if (angle < 1e-15) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

Pose3 Interpolate(const Pose3& a, const Pose3& b, double s) {
  const Eigen::Quaterniond qa(a.linear()), qb(b.linear());
  Pose3 out = Pose3::Identity();
  out.linear() = qa.slerp(s, qb).toRotationMatrix();
  out.translation() = (1.0 - s) * a.translation() + s * b.translation();
  return out;
}

double TranslationDistance(const Pose3& a, const Pose3& b) {
  return (a.translation() - b.translation()).norm();
}

double RotationAngle(const Pose3& a, const Pose3& b) {
  return Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle();
}

}  // namespace ifab
