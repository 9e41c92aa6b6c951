#pragma once
/// \file
/// Arm laser sweeps on any hal::Robot, and the arm laser's extrinsic calibration from sweeps of a
/// cube on the floor (paper Sec. V-A and V-C). A sweep turns one joint while the arm laser scans;
/// scans and joint states are mapped to host time by TICSync-style sync from the devices' pulses
/// (sync module), then assembled with eq. 6 (perception). Used by the mission and by the Table I
/// and Table II experiments; the robot is reached only through hal::Robot.

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "ifab/arm/primitives.h"
#include "ifab/hal/robot.h"
#include "ifab/model/robot_model.h"
#include "ifab/perception/calibration.h"
#include "ifab/perception/kinematic_calibration.h"
#include "ifab/perception/range_bias.h"
#include "ifab/perception/sweep_recording.h"
#include "ifab/sync/clock_sync.h"

namespace ifab {
class ConfigNode;
}

namespace ifab::sequencer {

/// Where the laser looks from, relative to the look point (the target plus the sweep's aim
/// offset): the scan pose is then found by IK instead of by aiming a posture.
struct LaserView {
  double distance{1.2};   ///< [m] laser origin to the look point
  double elevation{0.8};  ///< [rad] the centre beam's angle below horizontal
  double azimuth{0.0};    ///< [rad] the laser's bearing from the look point, from the side of the
                          ///< arm's foot (0: between the foot and the target, looking away from it)
  double roll{0.0};       ///< [rad] scan plane about the centre beam (0: it holds the horizontal
                          ///< perpendicular to the view; 90 deg: it holds the vertical)
  double height{0.0};     ///< [m] height of the look point above the floor (base z = 0)
};

/// One sweep: joint `joint` (0-based) from `from` to `to` about the scan pose, the other joints
/// at the scan pose plus `pose_offset` (e.g. joint 6 turned 90 deg so the scan plane crosses a
/// joint-1 sweep). The scan pose is the posture aimed at the target (AimAt), or, with `view`,
/// the IK solution that puts the laser there.
struct SweepSpec {
  int joint{4};                    ///< swept joint, 0-based
  double from{0.0};                ///< [rad] start, relative to the aimed scan pose
  double to{0.0};                  ///< [rad] end, relative to the aimed scan pose
  double speed{0.17};              ///< [rad/s]
  Vector6d pose_offset{Vector6d::Zero()};  ///< [rad] added to the aimed scan pose
  /// [m] the centre beam aims this far off the target along (radial, lateral): radial points
  /// from the arm's foot to the target, lateral 90 deg to its left. A scan line across the arm
  /// (joint 6 at 0) aimed at a lateral offset crosses the target mid-sweep when joints 2, 3 or 5
  /// sweep.
  Eigen::Vector2d aim_offset{Eigen::Vector2d::Zero()};
  std::optional<LaserView> view;   ///< set: the scan pose by IK from this view
};

/// Reads a YAML list of sweeps, each
/// `{joint: 1..6, range_deg: [from, to], speed_deg_s, offset_deg: [6 numbers], aim_offset: [radial, lateral],
///   view: {distance, elevation_deg, azimuth_deg, roll_deg, height}}`
/// (all but joint and range_deg optional). Throws InputError naming the entry and field.
std::vector<SweepSpec> ReadSweepSpecs(const ConfigNode& list);

/// A scan pose whose laser centre beam meets the floor (z = 0 of base) at `target_in_base`:
/// joint 1 turns towards it, joint 5 tilts the laser until the beam lands at its distance
/// (design model). The other joints are the posture's.
Vector6d AimAt(const RobotModel& robot, const Eigen::Vector2d& target_in_base, const Vector6d& posture);

/// The arm configuration (IK, nearest to q_near) that puts the laser at `view` of the look point
/// (base frame, on the floor), with the design mount; nullopt if out of reach.
std::optional<Vector6d> ViewPose(arm::IkSolver& ik, const RobotModel& robot, const Eigen::Vector2d& look_in_base,
                                 const LaserView& view, const Vector6d& q_near);

struct SweepRecorderOptions {
  double settle_time{0.3};  ///< [s] standstill at the sweep's start pose before sweeping
  double tail_time{0.1};    ///< [s] wait after the sweep so its last scans arrive
  /// The arm laser's state between sweeps (hal cannot read it back): a sweep switches the laser
  /// on and leaves it in this state. The mission keeps it off between sweeps.
  bool laser_on_between_sweeps{true};
};

/// What the recorder drains from the robot besides the arm laser's scans and the arm's joint
/// states: every sync pulse (all devices, also the ones it uses), base laser scans and gyro
/// samples, handed on so a caller that tracks those devices loses nothing.
struct DrainedData {
  std::vector<SyncPulse> sync_pulses;
  std::vector<LaserScan> base_laser_scans;
  std::vector<GyroSample> gyro_samples;
  std::vector<AccelSample> accel_samples;  ///< raw stamps (the sweep's own copy is synced)
};

/// Drives the arm laser through sweeps and returns them in host time, the devices' clocks mapped
/// from the pulses seen so far. The base must stand still. Errors of planning or execution throw
/// std::runtime_error naming the sweep.
class SweepRecorder {
 public:
  /// `q` is the arm's configuration now.
  SweepRecorder(hal::Robot& robot, arm::ArmPrimitives& arm, const Vector6d& q, SweepRecorderOptions options = {});

