#include "ifab/sequencer/laser_sweeps.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <variant>

#include "ifab/core/angles.h"
#include "ifab/core/config.h"
#include "ifab/perception/scan_assembly.h"
#include "ifab/sequencer/tilt.h"

namespace ifab::sequencer {

std::vector<SweepSpec> ReadSweepSpecs(const ConfigNode& list) {
  list.ExpectSequence();
  std::vector<SweepSpec> out;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const ConfigNode s = list[i];
    s.ExpectMap();
    s.ExpectKeys({"joint", "range_deg", "speed_deg_s", "offset_deg", "aim_offset", "view"});
    SweepSpec spec;
    const int joint = s.Get<int>("joint");
    if (joint < 1 || joint > 6) s["joint"].Fail("a joint number 1..6");
    spec.joint = joint - 1;
    const auto r = s["range_deg"].AsNumbers(2);
    if (r[0] == r[1]) s["range_deg"].Fail("two different angles [from, to]");
    spec.from = DegToRad(r[0]);
    spec.to = DegToRad(r[1]);
    double speed = 10.0;
    s.ReadPositive("speed_deg_s", speed);
    spec.speed = DegToRad(speed);
    if (auto a = s.Find("aim_offset")) {
      const auto v = a->AsNumbers(2);
      spec.aim_offset = Eigen::Vector2d(v[0], v[1]);
    }
    if (auto o = s.Find("offset_deg")) {
      const auto v = o->AsNumbers(6);
      for (int k = 0; k < 6; ++k) spec.pose_offset[k] = DegToRad(v[static_cast<std::size_t>(k)]);
    }
    if (auto v = s.Find("view")) {
      v->ExpectMap();
      v->ExpectKeys({"distance", "elevation_deg", "azimuth_deg", "roll_deg", "height"});
      LaserView view;
      v->ReadPositive("distance", view.distance);
      double elevation = RadToDeg(view.elevation), azimuth = 0.0, roll = 0.0;
      v->ReadInRange("elevation_deg", elevation, 5.0, 90.0);
      v->Read("azimuth_deg", azimuth);
      v->Read("roll_deg", roll);
      v->Read("height", view.height);
      view.elevation = DegToRad(elevation);
      view.azimuth = DegToRad(azimuth);
      view.roll = DegToRad(roll);
      spec.view = view;
    }
    out.push_back(spec);
  }
  return out;
}

std::optional<Vector6d> ViewPose(arm::IkSolver& ik, const RobotModel& robot, const Eigen::Vector2d& look_in_base,
                                 const LaserView& view, const Vector6d& q_near) {
  const Eigen::Vector2d foot = robot.T_base_arm_base.translation().head<2>();
  const double bearing = std::atan2(look_in_base.y() - foot.y(), look_in_base.x() - foot.x()) + M_PI + view.azimuth;
  const Eigen::Vector3d look(look_in_base.x(), look_in_base.y(), view.height);
  const Eigen::Vector3d out(std::cos(view.elevation) * std::cos(bearing), std::cos(view.elevation) * std::sin(bearing),
                            std::sin(view.elevation));
  Pose3 T_base_laser = Pose3::Identity();
  const Eigen::Vector3d x = -out;  // the centre beam
  const Eigen::Vector3d y0 = Eigen::Vector3d::UnitZ().cross(x).normalized();
  const Eigen::Vector3d z0 = x.cross(y0);
  T_base_laser.linear().col(0) = x;
  T_base_laser.linear().col(1) = std::cos(view.roll) * y0 + std::sin(view.roll) * z0;
  T_base_laser.linear().col(2) = -std::sin(view.roll) * y0 + std::cos(view.roll) * z0;
  T_base_laser.translation() = look + view.distance * out;
  const Pose3 T_arm_base_tool0 =
      robot.T_base_arm_base.inverse() * T_base_laser * robot.T_tool0_arm_laser.inverse();
  const arm::IkResult r = ik.Solve(T_arm_base_tool0, q_near);
  if (!r.ok()) return std::nullopt;
  return r.q;
}

