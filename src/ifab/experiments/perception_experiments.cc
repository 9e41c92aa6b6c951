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
#include <memory>

#include "ifab/experiments/atomic_file.h"
#include "ifab/arm/primitives.h"
#include "ifab/core/angles.h"
#include "ifab/core/config.h"
#include "ifab/core/data_path.h"
#include "ifab/core/error.h"
#include "ifab/core/random.h"
#include "ifab/experiments/experiments.h"
#include "ifab/perception/calibration.h"
#include "ifab/experiments/perception_json.h"
#include "ifab/experiments/ply_file.h"
#include "ifab/perception/ply.h"
#include "ifab/perception/registration.h"
#include "ifab/perception/scan_assembly.h"
#include "ifab/experiments/sweep_io.h"
#include "ifab/sequencer/laser_sweeps.h"
#include "ifab/sim/sim_robot.h"

namespace ifab::experiments {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::string Relative(const ConfigNode& c, const std::string& key) {
  return (fs::path(c.file()).parent_path() / c.Get<std::string>(key)).string();
}

// What both experiments share: the simulated machine, the design model and the arm.
struct ConsistencySetup {
  sim::SimOptions sim;
  RobotModel robot;
  arm::ArmOptions arm;
  Vector6d posture;  // scan posture before aiming (joints 2, 3, 6; 1 and 5 are aimed)
  int beam_stride{1};
};

ConsistencySetup ReadConsistencySetup(const ConfigNode& c) {
  ConsistencySetup s;
  const ConfigNode robot_yaml = ConfigNode::LoadFile(Relative(c, "robot_yaml"));
  robot_yaml.ExpectKeys({"feeder_in_base", "sim"});
  s.sim = sim::SimOptions::FromConfig(robot_yaml["sim"]);
  if (auto b = c.Find("range_bias")) {
    const bool bias = b->As<bool>();
    s.sim.arm_laser.bias_enabled = bias;
  }
  // Diagnostics only: the arm laser without any noise (then only model errors are left).
  if (auto n = c.Find("laser_noise")) s.sim.arm_laser.noise_enabled = n->As<bool>();
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

struct PoseStats {
  std::array<double, 6> mean{}, std{}, mean_abs_error{};
};
PoseStats Statistics(const std::vector<std::array<double, 6>>& v, const std::array<double, 6>& truth) {
  PoseStats s;
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

// The simulated robot placed so that the cube truly sits at T_base_cube_true (the plan's
// cube_in_base is its design placement, which the sweeps aim at).
std::unique_ptr<sim::SimRobot> CubeSim(const ConsistencySetup& setup, const sequencer::LaserCalibrationPlan& plan,
                                       const Pose3& T_base_cube_true, std::uint64_t seed) {
  // The cube stands at the site origin; the robot is placed around it.
  const Pose3 T_site_cube = PoseFromXyzRpy(0.0, 0.0, 0.5 * plan.cube_size, 0.0, 0.0, 0.0);
  const auto b = XyzRpyFromPose(T_site_cube * T_base_cube_true.inverse());
  auto sim = std::make_unique<sim::SimRobot>(setup.sim, Pose2(b[0], b[1], b[5]), plan.scan_posture, seed);
  sim->mutable_world().AddBrick({"cube", T_site_cube, Box{Eigen::Vector3d::Constant(plan.cube_size)}});
  return sim;
}

// One calibration data set: the cube swept as the plan says.
std::vector<CalibrationSweep> RecordCalibrationSet(const ConsistencySetup& setup, const sequencer::LaserCalibrationPlan& plan,
                                                   const Pose3& T_base_cube_true, std::uint64_t seed,
                                                   const RunContext& ctx, const std::string& label,
                                                   const std::string& save_dir, const std::string& file_prefix) {
  const auto sim = CubeSim(setup, plan, T_base_cube_true, seed);
  arm::ArmPrimitives arm(setup.robot, setup.arm);
  sequencer::SweepRecorder recorder(*sim, arm, plan.scan_posture);
  std::vector<SweepRecording> raw;
  auto sets = sequencer::RecordCubeSweeps(recorder, setup.robot, plan,
                                          [&](const std::string& what) { ctx.Progress(label + ": " + what); },
                                          save_dir.empty() ? nullptr : &raw);
  for (std::size_t k = 0; k < raw.size(); ++k)
    SaveSweep((fs::path(save_dir) / fmt::format("{}_sweep_{}.json", file_prefix, k + 1)).string(), raw[k]);
  return sets;
}

// ---- Table I -------------------------------------------------------------------------------

json RunRegistrationConsistency(const RunContext& ctx) {
  const ConfigNode& c = *ctx.config;
  c.ExpectKeys({"seed", "robot_yaml", "arm", "range_bias", "scan_posture_deg", "beam_stride", "brick_in_base",
                "brick_placement_sigma", "guess_error", "sweeps", "passes", "mount", "calibration", "bodies",
                "registration", "save_sweeps", "laser_noise", "crop_radius", "min_range"});
  const bool save_sweeps = c.Get<bool>("save_sweeps", false);
  const ConsistencySetup setup = ReadConsistencySetup(c);
  const std::vector<sequencer::SweepSpec> sweeps = sequencer::ReadSweepSpecs(c["sweeps"]);
  int passes = 2;
  c.ReadPositive("passes", passes);
  double crop_radius = 0.0;
  c.ReadNonNegative("crop_radius", crop_radius);
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
    // The section may name its own scan posture and beam stride; else the experiment's apply.
    const ConfigNode k = c["calibration"];
    sequencer::LaserCalibrationPlan plan = sequencer::LaserCalibrationPlan::FromConfig(k);
    if (!k.Has("scan_posture_deg")) plan.scan_posture = setup.posture;
    if (!k.Has("beam_stride")) plan.beam_stride = setup.beam_stride;
    // To keep the sweeps, record them once more apart (same seed: the same sweeps).
    if (save_sweeps) RecordCalibrationSet(setup, plan, plan.T_base_cube(), ctx.seed, ctx, "calibration", ctx.out_dir, "calibration");
    const auto cube_sim = CubeSim(setup, plan, plan.T_base_cube(), ctx.seed);
    const CalibrationSummary cs = sequencer::CalibrateArmLaser(*cube_sim, setup.robot, setup.arm, plan, plan.scan_posture,
                                                               [&](const std::string& what) { ctx.Progress(what); });
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
  // Named draws, last argument first: gcc's order (C++ leaves a call's order open), every compiler alike.
  const double place_yaw = DegToRad(rng.Normal(place_sigma[1]));
  const double place_y = rng.Normal(place_sigma[0]), place_x = rng.Normal(place_sigma[0]);
  const Pose3 T_base_brick_true = T_base_brick_design * PoseFromXyzRpy(place_x, place_y, 0, 0, 0, place_yaw);
  const Pose3 T_site_brick = PoseFromXyzRpy(0.0, 0.0, 0.026, 0, 0, 0);
  const Pose3 T_site_base = T_site_brick * T_base_brick_true.inverse();
  const auto b = XyzRpyFromPose(T_site_base);
  sim::SimRobot sim(setup.sim, Pose2(b[0], b[1], b[5]), setup.posture, ctx.seed + 1000);
  sim.mutable_world().AddBrick({"brick", T_site_brick, brick});
  const Pose3 T_base_site_true = PoseFromXyzRpy(sim.true_base_pose().x, sim.true_base_pose().y, 0, 0, 0,
                                                sim.true_base_pose().theta).inverse();
  const Pose3 T_base_brick = T_base_site_true * T_site_brick;  // truth, for scoring

  arm::ArmPrimitives arm(setup.robot, setup.arm);
  sequencer::SweepRecorder recorder(sim, arm, setup.posture);
  ScanAssemblyOptions assembly;
  assembly.beam_stride = setup.beam_stride;
  c.ReadNonNegative("min_range", assembly.min_range);

  std::vector<std::array<double, 6>> poses;
  json scans = json::array();
  AtomicOfstream csv(fs::path(ctx.out_dir) / "registration_scans.csv");
  csv << "scan,joint,points,brick_inliers,x_m,y_m,z_m,roll_deg,pitch_deg,yaw_deg,status\n";
  for (std::size_t k = 0; k < sweeps.size(); ++k) {
    for (int pass = 0; pass < passes; ++pass) {
      const std::string name = fmt::format("scan {} (joint {}, pass {})", poses.size() + 1, sweeps[k].joint + 1, pass + 1);
      ctx.Progress(name);
      const SweepRecording rec = recorder.Record(Eigen::Vector2d(bb[0], bb[1]), setup.posture, sweeps[k], pass % 2 == 1, name);
      if (save_sweeps) SaveSweep((fs::path(ctx.out_dir) / fmt::format("scan_{}_sweep.json", scans.size() + 1)).string(), rec);
      std::vector<RayPoint> cloud = AssembleCloud(rec.scans, rec.joint_states, setup.robot, T_tool0_laser, assembly);
      // The model (a brick on a flat floor) holds near the brick only: keep the points within
      // crop_radius of its design spot (horizontally), as the mission does.
      if (crop_radius > 0.0)
        std::erase_if(cloud, [&](const RayPoint& p) { return (p.p.head<2>() - Eigen::Vector2d(bb[0], bb[1])).norm() > crop_radius; });
      // The expected brick pose: its design spot, the robot's localization off by guess_error.
      const double guess_yaw = DegToRad(rng.Uniform(-guess_error[1], guess_error[1]));  // last first, as above
      const double guess_y = rng.Uniform(-guess_error[0], guess_error[0]);
      const double guess_x = rng.Uniform(-guess_error[0], guess_error[0]);
      const Pose3 guess = T_base_brick_design * PoseFromXyzRpy(guess_x, guess_y, 0, 0, 0, guess_yaw);
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
      std::array<double, 6> predicted{};  // the solver's own std (base axes; rotations about them)
      for (int i = 0; i < 6; ++i) {
        const double sd = std::sqrt(found->covariance(i, i));
        predicted[static_cast<std::size_t>(i)] = i < 3 ? 1e3 * sd : RadToDeg(sd);
      }
      scans.push_back({{"name", name}, {"points", s.num_points}, {"brick_inliers", found->inliers},
                       {"status", ToString(s.status)}, {"message", s.message}, {"pose_mm_deg", pose},
                       {"predicted_std_mm_deg", predicted}, {"rms_whitened", s.rms_whitened},
                       {"shadow_removed", s.num_shadow_removed}, {"warnings", s.warnings}});
      csv << fmt::format("{},{},{},{},{:.6f},{:.6f},{:.6f},{:.4f},{:.4f},{:.4f},{}\n", poses.size(), sweeps[k].joint + 1,
                         s.num_points, found->inliers, v[0], v[1], v[2], pose[3], pose[4], pose[5], ToString(s.status));
      if (k == 0 && pass == 0) {  // one labelled cloud for the report (paper Fig. 3)
        PointCloud pc = ToPointCloud(cloud);
        std::vector<double> label(cloud.size());
        for (std::size_t i = 0; i < cloud.size(); ++i) label[i] = s.point_body[i] == static_cast<int>(bodies.size()) - 1 ? 1 : 0;
        pc.SetField("on_brick", std::move(label));
        SavePly((fs::path(ctx.out_dir) / "registration_scan_1.ply").string(), pc);
      }
    }
  }
  if (poses.size() < 2) throw std::runtime_error("fewer than two usable registrations");
  const auto vt = XyzRpyFromPose(T_base_brick);
  std::array<double, 6> truth{1e3 * vt[0], 1e3 * vt[1], 1e3 * vt[2], RadToDeg(vt[3]), RadToDeg(vt[4]), RadToDeg(vt[5])};
  // Yaw of a brick is defined modulo 180 deg; bring every estimate next to the truth.
  for (auto& p : poses) p[5] += 180.0 * std::round((truth[5] - p[5]) / 180.0);
  const PoseStats st = Statistics(poses, truth);
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
                "save_sweeps", "laser_noise", "min_range", "crop_radius"});
  const bool save_sweeps = c.Get<bool>("save_sweeps", false);
  const ConsistencySetup setup = ReadConsistencySetup(c);
  sequencer::LaserCalibrationPlan plan;
  plan.sweeps = sequencer::ReadSweepSpecs(c["sweeps"]);
  plan.scan_posture = setup.posture;
  plan.beam_stride = setup.beam_stride;
  c.ReadPositive("cube_size", plan.cube_size);
  c.ReadNonNegative("min_range", plan.min_range);
  c.ReadNonNegative("crop_radius", plan.crop_radius);
  const double size = plan.cube_size;
  const auto place_sigma = c["cube_placement_sigma"].AsNumbers(2);
  const auto guess = c["initial_guess"].AsNumbers(2);  // +- [m], +- [deg]
  int trials = 20, jobs = 1;
  c.ReadPositive("trials", trials);
  c.ReadPositive("jobs", jobs);
  if (auto o = c.Find("calibration")) plan.calibration = CalibrationOptions::FromConfig(*o);
  const ConfigNode ds = c["datasets"];
  ds.ExpectSequence();
  RandomStream rng(ctx.seed);
  const Pose3 design = setup.robot.T_tool0_arm_laser;
  // The truth of the mount (for scoring) is the same in every simulated robot of this run.
  const Pose3 truth_mount = sim::SimRobot(setup.sim, Pose2(), setup.posture, ctx.seed).true_T_tool0_arm_laser();

  std::vector<std::array<double, 6>> calibrations;
  double worst_trial_std_mm = 0.0, worst_trial_std_deg = 0.0;
  json sets = json::array();
  AtomicOfstream csv(fs::path(ctx.out_dir) / "calibration_datasets.csv");
  csv << "dataset,cube_x_m,cube_y_m,points,x_mm,y_mm,z_mm,roll_deg,pitch_deg,yaw_deg,trial_std_mm_max,trial_std_deg_max\n";
  for (std::size_t d = 0; d < ds.size(); ++d) {
    const auto cb = ds[d].AsNumbers(3);  // cube x y [m], yaw [deg] in base (design placement)
    const Pose3 T_base_cube_design = PoseFromXyzRpy(cb[0], cb[1], 0.5 * size, 0, 0, DegToRad(cb[2]));
    // Named draws, last argument first: gcc's order (C++ leaves a call's order open), every compiler alike.
    const double place_yaw = DegToRad(rng.Normal(place_sigma[1]));
    const double place_y = rng.Normal(place_sigma[0]), place_x = rng.Normal(place_sigma[0]);
    const Pose3 T_base_cube_true = T_base_cube_design * PoseFromXyzRpy(place_x, place_y, 0, 0, 0, place_yaw);
    const std::string label = fmt::format("data set {}", d + 1);
    plan.cube_in_base = Eigen::Vector3d(cb[0], cb[1], DegToRad(cb[2]));
    const auto recorded = RecordCalibrationSet(setup, plan, T_base_cube_true, ctx.seed + 100 * (d + 1), ctx, label,
                                               save_sweeps ? ctx.out_dir : "", fmt::format("dataset_{}", d + 1));
    // 20 trials from random guesses of the mount, the cube and the ground (+-0.02 m, +-3 deg).
    std::vector<std::array<double, 6>> initial(static_cast<std::size_t>(trials));
    std::vector<Pose3> guesses_mount, guesses_cube;
    std::vector<double> guesses_ground;
    auto jitter = [&]() {
      const double yaw = DegToRad(rng.Uniform(-guess[1], guess[1]));  // last first, as above
      const double pitch = DegToRad(rng.Uniform(-guess[1], guess[1]));
      const double roll = DegToRad(rng.Uniform(-guess[1], guess[1]));
      const double z = rng.Uniform(-guess[0], guess[0]), y = rng.Uniform(-guess[0], guess[0]);
      const double x = rng.Uniform(-guess[0], guess[0]);
      return PoseFromXyzRpy(x, y, z, roll, pitch, yaw);
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
            CalibrateLaserMount(recorded, bodies, guesses_mount[static_cast<std::size_t>(t)], plan.calibration);
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
    const PoseStats trial_stats = Statistics(trial_deltas, delta);
    const double std_mm = std::max({trial_stats.std[0], trial_stats.std[1], trial_stats.std[2]});
    const double std_deg = std::max({trial_stats.std[3], trial_stats.std[4], trial_stats.std[5]});
    worst_trial_std_mm = std::max(worst_trial_std_mm, std_mm);
    worst_trial_std_deg = std::max(worst_trial_std_deg, std_deg);
    int points = 0;
    for (const auto& s : recorded) points += static_cast<int>(s.points.size());
    // What the solver expects of its own scatter (from J^T J; rotations about tool0 axes), to
    // compare with the scatter over data sets: far smaller means model errors dominate.
    const CalibrationSummary& first = results.front();
    std::array<double, 6> predicted{}, error{};
    for (std::size_t k = 0; k < 6; ++k) {
      const double sd = std::sqrt(first.covariance(static_cast<int>(k), static_cast<int>(k)));
      predicted[k] = k < 3 ? 1e3 * sd : RadToDeg(sd);
      error[k] = delta[k] - MountDelta(design, truth_mount)[k];
    }
    sets.push_back({{"cube_in_base", cb}, {"points", points}, {"usable_trials", mounts.size()},
                    {"mount_mm_deg", delta}, {"error_vs_truth_mm_deg", error}, {"predicted_std_mm_deg", predicted},
                    {"trial_std_mm_max", std_mm}, {"trial_std_deg_max", std_deg}, {"inliers", first.num_inliers},
                    {"shadow_removed", first.num_shadow_removed}, {"rms_whitened", first.rms_whitened},
                    {"sweep_inliers", first.sweep_inliers}, {"warnings", first.warnings}});
    csv << fmt::format("{},{},{},{},{:.3f},{:.3f},{:.3f},{:.4f},{:.4f},{:.4f},{:.4f},{:.5f}\n", d + 1, cb[0], cb[1], points,
                       delta[0], delta[1], delta[2], delta[3], delta[4], delta[5], std_mm, std_deg);
  }
  const auto truth = MountDelta(design, truth_mount);
  const PoseStats st = Statistics(calibrations, truth);
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
