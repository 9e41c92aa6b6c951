#pragma once
/// \file
/// Plain sensor and command messages. Each sensor message carries the device's own time stamp
/// (`t_device`, on the device clock, with its offset and skew) and the host time at which the
/// packet was received (`t_host_received`, late by a variable transport delay). The sync module
/// maps device time to host time; algorithms use `t` (host time) once it is filled in.

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "ifab/core/time.h"

namespace ifab {

/// Device identifiers used in stamps and sync pulses.
enum class DeviceId : std::uint8_t { kBaseLaser = 0, kArmLaser = 1, kGyro = 2, kArm = 3 };
const char* DeviceName(DeviceId id);

/// Common stamping of every sensor packet.
struct Stamp {
  Seconds t{0.0};                ///< host time of the measurement (after clock sync)
  Seconds t_device{0.0};         ///< time stamp on the device's own clock
  Seconds t_host_received{0.0};  ///< host time the packet arrived (late, with jitter)
  std::uint64_t sequence{0};     ///< packet counter, matches the SyncPulse of the same number
};

/// One sweep of a 2D laser range finder (Hokuyo UTM-30LX style). Beam i has angle
/// angle_min + i * angle_increment in the laser frame (x forward, rotating about z) and was
/// measured at stamp.t + i * time_increment. A beam with no return holds NaN.
struct LaserScan {
  Stamp stamp;
  double angle_min{0.0};        ///< [rad]
  double angle_increment{0.0};  ///< [rad]
  double time_increment{0.0};   ///< [s] between consecutive beams
  double range_min{0.1};        ///< [m]
  double range_max{30.0};       ///< [m]
  std::vector<double> ranges;   ///< [m], NaN = no return

  static constexpr double kNoReturn = std::numeric_limits<double>::quiet_NaN();

  std::size_t size() const { return ranges.size(); }
  double Angle(std::size_t i) const { return angle_min + static_cast<double>(i) * angle_increment; }
  double BeamTime(std::size_t i) const { return stamp.t + static_cast<double>(i) * time_increment; }
  bool IsValid(std::size_t i) const {
    const double r = ranges[i];
    return std::isfinite(r) && r >= range_min && r <= range_max;
  }
  /// Time of the middle beam (the paper treats a base scan as rigid at this time).
  double MidTime() const { return BeamTime(ranges.empty() ? 0 : (ranges.size() - 1) / 2); }
  /// Beam endpoint in the laser frame (z = 0 plane).
  Eigen::Vector3d Point(std::size_t i) const {
    const double a = Angle(i);
    return {ranges[i] * std::cos(a), ranges[i] * std::sin(a), 0.0};
  }
};

/// One gyro sample (Xsens MTi-G-700 style): angular rate about the sensor axes.
struct GyroSample {
  Stamp stamp;
  Eigen::Vector3d rate{Eigen::Vector3d::Zero()};  ///< [rad/s]
};

/// One accelerometer sample of the same IMU (MTi-G-700): specific force along the sensor axes
/// (at rest: +g along the up direction, so roll and pitch follow). Sent in the gyro's packet:
/// the same stamp and sync pulse as the GyroSample of that instant.
struct AccelSample {
  Stamp stamp;
  Eigen::Vector3d specific_force{Eigen::Vector3d::Zero()};  ///< [m/s^2]
};

/// Measured arm joint positions and velocities.
struct JointState {
  Stamp stamp;
  Eigen::Matrix<double, 6, 1> q{Eigen::Matrix<double, 6, 1>::Zero()};   ///< [rad]
  Eigen::Matrix<double, 6, 1> qd{Eigen::Matrix<double, 6, 1>::Zero()};  ///< [rad/s]
};

/// Speed references for the left and right track [m/s], forward positive.
struct TrackCommand {
  Seconds t{0.0};
  double v_left{0.0};
  double v_right{0.0};
};

/// A joint position trajectory for the arm's own controller; times relative to its start.
struct JointTrajectory {
  struct Point {
    Seconds t{0.0};
    Eigen::Matrix<double, 6, 1> q{Eigen::Matrix<double, 6, 1>::Zero()};
    Eigen::Matrix<double, 6, 1> qd{Eigen::Matrix<double, 6, 1>::Zero()};
  };
  std::vector<Point> points;
  Seconds Duration() const { return points.empty() ? 0.0 : points.back().t; }
};

/// A digital sync pulse from a device, time stamped by the host's acquisition system.
/// Pulse k is emitted when the device stamps packet k, so (packet.t_device, pulse.t_host)
/// pairs relate the two clocks (TICSync-style).
struct SyncPulse {
  DeviceId device{DeviceId::kBaseLaser};
  std::uint64_t sequence{0};
  Seconds t_host{0.0};
};

}  // namespace ifab
