#pragma once
/// \file
/// The building sequencer's mission (paper Fig. 2): for every building position it asks the base
/// planner for a trajectory, drives it with the controller on the estimator's poses, predicts
/// where the workpiece is, sweeps the arm laser over it, registers the cloud against the model
/// of what is built so far, takes the registered pose as the robot's pose (and the estimator's
/// new start), then picks bricks from the on-board feeder and places them. It talks to the robot
/// only through hal::Robot, and never to ground truth.
///
/// Failures are outcomes, not crashes: a plan that fails is retried, then the position skipped;
/// a registration that is not trusted triggers another sweep, and after a bounded number the
/// mission stops safely (arm parked, tracks stopped) instead of placing a brick on a pose it
/// does not trust.

#include <array>
#include <cmath>
#include <functional>
#include <memory>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "ifab/arm/primitives.h"
#include "ifab/base/controller/trajectory_controller.h"
#include "ifab/base/estimator/base_state_estimator.h"
#include "ifab/base/estimator/commanded_motion.h"
#include "ifab/base/planner/stomp_planner.h"
#include "ifab/hal/robot.h"
#include "ifab/model/robot_model.h"
#include "ifab/model/site.h"
#include "ifab/perception/registration.h"
#include "ifab/perception/scan_assembly.h"
#include "ifab/sequencer/building_plan.h"
#include "ifab/sequencer/placement_bias.h"
#include "ifab/sequencer/top_face.h"
#include "ifab/sync/clock_sync.h"

