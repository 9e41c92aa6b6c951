// `ifab run registration-consistency` (paper Table I) and `ifab run calibration-consistency`
// (Table II) in simulation. The arm laser sweeps single joints (arm primitives) on the simulated
// robot; scans and joint states are synced to host time from the sync pulses (sync module),
// assembled with eq. 6 and registered (eq. 7) or used to calibrate the laser mount (Sec. V-C).
// Only the scoring reads the simulator's truth.

#include <fmt/format.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/task_arena.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "ifab/arm/primitives.h"
#include "ifab/core/angles.h"
#include "ifab/core/config.h"
#include "ifab/core/data_path.h"
#include "ifab/core/error.h"
#include "ifab/core/random.h"
#include "ifab/experiments/experiments.h"
#include "ifab/perception/calibration.h"
#include "ifab/perception/commands.h"
#include "ifab/perception/ply.h"
#include "ifab/perception/registration.h"
#include "ifab/perception/scan_assembly.h"
#include "ifab/perception/sweep_io.h"
#include "ifab/sim/sim_robot.h"
#include "ifab/sync/clock_sync.h"

namespace ifab::experiments {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::string Relative(const ConfigNode& c, const std::string& key) {
  return (fs::path(c.file()).parent_path() / c.Get<std::string>(key)).string();
}

// One sweep: joint (0-based) from -> to at speed, the other joints at the scan pose, offset by
// `pose_offset` (e.g. joint 6 turned 90 deg so the scan plane crosses a joint-1 sweep).
struct SweepSpec {
  int joint{4};
  double from{0.0}, to{0.0};  // relative to the aimed scan pose [rad]
  double speed{0.17};         // [rad/s]
  Vector6d pose_offset{Vector6d::Zero()};
  // The centre beam aims this far off the target [m], along (radial, lateral): radial points from
  // the arm's foot to the target, lateral 90 deg to its left. A scan line across the arm (joint 6
  // at 0) aimed at a lateral offset crosses the target mid-sweep when joints 2, 3 or 5 sweep.
  Eigen::Vector2d aim_offset{Eigen::Vector2d::Zero()};
};

std::vector<SweepSpec> ReadSweeps(const ConfigNode& list) {
  list.ExpectSequence();
  std::vector<SweepSpec> out;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const ConfigNode s = list[i];
    s.ExpectKeys({"joint", "range_deg", "speed_deg_s", "offset_deg", "aim_offset"});
    SweepSpec spec;
    const int joint = s.Get<int>("joint");
    if (joint < 1 || joint > 6) s["joint"].Fail("a joint number 1..6");
    spec.joint = joint - 1;
    const auto r = s["range_deg"].AsNumbers(2);
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
    out.push_back(spec);
  }
  return out;
}

