#include "ifab/sequencer/mission.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <algorithm>
#include <limits>
#include <optional>

#include "ifab/core/angles.h"
#include "ifab/core/config.h"
#include "ifab/core/se3.h"
#include "ifab/sequencer/floor_prior.h"
#include "ifab/sequencer/tilt.h"
#include "ifab/sequencer/top_face.h"

namespace ifab::sequencer {
namespace {

Pose2 Pose2Of(const Pose3& p) {
  const auto v = XyzRpyFromPose(p);
  return Pose2(v[0], v[1], v[5]);
}

}  // namespace

MissionOptions MissionOptions::FromConfig(const ConfigNode& c) {
  c.ExpectKeys({"control_period", "drive_timeout_factor", "drive_timeout_margin", "settle_time", "plan_attempts",
                "max_sweeps", "min_inliers", "max_localization_std_m", "max_localization_std_deg",
                "max_localization_jump_m", "scan_distance", "scan_elevation_deg", "sweep_half_angle_deg",
                "sweep_speed_deg_s", "crop_radius", "park_joints_deg", "localize", "place_bricks", "measure_top", "measure_footprint", "brick_size_sigma_mm", "hold_measured_position",
                "learn_placement_bias", "placement_bias_per_position", "placement_bias_robot_part", "placement_bias_prior_m", "placement_scatter_m", "placement_bias_walk_m", "placement_bias_adapt_noise",
                "full_covariance_prior", "max_reapproaches",
                "reapproach_tolerance", "reapproach_distance", "reapproach_speed", "tilt_compensation", "tilt_settle",
                "tilt_window", "attitude_prior_deg", "floor_prior_on_imu_tilt", "height_prior_m", "registration_attitude", "level_sweeps", "imu_tilt_sigma_deg", "check_placement", "gate_placement_check", "placement_correction", "check_against", "hold_fused_look", "look_footprint", "min_brick_inliers", "max_scan_gap",
                "sensor_wait_timeout", "protective_field", "protective_field_points", "protective_field_margin",
                "obstacle_wait_timeout", "max_stamp_lag", "max_gyro_rate_factor", "arm_retries", "pick_retries",
                "drive_retries"});
  MissionOptions o;
  c.ReadPositive("control_period", o.control_period);
  c.ReadPositive("drive_timeout_factor", o.drive_timeout_factor);
  c.ReadNonNegative("drive_timeout_margin", o.drive_timeout_margin);
  c.ReadNonNegative("settle_time", o.settle_time);
  c.ReadPositive("plan_attempts", o.plan_attempts);
  c.ReadPositive("max_sweeps", o.max_sweeps);
  c.ReadNonNegative("min_inliers", o.min_inliers, std::numeric_limits<int>::max());  // a threshold, sizes nothing
  c.ReadPositive("max_localization_std_m", o.max_localization_std_m);
  c.ReadPositive("max_localization_std_deg", o.max_localization_std_deg);
  c.ReadPositive("max_localization_jump_m", o.max_localization_jump_m);
  c.ReadPositive("scan_distance", o.scan_distance);
  c.ReadInRange("scan_elevation_deg", o.scan_elevation_deg, 0.0, 90.0);
  c.ReadPositive("sweep_half_angle_deg", o.sweep_half_angle_deg);
  c.ReadPositive("sweep_speed_deg_s", o.sweep_speed_deg_s);
  c.ReadPositive("crop_radius", o.crop_radius);
  c.Read("localize", o.localize);
  c.Read("place_bricks", o.place_bricks);
  c.Read("measure_top", o.measure_top);
  c.Read("measure_footprint", o.measure_footprint);
  c.Read("hold_measured_position", o.hold_measured_position);
  c.Read("learn_placement_bias", o.learn_placement_bias);
  c.Read("placement_bias_per_position", o.placement_bias_per_position);
  c.Read("placement_bias_robot_part", o.placement_bias_robot_part);
  c.ReadPositive("placement_bias_prior_m", o.placement_bias.prior_std);
  c.ReadNonNegative("placement_scatter_m", o.placement_bias.scatter);
  c.ReadNonNegative("placement_bias_walk_m", o.placement_bias.walk);
  c.Read("placement_bias_adapt_noise", o.placement_bias.adapt_noise);
  if (auto v = c.Find("brick_size_sigma_mm")) {
    const auto sigma = v->AsNumbers(2);
    if (!(sigma[0] > 0.0 && sigma[1] > 0.0)) v->Fail("two positive numbers (length and width) [mm]");
    o.brick_size_sigma = 1e-3 * Eigen::Vector2d(sigma[0], sigma[1]);
  }
  c.Read("full_covariance_prior", o.full_covariance_prior);
  c.ReadNonNegative("max_reapproaches", o.max_reapproaches);
  c.ReadPositive("reapproach_tolerance", o.reapproach_tolerance);
  c.ReadPositive("reapproach_distance", o.reapproach_distance);
  c.ReadPositive("reapproach_speed", o.reapproach_speed);
  c.ReadPositive("max_scan_gap", o.max_scan_gap);
  c.ReadPositive("sensor_wait_timeout", o.sensor_wait_timeout);
  c.ReadNonNegative("protective_field", o.protective_field);
  c.ReadPositive("protective_field_points", o.protective_field_points);
  c.ReadNonNegative("protective_field_margin", o.protective_field_margin);
  c.ReadPositive("obstacle_wait_timeout", o.obstacle_wait_timeout);
  c.ReadPositive("max_stamp_lag", o.max_stamp_lag);
  c.ReadPositive("max_gyro_rate_factor", o.max_gyro_rate_factor);
  c.ReadNonNegative("arm_retries", o.arm_retries, 10);
  c.ReadNonNegative("pick_retries", o.pick_retries, 10);
  c.ReadNonNegative("drive_retries", o.drive_retries, 10);
  if (auto q = c.Find("park_joints_deg")) {
    const auto v = q->AsNumbers(6);
    for (int i = 0; i < 6; ++i) o.q_park[i] = DegToRad(v[static_cast<std::size_t>(i)]);
  }
  if (auto t = c.Find("tilt_compensation")) {
    const std::string v = t->As<std::string>();
    if (v == "imu") o.tilt_compensation = TiltCompensation::kImu;
    else if (v == "registered") o.tilt_compensation = TiltCompensation::kRegistered;
    else if (v == "none") o.tilt_compensation = TiltCompensation::kNone;
    else t->Fail("imu, registered or none");
  }
  c.ReadNonNegative("tilt_settle", o.tilt_settle);
  c.ReadPositive("tilt_window", o.tilt_window);
  c.ReadPositive("attitude_prior_deg", o.attitude_prior_deg);
  c.Read("floor_prior_on_imu_tilt", o.floor_prior_on_imu_tilt);
  c.ReadPositive("height_prior_m", o.height_prior_m);
  if (auto t = c.Find("registration_attitude")) {
    const std::string v = t->As<std::string>();
    if (v == "imu") o.registration_attitude = RegistrationAttitude::kImu;
    else if (v == "free") o.registration_attitude = RegistrationAttitude::kFree;
    else t->Fail("imu or free");
  }
  c.ReadPositive("imu_tilt_sigma_deg", o.imu_tilt_sigma_deg);
  c.Read("level_sweeps", o.level_sweeps);
  c.Read("check_placement", o.check_placement);
  c.Read("gate_placement_check", o.gate_placement_check);
  c.Read("placement_correction", o.placement_correction);
  c.Read("hold_fused_look", o.hold_fused_look);
  c.Read("look_footprint", o.look_footprint);
  if (auto t = c.Find("check_against")) {
    const std::string v = t->As<std::string>();
    if (v == "stack") o.check_against = CheckAgainst::kStack;
    else if (v == "localization") o.check_against = CheckAgainst::kLocalization;
    else t->Fail("stack or localization");
  }
  c.ReadPositive("min_brick_inliers", o.min_brick_inliers, 100000);
  return o;
}

Mission::Mission(hal::Robot& robot, MissionComponents components, MissionOptions options, std::uint64_t seed)
    : robot_(robot),
      c_(std::move(components)),
      o_(options),
      rng_(seed),
      sync_base_laser_(c_.clock_sync),
      sync_arm_laser_(c_.clock_sync),
      sync_gyro_(c_.clock_sync),
      sync_arm_(c_.clock_sync),
      step_base_laser_(o_.max_stamp_lag),
      step_arm_laser_(o_.max_stamp_lag),
      step_gyro_(o_.max_stamp_lag),
      step_arm_(o_.max_stamp_lag),
      workpiece_(c_.site),
      placement_bias_(o_.placement_bias, !o_.placement_bias_per_position ? PlacementBiasScope::kRobot
                                        : o_.placement_bias_robot_part ? PlacementBiasScope::kRobotAndPosition
                                                                       : PlacementBiasScope::kPosition) {
  const Pose3& T = c_.robot.T_base_base_laser;
  estimator_ = std::make_unique<base::BaseStateEstimator>(c_.estimator, Pose2Of(T));
  commands_sent_ = std::make_unique<base::TrackCommandHistory>(c_.base_geometry.track_gauge);
  arm_ = std::make_unique<arm::ArmPrimitives>(c_.robot, c_.arm);
  workpiece_.bricks.clear();
  // The fastest turn the tracks allow (one forward, one back at full speed); a gyro reading far
  // beyond it is a shock or a glitch, not motion.
  const auto& g = c_.base_geometry;
  max_gyro_rate_ = o_.max_gyro_rate_factor * 2.0 * g.max_track_speed / std::max(1e-3, g.track_gauge);
}

void Mission::SendTracks(const TrackCommand& command) {
  robot_.CommandTracks(command);
  commands_sent_->Add(command);  // what the controller sent: the commanded-speed prior's input
}

void Mission::Note(const std::string& kind, const std::string& what) {
  incidents_.push_back({robot_.Now(), kind, what});
  spdlog::warn("{}: {}", kind, what);
}

Mission::~Mission() = default;

void Mission::Progress(const std::string& text) {
  spdlog::info("{}", text);
  if (on_progress) on_progress(text);
}

Pose3 Mission::Pose3Of(const Pose2& p) const {
  return PoseFromXyzRpy(p.x, p.y, c_.site.ground_z, 0, 0, p.theta);
}

void Mission::Start(const Pose2& T_site_base, const Vector6d& q) {
  T_site_base_ = T_site_base;
  estimating_ = false;  // standing at the start; estimation begins with the first drive
  q_ = q;
  last_scan_mid_ = robot_.Now();
  last_base_scan_arrival_ = robot_.Now();
  estimator_->Reset(T_site_base, last_scan_mid_);
  robot_.SetLaserActive(DeviceId::kArmLaser, false);
  T_site_base_ref_ = Pose3Of(T_site_base);  // given, not measured: the reference until the first scan
  up_ref_.reset();
}

void Mission::PumpSensors() {
  // Clock sync first: pulses, then every packet's device stamp mapped to host time.
  for (const SyncPulse& p : robot_.TakeSyncPulses()) {
    switch (p.device) {
      case DeviceId::kBaseLaser: sync_base_laser_.AddPulse(p); break;
      case DeviceId::kArmLaser: sync_arm_laser_.AddPulse(p); break;
      case DeviceId::kGyro: sync_gyro_.AddPulse(p); break;
      case DeviceId::kArm: sync_arm_.AddPulse(p); break;
    }
  }
  // Every packet's stamp enters its device's sync first (one refit per device and pump, not one
  // per packet), then the packets are mapped to host time. A packet is used once its device's
  // clock is synced, and only if it is newer than the last one used.
  std::vector<GyroSample> gyro_in = robot_.TakeGyroSamples();
  std::vector<LaserScan> base_in = robot_.TakeLaserScans(DeviceId::kBaseLaser);
  std::vector<LaserScan> arm_in = robot_.TakeLaserScans(DeviceId::kArmLaser);
  std::vector<JointState> joints_in = robot_.TakeJointStates();
  std::vector<AccelSample> accel_in = robot_.TakeAccelSamples();
  if (!base_in.empty()) {
    // The newest scan's points in the base frame (design mount), for the protective field.
    const LaserScan& s = base_in.back();
    const Pose3& T = c_.robot.T_base_base_laser;
    last_scan_points_.clear();
    for (std::size_t i = 0; i < s.size(); ++i) {
      const double r = s.ranges[i];
      if (!std::isfinite(r) || r < s.range_min || r > s.range_max) continue;
      const double a = s.angle_min + static_cast<double>(i) * s.angle_increment;
      const Eigen::Vector3d p = T * Eigen::Vector3d(r * std::cos(a), r * std::sin(a), 0.0);
      last_scan_points_.emplace_back(p.x(), p.y());
    }
  }
  // A device whose synced stamps land far from their arrival time has a broken clock mapping,
  // and one whose raw stamps step against their arrival had its clock jump (seen even when the
  // sync has restarted on the new pairs meanwhile): forget its sync, learn it from the next pulses.
  auto check_clock = [&](DeviceClockSync& sync, ClockStepDetector& steps, auto& packets, const char* name) {
    int off = 0;
    Seconds step = 0.0;
    // The skew as the sync fitted it; its line is pinned to within max_early at both ends of the
    // window, so the slope to about 2 max_early / window. Before any fit: the largest skew trusted.
    const std::optional<ClockMapping> m = sync.clock().Mapping();
    const double skew = m ? m->Skew() : 0.0;
    const double skew_unc = m && c_.clock_sync.max_early > 0
                                ? 2.0 * c_.clock_sync.max_early / c_.clock_sync.window
                                : c_.clock_sync.max_abs_skew;
    for (const auto& p : packets) {
      Stamp st = p.stamp;
      if (sync.Apply(st) && std::abs(st.t - st.t_host_received) > o_.max_stamp_lag) ++off;
      if (const Seconds s = steps.Add(p.stamp, skew, skew_unc); s != 0.0) step = s;
    }
    if (off == 0 && step == 0.0) return;
    sync = DeviceClockSync(c_.clock_sync);
    packets.clear();
    if (step != 0.0)
      Note("clock_sync_reset", fmt::format("the {}'s clock stepped by {:+.2f} s against its packets' arrival; "
                                           "re-syncing it", name, step));
    else
      Note("clock_sync_reset", fmt::format("{} packets of the {} synced more than {:.2f} s from their arrival; "
                                           "re-syncing its clock", off, name, o_.max_stamp_lag));
  };
  for (const auto& g : gyro_in) sync_gyro_.AddPacket(g.stamp);
  for (const auto& s : base_in) sync_base_laser_.AddPacket(s.stamp);
  for (const auto& s : arm_in) sync_arm_laser_.AddPacket(s.stamp);
  for (const auto& j : joints_in) sync_arm_.AddPacket(j.stamp);
  check_clock(sync_gyro_, step_gyro_, gyro_in, "gyro");
  check_clock(sync_base_laser_, step_base_laser_, base_in, "base laser");
  check_clock(sync_arm_laser_, step_arm_laser_, arm_in, "arm laser");
  check_clock(sync_arm_, step_arm_, joints_in, "arm");
  auto synced = [](const DeviceClockSync& sync, Stamp& stamp, Seconds& last) {
    if (!sync.Apply(stamp) || stamp.t <= last) return false;
    last = stamp.t;
    return true;
  };
  std::vector<GyroSample> gyro;
  int spikes = 0;
  for (auto& g : gyro_in) {
    if (std::abs(g.rate.z()) > max_gyro_rate_) {
      ++spikes;
      continue;
    }
    if (synced(sync_gyro_, g.stamp, last_gyro_)) gyro.push_back(g);
  }
  if (spikes > 0)
    Note("gyro_spikes", fmt::format("{} gyro samples beyond {:.2f} rad/s (the tracks' fastest turn x {:.1f}) "
                                    "left out", spikes, max_gyro_rate_, o_.max_gyro_rate_factor));
  std::vector<LaserScan> scans;
  for (auto& s : base_in)
    if (synced(sync_base_laser_, s.stamp, last_base_scan_)) scans.push_back(std::move(s));
  // Silence is judged on scans the estimator can use (arrived and synced), not on raw packets.
  if (!scans.empty()) last_base_scan_arrival_ = robot_.Now();
  for (auto& s : arm_in)
    if (synced(sync_arm_laser_, s.stamp, last_arm_scan_)) arm_scans_.push_back(std::move(s));
  for (auto& j : joints_in)
    if (synced(sync_arm_, j.stamp, last_joint_state_)) joint_states_.push_back(j);
  // Accelerometer samples come in the gyro's packets: the gyro's sync maps their stamps. Only the
  // last minute is kept (tilt is measured over windows of a second or two).
  for (auto& a : accel_in)
    if (sync_gyro_.Apply(a.stamp)) accel_.push_back(a);
  if (!accel_.empty() && accel_.front().stamp.t < accel_.back().stamp.t - 60.0) {
    const Seconds keep = accel_.back().stamp.t - 30.0;
    accel_.erase(accel_.begin(), std::find_if(accel_.begin(), accel_.end(),
                                              [&](const AccelSample& a) { return a.stamp.t >= keep; }));
  }
  // While the base stands still for arm work nothing moves it: the estimator rests, and is reset
  // to the current pose before the next drive.
  if (!estimating_) {
    if (!scans.empty()) last_scan_mid_ = scans.back().MidTime();
    return;
  }
  // Gyro samples up to each scan go in before it (the estimator integrates between scans).
  std::size_t gi = 0;
  for (const auto& scan : scans) {
    const double t_scan = scan.MidTime();
    while (gi < gyro.size() && gyro[gi].stamp.t <= t_scan) estimator_->AddGyro(gyro[gi++]);
    // The commanded track speeds since the previous scan as a weak motion prior (an option;
    // the default is the paper's gyro-only eq. 2).
    const auto& commanded = c_.estimator.commanded_speeds;
    const base::BaseEstimate& e =
        commanded.use ? estimator_->AddScan(scan, commands_sent_->Measure(last_scan_mid_, t_scan, commanded.noise))
                      : estimator_->AddScan(scan);
    last_scan_mid_ = t_scan;
    commands_sent_->DropBefore(t_scan);
    if (e.IsUsable() || e.status == base::EstimateStatus::kTooFewPoints) T_site_base_ = e.T_world_base;
    if (trace_) trace_->push_back({e.t, e.T_world_base});
  }
  for (; gi < gyro.size(); ++gi) estimator_->AddGyro(gyro[gi]);
}

base::PlanningScene Mission::Scene() const {
  base::PlanningScene scene;
  scene.boundary = workpiece_.boundary;
  for (const auto* group : {&workpiece_.walls, &workpiece_.obstacles, &workpiece_.bricks}) {
    for (const auto& b : *group) {
      scene.obstacles.push_back(Footprint(b));
      scene.obstacle_names.push_back(b.name);
    }
  }
  return scene;
}

bool Mission::RunArm(const arm::PrimitiveResult& steps, const std::string& what) {
  bool lost = false;
  if (RunArmSteps(steps, what, false, &lost)) return true;
  if (lost && !stopped_) StopSafely(fmt::format("{}: the vacuum lost the brick", what));
  return false;
}

bool Mission::RunArmSteps(const arm::PrimitiveResult& steps, const std::string& what, bool holding, bool* lost_grip) {
  *lost_grip = false;
  if (!steps.ok) {
    StopSafely(fmt::format("{}: {}", what, steps.message));
    return false;
  }
  // Where the arm is after the first n steps (the last trajectory's end point).
  const auto q_after = [&](std::size_t n) {
    Vector6d q = q_;
    for (std::size_t i = 0; i < n && i < steps.steps.size(); ++i)
      if (!steps.steps[i].trajectory.points.empty()) q = steps.steps[i].trajectory.points.back().q;
    return q;
  };
  std::size_t next = 0;
  for (int attempt = 0;; ++attempt) {
    const std::vector<arm::ArmStep> rest(steps.steps.begin() + static_cast<std::ptrdiff_t>(next), steps.steps.end());
    arm::ExecuteOptions eo;
    eo.holding = holding;
    const arm::ExecuteResult r = arm::ExecuteSteps(robot_, rest, eo);
    PumpSensors();
    for (std::size_t i = 0; i < static_cast<std::size_t>(r.steps_done); ++i)
      if (rest[i].gripper != arm::GripperAction::kNone) holding = rest[i].gripper == arm::GripperAction::kGrip;
    q_ = q_after(next + static_cast<std::size_t>(r.steps_done));
    if (r.ok) {
      q_ = steps.q_end;
      return true;
    }
    if (r.lost_grip) {
      *lost_grip = true;
      return false;
    }
    // A refused trajectory did not move the arm: the same one is sent again from where it is.
    if (r.rejected && attempt < o_.arm_retries) {
      Note("arm_rejected", fmt::format("{}: {}; sending it again (retry {} of {})", what, r.message, attempt + 1,
                                       o_.arm_retries));
      next += static_cast<std::size_t>(r.steps_done);
      continue;
    }
    StopSafely(fmt::format("{}: {}", what, r.message));
    return false;
  }
}

void Mission::StopSafely(const std::string& why) {
  SendTracks({robot_.Now(), 0.0, 0.0});
  if (!stopped_) {
    stopped_ = true;
    stop_reason_ = why;
    spdlog::warn("mission stopped: {}", why);
    Note("safe_stop", why);
    // A held brick goes back onto the feeder first (a stopped robot holds nothing), then the arm
    // parks. If either cannot be planned the vacuum stays on: a held brick is not dropped.
    if (robot_.VacuumHolding() == true) {
      const Pose3 T_site_base = Pose3Of(T_site_base_);
      const auto back = arm_->PlaceBrick(q_, T_site_base, T_site_base * o_.T_base_feeder, c_.site.brick);
      if (back.ok && arm::ExecuteSteps(robot_, back.steps, {.holding = true}).ok) q_ = back.q_end;
    }
    const auto park = arm_->MoveToJoints(q_, o_.q_park);
    if (park.ok) arm::ExecuteSteps(robot_, park.steps);
  }
}

bool Mission::Reposition(const BuildingPosition& goal, VisitLog& log) {
  log.desired = goal.T_site_base;
  log.start_estimate = T_site_base_;
  // The arm is parked while driving.
  if ((q_ - o_.q_park).cwiseAbs().maxCoeff() > 1e-3) {
    Progress(fmt::format("{}: parking the arm", goal.name));
    if (!RunArm(arm_->MoveToJoints(q_, o_.q_park), "park the arm")) return false;
  }

  Progress(fmt::format("{}: planning the base trajectory", goal.name));
  const base::StompBasePlanner planner(Scene(), c_.base_geometry, c_.planner);
  for (int attempt = 0; attempt < o_.plan_attempts; ++attempt) {
    log.plan = planner.Plan(T_site_base_, goal.T_site_base, rng_.Derive(static_cast<std::uint64_t>(attempt)));
    if (log.plan.IsUsable()) break;
    spdlog::warn("plan to {} failed ({}), attempt {}", goal.name, log.plan.BriefReport(), attempt + 1);
  }
  if (!log.plan.IsUsable()) {
    log.failure = "no plan: " + log.plan.BriefReport();
    return false;
  }

  Progress(fmt::format("{}: driving ({:.1f} m planned)", goal.name, log.plan.trajectory.Length()));
  estimator_->Reset(T_site_base_, last_scan_mid_, /*keep_references=*/true);
  estimating_ = true;
  trace_ = &log.estimated;
  known_.emplace(Scene(), c_.base_geometry);
  bool arrived = false;
  base::BaseControllerOutput u = Follow(log.plan.trajectory, &arrived);
  // Timed out off the goal (a stalled or slipping track): plan from where it is and drive again.
  for (int retry = 0; !arrived && !stopped_ && retry < o_.drive_retries; ++retry) {
    const base::PlanResult again = planner.Plan(T_site_base_, goal.T_site_base, rng_.Derive(100u + static_cast<std::uint64_t>(retry)));
    if (!again.IsUsable()) break;
    Note("replan", fmt::format("{}: the maneuver timed out {:.1f} cm from the goal; planned again ({:.1f} m)", goal.name,
                               100.0 * u.end_distance, again.trajectory.Length()));
    u = Follow(again.trajectory, &arrived);
  }
  // A tracked base cannot move sideways: an offset the tracking left at the end is driven out by
  // reversing along the goal's line and coming forward onto it (or forward first, if reversing
  // would hit something).
  std::optional<base::FootprintChecker> footprint;  // built only if a re-approach is needed
  spdlog::debug("{}: maneuver ended {} at {:.1f} cm from the goal ({:.1f} cm sideways)", goal.name,
                arrived ? "in tolerance" : "on time-out", 100.0 * u.end_distance, 100.0 * u.end_lateral_error);
  while (arrived && u.end_distance > o_.reapproach_tolerance && log.reapproaches < o_.max_reapproaches) {
    if (!footprint) footprint.emplace(Scene(), c_.base_geometry);
    std::optional<std::array<base::BaseTrajectory, 2>> legs;
    for (bool reverse_first : {true, false}) {
      auto candidate = base::ReapproachTrajectories(T_site_base_, goal.T_site_base, o_.reapproach_distance,
                                                    o_.reapproach_speed, reverse_first);
      bool clear = true;
      for (const auto& leg : candidate)
        for (const auto& p : leg.points) clear = clear && footprint->Clearance(p.pose) > 0.0;
      if (clear) {
        legs = std::move(candidate);
        break;
      }
    }
    if (!legs) {
      spdlog::debug("{}: no collision-free re-approach", goal.name);
      break;
    }
    ++log.reapproaches;
    Progress(fmt::format("{}: re-approaching ({:.1f} cm sideways)", goal.name, 100.0 * u.end_lateral_error));
    for (const auto& leg : *legs) {
      u = Follow(leg, &arrived);
      if (!arrived) break;
    }
  }
  if (stopped_) {
    trace_ = nullptr;
    estimating_ = false;
    log.failure = stop_reason_;
    return false;
  }
  SendTracks({robot_.Now(), 0.0, 0.0});
  for (double t = 0; t < o_.settle_time; t += o_.control_period) {
    robot_.Wait(o_.control_period);
    PumpSensors();
  }
  trace_ = nullptr;
  estimating_ = false;
  log.end_estimate = T_site_base_;
  // A new stop: until the workpiece is scanned here, the estimate is all there is.
  T_site_base_ref_ = Pose3Of(T_site_base_);
  up_ref_.reset();
  if (!arrived) spdlog::warn("{}: the controller did not reach the goal tolerance in time", goal.name);
  return true;
}

base::BaseControllerOutput Mission::Follow(const base::BaseTrajectory& trajectory, bool* arrived) {
  base::BaseTrajectoryController controller(c_.controller);
  controller.SetTrajectory(trajectory);
  Seconds deadline = robot_.Now() + o_.drive_timeout_factor * trajectory.duration + o_.drive_timeout_margin;
  *arrived = false;
  base::BaseControllerOutput u;
  while (robot_.Now() < deadline && !stopped_) {
    robot_.Wait(o_.control_period);
    PumpSensors();
    u = controller.Update(T_site_base_, robot_.Now());
    if (u.done) {
      *arrived = true;
      break;
    }
    TrackCommand command = u.command;
    // Never drive blind (a silent base laser leaves the pose stale) or into something the site
    // model does not have (a person): stop, wait, go on where the controller left off.
    Seconds held = 0.0;
    if (!HoldWhileUnsafe(command.v_left + command.v_right, &held)) break;
    if (held > 0.0) {
      deadline += held;
      continue;
    }
    command.t = robot_.Now();
    SendTracks(command);
  }
  SendTracks({robot_.Now(), 0.0, 0.0});
  return u;
}

int Mission::PointsInProtectiveField(double direction) const {
  if (o_.protective_field <= 0.0 || !known_) return 0;
  const auto& g = c_.base_geometry;
  const double half_l = 0.5 * g.length, half_w = 0.5 * g.width + 0.1;
  const Pose2 T = T_site_base_;
  int n = 0;
  for (const Eigen::Vector2d& p : last_scan_points_) {
    const Eigen::Vector2d q = p - g.footprint_offset;
    const double ahead = direction >= 0 ? q.x() - half_l : -q.x() - half_l;
    if (ahead < 0.0 || ahead > o_.protective_field || std::abs(q.y()) > half_w) continue;
    // Explained by the site as known (walls, obstacles, the stack)?
    if (known_->PointClearance(T * p) < o_.protective_field_margin) continue;
    ++n;
  }
  return n;
}

bool Mission::HoldWhileUnsafe(double direction, Seconds* held) {
  *held = 0.0;
  const Seconds t0 = robot_.Now();
  bool noted_silence = false, noted_block = false;
  for (;;) {
    const bool silent = robot_.Now() - last_base_scan_arrival_ > o_.max_scan_gap;
    const bool blocked = !silent && std::abs(direction) > 1e-6 &&
                         PointsInProtectiveField(direction) >= o_.protective_field_points;
    if (!silent && !blocked) break;
    if (*held == 0.0) SendTracks({robot_.Now(), 0.0, 0.0});
    if (silent && !noted_silence) {
      Note("base_laser_silent", fmt::format("no base laser scan for {:.2f} s: stopped the base to wait for it",
                                            robot_.Now() - last_base_scan_arrival_));
      noted_silence = true;
    }
    if (blocked && !noted_block) {
      Note("path_blocked", fmt::format("{} unknown points within {:.1f} m {} the base: stopped to wait for the path "
                                       "to clear", PointsInProtectiveField(direction), o_.protective_field,
                                       direction >= 0 ? "ahead of" : "behind"));
      noted_block = true;
    }
    const double limit = silent ? o_.sensor_wait_timeout : o_.obstacle_wait_timeout;
    if (robot_.Now() - t0 > limit) {
      StopSafely(silent ? fmt::format("the base laser stayed silent for {:.0f} s", limit)
                        : fmt::format("the path stayed blocked for {:.0f} s", limit));
      return false;
    }
    robot_.Wait(o_.control_period);
    PumpSensors();
    *held = robot_.Now() - t0;
  }
  if (*held > 0.0) {
    // Clear for a moment more (a person walking off), then go on.
    for (double t = 0; t < 1.0; t += o_.control_period) {
      robot_.Wait(o_.control_period);
      PumpSensors();
    }
    *held = robot_.Now() - t0;
    Note(noted_block ? "path_blocked" : "base_laser_silent",
         fmt::format("resumed driving after {:.1f} s", *held));
  }
  return true;
}

Mission::Sweep Mission::SweepWorkpiece(VisitLog& log, int sweep) {
  Sweep out;
  // Predict where the top of the workpiece is, and look at it along a diagonal of the brick
  // so that its top and two side faces are seen.
  const Pose3 T_site_base = Pose3Of(T_site_base_);
  const SiteBox& top = workpiece_.bricks.back();
  const Eigen::Vector3d p_top = top.T_site_box * Eigen::Vector3d(0, 0, 0.5 * top.box.size.z());
  const Eigen::Vector2d to_robot = (T_site_base.translation() - p_top).head<2>().normalized();
  const double brick_yaw = XyzRpyFromPose(top.T_site_box)[5];
  double best = -2;
  Eigen::Vector2d diagonal = to_robot;
  for (int k = 0; k < 4; ++k) {
    const double a = brick_yaw + kPi / 4 + k * kPi / 2 + (sweep % 2) * 0.15;  // vary between sweeps
    const Eigen::Vector2d d(std::cos(a), std::sin(a));
    if (d.dot(to_robot) > best) {
      best = d.dot(to_robot);
      diagonal = d;
    }
  }
  const double el = DegToRad(o_.scan_elevation_deg);
  const Eigen::Vector3d p_laser = p_top + o_.scan_distance * Eigen::Vector3d(std::cos(el) * diagonal.x(),
                                                                           std::cos(el) * diagonal.y(), std::sin(el));
  const Eigen::Vector3d look = (p_top - p_laser).normalized();
  const Eigen::Vector3d x_tool = look.cross(Eigen::Vector3d::UnitZ()).normalized();  // scan plane vertical
  Pose3 T_site_tool0 = Pose3::Identity();
  T_site_tool0.linear().col(0) = x_tool;
  T_site_tool0.linear().col(1) = look.cross(x_tool);
  T_site_tool0.linear().col(2) = look;
  // The laser, not the flange, is at p_laser: shift the flange back by the mount.
  T_site_tool0.translation() = p_laser - T_site_tool0.linear() * c_.T_tool0_arm_laser.translation();
  const Pose3 T_arm_base_tool0 =
      (T_site_base * c_.robot.T_base_arm_base).inverse(Eigen::Isometry) * T_site_tool0;
  const auto ik = arm_->ik().Solve(T_arm_base_tool0, q_);
  if (!ik.ok()) {
    log.failure = "scan pose out of reach: " + ik.message;
    return out;
  }
  const double half = DegToRad(o_.sweep_half_angle_deg);
  // To the scan pose (joint 1 turned to the sweep's start), then sweep joint 1 across it.
  Vector6d q_start = ik.q;
  q_start[0] -= half;
  arm::PrimitiveResult sweep_steps = arm_->MoveToJoints(q_, q_start);
  if (sweep_steps.ok)
    sweep_steps.Append(arm_->SweepJoint(q_start, 0, q_start[0], ik.q[0] + half, DegToRad(o_.sweep_speed_deg_s)));
  if (!sweep_steps.ok) {
    log.failure = "sweep: " + sweep_steps.message;
    return out;
  }
  arm_scans_.clear();
  joint_states_.clear();
  PumpSensors();
  arm_scans_.clear();
  joint_states_.clear();
  robot_.SetLaserActive(DeviceId::kArmLaser, true);  // the arm laser works only for sweeps
  const Seconds sweep_t0 = robot_.Now();
  const bool sweep_ok = RunArm(sweep_steps, "scan sweep");
  const Seconds sweep_t1 = robot_.Now();
  robot_.SetLaserActive(DeviceId::kArmLaser, false);
  if (!sweep_ok) {
    out.status = SweepStatus::kStop;
    return out;
  }

  // Eq. 6, then keep what lies near the workpiece (and the floor around it).
  // The ranges as read are kept: once the workpiece is registered, each return's incidence comes
  // from the model's face (Localize); until then from its neighbours' normal.
  ScanAssemblyOptions as_read = c_.assembly;
  as_read.range_bias.compensate = false;
  std::vector<SweepPoint> points = AssembleSweep(arm_scans_, joint_states_, c_.robot, as_read).points;
  if (o_.level_sweeps)
    if (const auto up = MeanUp(accel_, sweep_t0, sweep_t1)) LevelSweepPoints(points, accel_, *up);
  const std::vector<RayPoint> swept = ToBaseFrame(points, c_.T_tool0_arm_laser);
  const Eigen::Vector3d p_stack_base = T_site_base.inverse(Eigen::Isometry) * p_top;
  for (const RayPoint& p : swept)
    if ((p.p - p_stack_base).head<2>().norm() < o_.crop_radius) out.raw_cloud.push_back(p);
  if (o_.measure_footprint) out.uncropped = swept;
  out.cloud = out.raw_cloud;
  CompensateRangeBias(out.cloud, c_.assembly.range_bias);
  out.status = SweepStatus::kOk;
  out.t0 = sweep_t0;
  out.t1 = sweep_t1;
  out.T_site_base = T_site_base;
  return out;
}

namespace {
/// A registration whose result only starts the next one (after the range bias is compensated with
/// the incidences it gives): without restarts, which the final registration runs from there.
RegistrationOptions Preliminary(RegistrationOptions o) {
  o.restarts = 0;
  return o;
}
}  // namespace

bool Mission::Localize(VisitLog& log) {
  if (workpiece_.bricks.empty()) {  // nothing built yet: the start pose is all there is
    log.localized = false;
    return true;
  }
  for (int sweep = 0; sweep < o_.max_sweeps; ++sweep) {
    Progress(fmt::format("{}: scanning the workpiece (sweep {})", log.position, sweep + 1));
    Sweep swept = SweepWorkpiece(log, sweep);
    if (swept.status == SweepStatus::kStop) return false;
    if (swept.status == SweepStatus::kRetry) continue;
    ++log.sweeps;
    log.cloud = std::move(swept.cloud);
    const Pose3& T_site_base = swept.T_site_base;
    const Seconds sweep_t0 = swept.t0, sweep_t1 = swept.t1;
    Site model = workpiece_;  // register against the workpiece (the stack as built) and the ground
    model.walls.clear();
    model.obstacles.clear();
    // The base's up while it scanned (it stands still; the sweep turns only joint 1).
    const std::optional<Eigen::Vector3d> up_scan = MeanUp(accel_, sweep_t0, sweep_t1);
    Pose3 guess = T_site_base;
    std::array<bool, 6> held{};
    if (o_.registration_attitude == RegistrationAttitude::kImu && up_scan) {
      guess = LevelledPose(T_site_base, *up_scan);
      held[3] = held[4] = true;  // roll and pitch, about the base's x and y through the site origin
    }
    // With the range bias's incidence taken from the model, this registration only says where the
    // model is for that, and the one after it starts from its result: restarts there (issue 15).
    const RangeBiasCompensation& bias = c_.assembly.range_bias;
    const bool preliminary = bias.active() && bias.incidence_from_model;
    SiteLocalization loc = LocalizeInSite(log.cloud, model, guess, preliminary ? Preliminary(c_.registration) : c_.registration,
                                          true, held);
    // Range bias with the incidence on the registered model (a brick's 52 mm side is narrower
    // than the normals' neighbourhood), then register again from there. That registration waits
    // for the top brick's footprint below, which changes the model and registers again anyway:
    // one registration instead of two (the size comes from near faces and far edges both, so
    // the first registration's pose measures it as well; issue 15, session 24).
    bool register_again = false;
    if (preliminary && loc.IsUsable()) {
      const ifab::Scene at_registration(SiteBodies(model, loc.T_site_base, true));
      log.cloud = swept.raw_cloud;
      CompensateRangeBias(log.cloud, bias, &at_registration);
      register_again = true;
    }
    const auto register_if_pending = [&] {
      if (!register_again) return;
      loc = LocalizeInSite(log.cloud, model, loc.T_site_base, c_.registration, true, held);
      register_again = false;
    };
    if (o_.measure_top) register_if_pending();  // the top face is measured on the final pose, as before
    // The stack as built (measure_top): move the model's top brick to the height its top face is
    // seen at, and register again when that moved it by more than twice the measurement's error.
    std::optional<Pose3> top_before;
    if (o_.measure_top && loc.IsUsable()) {
      SiteBox& top_brick = workpiece_.bricks.back();
      const double designed_top = top_brick.T_site_box.translation().z() + 0.5 * top_brick.box.size.z();
      if (const auto m = MeasureTopFace(log.cloud, loc.T_site_base, top_brick, c_.site.ground_z);
          m && std::abs(c_.site.ground_z + m->height - designed_top) > 2.0 * m->std) {
        top_before = top_brick.T_site_box;
        top_brick.T_site_box.translation().z() += c_.site.ground_z + m->height - designed_top;
        model.bricks = workpiece_.bricks;
        loc = LocalizeInSite(log.cloud, model, loc.T_site_base, c_.registration, true, held);
        spdlog::debug("{}: top face {:.1f} mm above the floor ({:.2f} mm, {} / {} points); registered again",
                      log.position, 1e3 * m->height, 1e3 * m->std, m->points, m->floor_points);
      }
    }
    // The top brick as built (measure_footprint): its length and width, each measured axis fused
    // with the design and its tolerance (a Kalman update of one number), and (hold_measured_position)
    // its centre where measured, once there is a stack below it to measure it against (the
    // first brick defines the site); then registered again when the model changed by more than
    // half a millimetre. The size does not depend on the registration (near faces and far edges
    // are both measured), once is enough; the centre is measured against a registration that
    // follows the model's top brick in part, so it is measured up to three times.
    std::optional<SiteBox> top_before_footprint;
    std::optional<FootprintMeasurement> last_footprint;  // the last pass's, and whether it moved the model
    bool last_footprint_held = false;
    const int footprint_passes = o_.hold_measured_position ? 3 : 1;
    for (int pass = 0; o_.measure_footprint && loc.IsUsable() && pass < footprint_passes; ++pass) {
      SiteBox& top_brick = workpiece_.bricks.back();
      const auto m = MeasureTopFootprint(log.cloud, loc.T_site_base, top_brick, c_.site.ground_z, &swept.uncropped);
      if (!m) break;
      last_footprint = m;
      last_footprint_held = false;
      if (pass == 0)
        for (int a = 0; a < 2; ++a)
          log.top_offset_mm[a] = m->measured[static_cast<std::size_t>(a)] ? 1e3 * m->centre_offset[a] : std::nan("");
      SiteBox moved = top_brick;
      for (int a = 0; a < 2; ++a) {
        if (!m->measured[static_cast<std::size_t>(a)]) continue;
        moved.box.size[a] = BrickSizeAsBuilt(a, *m);
        if (o_.hold_measured_position && workpiece_.bricks.size() > 1)
          moved.T_site_box.translation() += moved.T_site_box.linear().col(a) * m->centre_offset[a];
      }
      const double change = std::max((moved.box.size - top_brick.box.size).cwiseAbs().maxCoeff(),
                                     (moved.T_site_box.translation() - top_brick.T_site_box.translation()).norm());
      spdlog::debug("{}: top brick measured {:.1f} x {:.1f} mm (+-{:.2f} / {:.2f}), centre {:+.1f} / {:+.1f} mm; "
                    "modelled {:.1f} x {:.1f} mm ({} / {} rays at the far edges)", log.position, 1e3 * m->size.x(),
                    1e3 * m->size.y(), 1e3 * m->std.x(), 1e3 * m->std.y(), 1e3 * m->centre_offset.x(),
                    1e3 * m->centre_offset.y(), 1e3 * moved.box.size.x(), 1e3 * moved.box.size.y(), m->edge_rays[0],
                    m->edge_rays[1]);
      if (change <= 0.0005) break;
      if (!top_before_footprint) top_before_footprint = top_brick;
      top_brick = moved;
      last_footprint_held = o_.hold_measured_position && workpiece_.bricks.size() > 1;
      model.bricks = workpiece_.bricks;
      loc = LocalizeInSite(log.cloud, model, loc.T_site_base, c_.registration, true, held);
      register_again = false;
    }
    register_if_pending();  // the footprint did not change the model
    log.registration_report = loc.registration.BriefReport();
    log.cloud_labels = loc.registration.labels;
    // Trust is judged on the workpiece's pose in the base frame: that is what placing a brick
    // uses (T_site_base's position std is mostly the workpiece's yaw std times the distance).
    const RegisteredBody* workpiece = loc.registration.Find("site");
    const double std_xy = workpiece ? std::sqrt(std::max(workpiece->covariance(0, 0), workpiece->covariance(1, 1))) : 1e9;
    const double std_yaw = workpiece ? RadToDeg(std::sqrt(workpiece->covariance(5, 5))) : 1e9;
    const Pose2 localized = Pose2Of(loc.T_site_base);
    const double jump = TranslationDistance(localized, T_site_base_);
    std::string why;
    if (!loc.IsUsable()) why = "registration failed";
    else if (!workpiece || workpiece->inliers < o_.min_inliers)
      why = fmt::format("{} points on the workpiece", workpiece ? workpiece->inliers : 0);
    else if (std_xy > o_.max_localization_std_m) why = fmt::format("position std {:.4f} m", std_xy);
    else if (std_yaw > o_.max_localization_std_deg) why = fmt::format("heading std {:.3f} deg", std_yaw);
    else if (jump > o_.max_localization_jump_m) why = fmt::format("correction of {:.3f} m", jump);
    for (const auto& b : loc.registration.bodies)
      if (b.name != "ground" && !b.unconstrained.empty() && why.empty()) why = "unconstrained: " + b.unconstrained.front();
    if (!why.empty() && top_before) workpiece_.bricks.back().T_site_box = *top_before;  // not measured after all
    if (!why.empty() && top_before_footprint) workpiece_.bricks.back() = *top_before_footprint;
    if (!why.empty()) {
      spdlog::warn("{}: registration not trusted ({}); {}", log.position, why, log.registration_report);
      for (const auto& b : loc.registration.bodies) {
        std::string dirs;
        for (const auto& d : b.unconstrained) dirs += d + "; ";
        spdlog::warn("  body {}: {} inliers, std diag [{:.4f} {:.4f} {:.4f} {:.4f} {:.4f} {:.4f}] {}", b.name,
                     b.inliers, std::sqrt(b.covariance(0, 0)), std::sqrt(b.covariance(1, 1)),
                     std::sqrt(b.covariance(2, 2)), std::sqrt(b.covariance(3, 3)), std::sqrt(b.covariance(4, 4)),
                     std::sqrt(b.covariance(5, 5)), dirs);
      }
      log.failure = "registration not trusted: " + why;
      if (sweep + 1 < o_.max_sweeps) Note("resweep", fmt::format("{}: {}; sweeping again", log.position, log.failure));
      continue;
    }
    log.failure.clear();
    // The last brick's miss, against the stack below it (the first brick defines the site).
    if (o_.learn_placement_bias && !LookFeedsPlacementBias() && last_footprint && last_sent_ && workpiece_.bricks.size() > 1 &&
        last_sent_->index + 1 == workpiece_.bricks.size()) {
      const SiteBox& top = workpiece_.bricks.back();
      Eigen::Vector2d offset;
      for (int a = 0; a < 2; ++a)
        offset[a] = top.T_site_box.linear().col(a).dot(top.T_site_box.translation() - last_sent_->intended) +
                    (last_footprint_held ? 0.0 : last_footprint->centre_offset[a]);
      LearnPlacementBias(offset, 0.5 * last_footprint->std, last_footprint->measured, log);
    }
    log.localized = true;
    log.localized_pose = localized;
    log.T_site_base_at_scan = T_site_base;
    T_site_base_ = localized;
    // The registered full pose and the IMU's up direction while it was scanned (the sweep turns
    // only joint 1 about the vertical: the arm's moment, and so the tilt, barely changes).
    if (held[3])  // the held tilt is the IMU's: its uncertainty, not zero
      loc.covariance = WithHeldTiltCovariance(workpiece->T_base_body, workpiece->covariance, DegToRad(o_.imu_tilt_sigma_deg));
    T_site_base_ref_ = FuseWithFloorPrior(loc.T_site_base, loc.covariance, held[3]);
    log.T_site_base_registered = T_site_base_ref_;
    up_ref_ = up_scan;
    // The registered pose holds from the scan on (the base stood still): reset at the last scan
    // the estimator has seen, so the next one follows it in time.
    estimator_->Reset(localized, last_scan_mid_, /*keep_references=*/true);
    return true;
  }
  StopSafely(fmt::format("{}: no trusted localization after {} sweeps ({})", log.position, log.sweeps, log.failure));
  return false;
}

void Mission::LearnPlacementBias(const Eigen::Vector2d& offset, const Eigen::Vector2d& offset_std,
                                 const std::array<bool, 2>& measured, VisitLog& log) {
  const SiteBox& top = workpiece_.bricks.back();
  const std::string& position = last_sent_->position;
  for (int a = 0; a < 2; ++a) {
    if (!measured[static_cast<std::size_t>(a)]) continue;
    // The miss along the box's axis a, in the base frame the brick was placed from: the bias
    // minus the correction sent, so the bias's look is the offset plus the correction.
    const Eigen::Vector2d u =
        (last_sent_->R_site_base.transpose() * top.T_site_box.linear().col(a).head<2>()).normalized();
    placement_bias_.Update(position, u, offset[a] + u.dot(last_sent_->correction), offset_std[a]);
  }
  // The looks were at the last placement's bias; the next may have moved (all stands: the stack
  // grew for each of them).
  placement_bias_.Predict();
  log.placement_bias_mm = 1e3 * placement_bias_.Bias(position);
  log.placement_bias_std_mm = 1e3 * placement_bias_.Covariance(position).diagonal().cwiseSqrt();
  spdlog::debug("{}: last brick (placed from {}) off by {:+.2f} / {:+.2f} mm (box x / y); placement bias now "
                "{:+.2f} / {:+.2f} mm (+-{:.2f} / {:.2f}, base frame)", log.position, last_sent_->position,
                1e3 * offset.x(), 1e3 * offset.y(), log.placement_bias_mm.x(), log.placement_bias_mm.y(),
                log.placement_bias_std_mm.x(), log.placement_bias_std_mm.y());
}

bool Mission::LookFeedsPlacementBias() const {
  return o_.check_placement && o_.learn_placement_bias && o_.check_against == CheckAgainst::kLocalization;
}

bool Mission::CheckPlacement(int k, VisitLog& log) {
  Progress(fmt::format("{}: checking brick {}", log.position, k + 1));
  const std::string failure_before = log.failure;
  Sweep swept = SweepWorkpiece(log, 0);
  if (swept.status == SweepStatus::kStop) return false;
  if (swept.status == SweepStatus::kRetry) {
    Note("check_skipped", fmt::format("{}: brick {} not checked ({})", log.position, k + 1, log.failure));
    log.failure = failure_before;
    return true;
  }
  // The new brick on its own (height and heading free, tilt as the stack's), the stack below as
  // one body, the ground apart.
  Site below = workpiece_;
  below.walls.clear();
  below.obstacles.clear();
  const SiteBox placed = below.bricks.back();
  below.bricks.pop_back();
  Site alone = below;
  alone.has_ground = false;
  alone.bricks = {placed};
  Pose3 guess = T_site_base_ref_;
  const std::optional<Eigen::Vector3d> up = MeanUp(accel_, swept.t0, swept.t1);
  std::array<bool, 6> held{};
  if (o_.registration_attitude == RegistrationAttitude::kImu && up) {
    guess = LevelledPose(guess, *up);
    held[3] = held[4] = true;
  }
  const bool against_localization = o_.check_against == CheckAgainst::kLocalization;
  std::vector<RegistrationBody> bodies = SiteBodies(below, guess, true);
  // Against the localization everything but the new brick is held where the visit registered it
  // (the ground too: the brick's height and heading are its own), so only the points the brick
  // could claim inform the fit: those within the registration's max_distance of its box. The
  // rest would be matched at every step to inform nothing (issue 15: a look cost more than a
  // localization).
  for (auto& b : bodies)
    if (b.name == "site" || (against_localization && b.name == "ground"))
      b.fixed = against_localization ? std::array<bool, 6>{true, true, true, true, true, true} : held;
  if (against_localization && c_.registration.max_distance > 0.0) {
    const Pose3 T_brick_base = placed.T_site_box.inverse(Eigen::Isometry) * guess;
    const Eigen::Vector3d half = 0.5 * placed.box.size;
    const double reach = c_.registration.max_distance;
    const auto near_brick = [&](const RayPoint& p) {
      const Eigen::Vector3d q = T_brick_base * p.p;
      return (q.cwiseAbs() - half).cwiseMax(0.0).norm() <= reach;
    };
    std::erase_if(swept.cloud, [&](const RayPoint& p) { return !near_brick(p); });
    std::erase_if(swept.raw_cloud, [&](const RayPoint& p) { return !near_brick(p); });
  }
  RegistrationBody brick{"placed", guess.inverse(Eigen::Isometry), {}, true};
  for (const RigidObject& o : alone.Objects())
    if (o.name == placed.name) brick.parts.push_back(o);
  brick.fixed = {false, false, false, true, true, false};  // it lies on the brick below
  bodies.push_back(brick);
  // The range bias with the incidence on the registered bodies, then register again, as Localize
  // does: the sweep's own normals blur a brick's 52 mm side into its top, and the bias they give
  // moved a lone brick by 1.5 / 2.5 mm in the exact world (README, session 19).
  const RangeBiasCompensation& bias = c_.assembly.range_bias;
  const bool preliminary = bias.active() && bias.incidence_from_model;
  RegistrationSummary reg = Register(swept.cloud, bodies, preliminary ? Preliminary(c_.registration) : c_.registration);
  std::vector<RayPoint> compensated;
  const std::vector<RayPoint>* look_cloud = &swept.cloud;
  if (bias.active() && bias.incidence_from_model && reg.IsUsable() && reg.bodies.size() == bodies.size()) {
    for (std::size_t i = 0; i < bodies.size(); ++i) bodies[i].T_base_body = reg.bodies[i].T_base_body;
    const ifab::Scene at_registration(bodies);
    compensated = swept.raw_cloud;
    CompensateRangeBias(compensated, bias, &at_registration);
    reg = Register(compensated, bodies, c_.registration);
    look_cloud = &compensated;
  }
  const RegisteredBody* b = reg.Find("placed");
  const RegisteredBody* stack = reg.Find("site");
  std::string why;
  if (!reg.IsUsable()) why = fmt::format("registration {} ({}); fit: {}", ToString(reg.status), reg.message, reg.fit.message);
  else if (!b || b->inliers < o_.min_brick_inliers) why = fmt::format("{} points on the brick", b ? b->inliers : 0);
  else if (!b->Constrained()) why = "unconstrained: " + b->unconstrained.front();
  else if (stack && !stack->Constrained()) why = "stack unconstrained: " + stack->unconstrained.front();
  if (!why.empty()) {
    Note("check_skipped", fmt::format("{}: brick {} not measured ({})", log.position, k + 1, why));
    return true;
  }
  // The brick relative to the stack below (both seen in this sweep: the sweep's systematic errors
  // cancel); at the start, with no stack yet, relative to the start pose (the site's definition).
  const Pose3 T_base_site = stack ? stack->T_base_body : guess.inverse(Eigen::Isometry);
  Pose3 T_site_brick = T_base_site.inverse(Eigen::Isometry) * b->T_base_body * placed.T_site_box;
  // The brick as built (look_footprint): its centre midway between the registered near faces and
  // the far edges, and its size; the centre's error (half the size's) joins the look's.
  SiteBox seen = placed;
  seen.T_site_box = T_site_brick;
  Eigen::Matrix2d footprint_cov = Eigen::Matrix2d::Zero();
  if (o_.look_footprint) {
    const auto m = MeasureTopFootprint(*look_cloud, T_base_site.inverse(Eigen::Isometry), seen, c_.site.ground_z,
                                       swept.uncropped.empty() ? nullptr : &swept.uncropped);
    for (int a = 0; m && a < 2; ++a) {
      if (!m->measured[static_cast<std::size_t>(a)]) continue;
      const Eigen::Vector3d axis = seen.T_site_box.linear().col(a);
      T_site_brick.translation() += axis * m->centre_offset[a];
      seen.box.size[a] = BrickSizeAsBuilt(a, *m);
      const Eigen::Vector2d u = axis.head<2>().normalized();
      footprint_cov += 0.25 * m->std[a] * m->std[a] * u * u.transpose();
    }
    seen.T_site_box = T_site_brick;
  }
  const Eigen::Vector2d offset =
      (T_site_brick.translation() - placed.T_site_box.translation()).head<2>() + correction_applied_;
  // Its uncertainty at the brick's centre: the brick's pose and the stack's, propagated to that
  // point (left perturbations about base axes through each body's origin), in the site frame.
  const Eigen::Vector3d p_base = b->T_base_body * placed.T_site_box.translation();
  const auto at_centre = [&](const RegisteredBody& body) {
    Eigen::Matrix<double, 3, 6> J;
    J << Eigen::Matrix3d::Identity(), -Skew(p_base - body.T_base_body.translation());
    return Eigen::Matrix3d(J * body.covariance * J.transpose());
  };
  // Against the localization, its error is no part of the look: the brick was sent in the same
  // frame the look measures it in.
  Eigen::Matrix3d cov = at_centre(*b);
  if (stack && !against_localization) cov += at_centre(*stack);
  const Eigen::Matrix3d R_site_base = T_base_site.linear().transpose();
  const Eigen::Matrix2d look_cov = (R_site_base * cov * R_site_base.transpose()).topLeftCorner<2, 2>() + footprint_cov;
  log.placement_offset_mm = 1e3 * (offset - correction_applied_);
  log.placement_offset_std_mm = 1e3 * look_cov.diagonal().cwiseSqrt();
  // A look the arm cannot explain is a wrong registration, not a miss (the placement-bias prior
  // and scatter come from the arm's specification): one good look in a thousand is let go.
  if (double d2 = 0; o_.gate_placement_check) {
    const Eigen::Vector2d miss = offset - correction_applied_;
    if (!ArmCanExplainMiss(miss, look_cov, o_.placement_bias, &d2)) {
      Note("check_rejected", fmt::format("{}: brick {} measured {:.1f} / {:.1f} mm from its goal, beyond what the arm "
                                         "misses by (Mahalanobis^2 {:.1f} > {:.1f}); not used",
                                         log.position, k + 1, 1e3 * miss.x(), 1e3 * miss.y(), d2, kChi2Dof2P999));
      return true;
    }
  }
  if (LookFeedsPlacementBias() && last_sent_ && last_sent_->index + 1 == workpiece_.bricks.size()) {
    // The miss in the base frame the brick was sent from, plus the bias it was sent against: one
    // look at the bias (both axes, with the look's covariance).
    const Eigen::Matrix2d R = last_sent_->R_site_base;
    const Eigen::Vector2d miss_site = (T_site_brick.translation() - last_sent_->intended).head<2>();
    const std::string& position = last_sent_->position;
    const Eigen::Vector2d z = R.transpose() * miss_site + last_sent_->correction;
    const Eigen::Matrix2d z_cov = R.transpose() * look_cov * R;
    // Where the model holds the brick: where the look put it, or (hold_fused_look) that fused
    // with where the filter expected it to land.
    Pose3 T_site_held = T_site_brick;
    if (o_.hold_fused_look)
      T_site_held.translation().head<2>() =
          last_sent_->intended.head<2>() + R * (placement_bias_.FusedMiss(position, z, z_cov) - last_sent_->correction);
    placement_bias_.Update(position, z, z_cov);
    placement_bias_.Predict();
    log.placement_bias_mm = 1e3 * placement_bias_.Bias(position);
    log.placement_bias_std_mm = 1e3 * placement_bias_.Covariance(position).diagonal().cwiseSqrt();
    // The model holds the brick where the look put it (the first stays where it was meant to be:
    // it defines the site), so the next registrations fit the stack as built and do not pull the
    // frame towards each brick's miss.
    if (workpiece_.bricks.size() > 1) workpiece_.bricks.back().T_site_box = T_site_held;
    if (o_.look_footprint) workpiece_.bricks.back().box.size = seen.box.size;
    return true;
  }
  placement_offsets_[log.position].push_back(offset);
  spdlog::debug("{}: brick {} measured {:.2f} / {:.2f} mm from its goal (correction {:.2f} / {:.2f} mm)", log.position,
                k + 1, 1e3 * (offset.x() - correction_applied_.x()), 1e3 * (offset.y() - correction_applied_.y()),
                1e3 * correction_applied_.x(), 1e3 * correction_applied_.y());
  // The model holds the brick where it was measured, once the stack is there to measure it
  // against (the first brick defines the site: it stays where it was meant to be).
  if (stack) workpiece_.bricks.back().T_site_box = T_site_brick;
  if (o_.look_footprint) workpiece_.bricks.back().box.size = seen.box.size;
  return true;
}

double Mission::BrickSizeAsBuilt(int axis, const FootprintMeasurement& m) const {
  // One measured axis fused with the design and its tolerance (a Kalman update of one number).
  const double prior = o_.brick_size_sigma[axis] * o_.brick_size_sigma[axis];
  const double design = c_.site.brick.size[axis];
  return design + prior / (prior + m.std[axis] * m.std[axis]) * (m.size[axis] - design);
}

Pose3 Mission::FuseWithFloorPrior(const Pose3& T_site_base, const Matrix6d& covariance, bool imu_tilt) const {
  const FloorPrior prior{c_.site.ground_z, o_.height_prior_m, DegToRad(o_.attitude_prior_deg),
                         /*on_tilt=*/!imu_tilt || o_.floor_prior_on_imu_tilt};
  return o_.full_covariance_prior ? FuseFloorPrior(T_site_base, covariance, prior)
                                  : FuseFloorPriorPerComponent(T_site_base, covariance, prior);
}

Pose3 Mission::PlacingPose(VisitLog& log) {
  robot_.Wait(o_.tilt_settle);
  PumpSensors();
  const Seconds t0 = robot_.Now();
  robot_.Wait(o_.tilt_window);
  PumpSensors();
  const std::optional<Eigen::Vector3d> up_now = MeanUp(accel_, t0, robot_.Now());
  if (!up_now) {
    if (!warned_no_accel_) spdlog::warn("no accelerometer data: the base's tilt change is not compensated");
    warned_no_accel_ = true;
    return T_site_base_ref_;
  }
  if (!up_ref_) up_ref_ = up_now;  // no scan at this stop (the start): the first placement is the reference
  log.tilt_change_deg.push_back(RadToDeg(TiltAngle(*up_ref_, *up_now)));
  return CompensateTilt(T_site_base_ref_, *up_ref_, *up_now);
}

bool Mission::PlaceBrick(int k, VisitLog& log) {
  const bool full_pose = o_.tilt_compensation != TiltCompensation::kNone;
  const Pose3 T_site_base = full_pose ? T_site_base_ref_ : Pose3Of(T_site_base_);
  const Pose3 T_site_feeder = T_site_base * o_.T_base_feeder;
  Pose3 T_site_goal = workpiece_.DesignedBrickPose(k);
  if (o_.measure_top && !workpiece_.bricks.empty()) {  // on the stack as measured
    const SiteBox& top = workpiece_.bricks.back();
    T_site_goal.translation().z() =
        top.T_site_box.translation().z() + 0.5 * top.box.size.z() + 0.5 * c_.site.brick.size.z();
  }
  const Pose3 T_site_intended = T_site_goal;  // where the brick should land (the model's belief)
  const Eigen::Matrix2d R_site_base = Eigen::Rotation2Dd(Pose2Of(T_site_base).theta).toRotationMatrix();
  if (o_.learn_placement_bias) T_site_goal.translation().head<2>() -= R_site_base * placement_bias_.Bias(log.position);
  correction_applied_.setZero();
  if (o_.placement_correction) {
    // The mean of this stand's last offsets: postures change slowly as the stack grows (a round
    // of four stands adds 0.2 m), so older offsets are let go.
    const auto it = placement_offsets_.find(log.position);
    if (it != placement_offsets_.end() && !it->second.empty()) {
      const std::size_t n = std::min<std::size_t>(it->second.size(), 3);
      for (std::size_t i = it->second.size() - n; i < it->second.size(); ++i) correction_applied_ += it->second[i];
      correction_applied_ /= static_cast<double>(n);
      T_site_goal.translation().head<2>() -= correction_applied_;
    }
  }
  // A brick the vacuum loses (a failed grip, a drop on the way) is replaced by the feeder's next
  // one: pick again, up to pick_retries times.
  for (int attempt = 0;; ++attempt) {
    bool lost = false;
    Progress(fmt::format("{}: picking brick {} from the feeder", log.position, k + 1));
    if (RunArmSteps(arm_->PickBrick(q_, T_site_base, T_site_feeder, c_.site.brick), "pick brick", false, &lost)) {
      Progress(fmt::format("{}: placing brick {}", log.position, k + 1));
      bool placed = false;
      if (o_.tilt_compensation == TiltCompensation::kImu) {
        // Above the goal first (the arm out, the brick held: the base leans as it will when
        // placing), then measure the tilt and plan the descent on the compensated pose.
        const arm::PrimitiveResult plan = arm_->PlaceBrick(q_, T_site_base, T_site_goal, c_.site.brick);
        if (!plan.ok) {
          placed = RunArmSteps(plan, "place brick", true, &lost);  // stops safely with the planner's message
        } else {
          bool above_ok = true;
          if (!plan.steps.empty() && !plan.steps.front().trajectory.points.empty()) {
            arm::PrimitiveResult above;
            above.steps.push_back(plan.steps.front());
            above.q_end = plan.steps.front().trajectory.points.back().q;
            above_ok = RunArmSteps(above, "move above the brick goal", true, &lost);
          }
          if (above_ok) {
            const Pose3 T_site_base_now = PlacingPose(log);
            placed = RunArmSteps(arm_->PlaceBrick(q_, T_site_base_now, T_site_goal, c_.site.brick), "place brick", true,
                                 &lost);
          }
        }
      } else {
        placed = RunArmSteps(arm_->PlaceBrick(q_, T_site_base, T_site_goal, c_.site.brick), "place brick", true, &lost);
      }
      if (placed) break;
    }
    if (!lost) return false;  // stopped safely inside
    if (attempt >= o_.pick_retries) {
      StopSafely(fmt::format("brick {}: the vacuum lost it {} times", k + 1, attempt + 1));
      return false;
    }
    Note("brick_lost", fmt::format("brick {}: the vacuum sensor reports no brick; picking the feeder's next one "
                                   "(retry {} of {})", k + 1, attempt + 1, o_.pick_retries));
  }
  workpiece_.bricks.push_back({fmt::format("brick_{}", k), T_site_intended, c_.site.brick});
  if (o_.learn_placement_bias)
    last_sent_ = SentBrick{workpiece_.bricks.size() - 1, T_site_intended.translation(), R_site_base,
                           placement_bias_.Bias(log.position), log.position};
  log.bricks_placed.push_back(k);
  ++bricks_placed_;
  return true;
}

std::vector<VisitLog> Mission::Run(const BuildingPlan& plan) {
  std::vector<VisitLog> logs;
  int brick = 0;
  for (std::size_t v = 0; v < plan.visits.size() && !stopped_; ++v) {
    const auto& visit = plan.visits[v];
    const BuildingPosition& position = plan.positions[static_cast<std::size_t>(visit.position)];
    VisitLog log;
    log.visit = static_cast<int>(v);
    log.position = position.name;
    log.t_start = robot_.Now();
    Progress(fmt::format("position {} of {} ({})", v, plan.Repositionings(), position.name));
    if (v > 0) {
      if (!Reposition(position, log)) {
        log.t_end = robot_.Now();
        if (on_visit_end) on_visit_end(log);
        logs.push_back(std::move(log));
        if (stopped_) break;
        continue;  // skip this position (reason logged)
      }
      if (o_.localize && !Localize(log)) {
        log.t_end = robot_.Now();
        if (on_visit_end) on_visit_end(log);
        logs.push_back(std::move(log));
        break;
      }
    } else {
      log.desired = log.start_estimate = log.end_estimate = T_site_base_;
    }
    for (int b = 0; o_.place_bricks && b < visit.bricks && !stopped_; ++b) PlaceBrick(brick++, log);
    if (o_.check_placement && !log.bricks_placed.empty() && !stopped_) CheckPlacement(log.bricks_placed.back(), log);
    log.t_end = robot_.Now();
    if (on_visit_end) on_visit_end(log);
    logs.push_back(std::move(log));
  }
  if (!stopped_ && (q_ - o_.q_park).cwiseAbs().maxCoeff() > 1e-3) RunArm(arm_->MoveToJoints(q_, o_.q_park), "park the arm");
  SendTracks({robot_.Now(), 0.0, 0.0});
  return logs;
}

}  // namespace ifab::sequencer