  /// A sweep about the scan pose aimed at `target_in_base` (+ the spec's aim offset), from `posture`
  /// (joints 2, 3, 4, 6; 1 and 5 are aimed). `reverse` sweeps from `to` to `from`.
  SweepRecording Record(const Eigen::Vector2d& target_in_base, const Vector6d& posture, const SweepSpec& spec,
                        bool reverse, const std::string& name);

  /// Move the arm to q (e.g. back to where it started).
  void MoveTo(const Vector6d& q, const std::string& name);

  /// The arm's configuration after the last motion.
  const Vector6d& q() const { return q_; }

  /// Receives what is drained but not used for the sweep (unset: discarded).
  std::function<void(DrainedData&&)> on_other_data;

 private:
  void Execute(const std::vector<arm::ArmStep>& steps, const std::string& name);
  void Drain(SweepRecording* rec);

  hal::Robot& robot_;
  arm::ArmPrimitives& arm_;
  Vector6d q_;
  SweepRecorderOptions options_;
  DeviceClockSync laser_sync_, arm_sync_, gyro_sync_;
};

/// The sweeps that identify the arm laser's range bias together with its mount (range_bias.h):
/// besides the cube's sweeps, the floor seen from above at several heights (the paper's Fig. 7
/// procedure: each height sees the floor at ranges from the height out and at every incidence).
struct RangeBiasPlan {
  std::vector<double> floor_heights{0.4, 0.6, 0.9, 1.3, 1.8};  ///< [m] the laser above the floor
  Eigen::Vector2d floor_aim{0.0, -0.8};  ///< [m] the floor patch from the cube (radial, lateral), clear of it
  double floor_elevation{1.48};          ///< [rad] the centre beam below horizontal (85 deg: almost straight down)
  int floor_joint{0};                    ///< joint swept over the floor, 0-based
  double floor_half_range{0.07};         ///< [rad] the sweep about the view (+-4 deg)
  double floor_speed{0.07};              ///< [rad/s]
  double floor_crop_radius{1.2};         ///< [m] keep floor points this close to the patch (a floor is
                                         ///< flat only locally)
  RangeBiasOptions identification;       ///< the solver's options
  RangeBiasCompensation compensation;    ///< how the mission's sweeps apply the identified model
  /// The cube sweeps' ground is cropped to where it is one plane before the mount's last solve.
  GroundExtentOptions ground_extent;

  /// Reads {floor_heights, floor_aim, floor_elevation_deg, floor_joint (1-6), floor_range_deg,
  /// floor_speed_deg_s, floor_crop_radius, identification: {...}, compensation: {...},
  /// ground_extent: {...}}.
  static RangeBiasPlan FromConfig(const ConfigNode& config);
};

/// Where and how to sweep a cube for the arm laser's calibration (Sec. V-C).
struct LaserCalibrationPlan {
  Eigen::Vector3d cube_in_base{1.70, 0.0, 0.0};  ///< cube centre x, y [m] and yaw [rad] in base, roughly known
  double cube_size{0.25};                        ///< [m] edge length (the paper: about 0.25 m)
  /// [s] how long the laser is on before the sweeps: a unit's range drifts while it warms up
  /// (Pomerleau et al. 2012 warm their lasers up before measuring), and the identification cannot
  /// tell a drift that later fades from a bias that stays.
  double warmup_s{0.0};
  std::vector<SweepSpec> sweeps;                 ///< the paper: 6-8 sweeps of different joints
  Vector6d scan_posture{Vector6d::Zero()};       ///< [rad] posture aimed by sweeps without a view
                                                 ///< (joints 1 and 5), and the IK seed of views
  int beam_stride{1};                            ///< keep every n-th beam of the scans
  double min_range{0.0};                         ///< [m] drop shorter ranges (the UTM-30LX's short-range bias)
  double crop_radius{0.0};                       ///< [m] keep points this close to the cube horizontally
                                                 ///< (design mount; 0 = all): the model of a cube on a
                                                 ///< flat floor holds only near it
  CalibrationOptions calibration;                ///< the solver's options
  std::optional<RangeBiasPlan> range_bias;       ///< set: identify the range bias with the mount
  /// Each scan's flange pose in the base levelled by the IMU's accelerometer (tilt.h
  /// LevelSweepPoints): the arm's weight tilts the base differently at every calibration posture.
  /// false: the base taken as rigid (the paper); also when a recording holds no accelerometer.
  bool level_with_imu{true};
  /// set: fit the arm's kinematic errors to the cube views after the mount (kinematic_calibration.h)
  std::optional<KinematicCalibrationOptions> kinematics;