// A scan pose whose laser centre beam meets the floor at `target` (base frame): joint 1 turns
// towards it, joint 5 tilts the laser until the beam lands at its distance (design model).
Vector6d AimAt(const RobotModel& robot, const Eigen::Vector2d& target, const Vector6d& posture) {
  Vector6d q = posture;
  const Eigen::Vector3d foot = robot.T_base_arm_base.translation();
  q[0] = std::atan2(target.y() - foot.y(), target.x() - foot.x());
  auto miss = [&](double q5) {
    Vector6d qq = q;
    qq[4] = q5;
    const Pose3 T = robot.T_base_arm_base * robot.ArmForwardKinematics(qq) * robot.T_tool0_arm_laser;
    const Eigen::Vector3d o = T.translation(), d = T.linear().col(0);
    if (d.z() > -0.2) return 1e9;
    const Eigen::Vector3d hit = o - (o.z() / d.z()) * d;
    return (hit.head<2>() - target).norm();
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

// Drives the arm laser through sweeps on the simulator and returns them in host time, the
// devices' clocks mapped by TICSync-style sync from the pulses seen so far.
class SweepRecorder {
 public:
  SweepRecorder(sim::SimRobot& sim, arm::ArmPrimitives& arm, Vector6d q) : sim_(sim), arm_(arm), q_(q) {}

  // A sweep about the scan pose aimed at `target` (+ the spec's aim offset), base frame.
  SweepRecording Record(const Eigen::Vector2d& target, const Vector6d& posture, const SweepSpec& spec, bool reverse,
                        const std::string& name) {
    // The aim point sits `lateral` beside the target as seen from itself (so the scan line
    // across the arm passes through the target: Thales), and `radial` further out.
    const Eigen::Vector2d foot = arm_.robot().T_base_arm_base.translation().head<2>();
    const double D = (target - foot).norm();
    const double L = std::clamp(spec.aim_offset.y(), -0.9 * D, 0.9 * D);
    const double bearing = std::atan2(target.y() - foot.y(), target.x() - foot.x()) + std::asin(L / D);
    const double reach = std::sqrt(D * D - L * L) + spec.aim_offset.x();
    const Vector6d aim = AimAt(arm_.robot(), foot + reach * Eigen::Vector2d(std::cos(bearing), std::sin(bearing)), posture);
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
    if (!move.empty()) Execute(move, name);
    sim_.Wait(0.3);
    Drain(nullptr);  // the move: only its sync pulses matter
    Execute({sweep}, name);
    sim_.Wait(0.1);
    SweepRecording rec;
    rec.name = name;
    Drain(&rec);
    std::vector<LaserScan> scans;
    for (auto& s : rec.scans)
      if (laser_sync_.Apply(s.stamp)) scans.push_back(s);
    rec.scans = std::move(scans);
    for (auto& j : rec.joint_states) arm_sync_.Apply(j.stamp);
    q_ = plan.q_end;
    return rec;
  }

 private:
  void Execute(const std::vector<arm::ArmStep>& steps, const std::string& name) {
    const arm::ExecuteResult r = arm::ExecuteSteps(sim_, steps);
    if (!r.ok) throw std::runtime_error("sweep '" + name + "': " + r.message);
  }
  void Drain(SweepRecording* rec) {
    auto scans = sim_.TakeLaserScans(DeviceId::kArmLaser);
    auto joints = sim_.TakeJointStates();
    for (const auto& p : sim_.TakeSyncPulses()) {
      if (p.device == DeviceId::kArmLaser) laser_sync_.AddPulse(p);
      if (p.device == DeviceId::kArm) arm_sync_.AddPulse(p);
    }
    for (const auto& s : scans) laser_sync_.AddPacket(s.stamp);
    for (const auto& j : joints) arm_sync_.AddPacket(j.stamp);
    sim_.TakeLaserScans(DeviceId::kBaseLaser);
    sim_.TakeGyroSamples();
    if (rec) {
      rec->scans = std::move(scans);
      rec->joint_states = std::move(joints);
    }
  }

  sim::SimRobot& sim_;
  arm::ArmPrimitives& arm_;
  Vector6d q_;
  DeviceClockSync laser_sync_, arm_sync_;
};

// What both experiments share: the simulated machine, the design model and the arm.
struct Setup {
  sim::SimOptions sim;
  RobotModel robot;
  arm::ArmOptions arm;
  Vector6d posture;  // scan posture before aiming (joints 2, 3, 6; 1 and 5 are aimed)
  int beam_stride{1};
};

Setup ReadSetup(const ConfigNode& c) {
  Setup s;
  const ConfigNode robot_yaml = ConfigNode::LoadFile(Relative(c, "robot_yaml"));
  s.sim = sim::SimOptions::FromConfig(robot_yaml["sim"]);
  if (auto b = c.Find("range_bias")) {
    const bool bias = b->As<bool>();
    s.sim.arm_laser.bias_enabled = bias;
  }
  s.robot = LoadRobotModel(s.sim.urdf);
  s.arm = arm::ArmOptions::Load(Relative(c, "arm"));
  const auto p = c["scan_posture_deg"].AsNumbers(6);
  for (int k = 0; k < 6; ++k) s.posture[k] = DegToRad(p[static_cast<std::size_t>(k)]);
  c.ReadPositive("beam_stride", s.beam_stride);
  return s;
}

// Small rotation and translation of a mount relative to the design one, as x y z [mm] and roll
// pitch yaw [deg] (the design mount's pitch is -90 deg, where roll-pitch-yaw are singular).
std::array<double, 6> MountDelta(const Pose3& design, const Pose3& T) {
  const Pose3 d = design.inverse() * T;
  const auto v = XyzRpyFromPose(d);
  const Eigen::Vector3d t = T.translation();
  return {1e3 * t.x(), 1e3 * t.y(), 1e3 * t.z(), RadToDeg(v[3]), RadToDeg(v[4]), RadToDeg(v[5])};
}

struct Stats {
  std::array<double, 6> mean{}, std{}, mean_abs_error{};
};
Stats Statistics(const std::vector<std::array<double, 6>>& v, const std::array<double, 6>& truth) {
  Stats s;
  const double n = static_cast<double>(v.size());
  for (const auto& x : v)
    for (std::size_t k = 0; k < 6; ++k) {
      s.mean[k] += x[k] / n;
      s.mean_abs_error[k] += std::abs(x[k] - truth[k]) / n;
    }
  for (const auto& x : v)
    for (std::size_t k = 0; k < 6; ++k) s.std[k] += (x[k] - s.mean[k]) * (x[k] - s.mean[k]);
  for (std::size_t k = 0; k < 6; ++k) s.std[k] = v.size() > 1 ? std::sqrt(s.std[k] / (n - 1)) : 0.0;
  return s;
}

json Xyz(const std::array<double, 6>& v) { return {{"x", v[0]}, {"y", v[1]}, {"z", v[2]}}; }
json Rpy(const std::array<double, 6>& v) { return {{"roll", v[3]}, {"pitch", v[4]}, {"yaw", v[5]}}; }

// One calibration data set: the robot placed so the cube sits at `cube_in_base` (x y yaw, its
// design placement; the true one differs a little), the cube swept with every sweep spec.
std::vector<CalibrationSweep> RecordCalibrationSet(const Setup& setup, const std::vector<SweepSpec>& sweeps,
                                                   const Eigen::Vector3d& cube_in_base, double cube_size,
                                                   const Pose3& T_base_cube_true, std::uint64_t seed,
                                                   const RunContext& ctx, const std::string& label,
                                                   const std::string& save_dir = "", const std::string& file_prefix = "") {
  // The cube stands at the site origin; the robot is placed around it.
  const Pose3 T_site_cube = PoseFromXyzRpy(0.0, 0.0, 0.5 * cube_size, 0.0, 0.0, 0.0);
  const Pose3 T_site_base3 = T_site_cube * T_base_cube_true.inverse();
  const auto b = XyzRpyFromPose(T_site_base3);
  sim::SimRobot sim(setup.sim, Pose2(b[0], b[1], b[5]), setup.posture, seed);
  sim.mutable_world().AddBrick({"cube", T_site_cube, Box{Eigen::Vector3d::Constant(cube_size)}});
  arm::ArmPrimitives arm(setup.robot, setup.arm);
  SweepRecorder recorder(sim, arm, setup.posture);
  ScanAssemblyOptions assembly;
  assembly.beam_stride = setup.beam_stride;
  std::vector<CalibrationSweep> out;
  for (std::size_t k = 0; k < sweeps.size(); ++k) {
    const std::string name = fmt::format("{} sweep {} (joint {})", label, k + 1, sweeps[k].joint + 1);
    ctx.Progress(name);
    const SweepRecording rec = recorder.Record(cube_in_base.head<2>(), setup.posture, sweeps[k], k % 2 == 1, name);
    if (!save_dir.empty())
      SaveSweep((fs::path(save_dir) / fmt::format("{}_sweep_{}.json", file_prefix, k + 1)).string(), rec);
    out.push_back({name, AssembleSweep(rec.scans, rec.joint_states, setup.robot, assembly).points});
  }
  return out;
}

// ---- Table I -------------------------------------------------------------------------------

json RunRegistrationConsistency(const RunContext& ctx) {
  const ConfigNode& c = *ctx.config;
  c.ExpectKeys({"seed", "robot_yaml", "arm", "range_bias", "scan_posture_deg", "beam_stride", "brick_in_base",
                "brick_placement_sigma", "guess_error", "sweeps", "passes", "mount", "calibration", "bodies",
                "registration", "save_sweeps"});
  const bool save_sweeps = c.Get<bool>("save_sweeps", false);
  const Setup setup = ReadSetup(c);
  const std::vector<SweepSpec> sweeps = ReadSweeps(c["sweeps"]);
  int passes = 2;
  c.ReadPositive("passes", passes);
  const auto bb = c["brick_in_base"].AsNumbers(3);  // x y [m], yaw [deg]
  const auto place_sigma = c["brick_placement_sigma"].AsNumbers(2);  // [m], [deg]
  const auto guess_error = c["guess_error"].AsNumbers(2);            // [m], [deg]
  RegistrationOptions reg;
  if (auto r = c.Find("registration")) reg = RegistrationOptions::FromConfig(*r);
  const std::string bodies_mode = c.Get<std::string>("bodies", "separate");
  if (bodies_mode != "separate" && bodies_mode != "one") c["bodies"].Fail("separate (ground apart, as the paper) or one");
  RandomStream rng(ctx.seed);

  // The laser mount eq. 6 uses: the design value, or calibrated first (Sec. V-C, one data set).
  const Box brick{{0.240, 0.115, 0.052}};
  Pose3 T_tool0_laser = setup.robot.T_tool0_arm_laser;
  json mount_info;
  const std::string mount = c.Get<std::string>("mount", "calibrate");
  if (mount == "calibrate") {
    const ConfigNode k = c["calibration"];
    k.ExpectKeys({"cube_in_base", "cube_size", "sweeps", "calibration"});
    const auto cb = k["cube_in_base"].AsNumbers(3);
    const double size = k.Get<double>("cube_size", 0.25);
    CalibrationOptions copt;
    if (auto o = k.Find("calibration")) copt = CalibrationOptions::FromConfig(*o);
    const Pose3 T_base_cube = PoseFromXyzRpy(cb[0], cb[1], 0.5 * size, 0, 0, DegToRad(cb[2]));
    const auto sets = RecordCalibrationSet(setup, ReadSweeps(k["sweeps"]), Eigen::Vector3d(cb[0], cb[1], cb[2]), size,
                                           T_base_cube, ctx.seed, ctx, "calibration",
                                           save_sweeps ? ctx.out_dir : "", "calibration");
    ctx.Progress("calibrating the arm laser mount");
    const CalibrationSummary cs =
        CalibrateLaserMount(sets, CubeOnGroundBodies(size, T_base_cube), setup.robot.T_tool0_arm_laser, copt);
    if (!cs.IsUsable()) throw std::runtime_error("mount calibration failed: " + cs.message);
    T_tool0_laser = cs.T_tool0_laser;
    mount_info = {{"source", "calibrated"}, {"message", cs.message}};
  } else if (mount == "design") {
    mount_info = {{"source", "design"}};
  } else if (mount == "true") {  // diagnostics: what registration gives with a perfect calibration
    T_tool0_laser = sim::SimRobot(setup.sim, Pose2(), setup.posture, ctx.seed).true_T_tool0_arm_laser();
    mount_info = {{"source", "simulator truth (diagnostics)"}};
  } else {
    c["mount"].Fail("calibrate, design or true (diagnostics)");
  }

  // The brick on the floor in front of the robot, placed within a few mm of its design spot.
  const Pose3 T_base_brick_design = PoseFromXyzRpy(bb[0], bb[1], 0.026, 0, 0, DegToRad(bb[2]));
  const Pose3 T_base_brick_true =
      T_base_brick_design * PoseFromXyzRpy(rng.Normal(place_sigma[0]), rng.Normal(place_sigma[0]), 0, 0, 0,
                                           DegToRad(rng.Normal(place_sigma[1])));
  const Pose3 T_site_brick = PoseFromXyzRpy(0.0, 0.0, 0.026, 0, 0, 0);
  const Pose3 T_site_base = T_site_brick * T_base_brick_true.inverse();
  const auto b = XyzRpyFromPose(T_site_base);
  sim::SimRobot sim(setup.sim, Pose2(b[0], b[1], b[5]), setup.posture, ctx.seed + 1000);
  sim.mutable_world().AddBrick({"brick", T_site_brick, brick});
  const Pose3 T_base_site_true = PoseFromXyzRpy(sim.true_base_pose().x, sim.true_base_pose().y, 0, 0, 0,
                                                sim.true_base_pose().theta).inverse();
  const Pose3 T_base_brick = T_base_site_true * T_site_brick;  // truth, for scoring

  arm::ArmPrimitives arm(setup.robot, setup.arm);
  SweepRecorder recorder(sim, arm, setup.posture);
  ScanAssemblyOptions assembly;
  assembly.beam_stride = setup.beam_stride;

  std::vector<std::array<double, 6>> poses;
  json scans = json::array();
  std::ofstream csv(fs::path(ctx.out_dir) / "registration_scans.csv");
  csv << "scan,joint,points,brick_inliers,x_m,y_m,z_m,roll_deg,pitch_deg,yaw_deg,status\n";
  for (std::size_t k = 0; k < sweeps.size(); ++k) {
    for (int pass = 0; pass < passes; ++pass) {
      const std::string name = fmt::format("scan {} (joint {}, pass {})", poses.size() + 1, sweeps[k].joint + 1, pass + 1);
      ctx.Progress(name);
      const SweepRecording rec = recorder.Record(Eigen::Vector2d(bb[0], bb[1]), setup.posture, sweeps[k], pass % 2 == 1, name);
      if (save_sweeps) SaveSweep((fs::path(ctx.out_dir) / fmt::format("scan_{}_sweep.json", scans.size() + 1)).string(), rec);
      const std::vector<RayPoint> cloud = AssembleCloud(rec.scans, rec.joint_states, setup.robot, T_tool0_laser, assembly);
      // The expected brick pose: its design spot, the robot's localization off by guess_error.
      const Pose3 guess = T_base_brick_design * PoseFromXyzRpy(rng.Uniform(-guess_error[0], guess_error[0]),
                                                               rng.Uniform(-guess_error[0], guess_error[0]), 0, 0, 0,
                                                               DegToRad(rng.Uniform(-guess_error[1], guess_error[1])));
      RigidObject ground{"ground", Pose3::Identity(), {Plane{Eigen::Vector3d::UnitZ(), -0.026}}};
      RigidObject brick_object{"brick", Pose3::Identity(), {brick}};
      std::vector<RegistrationBody> bodies;
      if (bodies_mode == "one") {
        bodies = {{"brick", guess, {brick_object, ground}, true}};
      } else {
        bodies = {{"ground", guess, {ground}, true}, {"brick", guess, {brick_object}, true}};
      }
      const RegistrationSummary s = Register(cloud, bodies, reg);
      const RegisteredBody* found = s.Find("brick");
      const auto v = XyzRpyFromPose(found->T_base_body);
      const std::array<double, 6> pose{1e3 * v[0], 1e3 * v[1], 1e3 * v[2], RadToDeg(v[3]), RadToDeg(v[4]), RadToDeg(v[5])};
      if (s.IsUsable()) poses.push_back(pose);
      scans.push_back({{"name", name}, {"points", s.num_points}, {"brick_inliers", found->inliers},
                       {"status", ToString(s.status)}, {"pose_mm_deg", pose}, {"warnings", s.warnings}});
      csv << fmt::format("{},{},{},{},{:.6f},{:.6f},{:.6f},{:.4f},{:.4f},{:.4f},{}\n", poses.size(), sweeps[k].joint + 1,
                         s.num_points, found->inliers, v[0], v[1], v[2], pose[3], pose[4], pose[5], ToString(s.status));
      if (k == 0 && pass == 0) {  // one labelled cloud for the report (paper Fig. 3)
        PointCloud pc = ToPointCloud(cloud);
        std::vector<double> label(cloud.size());
        for (std::size_t i = 0; i < cloud.size(); ++i) label[i] = s.point_body[i] == static_cast<int>(bodies.size()) - 1 ? 1 : 0;
        pc.SetField("on_brick", std::move(label));
        WritePly((fs::path(ctx.out_dir) / "registration_scan_1.ply").string(), pc);
      }
    }
  }
  if (poses.size() < 2) throw std::runtime_error("fewer than two usable registrations");
  const auto vt = XyzRpyFromPose(T_base_brick);
  std::array<double, 6> truth{1e3 * vt[0], 1e3 * vt[1], 1e3 * vt[2], RadToDeg(vt[3]), RadToDeg(vt[4]), RadToDeg(vt[5])};
  // Yaw of a brick is defined modulo 180 deg; bring every estimate next to the truth.
  for (auto& p : poses) p[5] += 180.0 * std::round((truth[5] - p[5]) / 180.0);
  const Stats st = Statistics(poses, truth);
  return {{"scans", poses.size()},
          {"std_mm", Xyz(st.std)},
          {"std_deg", Rpy(st.std)},
          {"mean_abs_error_mm", Xyz(st.mean_abs_error)},
          {"mean_abs_error_deg", Rpy(st.mean_abs_error)},
          {"range_bias", setup.sim.arm_laser.bias_enabled},
          {"bodies", bodies_mode},
          {"residual", reg.residual == RegistrationResidual::kRay ? "ray" : "closest"},
          {"mount", mount_info},
          {"T_tool0_laser_used", PoseToJson(T_tool0_laser)},
          {"T_tool0_laser_true", PoseToJson(sim.true_T_tool0_arm_laser())},
          {"brick_true_in_base", PoseToJson(T_base_brick)},
          {"per_scan", scans}};
}

std::vector<std::vector<std::string>> RegistrationTable(const json& r) {
  const std::array<std::pair<const char*, double>, 3> mm{{{"x", 0.44}, {"y", 1.05}, {"z", 0.69}}};
  const std::array<std::pair<const char*, double>, 3> deg{{{"roll", 0.056}, {"pitch", 0.113}, {"yaw", 0.717}}};
  std::vector<std::vector<std::string>> rows;
  for (const auto& [k, paper] : mm)
    rows.push_back({fmt::format("brick {} std [mm]", k), fmt::format("{:.2f}", r["std_mm"][k].get<double>()),
                    fmt::format("{:.2f}", paper)});
  for (const auto& [k, paper] : deg)
    rows.push_back({fmt::format("brick {} std [deg]", k), fmt::format("{:.3f}", r["std_deg"][k].get<double>()),
                    fmt::format("{:.3f}", paper)});
  for (const char* k : {"x", "y", "z"})
    rows.push_back({fmt::format("brick {} mean abs error [mm]", k),
                    fmt::format("{:.2f}", r["mean_abs_error_mm"][k].get<double>()), "-"});
  rows.push_back({"scans", std::to_string(r["scans"].get<int>()), "8"});
  return rows;
}

// ---- Table II ------------------------------------------------------------------------------

json RunCalibrationConsistency(const RunContext& ctx) {
  const ConfigNode& c = *ctx.config;
  c.ExpectKeys({"seed", "robot_yaml", "arm", "range_bias", "scan_posture_deg", "beam_stride", "cube_size",
                "cube_placement_sigma", "datasets", "sweeps", "trials", "initial_guess", "calibration", "jobs",
                "save_sweeps"});
  const bool save_sweeps = c.Get<bool>("save_sweeps", false);
  const Setup setup = ReadSetup(c);
  const std::vector<SweepSpec> sweeps = ReadSweeps(c["sweeps"]);
  const double size = c.Get<double>("cube_size", 0.25);
  const auto place_sigma = c["cube_placement_sigma"].AsNumbers(2);
  const auto guess = c["initial_guess"].AsNumbers(2);  // +- [m], +- [deg]
  int trials = 20, jobs = 1;
  c.ReadPositive("trials", trials);
  c.ReadPositive("jobs", jobs);
  CalibrationOptions copt;
  if (auto o = c.Find("calibration")) copt = CalibrationOptions::FromConfig(*o);
  const ConfigNode ds = c["datasets"];
  ds.ExpectSequence();
  RandomStream rng(ctx.seed);
  const Pose3 design = setup.robot.T_tool0_arm_laser;
  // The truth of the mount (for scoring) is the same in every simulated robot of this run.
  const Pose3 truth_mount = sim::SimRobot(setup.sim, Pose2(), setup.posture, ctx.seed).true_T_tool0_arm_laser();

  std::vector<std::array<double, 6>> calibrations;
  double worst_trial_std_mm = 0.0, worst_trial_std_deg = 0.0;
  json sets = json::array();
  std::ofstream csv(fs::path(ctx.out_dir) / "calibration_datasets.csv");
  csv << "dataset,cube_x_m,cube_y_m,points,x_mm,y_mm,z_mm,roll_deg,pitch_deg,yaw_deg,trial_std_mm_max,trial_std_deg_max\n";
  for (std::size_t d = 0; d < ds.size(); ++d) {
    const auto cb = ds[d].AsNumbers(3);  // cube x y [m], yaw [deg] in base (design placement)
    const Pose3 T_base_cube_design = PoseFromXyzRpy(cb[0], cb[1], 0.5 * size, 0, 0, DegToRad(cb[2]));
    const Pose3 T_base_cube_true =
        T_base_cube_design * PoseFromXyzRpy(rng.Normal(place_sigma[0]), rng.Normal(place_sigma[0]), 0, 0, 0,
                                            DegToRad(rng.Normal(place_sigma[1])));
    const std::string label = fmt::format("data set {}", d + 1);
    const auto recorded = RecordCalibrationSet(setup, sweeps, Eigen::Vector3d(cb[0], cb[1], cb[2]), size,
                                               T_base_cube_true, ctx.seed + 100 * (d + 1), ctx, label,
                                               save_sweeps ? ctx.out_dir : "", fmt::format("dataset_{}", d + 1));
    // 20 trials from random guesses of the mount, the cube and the ground (+-0.02 m, +-3 deg).
    std::vector<std::array<double, 6>> initial(static_cast<std::size_t>(trials));
    std::vector<Pose3> guesses_mount, guesses_cube;
    std::vector<double> guesses_ground;
    auto jitter = [&]() {
      return PoseFromXyzRpy(rng.Uniform(-guess[0], guess[0]), rng.Uniform(-guess[0], guess[0]),
                            rng.Uniform(-guess[0], guess[0]), DegToRad(rng.Uniform(-guess[1], guess[1])),
                            DegToRad(rng.Uniform(-guess[1], guess[1])), DegToRad(rng.Uniform(-guess[1], guess[1])));
    };
    for (int t = 0; t < trials; ++t) {
      guesses_mount.push_back(design * jitter());
      guesses_cube.push_back(T_base_cube_design * jitter());
      guesses_ground.push_back(rng.Uniform(-guess[0], guess[0]));
    }
    ctx.Progress(fmt::format("{}: {} calibrations from random initial guesses", label, trials));
    std::vector<CalibrationSummary> results(static_cast<std::size_t>(trials));
    tbb::task_arena arena(jobs);
    arena.execute([&] {
      tbb::parallel_for(0, trials, [&](int t) {
        auto bodies = CubeOnGroundBodies(size, guesses_cube[static_cast<std::size_t>(t)],
                                         guesses_ground[static_cast<std::size_t>(t)]);
        results[static_cast<std::size_t>(t)] =
            CalibrateLaserMount(recorded, bodies, guesses_mount[static_cast<std::size_t>(t)], copt);
      });
    });
    std::vector<Pose3> mounts;
    std::vector<std::array<double, 6>> trial_deltas;
    for (const auto& r : results) {
      if (!r.IsUsable()) continue;
      mounts.push_back(r.T_tool0_laser);
      trial_deltas.push_back(MountDelta(design, r.T_tool0_laser));
    }
    if (mounts.empty()) throw std::runtime_error(label + ": no calibration trial converged");
    const Pose3 mean = AveragePoses(mounts);
    const auto delta = MountDelta(design, mean);
    calibrations.push_back(delta);
    const Stats trial_stats = Statistics(trial_deltas, delta);
    const double std_mm = std::max({trial_stats.std[0], trial_stats.std[1], trial_stats.std[2]});
    const double std_deg = std::max({trial_stats.std[3], trial_stats.std[4], trial_stats.std[5]});
    worst_trial_std_mm = std::max(worst_trial_std_mm, std_mm);
    worst_trial_std_deg = std::max(worst_trial_std_deg, std_deg);
    int points = 0;
    for (const auto& s : recorded) points += static_cast<int>(s.points.size());
    sets.push_back({{"cube_in_base", cb}, {"points", points}, {"usable_trials", mounts.size()},
                    {"mount_mm_deg", delta}, {"trial_std_mm_max", std_mm}, {"trial_std_deg_max", std_deg},
                    {"warnings", results.front().warnings}});
    csv << fmt::format("{},{},{},{},{:.3f},{:.3f},{:.3f},{:.4f},{:.4f},{:.4f},{:.4f},{:.5f}\n", d + 1, cb[0], cb[1], points,
                       delta[0], delta[1], delta[2], delta[3], delta[4], delta[5], std_mm, std_deg);
  }
  const auto truth = MountDelta(design, truth_mount);
  const Stats st = Statistics(calibrations, truth);
  return {{"datasets", calibrations.size()},
          {"std_mm", Xyz(st.std)},
          {"std_deg", Rpy(st.std)},
          {"mean_abs_error_mm", Xyz(st.mean_abs_error)},
          {"mean_abs_error_deg", Rpy(st.mean_abs_error)},
          {"initial_guess_std_mm_max", worst_trial_std_mm},
          {"initial_guess_std_deg_max", worst_trial_std_deg},
          {"range_bias", setup.sim.arm_laser.bias_enabled},
          {"trials_per_dataset", trials},
          {"mount_convention", "x y z: laser origin in tool0 [mm]; roll pitch yaw: rotation from the design mount [deg]"},
          {"true_mount_mm_deg", truth},
          {"per_dataset", sets}};
}

std::vector<std::vector<std::string>> CalibrationTable(const json& r) {
  const std::array<std::pair<const char*, double>, 3> mm{{{"x", 2.9}, {"y", 1.4}, {"z", 4.1}}};
  const std::array<std::pair<const char*, double>, 3> deg{{{"roll", 0.389}, {"pitch", 0.053}, {"yaw", 0.389}}};
  std::vector<std::vector<std::string>> rows;
  for (const auto& [k, paper] : mm)
    rows.push_back({fmt::format("mount {} std [mm]", k), fmt::format("{:.2f}", r["std_mm"][k].get<double>()),
                    fmt::format("{:.1f} (target {:.2f})", paper, paper / 3)});
  for (const auto& [k, paper] : deg)
    rows.push_back({fmt::format("mount {} std [deg]", k), fmt::format("{:.3f}", r["std_deg"][k].get<double>()),
                    fmt::format("{:.3f} (target {:.3f})", paper, paper / 3)});
  for (const char* k : {"x", "y", "z"})
    rows.push_back({fmt::format("mount {} mean abs error [mm]", k),
                    fmt::format("{:.2f}", r["mean_abs_error_mm"][k].get<double>()), "-"});
  rows.push_back({"std over initial guesses, max [mm]", fmt::format("{:.3f}", r["initial_guess_std_mm_max"].get<double>()),
                  "< 0.5"});
  rows.push_back({"std over initial guesses, max [deg]", fmt::format("{:.4f}", r["initial_guess_std_deg_max"].get<double>()),
                  "< 0.1"});
  rows.push_back({"data sets", std::to_string(r["datasets"].get<int>()), "9"});
  return rows;
}

}  // namespace

ExperimentInfo RegistrationConsistencyExperiment() {
  return {"registration-consistency",
          "paper Table I: 8 registrations of one brick from 4 single-joint sweeps (std of the pose)",
          RunRegistrationConsistency, RegistrationTable};
}

ExperimentInfo CalibrationConsistencyExperiment() {
  return {"calibration-consistency",
          "paper Table II: laser mount calibrated on 9 data sets of cube sweeps (std over data sets)",
          RunCalibrationConsistency, CalibrationTable};
}

}  // namespace ifab::experiments