namespace ifab::sequencer {

/// How the base's pose for placing a brick is taken (the ablation's rows).
enum class TiltCompensation {
  kNone,        ///< the paper's: the registered planar pose on a flat floor (x, y, yaw)
  kRegistered,  ///< the registration's full pose at the scan (height, roll and pitch included)
  kImu,         ///< that, plus the tilt change since the scan from the IMU's accelerometers
};

/// What the look after placing measures a brick against (MissionOptions::check_against).
enum class CheckAgainst { kStack, kLocalization };

/// Where the workpiece's roll and pitch in the registration come from.
enum class RegistrationAttitude {
  kFree,  ///< registered with the rest of the pose (the paper: a 6-DoF fit to the model)
  kImu,   ///< held at the IMU's gravity direction during the sweep: the designed stack is plumb,
          ///< and a column of a few bricks pins its tilt only loosely; a free tilt follows any
          ///< lean of the bricks as placed, and the next brick then continues it
};

struct MissionOptions {
  double control_period{0.025};      ///< [s] controller rate (the base laser's 40 Hz)
  double drive_timeout_factor{3.0};  ///< give up driving after this times the planned duration ...
  double drive_timeout_margin{20.0}; ///< ... plus this [s]
  double settle_time{1.0};           ///< [s] standstill after driving, before scanning
  int plan_attempts{3};              ///< planner calls (different seeds) before skipping a position
  int max_sweeps{3};                 ///< sweeps per localization before the mission stops
  int min_inliers{300};              ///< registration with fewer points on the workpiece is not trusted
  double max_localization_std_m{0.003};   ///< ... nor one whose workpiece position std (base frame) exceeds this
  double max_localization_std_deg{1.0};   ///< ... or workpiece yaw std
  double max_localization_jump_m{0.3};    ///< ... nor a correction larger than this
  double scan_distance{0.8};         ///< [m] arm laser to the top of the workpiece
  double scan_elevation_deg{50.0};   ///< view direction's angle below horizontal
  double sweep_half_angle_deg{12.0}; ///< the sweep turns joint 1 this far each side
  double sweep_speed_deg_s{8.0};
  double crop_radius{0.6};            ///< [m] registration keeps points this close (horizontally) to the workpiece
  bool localize{true};               ///< localize against the workpiece after each maneuver
  bool place_bricks{true};           ///< pick and place the visit's bricks
  /// The workpiece model follows the stack as built: after each registration the top brick's
  /// height is measured from its top face and the model (and the next brick's goal) follow it.
  /// Bricks vary in height (EN 771-1 T1 allows +-2.9 mm on a 52 mm mean), so after n bricks the
  /// designed top can be millimetres off, and a top face seen obliquely then pulls the fit
  /// sideways. Off: on seeds 1-3 it did not help (README, issue 12); false: the designed stack.
  bool measure_top{false};
  /// The model's top brick takes the length and width its top face's far edges show
  /// (MeasureTopFootprint), and the workpiece is registered again: a sweep sees one end face and
  /// one long face, so a brick longer or wider than designed (EN 771-1 T1 and R1: up to about
  /// 10 mm) would otherwise be registered half the difference towards the robot.
  bool measure_footprint{false};
  /// The spread of a delivered brick's length and width about its design [m], the prior the
  /// measured footprint is fused with: EN 771-1 category T1 (the batch mean within 0.40 sqrt(d)
  /// mm, read as 3 sigma) and R1 (the range of a sample 0.6 sqrt(d) mm, read as 4 sigma) for a
  /// 240 x 115 mm brick: sqrt(2.07^2 + 2.32^2) = 3.1 mm and sqrt(1.43^2 + 1.61^2) = 2.2 mm.
  Eigen::Vector2d brick_size_sigma{0.0031, 0.0022};
  /// With measure_footprint: the model's top brick also moves to the centre its near faces and
  /// far edges show (relative to the stack below, as registered), so that a brick placed a few
  /// mm off does not pull the next registration, and the brick after it, its way. Off: over
  /// seeds 1-20 it traded the short face for the long one (1.57 / 1.24 mm against 1.47 / 1.44
  /// with the size alone; README, issue 12).
  bool hold_measured_position{false};
  /// With measure_footprint: learn where the arm puts a brick relative to where it was sent, in
  /// the base's frame, and send the next brick against it. An arm without absolute-accuracy
  /// calibration misses by millimetres, nearly the same at every stand (the four stands see the
  /// stack in the same posture), so a constant miss walks the stack away from the stands brick
  /// by brick. Each registration measures the last brick's centre against the stack below it
  /// (the footprint's near faces and far edges); that minus the correction sent is one look at
  /// the bias along each measured axis, fused in a Kalman filter. false: bricks go where designed.
  bool learn_placement_bias{false};
  /// Its filter: prior std 3 mm per axis (an IRB 4600 without Absolute Accuracy misses by
  /// millimetres at the flange; its repeatability is 0.05-0.06 mm, DESIGN.md); a placement's
  /// scatter 0.5 mm (the brick slides as the cups let go); a walk of 0.2 mm per placement (one
  /// course, 52 mm, changes the posture little: the prior's spread over the stack's 1.3 m is
  /// 0.1 mm per course). Keys placement_bias_prior_m, placement_scatter_m, placement_bias_walk_m.
  PlacementBiasOptions placement_bias;
  /// With learn_placement_bias: one filter per building position instead of one for the robot.
  /// What repeats is not only the arm's posture: each stand has its own floor under the tracks
  /// (the base's attitude there), and sees the stack's top along its own diagonal (other faces,
  /// other incidences, so other range-bias residuals); the robot comes back to each stand within
  /// centimetres. Every filter walks at each placement (the stack grows for all of them).
  bool placement_bias_per_position{false};
  /// With placement_bias_per_position: a stand's miss is the robot's part, learned from every
  /// stand's looks, plus the stand's own (PlacementBiasScope::kRobotAndPosition); the first brick
  /// at a stand is then sent against what the other stands showed. false: the stands apart.
  bool placement_bias_robot_part{false};
  /// Re-approaches (reverse and forward along the goal's line) when the maneuver ends with a
  /// sideways offset beyond the controller's tolerance; 0: the paper's single maneuver.
  int max_reapproaches{2};
  double reapproach_tolerance{0.015};  ///< [m] re-approach when the end is farther than this from the goal
  double reapproach_distance{0.4};   ///< [m] each leg of a re-approach
  double reapproach_speed{0.1};      ///< [m/s]
  // Faults (issue 14): what the mission watches for and how long it waits before a safe stop.
  double max_scan_gap{0.3};          ///< [s] stop driving when the base laser was silent this long (12 scans)
  double sensor_wait_timeout{15.0};  ///< [s] ... and stop the mission when it stays silent this long
  double protective_field{0.8};      ///< [m] stop when unknown points are this close ahead of the footprint (0: off)
  int protective_field_points{5};    ///< ... and at least this many (a person at 1 m returns ~40)
  double protective_field_margin{0.15};  ///< [m] points this close to a known object are the object
  double obstacle_wait_timeout{30.0};    ///< [s] wait for a blocked path to clear, then stop
  double max_stamp_lag{0.25};        ///< [s] a packet synced this far from its arrival time: reset the device's clock sync
  double max_gyro_rate_factor{2.0};  ///< gyro samples beyond this times the tracks' fastest turn are spikes
  int arm_retries{2};                ///< resend a trajectory the arm controller rejected
  int pick_retries{2};               ///< pick again after the vacuum lost a brick
  int drive_retries{1};              ///< plan and drive again when a maneuver timed out off the goal
  Vector6d q_park{Vector6d::Zero()}; ///< arm configuration while driving [rad]
  Pose3 T_base_feeder{Pose3::Identity()};  ///< where the on-board feeder presents a brick
  TiltCompensation tilt_compensation{TiltCompensation::kImu};  ///< `tilt_compensation: imu | registered | none`
  double tilt_settle{0.3};           ///< [s] wait above the goal before measuring the tilt (arm at rest)
  /// The base's attitude and height before a scan tells them: a finished floor (DIN 18202 Table
  /// 3 row 3, 4 mm over 1 m, the site's specification) under 1.6 m of track gives a few tenths of
  /// a degree and a few mm at most. The registered roll, pitch and height are fused with this
  /// prior by their covariance (a small workpiece pins them loosely).
  double attitude_prior_deg{0.1};
  /// The prior updates the registered pose with the registration's full covariance (a Kalman
  /// update); false: height, roll and pitch each fused alone (the default: on seeds 1-3 the
  /// full update kept the registration's tilt, which the straight-column model of a stack whose
  /// bricks sit a few mm apart biases by tenths of a degree; README, issue 12).
  bool full_covariance_prior{false};
  /// Whether the prior also pulls a tilt the IMU holds (registration_attitude: imu). The prior
  /// describes the floor; the IMU measures the base's attitude on it, which adds the chassis's
  /// lean under the arm's moment (a pitch of 0.1-0.25 deg in the as-built world) and is known to
  /// 0.08 deg: fused with a 0.1 deg prior, the IMU's tilt is pulled 40 % towards level, which
  /// leans the frame the brick is placed in by up to 0.1 deg (2 mm at the top of the stack).
  /// false: the IMU's tilt stands (height still fused). Seeds 1-20, paired against true: the
  /// default run -0.11 +- 0.07 / -0.08 +- 0.09 mm, worst brick -0.50 +- 0.24 mm (session 24); with
  /// the localization look, worst brick -0.45 +- 0.22 mm (session 23; README, issue 12).
  bool floor_prior_on_imu_tilt{false};
  double height_prior_m{0.004};
  /// After the visit's brick, sweep again from the same stand and register the new brick on its
  /// own: the model holds it where it was measured (the stack as built, not as designed), so the
  /// next registrations fit bricks where they are. Both sweeps share the scan's systematic errors
  /// (range bias, mount, arm), which cancel in the brick's pose relative to the stack.
  /// Against the stack (check_against), over seeds 1-20 with gate_placement_check, it is no
  /// better than without the look (+0.14 / +0.20 mm paired, long / short; session 20). Against the
  /// localization with learn_placement_bias it is the brick-stack experiment's default since
  /// session 29 (data/experiments/brick-stack.yaml): seeds 1-20 1.10 / 1.07 mm against 1.39 / 1.31
  /// without it, at about the old run's time once the look registers only its brick's points.
  /// false here: the mission as the paper flew it.
  bool check_placement{false};
  /// With check_placement: at each building position the goal is moved against the mean offset
  /// measured there before (scan-to-place errors repeat with the stand: the same postures, ranges
  /// and incidences every round); false: the goal as designed.
  bool placement_correction{true};
  /// With check_placement: a look farther from the goal than the arm's accuracy allows (the
  /// placement-bias prior and scatter, plus the look's covariance; chi-square, 2 dof, 99.9 %) is
  /// not used (a wrong registration, not a miss). false: every look is used.
  bool gate_placement_check{true};
  /// What the look after placing measures the brick against. `stack`: the stack below, registered
  /// again in the same sweep, and the model then holds the brick where it was seen. `localization`:
  /// the pose this visit placed from (the stack held there; the base has not moved), so the look
  /// is the miss of the whole scan-to-place chain that the placement had: the laser's view of the
  /// stack at the scan posture (mount, range bias, the arm's kinematics there) against the arm's
  /// reach at the place posture. With learn_placement_bias the look feeds the robot's miss filter
  /// (base frame) in place of the next visit's footprint, and the model holds the brick where the
  /// look put it.
  CheckAgainst check_against{CheckAgainst::kStack};
  /// With check_against: localization and learn_placement_bias: the model holds the brick where
  /// the look, fused with where the filter expected it, puts it (a look carries its own error,
  /// which the next registrations would otherwise take for the stack's); false: where the look
  /// put it.
  bool hold_fused_look{false};
  /// With check_placement: the look's brick centre midway between the near faces it registered
  /// and the far edges its sweep shows (MeasureTopFootprint), and the model's brick at that size
  /// (fused with the design and its tolerance). A sweep sees one end and one side: a brick
  /// registered at its design size sits half its size error towards the laser (EN 771-1 T1:
  /// up to 3 mm on the long axis), which the look would take for a miss. false: the registered
  /// design box's centre.
  bool look_footprint{false};
  int min_brick_inliers{100};        ///< a checked brick with fewer points is not measured
  RegistrationAttitude registration_attitude{RegistrationAttitude::kImu};  ///< `registration_attitude: imu | free`
  /// Each scan of a sweep into the base as it stood on average over the sweep, from the
  /// accelerometer (tilt.h LevelSweepPoints): the arm turning during the sweep rocks the base on its
  /// tracks. false: the base taken as rigid for the sweep (eq. 6 as written). Off by default: seeds
  /// 1-6 gained nothing (long +0.12 +- 0.06, short -0.05 +- 0.06 mm; session 25): the rocking within
  /// one sweep is small, and the accelerometer's noise over the window adds as much.
  bool level_sweeps{false};
  /// [deg] std of the IMU's roll and pitch at standstill, for the covariance of a registration
  /// whose tilt it holds: the MTi-G-700's residual turn-on bias (0.5 mg, data/sensors/mti_g_700.yaml)
  /// is 0.03 deg, and its sensor frame sits within 0.1 deg of its base plate (Xsens MTi user
  /// manual), on a bracket of its own: 0.08 deg together. The design has no better figure: a
  /// tilt offset of this size leans the stack by as much (2 mm at 1.3 m), which the README states.
  double imu_tilt_sigma_deg{0.08};
  double tilt_window{2.0};           ///< [s] accelerometer average (80 ug/sqrt(Hz): 6e-5 rad over 2 s)

