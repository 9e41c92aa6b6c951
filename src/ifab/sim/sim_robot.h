#pragma once
/// \file
/// The simulated In situ Fabricator behind hal::Robot: world, tracked base, two UTM-30LX, gyro,
/// arm servo, vacuum gripper, device clocks. The only holder of ground truth (truth() accessors
/// are for experiments' scoring and tests, never for algorithm modules).

#include <deque>
#include <memory>
#include <optional>
#include <string>

#include "ifab/hal/robot.h"
#include "ifab/model/robot_model.h"
#include "ifab/sim/as_built.h"
#include "ifab/sim/components.h"
#include "ifab/sim/faults.h"
#include "ifab/sim/lrf_model.h"
#include "ifab/sim/world.h"

namespace ifab::sim {

struct SimOptions {
  std::string urdf{"robots/insitu_fabricator.urdf"};  ///< under data/ unless absolute
  std::string site{"sites/brick_stack.yaml"};
  double step{0.0025};                  ///< [s] physics step (the gyro's 400 Hz)
  TrackOptions tracks;
  LrfOptions base_laser;
  LrfOptions arm_laser;
  GyroOptions gyro;
  ServoOptions servo;
  ClockOptions base_laser_clock, arm_laser_clock, gyro_clock, arm_clock;
  std::array<double, 6> base_laser_mount_error{};  ///< true mount = design * error (x y z r p y)
  std::array<double, 6> arm_laser_mount_error{};
  double grip_capture_distance{0.02};   ///< [m] the gripper grips a brick within this distance
  double release_sigma_xy{0.0003};      ///< [m] brick placement error at release
  double release_sigma_yaw_deg{0.05};
  Pose3 T_base_feeder{Pose3::Identity()};  ///< where the on-board feeder presents a brick (centre)
  double feeder_sigma_xy{0.0003};       ///< [m] how precisely the feeder presents a brick
  double feeder_sigma_yaw_deg{0.05};
  AccelOptions accel;                   ///< the IMU's accelerometers (same device and clock as the gyro)
  /// The as-built world and machine (DrawAsBuilt); default: the exact world (model = world).
  AsBuilt as_built;
  double seconds_since_power_on{0.0};   ///< [s] the lasers' warm-up at t = 0 (after an earlier session)

  /// Read data/sim/insitu_fabricator.yaml's `sim:` section and the sensor files it names.
  static SimOptions Load(const std::string& robot_yaml);
  static SimOptions FromConfig(const ConfigNode& config);
};

class SimRobot final : public hal::Robot {
 public:
  SimRobot(const SimOptions& options, Pose2 T_site_base0, Vector6d q0, std::uint64_t seed);

  // hal::Robot
  Seconds Now() const override { return t_; }
  void Wait(Seconds dt) override;
  void CommandTracks(const TrackCommand& command) override;
  void SendJointTrajectory(const JointTrajectory& trajectory) override;
  bool ArmBusy() const override;
  void SetGripper(bool grip) override;
  void SetLaserActive(DeviceId laser, bool active) override;
  std::vector<LaserScan> TakeLaserScans(DeviceId laser) override;
  std::vector<GyroSample> TakeGyroSamples() override;
  std::vector<AccelSample> TakeAccelSamples() override;
  std::vector<JointState> TakeJointStates() override;
  std::vector<SyncPulse> TakeSyncPulses() override;

  // Ground truth, for scoring and tests only.
  const World& world() const { return world_; }
  World& mutable_world() { return world_; }
  const RobotModel& robot_model() const { return robot_; }
  Pose2 true_base_pose() const { return base_.pose(); }
  /// The base's true pose in the site with its height and tilt on the floor (as built).
  Pose3 true_T_site_base() const { return T_site_base_; }
  /// Command an extra base tilt (roll, pitch [rad]) on top of the as-built one (tests).
  void set_extra_tilt(double roll, double pitch) { extra_tilt_ = {roll, pitch}; }
  void teleport_base(const Pose2& p) { base_.set_pose(p); }
  Pose3 true_T_tool0_arm_laser() const { return T_tool0_arm_laser_true_; }
  Pose3 true_T_base_base_laser() const { return T_base_base_laser_true_; }
  Vector6d true_joint_angles() const { return servo_.q_physical(); }
  /// True pose of the gripper contact point in the site.
  Pose3 true_T_site_gripper() const;
  bool holding_brick() const { return held_.has_value(); }
  /// The brick the feeder presents now (true pose in the site).
  SiteBox feeder_brick() const;
  /// The gyro's current bias (truth).
  Eigen::Vector3d true_gyro_bias() const { return gyro_.bias(); }