Vector6d AimAt(const RobotModel& robot, const Eigen::Vector2d& target_in_base, const Vector6d& posture) {
  Vector6d q = posture;
  const Eigen::Vector3d foot = robot.T_base_arm_base.translation();
  q[0] = std::atan2(target_in_base.y() - foot.y(), target_in_base.x() - foot.x());
  // Where the centre beam (the laser's x axis) meets the floor, as a function of joint 5.
  auto miss = [&](double q5) {
    Vector6d qq = q;
    qq[4] = q5;
    const Pose3 T_base_laser = robot.T_base_arm_base * robot.ArmForwardKinematics(qq) * robot.T_tool0_arm_laser;
    const Eigen::Vector3d o = T_base_laser.translation(), d = T_base_laser.linear().col(0);
    if (d.z() > -0.2) return 1e9;  // looking too flat to meet the floor nearby
    const Eigen::Vector3d hit = o - (o.z() / d.z()) * d;
    return (hit.head<2>() - target_in_base).norm();
  };
  double best = q[4], best_miss = miss(q[4]);
  for (double q5 = 0.3; q5 <= 2.0; q5 += 0.005) {
    const double m = miss(q5);
    if (m < best_miss) {
      best_miss = m;
      best = q5;
    }
  }
  q[4] = best;
  return q;
}

SweepRecorder::SweepRecorder(hal::Robot& robot, arm::ArmPrimitives& arm, const Vector6d& q, SweepRecorderOptions options)
    : robot_(robot), arm_(arm), q_(q), options_(options) {}

SweepRecording SweepRecorder::Record(const Eigen::Vector2d& target_in_base, const Vector6d& posture,
                                     const SweepSpec& spec, bool reverse, const std::string& name) {
  // The aim point sits `lateral` beside the target as seen from itself (so the scan line across
  // the arm passes through the target: Thales), and `radial` further out.
  const Eigen::Vector2d foot = arm_.robot().T_base_arm_base.translation().head<2>();
  const double D = (target_in_base - foot).norm();
  const double L = std::clamp(spec.aim_offset.y(), -0.9 * D, 0.9 * D);
  const double bearing =
      std::atan2(target_in_base.y() - foot.y(), target_in_base.x() - foot.x()) + std::asin(L / D);
  const double reach = std::sqrt(D * D - L * L) + spec.aim_offset.x();
  const Eigen::Vector2d look = foot + reach * Eigen::Vector2d(std::cos(bearing), std::sin(bearing));
  Vector6d aim;
  if (spec.view) {
    const auto q = ViewPose(arm_.ik(), arm_.robot(), look, *spec.view, posture);
    if (!q) throw std::runtime_error("sweep '" + name + "': its view is out of the arm's reach");
    aim = *q;
  } else {
    aim = AimAt(arm_.robot(), look, posture);
  }
  Vector6d start = aim + spec.pose_offset;
  double from = start[spec.joint] + spec.from, to = start[spec.joint] + spec.to;
  if (reverse) std::swap(from, to);
  start[spec.joint] = from;
  // SweepJoint holds the other joints where they are: move the whole arm to the start first.
  arm::PrimitiveResult plan = arm_.MoveToJoints(q_, start);
  if (!plan.ok) throw std::runtime_error("sweep '" + name + "': " + plan.message);
  plan.Append(arm_.SweepJoint(plan.q_end, spec.joint, from, to, spec.speed));
  if (!plan.ok) throw std::runtime_error("sweep '" + name + "': " + plan.message);
  std::vector<arm::ArmStep> move(plan.steps.begin(), plan.steps.end() - 1);
  const arm::ArmStep sweep = plan.steps.back();
  // The laser is on from the move on, so that its clock sync has pulses before the sweep.
  robot_.SetLaserActive(DeviceId::kArmLaser, true);
  if (!move.empty()) Execute(move, name);
  robot_.Wait(options_.settle_time);
  Drain(nullptr);  // the move: only its sync pulses matter
  Execute({sweep}, name);
  robot_.Wait(options_.tail_time);
  robot_.SetLaserActive(DeviceId::kArmLaser, options_.laser_on_between_sweeps);
  SweepRecording rec;
  rec.name = name;
  Drain(&rec);
  std::vector<LaserScan> scans;
  for (auto& s : rec.scans)
    if (laser_sync_.Apply(s.stamp)) scans.push_back(s);
  rec.scans = std::move(scans);
  std::vector<JointState> joints;
  for (auto& j : rec.joint_states)
    if (arm_sync_.Apply(j.stamp)) joints.push_back(j);
  rec.joint_states = std::move(joints);
  q_ = plan.q_end;
  return rec;
}