  /// Reads `{cube_in_base: [x, y, yaw_deg], cube_size, sweeps: [...], scan_posture_deg: [6],
  /// beam_stride, min_range, crop_radius, calibration: {...}, range_bias: {...}, kinematics: {...}, level_with_imu}`; `cube_in_base`
  /// and `sweeps` are required.
  static LaserCalibrationPlan FromConfig(const ConfigNode& config);

  /// The cube's pose in base as planned (standing on z = 0).
  Pose3 T_base_cube() const;
};

/// Records the plan's sweeps of the cube with `recorder` (every other sweep reversed), assembled
/// with eq. 6 but not yet through the mount, ranges below min_range dropped and the points cropped
/// to crop_radius about the cube. `raw` (if given) receives the recordings.
std::vector<CalibrationSweep> RecordCubeSweeps(SweepRecorder& recorder, const RobotModel& model,
                                               const LaserCalibrationPlan& plan,
                                               const std::function<void(const std::string&)>& progress,
                                               std::vector<SweepRecording>* raw = nullptr);

/// Calibrates the arm laser's mount: records the plan's sweeps of the cube, then solves the mount
/// (from the design mount model.T_tool0_arm_laser) together with the cube's and the ground's
/// poses (from the plan's, known roughly) with eq. 6 inside eq. 7. The arm returns to q_start.
/// The mount is summary.T_tool0_laser when summary.IsUsable(); a sweep that cannot be planned or
/// run gives status kNoPoints and its reason in the message. The arm laser is left as
/// recorder_options.laser_on_between_sweeps says (default on).
CalibrationSummary CalibrateArmLaser(hal::Robot& robot, const RobotModel& model, const arm::ArmOptions& arm_options,
                                     const LaserCalibrationPlan& plan, const Vector6d& q_start,
                                     const std::function<void(const std::string&)>& progress,
                                     const SweepRecorderOptions& recorder_options = {});

/// The arm laser's mount and range bias (CalibrateArmLaserAndRangeBias).
struct ArmLaserCalibration {
  CalibrationSummary mount;                ///< the mount, from the compensated cube sweeps when the bias is identified
  CalibrationSummary mount_uncompensated;  ///< the first solve, from the raw sweeps (eq. 6 as written)
  std::optional<RangeBiasSummary> bias;    ///< set when the plan has range_bias
  std::optional<GroundExtent> ground_extent;  ///< the cube sweeps' planar ground (range_bias plans)
  RangeBiasCompensation compensation;      ///< for scan assembly: the plan's options with the model (empty: none)
  std::vector<CalibrationSweep> floor_sweeps;  ///< raw floor sweeps (for inspection)
  std::vector<CalibrationSweep> cube_sweeps_compensated;  ///< the sweeps the mount was solved from (the
                                                          ///< bias compensated when it was identified)
  /// set when the plan has `kinematics` and the mount is usable: the per-view mounts and the arm's
  /// fitted errors; when usable, the mount to use with the corrected chain is kinematics->T_tool0_laser
  std::vector<FlangeObservation> views;
  std::vector<std::string> views_left_out;  ///< a view that does not fix the mount alone, and why
  std::optional<KinematicCalibration> kinematics;
};

/// Each cube sweep alone against the targets where `mount` put them (its own mount: the arm's
/// error at that view's posture), then the arm's kinematic errors fitted to those views.
/// `mount` must be usable.
void IdentifyArmKinematics(const KDL::Chain& design, const std::vector<CalibrationSweep>& cube_sweeps,
                           const std::vector<RegistrationBody>& bodies, const CalibrationSummary& mount,
                           const CalibrationOptions& calibration, const KinematicCalibrationOptions& options,
                           ArmLaserCalibration& out);

/// CalibrateArmLaser, and when the plan has `range_bias`: also records the floor sweeps, identifies
/// the bias with the mount and the targets' poses from all sweeps (starting from the first mount
/// solve), then solves the mount again from the cube sweeps compensated and guarded by the model.
/// `raw` (if given) receives every recording.
ArmLaserCalibration CalibrateArmLaserAndRangeBias(hal::Robot& robot, const RobotModel& model,
                                                  const arm::ArmOptions& arm_options, const LaserCalibrationPlan& plan,
                                                  const Vector6d& q_start,
                                                  const std::function<void(const std::string&)>& progress,
                                                  const SweepRecorderOptions& recorder_options = {},
                                                  std::vector<SweepRecording>* raw = nullptr);

/// The bias step alone on recorded sweeps: the first mount solve from `cube_sweeps`, the joint
/// identification from them and `floor_sweeps`, the mount again from the compensated cube sweeps.
/// (`ifab calibrate-bias` and CalibrateArmLaserAndRangeBias.)
ArmLaserCalibration IdentifyMountAndRangeBias(const std::vector<CalibrationSweep>& cube_sweeps,
                                              const std::vector<CalibrationSweep>& floor_sweeps,
                                              const std::vector<RegistrationBody>& bodies,
                                              const Pose3& T_tool0_laser_guess, const CalibrationOptions& calibration,
                                              const RangeBiasPlan& bias_plan,
                                              const std::function<void(const std::string&)>& progress = {});

}  // namespace ifab::sequencer