  static MissionOptions FromConfig(const ConfigNode& config);
};

/// Everything the mission uses, built from configs by the caller.
struct MissionComponents {
  RobotModel robot;
  Site site;                         ///< the site as designed, without bricks
  base::BaseGeometry base_geometry;
  base::StompPlannerOptions planner;
  base::EstimatorOptions estimator;
  base::BaseControllerOptions controller;
  arm::ArmOptions arm;
  ScanAssemblyOptions assembly;
  RegistrationOptions registration;
  ClockSyncOptions clock_sync;
  Pose3 T_tool0_arm_laser;           ///< the arm laser's mount (calibrated, or the design value)
};

/// Something the mission noticed and handled (a fault, issue 14), for the results.
struct Incident {
  Seconds t{0.0};
  std::string kind;   ///< base_laser_silent, path_blocked, clock_sync_reset, gyro_spikes, arm_rejected,
                      ///< brick_lost, resweep, replan, safe_stop
  std::string what;   ///< what it saw and did
};

/// What happened at one visit, for the results and for Fig. 6.
struct VisitLog {
  int visit{0};
  std::string position;
  Pose2 desired;                     ///< building position requested
  Pose2 start_estimate;              ///< estimated pose when the maneuver began
  base::PlanResult plan;             ///< (trajectory kept for Fig. 6)
  std::vector<Stamped<Pose2>> estimated;   ///< estimator poses while driving
  Pose2 end_estimate;                ///< estimator's pose at the end of the maneuver
  bool localized{false};
  Pose2 localized_pose;              ///< T_site_base from registration
  int sweeps{0};
  int reapproaches{0};               ///< straight re-approaches after the planned maneuver
  std::string registration_report;
  std::vector<RayPoint> cloud;       ///< the last assembled sweep (base frame)
  std::vector<PointLabel> cloud_labels;  ///< the registration's label per point of `cloud` (Fig. 4)
  Pose3 T_site_base_at_scan{Pose3::Identity()};
  Pose3 T_site_base_registered{Pose3::Identity()};  ///< the full pose bricks are placed from (fused)
  std::vector<int> bricks_placed;    ///< brick indices placed at this visit
  std::vector<double> tilt_change_deg;  ///< per brick placed: the measured tilt change since the scan
  /// check_placement: where the look after placing put the visit's last brick, from where it was
  /// meant to land (site frame, horizontal) [mm]; NaN if not measured.
  Eigen::Vector2d placement_offset_mm{Eigen::Vector2d::Constant(std::nan(""))};
  /// ... and its std from the registration's covariances (the brick's and the stack's, taken as
  /// independent) [mm]; NaN if not measured. Both are given also for a look the gate rejected
  /// (gate_placement_check; its incident says so).
  Eigen::Vector2d placement_offset_std_mm{Eigen::Vector2d::Constant(std::nan(""))};
  /// learn_placement_bias: the arm's miss learned so far (base frame x, y) [mm] and its std;
  /// NaN where nothing was learned at this visit.
  Eigen::Vector2d placement_bias_mm{Eigen::Vector2d::Constant(std::nan(""))};
  Eigen::Vector2d placement_bias_std_mm{Eigen::Vector2d::Constant(std::nan(""))};
  /// measure_footprint: where this visit's localization saw the centre of the top brick (the last
  /// visit's) from where the model held it, along the brick's x and y [mm]; NaN for an axis it
  /// did not measure.
  Eigen::Vector2d top_offset_mm{Eigen::Vector2d::Constant(std::nan(""))};
  std::string failure;               ///< empty when the visit went well
  Seconds t_start{0.0}, t_end{0.0};
};

class Mission {
 public:
  Mission(hal::Robot& robot, MissionComponents components, MissionOptions options, std::uint64_t seed);
  ~Mission();