void SweepRecorder::MoveTo(const Vector6d& q, const std::string& name) {
  const arm::PrimitiveResult plan = arm_.MoveToJoints(q_, q);
  if (!plan.ok) throw std::runtime_error(name + ": " + plan.message);
  if (!plan.steps.empty()) Execute(plan.steps, name);
  Drain(nullptr);
  q_ = plan.q_end;
}

void SweepRecorder::Execute(const std::vector<arm::ArmStep>& steps, const std::string& name) {
  const arm::ExecuteResult r = arm::ExecuteSteps(robot_, steps);
  if (!r.ok) throw std::runtime_error("sweep '" + name + "': " + r.message);
}

void SweepRecorder::Drain(SweepRecording* rec) {
  auto scans = robot_.TakeLaserScans(DeviceId::kArmLaser);
  auto joints = robot_.TakeJointStates();
  DrainedData other;
  other.sync_pulses = robot_.TakeSyncPulses();
  for (const auto& p : other.sync_pulses) {
    if (p.device == DeviceId::kArmLaser) laser_sync_.AddPulse(p);
    if (p.device == DeviceId::kArm) arm_sync_.AddPulse(p);
    if (p.device == DeviceId::kGyro) gyro_sync_.AddPulse(p);
  }
  for (const auto& s : scans) laser_sync_.AddPacket(s.stamp);
  for (const auto& j : joints) arm_sync_.AddPacket(j.stamp);
  other.base_laser_scans = robot_.TakeLaserScans(DeviceId::kBaseLaser);
  other.gyro_samples = robot_.TakeGyroSamples();
  other.accel_samples = robot_.TakeAccelSamples();
  // The accelerometer rides in the gyro's packets: the gyro's clock maps both.
  for (const auto& g : other.gyro_samples) gyro_sync_.AddPacket(g.stamp);
  if (rec) {
    rec->scans = std::move(scans);
    rec->joint_states = std::move(joints);
    for (AccelSample a : other.accel_samples)
      if (gyro_sync_.Apply(a.stamp)) rec->accel.push_back(a);
  }
  if (on_other_data) on_other_data(std::move(other));
}

LaserCalibrationPlan LaserCalibrationPlan::FromConfig(const ConfigNode& config) {
  config.ExpectMap();
  config.ExpectKeys({"cube_in_base", "cube_size", "sweeps", "scan_posture_deg", "beam_stride", "min_range",
                     "crop_radius", "calibration", "range_bias", "warmup_s", "kinematics", "level_with_imu"});
  LaserCalibrationPlan plan;
  const auto cb = config["cube_in_base"].AsNumbers(3);
  plan.cube_in_base = Eigen::Vector3d(cb[0], cb[1], DegToRad(cb[2]));
  config.ReadPositive("cube_size", plan.cube_size);
  config.ReadInRange("warmup_s", plan.warmup_s, 0.0, 86400.0);
  plan.sweeps = ReadSweepSpecs(config["sweeps"]);
  if (plan.sweeps.empty()) config["sweeps"].Fail("at least one sweep");
  plan.scan_posture << 0.0, DegToRad(17.0), DegToRad(17.0), 0.0, DegToRad(69.0), 0.0;
  if (auto p = config.Find("scan_posture_deg")) {
    const auto v = p->AsNumbers(6);
    for (int k = 0; k < 6; ++k) plan.scan_posture[k] = DegToRad(v[static_cast<std::size_t>(k)]);
  }
  config.ReadPositive("beam_stride", plan.beam_stride);
  config.ReadNonNegative("min_range", plan.min_range);
  config.ReadNonNegative("crop_radius", plan.crop_radius);
  if (auto o = config.Find("calibration")) plan.calibration = CalibrationOptions::FromConfig(*o);
  if (auto b = config.Find("range_bias")) plan.range_bias = RangeBiasPlan::FromConfig(*b);
  config.Read("level_with_imu", plan.level_with_imu);
  if (auto k = config.Find("kinematics")) plan.kinematics = KinematicCalibrationOptions::FromConfig(*k);
  return plan;
}

