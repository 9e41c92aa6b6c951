#include "ifab/sim/sim_robot.h"

#include <filesystem>

#include "ifab/core/angles.h"
#include "ifab/core/config.h"
#include "ifab/core/data_path.h"

namespace ifab::sim {
namespace {

std::string UnderData(const std::string& path, const std::string& relative_to) {
  if (path.empty() || path[0] == '/') return path;
  // Relative names are looked up next to the YAML that names them, then under data/.
  const auto beside = std::filesystem::path(relative_to).parent_path() / path;
  if (std::filesystem::exists(beside)) return beside.string();
  return DataPath(path);
}

std::array<double, 6> ReadSix(const ConfigNode& c, const char* key) {
  std::array<double, 6> out{};
  if (auto n = c.Find(key)) {
    const auto v = n->AsNumbers(6);
    std::copy(v.begin(), v.end(), out.begin());
  }
  return out;
}

}  // namespace

SimOptions SimOptions::Load(const std::string& robot_yaml) {
  const ConfigNode root = ConfigNode::LoadFile(robot_yaml);
  root.ExpectKeys({"feeder_in_base", "sim"});
  return FromConfig(root["sim"]);
}

SimOptions SimOptions::FromConfig(const ConfigNode& c) {
  c.ExpectKeys({"urdf", "site", "step", "tracks", "laser", "base_laser", "arm_laser", "gyro", "servo",
                "clocks", "base_laser_mount_error", "arm_laser_mount_error", "gripper", "feeder"});
  SimOptions o;
  const std::string here = c.file();
  if (auto u = c.Find("urdf")) o.urdf = UnderData(u->As<std::string>(), here);
  else o.urdf = DataPath(o.urdf);
  if (auto s = c.Find("site")) o.site = UnderData(s->As<std::string>(), here);
  else o.site = DataPath(o.site);
  c.ReadPositive("step", o.step);
  if (auto t = c.Find("tracks")) o.tracks = TrackOptions::FromConfig(*t);
  // Both lasers are UTM-30LX: one sensor file, optional per-laser overrides are not needed.
  if (auto l = c.Find("laser")) {
    o.base_laser = o.arm_laser = LrfOptions::FromConfig(ConfigNode::LoadSection(UnderData(l->As<std::string>(), here), "lrf"));
  }
  if (auto g = c.Find("gyro")) {
    o.gyro = GyroOptions::FromConfig(ConfigNode::LoadSection(UnderData(g->As<std::string>(), here), "gyro"));
  }
  if (auto s = c.Find("servo")) o.servo = ServoOptions::FromConfig(*s);
  if (auto clocks = c.Find("clocks")) {
    clocks->ExpectKeys({"base_laser", "arm_laser", "gyro", "arm"});
    if (auto k = clocks->Find("base_laser")) o.base_laser_clock = ClockOptions::FromConfig(*k);
    if (auto k = clocks->Find("arm_laser")) o.arm_laser_clock = ClockOptions::FromConfig(*k);
    if (auto k = clocks->Find("gyro")) o.gyro_clock = ClockOptions::FromConfig(*k);
    if (auto k = clocks->Find("arm")) o.arm_clock = ClockOptions::FromConfig(*k);
  }
  o.base_laser_mount_error = ReadSix(c, "base_laser_mount_error");
  o.arm_laser_mount_error = ReadSix(c, "arm_laser_mount_error");
  if (auto g = c.Find("gripper")) {
    g->ExpectKeys({"capture_distance", "release_sigma_xy", "release_sigma_yaw_deg"});
    g->ReadPositive("capture_distance", o.grip_capture_distance);
    g->ReadNonNegative("release_sigma_xy", o.release_sigma_xy);
    g->ReadNonNegative("release_sigma_yaw_deg", o.release_sigma_yaw_deg);
  }
  if (auto f = c.Find("feeder")) {
    f->ExpectKeys({"pose_in_base", "sigma_xy", "sigma_yaw_deg"});
    if (auto p = f->Find("pose_in_base")) {
      const auto v = p->AsNumbers(6);
      o.T_base_feeder = PoseFromXyzRpy(v[0], v[1], v[2], v[3], v[4], v[5]);
    }
    f->ReadNonNegative("sigma_xy", o.feeder_sigma_xy);
    f->ReadNonNegative("sigma_yaw_deg", o.feeder_sigma_yaw_deg);
  }
  return o;
}

SimRobot::SimRobot(const SimOptions& options, Pose2 T_site_base0, Vector6d q0, std::uint64_t seed)
    : options_(options),
      robot_(LoadRobotModel(options.urdf)),
      world_(LoadSite(options.site)),
      rng_(seed),
      base_(options.tracks, T_site_base0, rng_.Derive("tracks")),
      servo_(options.servo, robot_, q0, rng_.Derive("servo")),
      gyro_(options.gyro, rng_.Derive("gyro")),
      base_lrf_(options.base_laser),
      arm_lrf_(options.arm_laser),
      base_laser_clock_(options.base_laser_clock, DeviceId::kBaseLaser, rng_.Derive("clock.base_laser")),
      arm_laser_clock_(options.arm_laser_clock, DeviceId::kArmLaser, rng_.Derive("clock.arm_laser")),
      gyro_clock_(options.gyro_clock, DeviceId::kGyro, rng_.Derive("clock.gyro")),
      arm_clock_(options.arm_clock, DeviceId::kArm, rng_.Derive("clock.arm")),
      base_lrf_rng_(rng_.Derive("lrf.base")),
      arm_lrf_rng_(rng_.Derive("lrf.arm")),
      gripper_rng_(rng_.Derive("gripper")) {
  T_base_base_laser_true_ = robot_.T_base_base_laser * PoseFromXyzRpy(options.base_laser_mount_error);
  T_tool0_arm_laser_true_ = robot_.T_tool0_arm_laser * PoseFromXyzRpy(options.arm_laser_mount_error);
  base_scan_start_ = arm_scan_start_ = {t_, base_.pose(), servo_.q_physical()};
  PresentFeederBrick();
}

void SimRobot::PresentFeederBrick() {
  const Site& site = world_.site();
  feeder_brick_.name = "brick_" + std::to_string(bricks_released_);
  feeder_brick_.box = site.brick;
  feeder_brick_.T_site_box = options_.T_base_feeder *
      PoseFromXyzRpy(gripper_rng_.Normal(options_.feeder_sigma_xy), gripper_rng_.Normal(options_.feeder_sigma_xy), 0,
                     0, 0, DegToRad(gripper_rng_.Normal(options_.feeder_sigma_yaw_deg)));
}

Pose3 SimRobot::TrueSiteBase(const Pose2& p) const {
  return PoseFromXyzRpy(p.x, p.y, world_.site().ground_z, 0, 0, p.theta);
}

Pose3 SimRobot::ArmLaserPose(const Pose2& base, const Vector6d& q) const {
  return TrueSiteBase(base) * robot_.T_base_arm_base * robot_.ArmForwardKinematics(q) * T_tool0_arm_laser_true_;
}

SiteBox SimRobot::feeder_brick() const {
  SiteBox b = feeder_brick_;
  b.T_site_box = TrueSiteBase(base_.pose()) * feeder_brick_.T_site_box;
  return b;
}

Pose3 SimRobot::true_T_site_gripper() const {
  return TrueSiteBase(base_.pose()) * robot_.T_base_arm_base * robot_.ArmForwardKinematics(servo_.q_physical()) *
         robot_.T_tool0_gripper;
}

void SimRobot::Wait(Seconds dt) {
  const Seconds end = t_ + dt;
  while (t_ + 0.5 * options_.step <= end) Step();
}

void SimRobot::Step() {
  const double dt = options_.step;
  if (faults_) {
    faults_->OnStep(*this, t_, dt);
    double l = track_command_.v_left, r = track_command_.v_right;
    faults_->FilterTracks(&l, &r);
    base_.Command(l, r);
  }
  base_.Step(dt);
  servo_.Step(dt, t_ + dt);
  t_ = (++step_count_) * dt;

  // Gyro at the physics rate (400 Hz): the base only yaws.
  GyroSample g;
  SyncPulse pulse;
  g.stamp = gyro_clock_.StampPacket(t_, &pulse);
  g.rate = gyro_.Measure(Eigen::Vector3d(0, 0, base_.omega()));
  if (faults_) {
    faults_->FilterGyro(t_, &g);
    faults_->FilterStamp(DeviceId::kGyro, &g.stamp);
  }
  gyro_samples_.push_back(g);
  pulses_.push_back(pulse);

  if (t_ + 1e-9 >= next_state_) {
    next_state_ += 1.0 / options_.servo.state_rate_hz;
    JointState js;
    js.stamp = arm_clock_.StampPacket(t_, &pulse);
    js.q = servo_.q_reported();
    js.qd = servo_.qd();
    if (faults_) faults_->FilterStamp(DeviceId::kArm, &js.stamp);
    joint_states_.push_back(js);
    pulses_.push_back(pulse);
  }

  // Scans: the mirror sweeps the 270 deg in sweep_fraction of the period; the scan is made when
  // its sweep is over, with the motion during the sweep interpolated between two snapshots.
  auto scan_due = [&](const LrfModel& lrf, Seconds& next, Snapshot& start, bool arm, DeviceClock& clock,
                      RandomStream& rng, std::vector<LaserScan>& out) {
    const double sweep = lrf.options().scan_period * lrf.options().sweep_fraction;
    if (t_ + 1e-9 < next + sweep) return;
    const Snapshot end{t_, base_.pose(), servo_.q_physical()};
    LaserScan scan;
    scan.stamp = clock.StampPacket(next, &pulse);
    pulses_.push_back(pulse);
    const double span = std::max(1e-9, end.t - start.t);
    const double s0 = (next - start.t) / span;
    auto pose_at = [&](double s) {
      const double f = std::clamp(s0 + s * sweep / span, 0.0, 1.0);
      const Pose2 b = Interpolate(start.base, end.base, f);
      if (!arm) return TrueSiteBase(b) * T_base_base_laser_true_;
      const Vector6d q = start.q + f * (end.q - start.q);
      return ArmLaserPose(b, q);
    };
    lrf.Scan(world_, pose_at, rng, scan);
    // The host stamp arrives after the sweep is over (plus transport).
    scan.stamp.t_host_received += sweep;
    scan.stamp.t = scan.stamp.t_host_received;
    if (faults_) faults_->FilterStamp(arm ? DeviceId::kArmLaser : DeviceId::kBaseLaser, &scan.stamp);
    const bool lost = faults_ && !faults_->KeepScan(arm, t_, &scan);
    if (!lost && (!lrf.options().noise_enabled || !rng.Bernoulli(lrf.options().dropped_scan_probability)))
      out.push_back(scan);
    next += lrf.options().scan_period;
    start = end;
  };
  // An idle laser keeps its mirror turning (the schedule advances) but casts nothing.
  auto idle = [&](const LrfModel& lrf, Seconds& next, Snapshot& start) {
    const double sweep = lrf.options().scan_period * lrf.options().sweep_fraction;
    while (t_ + 1e-9 >= next + sweep) next += lrf.options().scan_period;
    start = {t_, base_.pose(), servo_.q_physical()};
  };
  if (base_laser_active_) scan_due(base_lrf_, next_base_scan_, base_scan_start_, false, base_laser_clock_, base_lrf_rng_, base_scans_);
  else idle(base_lrf_, next_base_scan_, base_scan_start_);
  if (arm_laser_active_) scan_due(arm_lrf_, next_arm_scan_, arm_scan_start_, true, arm_laser_clock_, arm_lrf_rng_, arm_scans_);
  else idle(arm_lrf_, next_arm_scan_, arm_scan_start_);
}

void SimRobot::CommandTracks(const TrackCommand& command) {
  track_command_ = command;
  base_.Command(command.v_left, command.v_right);
}

void SimRobot::SendJointTrajectory(const JointTrajectory& trajectory) {
  arm_rejection_.clear();
  if (faults_) {
    if (auto why = faults_->RejectTrajectory(t_)) {
      arm_rejection_ = *why;
      return;
    }
  }
  servo_.Follow(trajectory, t_);
}

void SimRobot::DropHeldBrick() {
  if (!held_) return;
  held_.reset();  // it falls beside the feeder, out of the scanned area
  ++bricks_released_;
  PresentFeederBrick();
}

bool SimRobot::ArmBusy() const { return servo_.Busy(t_); }

void SimRobot::SetGripper(bool grip) {
  const Pose3 T_site_gripper = true_T_site_gripper();
  if (grip && !held_) {
    // Grip the feeder's brick if the cup touches its top face.
    const Pose3 T_site_brick = feeder_brick().T_site_box;
    const Eigen::Vector3d top = T_site_brick * Eigen::Vector3d(0, 0, 0.5 * feeder_brick_.box.size.z());
    if ((T_site_gripper.translation() - top).norm() < options_.grip_capture_distance) {
      held_ = T_site_gripper.inverse(Eigen::Isometry) * T_site_brick;
      if (faults_) faults_->OnGrip(t_);
    }
  } else if (!grip && held_) {
    Pose3 T_site_brick = T_site_gripper * *held_;
    auto xyzrpy = XyzRpyFromPose(T_site_brick);
    xyzrpy[0] += gripper_rng_.Normal(options_.release_sigma_xy);
    xyzrpy[1] += gripper_rng_.Normal(options_.release_sigma_xy);
    // The brick settles flat on whatever is below it.
    const double half = 0.5 * world_.site().brick.size.z();
    const double support = world_.SupportHeight(xyzrpy[0], xyzrpy[1], 0.05);
    SiteBox placed = feeder_brick_;
    placed.T_site_box = PoseFromXyzRpy(xyzrpy[0], xyzrpy[1], support + half, 0, 0,
                                       xyzrpy[5] + DegToRad(gripper_rng_.Normal(options_.release_sigma_yaw_deg)));
    world_.AddBrick(placed);
    held_.reset();
    ++bricks_released_;
    PresentFeederBrick();
  }
}

void SimRobot::SetLaserActive(DeviceId laser, bool active) {
  if (faults_) faults_->OnLaserActive(laser, active, t_);
  if (laser == DeviceId::kBaseLaser) base_laser_active_ = active;
  if (laser == DeviceId::kArmLaser) arm_laser_active_ = active;
}

std::vector<LaserScan> SimRobot::TakeLaserScans(DeviceId laser) {
  std::vector<LaserScan> out;
  if (laser == DeviceId::kBaseLaser) std::swap(out, base_scans_);
  else if (laser == DeviceId::kArmLaser) std::swap(out, arm_scans_);
  return out;
}

std::vector<GyroSample> SimRobot::TakeGyroSamples() {
  std::vector<GyroSample> out;
  std::swap(out, gyro_samples_);
  return out;
}

std::vector<JointState> SimRobot::TakeJointStates() {
  std::vector<JointState> out;
  std::swap(out, joint_states_);
  return out;
}

std::vector<SyncPulse> SimRobot::TakeSyncPulses() {
  std::vector<SyncPulse> out;
  std::swap(out, pulses_);
  return out;
}

}  // namespace ifab::sim