  /// The robot's pose at the start (the site frame is the workpiece's: given, not measured).
  void Start(const Pose2& T_site_base, const Vector6d& q);

  /// Run the whole plan. Returns one log per visit; stops early (safely) on a failure.
  std::vector<VisitLog> Run(const BuildingPlan& plan);

  /// Progress text (position k of n, the phase) for a terminal.
  std::function<void(const std::string&)> on_progress;
  /// Called at the end of every visit, before its log is stored (experiments sample truth here).
  std::function<void(VisitLog&)> on_visit_end;

  /// The model of what is built so far (bricks at their designed poses).
  const Site& workpiece() const { return workpiece_; }
  bool stopped() const { return stopped_; }
  const std::string& stop_reason() const { return stop_reason_; }
  const std::vector<Incident>& incidents() const { return incidents_; }

 private:
  bool Reposition(const BuildingPosition& goal, VisitLog& log);
  /// Follow one trajectory with the controller on the estimator's poses until done or timeout.
  base::BaseControllerOutput Follow(const base::BaseTrajectory& trajectory, bool* arrived);
  bool Localize(VisitLog& log);
  enum class SweepStatus { kOk, kRetry, kStop };
  struct Sweep {
    SweepStatus status{SweepStatus::kRetry};  ///< kRetry: log.failure says why; kStop: stopped safely
    std::vector<RayPoint> cloud;              ///< base frame, cropped to the workpiece
    std::vector<RayPoint> raw_cloud;          ///< the same before range-bias compensation
    std::vector<RayPoint> uncropped;          ///< the whole sweep as read (rays past a tall stack
                                              ///< reach the floor beyond the crop)
    Seconds t0{0.0}, t1{0.0};                 ///< while the laser swept
    Pose3 T_site_base{Pose3::Identity()};     ///< the pose the sweep was planned from
  };
  /// One sweep of the workpiece's top from where the base stands (scan pose along a diagonal of
  /// the top brick, joint 1 swept across it; `sweep` varies the diagonal between attempts).
  Sweep SweepWorkpiece(VisitLog& log, int sweep);
  /// After placing brick k (the model's top brick, at its commanded pose): sweep from the same
  /// stand, register the new brick as its own body against the stack, and hold it in the model
  /// where it was measured; learn the stand's placement offset from it. False: stopped.
  bool CheckPlacement(int k, VisitLog& log);
  /// The look after placing feeds the placement-bias filter (check_against: localization).
  bool LookFeedsPlacementBias() const;
  /// The registered T_site_base with the floor's prior on its height and attitude.
  /// A brick's length (`axis` 0) or width (1) as built: measured by `m`, fused with the design.
  double BrickSizeAsBuilt(int axis, const FootprintMeasurement& m) const;
  /// `imu_tilt`: the registration held the IMU's roll and pitch.
  Pose3 FuseWithFloorPrior(const Pose3& T_site_base, const Matrix6d& covariance, bool imu_tilt) const;
  bool PlaceBrick(int k, VisitLog& log);
  /// The base's pose for placing now: the reference pose, turned by the measured tilt change.
  Pose3 PlacingPose(VisitLog& log);
  /// Command the tracks and record the command (the commanded-speed prior integrates them).
  void SendTracks(const TrackCommand& command);
  void StopSafely(const std::string& why);
  void Progress(const std::string& text);
  /// Drain the robot's sensor queues: clocks, gyro and base scans into the estimator.
  void PumpSensors();
  bool RunArm(const arm::PrimitiveResult& steps, const std::string& what);
  /// Run arm steps, resending a trajectory the controller rejected; StopSafely on other failures
  /// unless the vacuum lost the brick (then returns false with *lost_grip set, the arm where it stopped).
  bool RunArmSteps(const arm::PrimitiveResult& steps, const std::string& what, bool holding, bool* lost_grip);
  void Note(const std::string& kind, const std::string& what);
  /// Unknown base laser points in the protective field ahead (direction > 0) or behind.
  int PointsInProtectiveField(double direction) const;
  /// Stop and wait while the base laser is silent or the path is blocked; false: gave up (stopped).
  bool HoldWhileUnsafe(double direction, Seconds* held);
  base::PlanningScene Scene() const;
  Pose3 Pose3Of(const Pose2& p) const;