RangeBiasPlan RangeBiasPlan::FromConfig(const ConfigNode& c) {
  c.ExpectMap();
  c.ExpectKeys({"floor_heights", "floor_aim", "floor_elevation_deg", "floor_joint", "floor_range_deg",
                "floor_speed_deg_s", "floor_crop_radius", "identification", "compensation", "ground_extent"});
  RangeBiasPlan p;
  if (auto h = c.Find("floor_heights")) {
    p.floor_heights = h->AsNumbers();
    for (std::size_t i = 0; i < p.floor_heights.size(); ++i)
      if (!(p.floor_heights[i] > 0.1)) (*h)[i].Fail("a height above 0.1 m (the laser's minimum range)");
  }
  if (auto a = c.Find("floor_aim")) {
    const auto v = a->AsNumbers(2);
    p.floor_aim = Eigen::Vector2d(v[0], v[1]);
  }
  double elevation = RadToDeg(p.floor_elevation);
  c.ReadInRange("floor_elevation_deg", elevation, 30.0, 89.0);
  p.floor_elevation = DegToRad(elevation);
  int joint = p.floor_joint + 1;
  c.Read("floor_joint", joint);
  if (joint < 1 || joint > 6) c["floor_joint"].Fail("a joint number 1..6");
  p.floor_joint = joint - 1;
  if (auto r = c.Find("floor_range_deg")) {
    const double half = r->As<double>();
    if (!(half > 0.0 && half <= 30.0)) r->Fail("a half range in (0, 30] deg");
    p.floor_half_range = DegToRad(half);
  }
  double speed = RadToDeg(p.floor_speed);
  c.ReadPositive("floor_speed_deg_s", speed);
  p.floor_speed = DegToRad(speed);
  c.ReadPositive("floor_crop_radius", p.floor_crop_radius);
  if (auto o = c.Find("identification")) p.identification = RangeBiasOptions::FromConfig(*o);
  if (auto o = c.Find("compensation")) p.compensation = RangeBiasCompensation::FromConfig(*o);
  if (auto o = c.Find("ground_extent")) p.ground_extent = GroundExtentOptions::FromConfig(*o);
  return p;
}

Pose3 LaserCalibrationPlan::T_base_cube() const {
  return PoseFromXyzRpy(cube_in_base.x(), cube_in_base.y(), 0.5 * cube_size, 0.0, 0.0, cube_in_base.z());
}