  /// Faults to inject (faults.h; not owned; nullptr: none). The stack sees their effects only.
  void SetFaults(FaultInjector* faults) { faults_ = faults; }
  /// The held brick falls (a fault); the feeder presents the next one.
  void DropHeldBrick();
  // hal::Robot extras a real machine has: the controller's refusal, the vacuum sensor.
  std::string ArmRejection() const override { return arm_rejection_; }
  std::optional<bool> VacuumHolding() const override { return held_.has_value(); }

  /// A scan from the arm laser at the current state without noise or timing (tests).
  const LrfModel& arm_lrf() const { return arm_lrf_; }
  const LrfModel& base_lrf() const { return base_lrf_; }
  const SimOptions& options() const { return options_; }

 private:
  struct Snapshot {
    Seconds t;
    Pose3 T_site_base;
    Vector6d q;
  };
  void Step();
  /// The base on the floor at planar pose p with the arm at q: floor plane under the tracks,
  /// how the tracks seated at this stop, and the tilt from the arm's moment (as built).
  Pose3 TrueSiteBase(const Pose2& p, const Vector6d& q_physical) const;
  /// Link angles: the physical joint angles plus gravity's deflection of joints 2 and 3.
  Vector6d LinkAngles(const Vector6d& q_physical) const;
  Pose3 ArmLaserPose(const Pose3& T_site_base, const Vector6d& q_physical) const;
  Snapshot Now3() const { return {t_, T_site_base_, servo_.q_physical()}; }
  void PresentFeederBrick();

  SimOptions options_;
  RobotModel robot_;
  World world_;
  RandomStream rng_;
  TrackedBase base_;
  ArmServo servo_;
  Gyro gyro_;
  Accelerometer accel_;
  Eigen::Matrix3d R_imu_base_{Eigen::Matrix3d::Identity()};  ///< the IMU's mount (as built)
  LrfModel base_lrf_, arm_lrf_;
  DeviceClock base_laser_clock_, arm_laser_clock_, gyro_clock_, arm_clock_;
  RandomStream base_lrf_rng_, arm_lrf_rng_, gripper_rng_;
  Pose3 T_base_base_laser_true_, T_tool0_arm_laser_true_;

  Seconds t_{0.0};
  long step_count_{0};
  Seconds next_state_{0.0}, next_base_scan_{0.0}, next_arm_scan_{0.0};
  Snapshot base_scan_start_{}, arm_scan_start_{};
  std::vector<LaserScan> base_scans_, arm_scans_;
  std::vector<GyroSample> gyro_samples_;
  std::vector<AccelSample> accel_samples_;
  Pose3 T_site_base_{Pose3::Identity()};  ///< true base pose now (with tilt)
  Eigen::Vector2d seat_{Eigen::Vector2d::Zero()};  ///< roll, pitch of how the tracks seated at this stop
  Eigen::Vector2d extra_tilt_{Eigen::Vector2d::Zero()};
  bool base_moving_{false};
  double v_prev_{0.0};
  RandomStream seat_rng_, encoder_rng_;
  std::vector<double> brick_leans_;  ///< per feeder brick: lean about its x and y [rad] (as built)
  std::vector<JointState> joint_states_;
  std::vector<SyncPulse> pulses_;

  bool base_laser_active_{true}, arm_laser_active_{true};
  std::optional<Pose3> held_;  ///< T_gripper_brick of the held brick
  SiteBox feeder_brick_;  ///< its pose is T_base_brick: the feeder rides on the base
  int bricks_released_{0};
  FaultInjector* faults_{nullptr};
  std::string arm_rejection_;
  TrackCommand track_command_;
};

}  // namespace ifab::sim