  hal::Robot& robot_;
  MissionComponents c_;
  MissionOptions o_;
  RandomStream rng_;
  std::unique_ptr<base::BaseStateEstimator> estimator_;
  std::unique_ptr<base::TrackCommandHistory> commands_sent_;  ///< every track command sent, for the estimator
  std::unique_ptr<arm::ArmPrimitives> arm_;
  DeviceClockSync sync_base_laser_, sync_arm_laser_, sync_gyro_, sync_arm_;
  ClockStepDetector step_base_laser_, step_arm_laser_, step_gyro_, step_arm_;  // clock jumps, from raw stamps
  Seconds last_scan_mid_{0.0};  ///< mid time of the last base scan given to the estimator
  Seconds last_gyro_{-1e300}, last_base_scan_{-1e300}, last_arm_scan_{-1e300}, last_joint_state_{-1e300};
  std::vector<LaserScan> arm_scans_;
  std::vector<JointState> joint_states_;
  std::vector<AccelSample> accel_;  ///< recent accelerometer samples (host time)
  Pose3 T_site_base_ref_{Pose3::Identity()};  ///< full pose at the last scan (or the start)
  std::optional<Eigen::Vector3d> up_ref_;     ///< up direction at that moment (base frame)
  bool warned_no_accel_{false};
  Site workpiece_;        ///< the site plus the bricks built so far (as commanded, or as measured: check_placement)
  /// Per building position: the placement offsets measured there so far (site frame, horizontal),
  /// each the brick's measured position minus its designed one plus the correction applied.
  std::map<std::string, std::vector<Eigen::Vector2d>> placement_offsets_;
  Eigen::Vector2d correction_applied_{Eigen::Vector2d::Zero()};  ///< to the last brick's goal
  // learn_placement_bias: the arm's miss in the base frame (x, y), one for the robot or one per
  // building position, and what the last brick was sent with (to tell the bias from the correction when it is measured).
  PlacementBiasLearner placement_bias_;
  struct SentBrick {
    std::size_t index;          ///< in workpiece_.bricks
    Eigen::Vector3d intended;   ///< where it should land (site)
    Eigen::Matrix2d R_site_base;  ///< the base's heading when it was placed
    Eigen::Vector2d correction; ///< the bias it was sent against (base frame)
    std::string position;       ///< the building position it was placed from
  };
  std::optional<SentBrick> last_sent_;
  /// One look at the last brick's miss (`offset` along its box's x and y, site frame, measured
  /// axes only) updates the learned bias.
  void LearnPlacementBias(const Eigen::Vector2d& offset, const Eigen::Vector2d& offset_std,
                          const std::array<bool, 2>& measured, VisitLog& log);
  Pose2 T_site_base_;     ///< the current best pose (estimator or localization)
  Vector6d q_;            ///< last commanded arm configuration
  int bricks_placed_{0};
  bool stopped_{false};
  std::string stop_reason_;
  std::vector<Stamped<Pose2>>* trace_{nullptr};  // where PumpSensors logs estimates
  std::vector<Incident> incidents_;
  Seconds last_base_scan_arrival_{0.0};  // host time the base laser last sent anything
  std::vector<Eigen::Vector2d> last_scan_points_;  // the newest base scan's points (base frame)
  std::optional<base::FootprintChecker> known_;  // the scene as known, for the protective field
  double max_gyro_rate_{0.0};
  bool estimating_{true};  // false while the base stands still for arm work: scans are not matched
};

}  // namespace ifab::sequencer