std::vector<CalibrationSweep> RecordCubeSweeps(SweepRecorder& recorder, const RobotModel& model,
                                               const LaserCalibrationPlan& plan,
                                               const std::function<void(const std::string&)>& progress,
                                               std::vector<SweepRecording>* raw) {
  ScanAssemblyOptions assembly;
  assembly.beam_stride = plan.beam_stride;
  assembly.min_range = plan.min_range;
  const Eigen::Vector2d cube = plan.cube_in_base.head<2>();
  std::vector<CalibrationSweep> out;
  for (std::size_t k = 0; k < plan.sweeps.size(); ++k) {
    const std::string name = fmt::format("calibration sweep {} of {} (joint {})", k + 1, plan.sweeps.size(),
                                         plan.sweeps[k].joint + 1);
    if (progress) progress(name);
    SweepRecording rec = recorder.Record(plan.cube_in_base.head<2>(), plan.scan_posture, plan.sweeps[k], k % 2 == 1, name);
    std::vector<SweepPoint> points = AssembleSweep(rec.scans, rec.joint_states, model, assembly).points;
    if (plan.level_with_imu) LevelSweepPoints(points, rec.accel);
    if (plan.crop_radius > 0.0) {
      std::erase_if(points, [&](const SweepPoint& p) {
        const Eigen::Vector3d p_base = p.T_base_tool0 * (model.T_tool0_arm_laser * p.p_laser);
        return (p_base.head<2>() - cube).norm() > plan.crop_radius;
      });
    }
    out.push_back({name, std::move(points)});
    if (raw) raw->push_back(std::move(rec));
  }
  return out;
}

CalibrationSummary CalibrateArmLaser(hal::Robot& robot, const RobotModel& model, const arm::ArmOptions& arm_options,
                                     const LaserCalibrationPlan& plan, const Vector6d& q_start,
                                     const std::function<void(const std::string&)>& progress,
                                     const SweepRecorderOptions& recorder_options) {
  return CalibrateArmLaserAndRangeBias(robot, model, arm_options, plan, q_start, progress, recorder_options).mount;
}

}  // namespace ifab::sequencer

