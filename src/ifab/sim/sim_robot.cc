#include "ifab/sim/sim_robot.h"

#include <kdl/chainidsolver_recursive_newton_euler.hpp>

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
    // The sensor file also holds the perception side's noise profile (`noise:`), not the simulator's.
    const ConfigNode sensor = ConfigNode::LoadFile(UnderData(l->As<std::string>(), here));
    sensor.ExpectKeys({"lrf", "noise"});
    o.base_laser = o.arm_laser = LrfOptions::FromConfig(sensor["lrf"]);
  }
  if (auto g = c.Find("gyro")) {
    const ConfigNode sensor = ConfigNode::LoadFile(UnderData(g->As<std::string>(), here));
    o.gyro = GyroOptions::FromConfig(sensor["gyro"]);
    if (auto a = sensor.Find("accelerometer")) o.accel = AccelOptions::FromConfig(*a);
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

namespace {

// The laser units of the world: the as-built draws (keeping the experiment's switches) or nominal.
LrfOptions UnitOptions(const LrfOptions& nominal, const AsBuilt& a, bool arm) {
  if (a.exact) return nominal;
  LrfOptions unit = arm ? a.arm_laser : a.base_laser;
  unit.bias_enabled = nominal.bias_enabled;
  unit.noise_enabled = nominal.noise_enabled;
  return unit;
}

}  // namespace

SimRobot::SimRobot(const SimOptions& options, Pose2 T_site_base0, Vector6d q0, std::uint64_t seed)
    : options_(options),
      robot_(options.as_built.TrueRobot(LoadRobotModel(options.urdf))),
      world_(LoadSite(options.site), options.as_built.floor),
      rng_(seed),
      base_(options.tracks, T_site_base0, rng_.Derive("tracks")),
      servo_(options.servo, robot_, q0, rng_.Derive("servo")),
      gyro_(options.gyro, rng_.Derive("gyro")),
      accel_(options.accel, options.gyro.rate_hz, rng_.Derive("accel")),
      base_lrf_(UnitOptions(options.base_laser, options.as_built, false)),
      arm_lrf_(UnitOptions(options.arm_laser, options.as_built, true)),
      base_laser_clock_(options.base_laser_clock, DeviceId::kBaseLaser, rng_.Derive("clock.base_laser")),
      arm_laser_clock_(options.arm_laser_clock, DeviceId::kArmLaser, rng_.Derive("clock.arm_laser")),
      gyro_clock_(options.gyro_clock, DeviceId::kGyro, rng_.Derive("clock.gyro")),
      arm_clock_(options.arm_clock, DeviceId::kArm, rng_.Derive("clock.arm")),
      base_lrf_rng_(rng_.Derive("lrf.base")),
      arm_lrf_rng_(rng_.Derive("lrf.arm")),
      gripper_rng_(rng_.Derive("gripper")),
      seat_rng_(rng_.Derive("seat")),
      encoder_rng_(rng_.Derive("encoder")) {
  const AsBuilt& a = options.as_built;
  T_base_base_laser_true_ =
      robot_.T_base_base_laser * PoseFromXyzRpy(a.exact ? options.base_laser_mount_error : a.base_laser_mount_error);
  T_tool0_arm_laser_true_ =
      robot_.T_tool0_arm_laser * PoseFromXyzRpy(a.exact ? options.arm_laser_mount_error : a.arm_laser_mount_error);
  if (!a.exact) servo_.set_offsets(a.joint_offsets);
  if (!a.exact) {
    const Eigen::Vector3d& e = a.imu_mount_error_rpy;
    R_imu_base_ = PoseFromXyzRpy(0, 0, 0, e[0], e[1], e[2]).linear().transpose();
  }
  if (!a.exact) seat_ = {seat_rng_.Normal(a.base_seat_sigma), seat_rng_.Normal(a.base_seat_sigma)};
  T_site_base_ = TrueSiteBase(base_.pose(), servo_.q_physical());
  base_scan_start_ = arm_scan_start_ = Now3();
  PresentFeederBrick();
}

void SimRobot::PresentFeederBrick() {
  const Site& site = world_.site();
  const AsBuilt& a = options_.as_built;
  feeder_brick_.name = "brick_" + std::to_string(bricks_released_);
  feeder_brick_.box = site.brick;
  brick_leans_ = {0.0, 0.0};
  if (!a.exact) {  // this brick's own size about its batch's mean, and how it leans (out of square)
    RandomStream rng = gripper_rng_.Derive(static_cast<std::uint64_t>(bricks_released_));
    for (int k = 0; k < 3; ++k) feeder_brick_.box.size[k] = a.brick_mean_size[k] + rng.Normal(a.brick_size_sigma[k]);
    brick_leans_ = {rng.Normal(a.brick_lean_sigma), rng.Normal(a.brick_lean_sigma)};
  }
  // Named draws in gcc's order of the arguments (last first), so every compiler draws the same brick.
  const double yaw = DegToRad(gripper_rng_.Normal(options_.feeder_sigma_yaw_deg));
  const double y = gripper_rng_.Normal(options_.feeder_sigma_xy), x = gripper_rng_.Normal(options_.feeder_sigma_xy);
  feeder_brick_.T_site_box = options_.T_base_feeder * PoseFromXyzRpy(x, y, 0, 0, 0, yaw);
}

Vector6d SimRobot::LinkAngles(const Vector6d& q) const {
  const AsBuilt& a = options_.as_built;
  if (a.exact || a.gravity_compliance.isZero()) return q;
  // Gravity torques from the URDF's link masses (KDL's Newton-Euler at rest); joints 2 and 3 yield
  // against the torque their motors hold.
  KDL::ChainIdSolver_RNE rne(robot_.arm_chain, KDL::Vector(0, 0, -9.81));
  const unsigned n = robot_.arm_chain.getNrOfJoints();
  KDL::JntArray jq(n), zero(n), tau(n);
  for (unsigned i = 0; i < n; ++i) jq(i) = q[static_cast<int>(i)];
  KDL::Wrenches f_ext(robot_.arm_chain.getNrOfSegments(), KDL::Wrench::Zero());
  if (rne.CartToJnt(jq, zero, zero, f_ext, tau) < 0) return q;
  Vector6d out = q;
  out[1] -= a.gravity_compliance[0] * tau(1);
  out[2] -= a.gravity_compliance[1] * tau(2);
  return out;
}

Pose3 SimRobot::TrueSiteBase(const Pose2& p, const Vector6d& q) const {
  const AsBuilt& a = options_.as_built;
  if (a.exact && extra_tilt_.isZero()) return PoseFromXyzRpy(p.x, p.y, world_.site().ground_z, 0, 0, p.theta);
  double z = world_.site().ground_z, roll = extra_tilt_[0], pitch = extra_tilt_[1];
  if (!a.exact) {
    // The plane through the floor under the four track ends (base frame: x along the tracks).
    const double half_l = 0.5 * a.track_contact_length, half_b = 0.5 * options_.tracks.track_gauge;
    const double c = std::cos(p.theta), s = std::sin(p.theta);
    auto h = [&](double bx, double by) { return world_.FloorHeight(p.x + c * bx - s * by, p.y + s * bx + c * by); };
    const double fl = h(half_l, half_b), fr = h(half_l, -half_b), bl = h(-half_l, half_b), br = h(-half_l, -half_b);
    z = 0.25 * (fl + fr + bl + br);
    const double slope_x = 0.5 * ((fl + fr) - (bl + br)) / (2 * half_l);
    const double slope_y = 0.5 * ((fl + bl) - (fr + br)) / (2 * half_b);
    roll += std::atan(slope_y) + seat_[0];
    pitch += -std::atan(slope_x) + seat_[1];
    // The arm's weight (and a held brick) about the footprint centre tilts the base towards it.
    KDL::Vector moment_arm(0, 0, 0);
    KDL::Frame F = ToKdl(robot_.T_base_arm_base);
    unsigned j = 0;
    const Vector6d ql = LinkAngles(q);
    for (unsigned i = 0; i < robot_.arm_chain.getNrOfSegments(); ++i) {
      const KDL::Segment& seg = robot_.arm_chain.getSegment(i);
      const bool moves = seg.getJoint().getType() != KDL::Joint::None;
      F = F * seg.pose(moves ? ql[static_cast<int>(j)] : 0.0);
      if (moves) ++j;
      const double m = seg.getInertia().getMass();
      moment_arm += m * (F * seg.getInertia().getCOG());
    }
    Eigen::Vector2d weighted(moment_arm.x(), moment_arm.y());
    if (held_) {
      const Pose3 T_base_gripper = robot_.T_base_arm_base * robot_.ArmForwardKinematics(ql) * robot_.T_tool0_gripper;
      weighted += a.payload_kg * T_base_gripper.translation().head<2>();
    }
    constexpr double kG = 9.81;
    pitch += a.base_compliance * kG * weighted.x();
    roll -= a.base_compliance * kG * weighted.y();
  }
  return PoseFromXyzRpy(p.x, p.y, z, 0, 0, p.theta) * PoseFromXyzRpy(0, 0, 0, roll, pitch, 0);
}

Pose3 SimRobot::ArmLaserPose(const Pose3& T_site_base, const Vector6d& q) const {
  return T_site_base * robot_.T_base_arm_base * robot_.ArmForwardKinematics(LinkAngles(q)) * T_tool0_arm_laser_true_;
}

SiteBox SimRobot::feeder_brick() const {
  SiteBox b = feeder_brick_;
  b.T_site_box = T_site_base_ * feeder_brick_.T_site_box;
  return b;
}

Pose3 SimRobot::true_T_site_gripper() const {
  return T_site_base_ * robot_.T_base_arm_base * robot_.ArmForwardKinematics(LinkAngles(servo_.q_physical())) *
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
  // A new rest attitude each time the base comes to a stop (how the tracks seat on the floor).
  const bool moving = base_.track_speeds().cwiseAbs().maxCoeff() > 1e-4;
  if (base_moving_ && !moving && !options_.as_built.exact)
    seat_ = {seat_rng_.Normal(options_.as_built.base_seat_sigma), seat_rng_.Normal(options_.as_built.base_seat_sigma)};
  base_moving_ = moving;
  T_site_base_ = TrueSiteBase(base_.pose(), servo_.q_physical());

  // IMU at the physics rate (400 Hz): the gyro sees the base's yaw (its tilting is slow); the
  // accelerometers the specific force in the base frame: the base's acceleration plus gravity.
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
  {
    const Eigen::Vector3d a_base((base_.v() - v_prev_) / dt, base_.v() * base_.omega(), 0.0);
    v_prev_ = base_.v();
    AccelSample a;
    a.stamp = g.stamp;
    // In the IMU's own axes (its mount on the chassis; the design has it along the base's).
    a.specific_force = accel_.Measure(R_imu_base_ * (a_base + T_site_base_.linear().transpose() * Eigen::Vector3d(0, 0, 9.80665)));
    accel_samples_.push_back(a);
  }

  if (t_ + 1e-9 >= next_state_) {
    next_state_ += 1.0 / options_.servo.state_rate_hz;
    JointState js;
    js.stamp = arm_clock_.StampPacket(t_, &pulse);
    js.q = servo_.q_reported();
    if (options_.as_built.encoder_noise > 0.0 && !options_.as_built.exact)
      for (int i = 0; i < 6; ++i) js.q[i] += encoder_rng_.Normal(options_.as_built.encoder_noise);
    js.qd = servo_.qd();
    if (faults_) faults_->FilterStamp(DeviceId::kArm, &js.stamp);
    joint_states_.push_back(js);
    pulses_.push_back(pulse);
  }

  // Scans: the mirror sweeps the 270 deg in sweep_fraction of the period; the scan is made when
  // its sweep is over, with the motion during the sweep interpolated between two snapshots.
  auto scan_due = [&](LrfModel& lrf, Seconds& next, Snapshot& start, bool arm, DeviceClock& clock,
                      RandomStream& rng, std::vector<LaserScan>& out) {
    const double sweep = lrf.options().scan_period * lrf.options().sweep_fraction;
    if (t_ + 1e-9 < next + sweep) return;
    const Snapshot end = Now3();
    LaserScan scan;
    scan.stamp = clock.StampPacket(next, &pulse);
    pulses_.push_back(pulse);
    const double span = std::max(1e-9, end.t - start.t);
    const double s0 = (next - start.t) / span;
    auto pose_at = [&](double s) {
      const double f = std::clamp(s0 + s * sweep / span, 0.0, 1.0);
      const Pose3 b = Interpolate(start.T_site_base, end.T_site_base, f);
      if (!arm) return Pose3(b * T_base_base_laser_true_);
      const Vector6d q = start.q + f * (end.q - start.q);
      return ArmLaserPose(b, q);
    };
    lrf.SetTimeSincePowerOn(options_.seconds_since_power_on + t_);
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
    start = Now3();
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
    const AsBuilt& a = options_.as_built;
    // The brick slides as the vacuum lets go; a leaning (out of square) brick slides more.
    const double lean = std::hypot(brick_leans_[0], brick_leans_[1]);
    const double sigma_xy = a.exact ? options_.release_sigma_xy : a.release_sigma_xy + a.release_sigma_per_lean * lean;
    const double sigma_yaw = a.exact ? DegToRad(options_.release_sigma_yaw_deg) : a.release_sigma_yaw;
    xyzrpy[0] += gripper_rng_.Normal(sigma_xy);
    xyzrpy[1] += gripper_rng_.Normal(sigma_xy);
    // The brick settles on whatever is below it: flat in the exact world; as built it leans by
    // its own out-of-squareness, and on the floor also with the floor's slope.
    const double half = 0.5 * feeder_brick_.box.size.z();
    const double support = world_.SupportHeight(xyzrpy[0], xyzrpy[1], 0.05);
    double roll = brick_leans_[0], pitch = brick_leans_[1];
    const double yaw = xyzrpy[5] + gripper_rng_.Normal(sigma_yaw);
    if (!a.exact && world_.SupportHeight(xyzrpy[0], xyzrpy[1], 0.05) <= world_.FloorHeight(xyzrpy[0], xyzrpy[1]) + 0.01) {
      const Eigen::Vector2d g = world_.floor().Gradient(xyzrpy[0], xyzrpy[1]);
      const Eigen::Vector2d g_brick(std::cos(yaw) * g.x() + std::sin(yaw) * g.y(), -std::sin(yaw) * g.x() + std::cos(yaw) * g.y());
      roll += std::atan(g_brick.y());
      pitch -= std::atan(g_brick.x());
    }
    SiteBox placed = feeder_brick_;
    placed.T_site_box = PoseFromXyzRpy(xyzrpy[0], xyzrpy[1], support + half, 0, 0, yaw) *
                        PoseFromXyzRpy(0, 0, 0, roll, pitch, 0);
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

std::vector<AccelSample> SimRobot::TakeAccelSamples() {
  std::vector<AccelSample> out;
  std::swap(out, accel_samples_);
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
