#pragma once
/// \file
/// Point types shared by scan assembly, registration, calibration and PLY I/O.

#include <Eigen/Core>
#include <Eigen/StdVector>
#include <string>
#include <vector>

#include "ifab/core/se3.h"

namespace ifab {

/// A laser point in the robot base frame with the laser's centre when it was measured, which
/// gives its ray (direction of the largest noise, Sec. V-B, and the shadow test).
struct RayPoint {
  Eigen::Vector3d p{Eigen::Vector3d::Zero()};       ///< p_base [m]
  Eigen::Vector3d origin{Eigen::Vector3d::Zero()};  ///< laser centre in base [m]

  double Range() const { return (p - origin).norm(); }
  Eigen::Vector3d Ray() const { return (p - origin).normalized(); }
};

/// A raw laser point of an arm sweep with the flange pose at its own time (eq. 6 before the
/// laser mount is applied): p_base = T_base_tool0 * T_tool0_laser * p_laser.
struct SweepPoint {
  Eigen::Vector3d p_laser{Eigen::Vector3d::Zero()};  ///< in the laser frame (scan plane z = 0)
  Pose3 T_base_tool0{Pose3::Identity()};             ///< flange at the beam's time stamp
  Eigen::Matrix<double, 6, 1> q{Eigen::Matrix<double, 6, 1>::Zero()};  ///< joint angles then [rad]
  double t{0.0};                                     ///< beam time stamp (host clock) [s]
  int scan{0};                                       ///< index of its scan in the sweep
  int beam{0};                                       ///< beam index in its scan
};

/// Eq. 6 for every point: the cloud in the base frame with each point's ray origin.
std::vector<RayPoint> ToBaseFrame(const std::vector<SweepPoint>& points, const Pose3& T_tool0_laser);

/// A point cloud as read from or written to PLY: positions plus named per-point scalar fields.
struct PointCloud {
  struct Field {
    std::string name;
    std::vector<double> values;  ///< one per point
  };
  std::vector<Eigen::Vector3d> points;
  std::vector<Field> fields;

  std::size_t size() const { return points.size(); }
  /// The field of that name, or nullptr.
  const std::vector<double>* Find(const std::string& name) const;
  /// Add (or replace) a field; values.size() must equal size().
  void SetField(const std::string& name, std::vector<double> values);
};

/// A cloud of RayPoints as a PointCloud with fields origin_x, origin_y, origin_z.
PointCloud ToPointCloud(const std::vector<RayPoint>& points);
/// RayPoints from a PointCloud with origin_x/y/z fields, or all with one origin if it lacks them
/// and `fallback_origin` is given. Throws InputError (naming `what`) if neither.
std::vector<RayPoint> ToRayPoints(const PointCloud& cloud, const std::string& what,
                                  const Eigen::Vector3d* fallback_origin = nullptr);

}  // namespace ifab
