#pragma once
/// \file
/// The simulated machine's parts, each a small model with its options (ground truth; sim only):
/// the tracked base with ICR slip and hydraulic lag, the gyro, device clocks, the arm servo.

#include <Eigen/Core>

#include "ifab/core/random.h"
#include "ifab/core/se2.h"
#include "ifab/model/robot_model.h"
#include "ifab/msgs/msgs.h"

namespace ifab {
class ConfigNode;
}

namespace ifab::sim {

/// A scalar Ornstein-Uhlenbeck process clipped to [lo, hi]: slip that wanders while driving.
struct Wander {
  double mean{0.0}, sigma{0.0}, tau{5.0}, lo{-1e9}, hi{1e9};
  double value{0.0};
  void Reset(RandomStream& rng) { value = std::clamp(mean + rng.Normal(sigma), lo, hi); }
  void Step(double dt, RandomStream& rng) {
    const double a = std::exp(-dt / tau);
    value = mean + a * (value - mean) + sigma * std::sqrt(1 - a * a) * rng.Normal();
    value = std::clamp(value, lo, hi);
  }
};

/// Skid-steer tracked base: ICR kinematics (Martinez et al. 2005) with a steering efficiency chi
/// (omega = chi (v_r - v_l) / B), a speed factor (v = s (v_l + v_r) / 2), a lateral slip from the
/// ICR's longitudinal offset, all wandering while the robot drives; each track follows its
/// speed reference with a first-order hydraulic lag and an acceleration limit.
struct TrackOptions {
  double track_gauge{1.0};        ///< [m] distance between the track centre lines
  double lag_tau{0.3};            ///< [s] hydraulic response time constant
  double max_track_accel{0.5};    ///< [m/s^2]
  double max_track_speed{0.4};    ///< [m/s] hardware limit
  Wander steering_efficiency{0.73, 0.015, 4.0, 0.70, 0.76};
  Wander speed_factor{0.925, 0.012, 4.0, 0.90, 0.95};
  Wander icr_x_offset{0.0, 0.03, 4.0, -0.08, 0.08};  ///< [m] ICR ahead of the centre: sideways slip
  static TrackOptions FromConfig(const ConfigNode& config);
};

class TrackedBase {
 public:
  TrackedBase(TrackOptions options, Pose2 T_site_base, RandomStream rng);
  void Command(double v_left, double v_right);
  void Step(double dt);
  const Pose2& pose() const { return pose_; }
  void set_pose(const Pose2& p) { pose_ = p; }
  double omega() const { return omega_; }  ///< true yaw rate [rad/s]
  double v() const { return v_; }
  Eigen::Vector2d track_speeds() const { return {v_left_, v_right_}; }

 private:
  TrackOptions o_;
  Pose2 pose_;
  RandomStream rng_;
  double ref_left_{0}, ref_right_{0}, v_left_{0}, v_right_{0}, v_{0}, omega_{0};
};

/// Rate gyro (Xsens MTi-G-700): white noise, constant turn-on bias, bias random walk.
struct GyroOptions {
  double rate_hz{400.0};
  double noise_density_deg_s_sqrt_hz{0.01};  ///< angle random walk
  double bias_stability_deg_h{10.0};         ///< in-run bias stability -> random-walk strength
  double turn_on_bias_sigma_deg_s{0.005};    ///< residual bias after the device's own estimation
  double range_deg_s{450.0};
  static GyroOptions FromConfig(const ConfigNode& config);
};

class Gyro {
 public:
  Gyro(GyroOptions options, RandomStream rng);
  /// Measured rates for true body rates `omega` over the last sample period.
  Eigen::Vector3d Measure(const Eigen::Vector3d& omega);
  const Eigen::Vector3d& bias() const { return bias_; }