namespace ifab::sequencer {

ArmLaserCalibration IdentifyMountAndRangeBias(const std::vector<CalibrationSweep>& cube_sweeps,
                                              const std::vector<CalibrationSweep>& floor_sweeps,
                                              const std::vector<RegistrationBody>& bodies,
                                              const Pose3& T_tool0_laser_guess, const CalibrationOptions& calibration,
                                              const RangeBiasPlan& bias_plan,
                                              const std::function<void(const std::string&)>& progress) {
  ArmLaserCalibration out;
  out.compensation = bias_plan.compensation;
  out.compensation.model = {};
  if (progress) progress("calibrating the arm laser mount (raw sweeps)");
  out.mount_uncompensated = CalibrateLaserMount(cube_sweeps, bodies, T_tool0_laser_guess, calibration);
  out.mount = out.mount_uncompensated;
  if (!out.mount.IsUsable()) return out;
  // The targets where the first solve left them.
  std::vector<RegistrationBody> solved = bodies;
  for (std::size_t b = 0; b < solved.size() && b < out.mount.bodies.size(); ++b)
    solved[b].T_base_body = out.mount.bodies[b].T_base_body;
  // The bias from the cube sweeps `cube` and the floor sweeps, starting from `solved` and the mount
  // `T_tool0_laser`; then the cube
  // sweeps compensated, with each return's incidence from the cube and ground where the joint
  // solve put them (the returns the model is unsure of are left out: this replaces a fixed
  // minimum range and incidence).
  std::vector<CalibrationSweep> compensated;
  auto identify = [&](const std::vector<CalibrationSweep>& cube, const Pose3& T_tool0_laser) {
    std::vector<CalibrationSweep> all = cube;
    all.insert(all.end(), floor_sweeps.begin(), floor_sweeps.end());
    if (progress) progress("identifying the arm laser's range bias");
    out.bias = IdentifyRangeBias(all, solved, T_tool0_laser, bias_plan.identification);
    if (!out.bias->usable) return false;
    out.compensation.model = out.bias->model;
    for (std::size_t b = 0; b < solved.size() && b < out.bias->T_base_body.size(); ++b)
      solved[b].T_base_body = out.bias->T_base_body[b];
    const Scene targets(solved);
    compensated = cube;
    for (auto& sw : compensated) CompensateRangeBias(sw.points, out.bias->T_tool0_laser, out.compensation, &targets);
    return true;
  };
  if (!identify(cube_sweeps, out.mount.T_tool0_laser)) return out;
  // A floor is flat only locally. Where the compensated ground stops being one plane, the cube
  // sweeps are cropped, and the bias is identified again from the cropped sweeps.
  const auto ground = std::find_if(solved.begin(), solved.end(), [](const auto& b) { return b.name == "ground"; });
  const auto cube = std::find_if(solved.begin(), solved.end(), [](const auto& b) { return b.name == "cube"; });
  if (bias_plan.ground_extent.enabled && ground != solved.end() && cube != solved.end() && !cube->parts.empty() &&
      !cube->parts[0].primitives.empty() && std::holds_alternative<Box>(cube->parts[0].primitives[0])) {
    const double cube_size = std::get<Box>(cube->parts[0].primitives[0]).size.x();
    out.ground_extent = MeasureGroundExtent(compensated, out.bias->T_tool0_laser, ground->T_base_body,
                                            cube->T_base_body, cube_size, std::numeric_limits<double>::infinity(),
                                            bias_plan.ground_extent);
    spdlog::info("calibration: {}", out.ground_extent->message);
    if (out.ground_extent->limited) {
      std::vector<CalibrationSweep> cropped = cube_sweeps;
      CropSweeps(cropped, out.bias->T_tool0_laser, cube->T_base_body.translation().head<2>(), out.ground_extent->radius);
      if (!identify(cropped, out.bias->T_tool0_laser)) return out;
    }
  }
  if (progress) progress("calibrating the arm laser mount (compensated sweeps)");
  out.mount = CalibrateLaserMount(compensated, solved, out.bias->T_tool0_laser, calibration);
  out.cube_sweeps_compensated = std::move(compensated);
  return out;
}

void IdentifyArmKinematics(const KDL::Chain& design, const std::vector<CalibrationSweep>& cube_sweeps,
                           const std::vector<RegistrationBody>& bodies, const CalibrationSummary& mount,
                           const CalibrationOptions& calibration, const KinematicCalibrationOptions& options,
                           ArmLaserCalibration& out) {
  // The targets held where the joint solve put them: a view alone then finds the mount that its
  // posture's arm error makes of the true one.
  std::vector<RegistrationBody> held = bodies;
  // The cube alone is held: the as-built floor is flat only locally, and each view sees its own
  // patch of it, so the ground stays free in every view.
  for (std::size_t b = 0; b < held.size() && b < mount.bodies.size(); ++b) {
    held[b].T_base_body = mount.bodies[b].T_base_body;
    held[b].free = held[b].name != "cube";
    if (held[b].free) held[b].fixed = {true, true, false, false, false, true};  // a plane: its height and tilt
  }
  out.views.clear();
  out.views_left_out.clear();
  for (const CalibrationSweep& sweep : cube_sweeps) {
    if (sweep.points.empty()) continue;
    const CalibrationSummary s = CalibrateLaserMount({sweep}, held, mount.T_tool0_laser, calibration);
    if (!s.IsUsable()) {  // a view that does not fix the mount alone says nothing here
      std::string why = s.message + (s.fit.consistent ? "" : "; fit: " + s.fit.message);
      for (const auto& u : s.unconstrained) why += "; free: " + u;
      out.views_left_out.push_back(sweep.name + ": " + why);
      continue;
    }
    FlangeObservation v;
    v.name = sweep.name;
    // The sweep turns one joint evenly about its middle: the mean posture is the middle one.
    for (const SweepPoint& p : sweep.points) v.q += p.q;
    v.q /= static_cast<double>(sweep.points.size());
    v.T_tool0_laser = s.T_tool0_laser;
    v.covariance = s.covariance;
    out.views.push_back(v);
  }
  out.kinematics = CalibrateArmKinematics(design, out.views, mount.T_tool0_laser, options);
}

ArmLaserCalibration CalibrateArmLaserAndRangeBias(hal::Robot& robot, const RobotModel& model,
                                                  const arm::ArmOptions& arm_options, const LaserCalibrationPlan& plan,
                                                  const Vector6d& q_start,
                                                  const std::function<void(const std::string&)>& progress,
                                                  const SweepRecorderOptions& recorder_options,
                                                  std::vector<SweepRecording>* raw) {
  arm::ArmPrimitives arm(model, arm_options);
  SweepRecorder recorder(robot, arm, q_start, recorder_options);
  std::vector<CalibrationSweep> cube_sweeps, floor_sweeps;
  const auto bodies = CubeOnGroundBodies(plan.cube_size, plan.T_base_cube());
  try {
    cube_sweeps = RecordCubeSweeps(recorder, model, plan, progress, raw);
    if (plan.range_bias) {
      const RangeBiasPlan& bp = *plan.range_bias;
      ScanAssemblyOptions assembly;
      assembly.beam_stride = plan.beam_stride;
      for (std::size_t k = 0; k < bp.floor_heights.size(); ++k) {
        const double h = bp.floor_heights[k];
        const std::string name = fmt::format("range-bias sweep {} of {}: the floor from {:.2f} m", k + 1,
                                             bp.floor_heights.size(), h);
        if (progress) progress(name);
        SweepSpec spec;
        spec.joint = bp.floor_joint;
        spec.from = -bp.floor_half_range;
        spec.to = bp.floor_half_range;
        spec.speed = bp.floor_speed;
        spec.aim_offset = bp.floor_aim;
        LaserView view;
        view.distance = h / std::sin(bp.floor_elevation);
        view.elevation = bp.floor_elevation;
        spec.view = view;
        SweepRecording rec = recorder.Record(plan.cube_in_base.head<2>(), plan.scan_posture, spec, k % 2 == 1, name);
        std::vector<SweepPoint> points = AssembleSweep(rec.scans, rec.joint_states, model, assembly).points;
        if (plan.level_with_imu) LevelSweepPoints(points, rec.accel);
        if (!points.empty()) {
          // Keep the patch below the laser (design mount): the floor is flat only locally.
          const SweepPoint& mid = points[points.size() / 2];
          const Eigen::Vector2d below = (mid.T_base_tool0 * model.T_tool0_arm_laser).translation().head<2>();
          std::erase_if(points, [&](const SweepPoint& p) {
            const Eigen::Vector3d p_base = p.T_base_tool0 * (model.T_tool0_arm_laser * p.p_laser);
            return (p_base.head<2>() - below).norm() > bp.floor_crop_radius;
          });
        }
        floor_sweeps.push_back({name, std::move(points)});
        if (raw) raw->push_back(std::move(rec));
      }
    }
    recorder.MoveTo(q_start, "back to the start after calibration sweeps");
  } catch (const std::runtime_error& e) {
    ArmLaserCalibration failed;
    failed.mount.status = RegistrationStatus::kNoPoints;
    failed.mount.message = e.what();
    failed.mount.T_tool0_laser = model.T_tool0_arm_laser;
    failed.mount_uncompensated = failed.mount;
    return failed;
  }
  ArmLaserCalibration out;
  if (!plan.range_bias) {
    if (progress) progress("calibrating the arm laser mount");
    out.mount = CalibrateLaserMount(cube_sweeps, bodies, model.T_tool0_arm_laser, plan.calibration);
    out.mount_uncompensated = out.mount;
    out.cube_sweeps_compensated = std::move(cube_sweeps);  // nothing to compensate: as recorded
  } else {
    out = IdentifyMountAndRangeBias(cube_sweeps, floor_sweeps, bodies, model.T_tool0_arm_laser, plan.calibration,
                                    *plan.range_bias, progress);
    out.floor_sweeps = std::move(floor_sweeps);
  }
  if (plan.kinematics && out.mount.IsUsable()) {
    if (progress) progress("fitting the arm's kinematic errors to the calibration views");
    IdentifyArmKinematics(model.arm_chain, out.cube_sweeps_compensated, bodies, out.mount, plan.calibration,
                          *plan.kinematics, out);
  }
  return out;
}

}  // namespace ifab::sequencer