 private:
  GyroOptions o_;
  RandomStream rng_;
  Eigen::Vector3d bias_{Eigen::Vector3d::Zero()};
};

/// The IMU's accelerometers (Xsens MTi-G-700): specific force with white noise, a turn-on bias
/// and a bias random walk; sampled with the gyro (one packet, one time stamp).
struct AccelOptions {
  double noise_density_ug_sqrt_hz{80.0};  ///< [micro-g / sqrt(Hz)]
  double bias_stability_ug{40.0};         ///< in-run bias stability [micro-g]
  double turn_on_bias_sigma_mg{0.5};      ///< residual turn-on bias [milli-g]
  double range_m_s2{50.0};                ///< full range [m/s^2]
  static AccelOptions FromConfig(const ConfigNode& config);
};

class Accelerometer {
 public:
  Accelerometer(AccelOptions options, double rate_hz, RandomStream rng);
  /// Measured specific force for the true one `f` [m/s^2] (sensor axes).
  Eigen::Vector3d Measure(const Eigen::Vector3d& f);
  const Eigen::Vector3d& bias() const { return bias_; }

 private:
  AccelOptions o_;
  double rate_hz_;
  RandomStream rng_;
  Eigen::Vector3d bias_{Eigen::Vector3d::Zero()};
};

/// A device's clock and link: t_device = (1 + skew) t + offset + jitter; packets reach the host
/// after a random transport delay; the device's sync pulse is time stamped by the host's
/// acquisition hardware with a small jitter, and now and then late.
struct ClockOptions {
  double offset{0.0};             ///< [s]
  double skew_ppm{0.0};           ///< [1e-6]
  double stamp_jitter{20e-6};     ///< [s] sigma of the device's own stamping
  double latency_mean{0.004};     ///< [s] transport delay (exponential part on top of latency_min)
  double latency_min{0.001};      ///< [s]
  double pulse_jitter{5e-6};      ///< [s] sigma of the host's pulse time stamps
  double pulse_late_probability{0.02};  ///< a pulse stamped late (interrupt busy)
  double pulse_late_max{0.003};   ///< [s]
  static ClockOptions FromConfig(const ConfigNode& config);
};

class DeviceClock {
 public:
  DeviceClock(ClockOptions options, DeviceId id, RandomStream rng)
      : o_(options), id_(id), rng_(std::move(rng)) {}
  /// Stamp a packet measured at true time t; also emits the matching sync pulse.
  Stamp StampPacket(Seconds t_true, SyncPulse* pulse);

 private:
  ClockOptions o_;
  DeviceId id_;
  RandomStream rng_;
  std::uint64_t sequence_{0};
};

/// The arm's own controller following a joint position trajectory: each joint tracks the
/// interpolated reference with a second-order lag, limited in speed; the reported angles differ
/// from the physical ones by small constant encoder offsets (the arm's absolute error).
struct ServoOptions {
  double bandwidth{25.0};             ///< [rad/s] natural frequency of the tracking loop
  double settle_tolerance{1e-5};      ///< [rad] busy until this close to the final point
  double encoder_offset_sigma_deg{0.003};  ///< constant per run: joint zero offsets
  double state_rate_hz{250.0};        ///< joint state messages (EGM-like)
  static ServoOptions FromConfig(const ConfigNode& config);
};

class ArmServo {
 public:
  ArmServo(ServoOptions options, const RobotModel& robot, Vector6d q0, RandomStream rng);
  void Follow(const JointTrajectory& trajectory, Seconds t_now);
  void Step(double dt, Seconds t_now);
  bool Busy(Seconds t_now) const;
  const Vector6d& q_reported() const { return q_; }
  /// Replace the drawn zero offsets (the as-built arm's own).
  void set_offsets(const Vector6d& offsets) { offsets_ = offsets; }
  const Vector6d& qd() const { return qd_; }
  /// Physical joint angles (reported + encoder offsets): what FK of the real arm uses.
  Vector6d q_physical() const { return q_ + offsets_; }

 private:
  Vector6d Reference(Seconds t_now) const;
  ServoOptions o_;
  const RobotModel* robot_;
  Vector6d q_, qd_, offsets_;
  JointTrajectory trajectory_;
  Seconds start_{0.0};
};

}  // namespace ifab::sim
