// `ifab run` (brick-stack): the paper's brick stacking experiment (Sec. VI-VII) in simulation.
// The mission sees the simulated robot only through hal::Robot; this file alone holds both
// sides, and reads the truth only to score.

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "ifab/experiments/atomic_file.h"
#include "ifab/experiments/brick_stack_setup.h"
#include "ifab/experiments/perception_json.h"
#include "ifab/core/angles.h"
#include "ifab/core/data_path.h"
#include "ifab/experiments/experiments.h"
#include "ifab/experiments/report_data.h"
#include "ifab/experiments/sim_forwarding_robot.h"
#include "ifab/perception/cloud.h"
#include "ifab/perception/ply.h"
#include "ifab/sequencer/laser_sweeps.h"
#include "ifab/sequencer/mission.h"
#include "ifab/sim/sim_robot.h"

namespace ifab::experiments {
namespace {
namespace fs = std::filesystem;

std::string Beside(const ConfigNode& c, const std::string& key) {
  const std::string v = c.Get<std::string>(key);
  if (!v.empty() && v[0] == '/') return v;
  return (fs::path(c.file()).parent_path() / v).string();
}

// Forwards to the simulator and samples the true base pose as time passes (for Fig. 6).
class RecordingRobot final : public SimForwardingRobot {
 public:
  explicit RecordingRobot(sim::SimRobot& sim) : SimForwardingRobot(sim) {}
  void Wait(Seconds dt) override {
    sim_.Wait(dt);
    if (replay)
      replay->Offer({sim_.Now(), sim_.true_base_pose(), sim_.true_joint_angles(), sim_.holding_brick(),
                     static_cast<int>(sim_.world().bricks().size())});
    if (sim_.Now() >= next_) {
      truth.push_back({sim_.Now(), sim_.true_base_pose()});
      next_ = sim_.Now() + truth_period;
    }
  }
  void SetLaserActive(DeviceId id, bool active) override {
    if (replay && id == DeviceId::kArmLaser) replay->ArmLaser(sim_.Now(), active);
    sim_.SetLaserActive(id, active);
  }

  std::vector<Stamped<Pose2>> truth;
  /// The sampled true base poses as CSV (t, x, y, theta; SI units), to redraw Fig. 6.
  void WriteTruthCsv(const std::string& path) const {
    AtomicOfstream csv(path);
    csv << "t,x,y,theta\n";
    for (const auto& s : truth)
      csv << fmt::format("{:.4f},{:.5f},{:.5f},{:.6f}\n", s.t, s.value.x, s.value.y, s.value.theta);
  }
  Seconds truth_period{0.1};  ///< [s] how often the true pose is recorded
  ReplayRecorder* replay{nullptr};  ///< samples for the report's 3D replay (optional)

 private:
  Seconds next_{0.0};
};

struct Stats {
  double sum{0}, max{0};
  int n{0};
  void Add(double v) {
    sum += v;
    max = std::max(max, v);
    ++n;
  }
  double Mean() const { return n ? sum / n : 0.0; }
};


// The path of an optional config key (relative to the config), else a file under data/.
std::string BesideOr(const ConfigNode& c, const std::string& key, const std::string& data_default) {
  return c.Has(key) ? Beside(c, key) : DataPath(data_default);
}

// The stack's side: design files only (the URDF, the site, the design robot YAML, algorithm
// configs). Nothing here opens data/sim/ (tests/check_layering.cmake; brick_stack_test checks the
// files this opens).
void LoadStackSide(const ConfigNode& c, Setup& s) {
  sequencer::MissionComponents& parts = s.parts;
  parts.robot = LoadRobotModel(BesideOr(c, "urdf", "robots/insitu_fabricator.urdf"));
  parts.site = LoadSite(Beside(c, "site"));
  parts.site.RequireBoundary(Beside(c, "site"), "ifab run");
  parts.base_geometry = base::BaseGeometry::Load(Beside(c, "base"));
  parts.planner = base::StompPlannerOptions::FromConfig(ConfigNode::LoadSection(Beside(c, "planner"), "base_planner"));
  parts.estimator = base::EstimatorOptions::FromConfig(ConfigNode::LoadSection(Beside(c, "estimator"), "estimator"));
  parts.controller =
      base::BaseControllerOptions::FromConfig(ConfigNode::LoadSection(Beside(c, "controller"), "base_controller"));
  parts.controller.track_gauge = parts.base_geometry.track_gauge;
  parts.controller.max_track_speed = parts.base_geometry.max_track_speed;
  parts.arm = arm::ArmOptions::Load(Beside(c, "arm"));
  const ConfigNode perception = ConfigNode::LoadFile(Beside(c, "perception"));
  // The sections `ifab register` / `ifab calibrate` read from the same file, and clock sync.
  perception.ExpectKeys({"registration", "calibration", "scan_assembly", "clock_sync"});
  if (auto a = perception.Find("scan_assembly")) parts.assembly = ScanAssemblyOptions::FromConfig(*a);
  if (auto r = perception.Find("registration")) parts.registration = RegistrationOptions::FromConfig(*r);
  if (auto sy = perception.Find("clock_sync")) parts.clock_sync = ClockSyncOptions::FromConfig(*sy);
  parts.T_tool0_arm_laser = parts.robot.T_tool0_arm_laser;  // the design mount until calibrated
  const ConfigNode robot_yaml = ConfigNode::LoadFile(Beside(c, "robot"));
  if (robot_yaml.Has("sim")) robot_yaml["sim"].Fail("no sim: section in a design file (it belongs in data/sim/)");
  const auto v = robot_yaml["feeder_in_base"].AsNumbers(6);
  s.T_base_feeder_design = PoseFromXyzRpy(v[0], v[1], v[2], v[3], v[4], v[5]);
}

// The simulator's side: its machine (data/sim/) on the design URDF and site, and, in the
// as-built world, this seed's draws from data/sim/as_built.yaml.
void LoadSimSide(const ConfigNode& c, Setup& s) {
  const ConfigNode sim_yaml = ConfigNode::LoadFile(BesideOr(c, "sim", "sim/insitu_fabricator.yaml"));
  s.sim_options = sim::SimOptions::FromConfig(sim_yaml["sim"]);
  s.sim_options.urdf = BesideOr(c, "urdf", "robots/insitu_fabricator.urdf");
  s.sim_options.site = Beside(c, "site");
  if (auto b = c.Find("range_bias")) s.sim_options.arm_laser.bias_enabled = b->As<bool>();  // for comparisons
  const std::string world = c.Get<std::string>("world", "as-built");
  if (world != "as-built" && world != "exact") c["world"].Fail("as-built or exact");
  s.as_built_world = world == "as-built";
  if (s.as_built_world) s.tolerances = sim::AsBuiltTolerances::Load(BesideOr(c, "as_built", "sim/as_built.yaml"));
}

// This seed's as-built world (the same machine and floor for the calibration and the mission).
}  // namespace

void DrawWorld(Setup& s, std::uint64_t seed) {
  if (!s.as_built_world) return;
  s.sim_options.as_built = sim::DrawAsBuilt(s.tolerances, s.parts.robot, s.parts.site, s.sim_options.arm_laser, seed);
}

Setup LoadSetup(const ConfigNode& c) {
  c.ExpectKeys({"seed", "robot", "urdf", "site", "sim", "world", "as_built", "arm", "estimator", "planner",
                "controller", "base", "perception", "plan", "mission", "start_joints_deg", "write_clouds", "mount",
                "laser_calibration", "range_bias", "range_bias_compensation"});
  Setup s;
  LoadStackSide(c, s);
  LoadSimSide(c, s);
  const std::string mount = c.Get<std::string>("mount", "calibrate");
  if (mount != "calibrate" && mount != "design") c["mount"].Fail("calibrate or design");
  s.calibrate_mount = mount == "calibrate";
  if (s.calibrate_mount)
    s.calibration = sequencer::LaserCalibrationPlan::FromConfig(ConfigNode::LoadFile(Beside(c, "laser_calibration")));
  // false: no range-bias identification, eq. 6 as written (the ablation "without bias compensation").
  s.compensate_bias = c.Get<bool>("range_bias_compensation", true);
  if (!s.compensate_bias) s.calibration.range_bias.reset();
  s.mission_options = sequencer::MissionOptions::FromConfig(c["mission"]);
  s.mission_options.T_base_feeder = s.T_base_feeder_design;
  s.plan = sequencer::BuildingPlan::FromConfig(c["plan"]);
  s.q0 = s.mission_options.q_park;
  if (auto q = c.Find("start_joints_deg")) {
    const auto v = q->AsNumbers(6);
    for (int i = 0; i < 6; ++i) s.q0[i] = DegToRad(v[static_cast<std::size_t>(i)]);
  }
  return s;
}

// Scoring only: the identified range bias against the simulated unit's curve, over the ranges and
// incidences where compensation uses it (its std below the guard) and beside it.
namespace {

nlohmann::json ScoreRangeBias(const RangeBiasSummary& bias, const RangeBiasCompensation& comp,
                              const sim::LrfOptions& unit, double drift_at_sweeps) {
  Stats err, err_used, z;
  int used = 0, within2 = 0;
  nlohmann::json table = nlohmann::json::array();
  for (double r = 0.3; r <= 3.0001; r += 0.1)
    for (double deg = 0.0; deg <= 80.0; deg += 10.0) {
      const double inc = DegToRad(deg);
      // The unit's curve plus its warm-up drift while the sweeps were taken (what they measured).
      const double b = bias.model.Bias(r, inc), truth = unit.Bias(r, inc) + drift_at_sweeps;
      const double sd = bias.model.Std(r, inc);
      const bool in_use = sd <= comp.max_std_fraction * comp.sigma_along;
      err.Add(1e3 * std::abs(b - truth));
      if (in_use) {
        err_used.Add(1e3 * std::abs(b - truth));
        ++used;
        within2 += std::abs(b - truth) <= 2.0 * sd;
        z.Add(std::abs(b - truth) / sd);
      }
      if (std::abs(r - std::round(r * 2.0) / 2.0) < 1e-6 && static_cast<int>(deg) % 20 == 0)
        table.push_back({{"range_m", r}, {"incidence_deg", deg}, {"identified_mm", 1e3 * b}, {"true_mm", 1e3 * truth},
                         {"std_mm", 1e3 * sd}, {"used", in_use}});
    }
  return {{"message", bias.message},
          {"points_used", bias.num_used},
          {"rms_whitened", bias.rms_whitened},
          {"variance_factor", bias.variance_factor},
          {"cells_in_use", used},
          {"cells", err.n},
          {"error_vs_true_mm_mean_in_use", err_used.Mean()},
          {"error_vs_true_mm_max_in_use", err_used.max},
          {"error_vs_true_mm_mean_all", err.Mean()},
          {"within_2_std_fraction_in_use", used ? double(within2) / used : 0.0},
          {"warmup_drift_at_sweeps_mm", 1e3 * drift_at_sweeps},
          {"curve", table}};
}

// The arm laser's mount calibrated before the mission, as on the real machine (Sec. V-C): the same
// simulated robot sweeps a cube standing where the stack will be, placed within a few mm of where
// the plan says (registration finds it). Returns the mount and a summary for results.json.
// Scoring only: what this seed's as-built world drew (results.json `as_built`).
nlohmann::json AsBuiltSummary(const Setup& setup) {
  const sim::AsBuilt& a = setup.sim_options.as_built;
  if (a.exact) return {{"world", "exact"}};
  const Site& site = setup.parts.site;
  const sim::LrfOptions& unit = a.arm_laser;
  const sim::LrfOptions& nominal = setup.sim_options.arm_laser;
  auto mm3 = [](const Eigen::Vector3d& v) { return std::vector<double>{1e3 * v.x(), 1e3 * v.y(), 1e3 * v.z()}; };
  auto mount = [](const std::array<double, 6>& m) {
    return nlohmann::json{{"xyz_mm", {1e3 * m[0], 1e3 * m[1], 1e3 * m[2]}},
                          {"rpy_deg", {RadToDeg(m[3]), RadToDeg(m[4]), RadToDeg(m[5])}}};
  };
  std::vector<double> offsets_deg;
  for (int i = 0; i < 6; ++i) offsets_deg.push_back(RadToDeg(a.joint_offsets[i]));
  // The arm's kinematic error at the flange, at the park pose and over a few working poses.
  const Vector6d q_park = setup.mission_options.q_park;
  // Against the design chain (the stack's may carry its kinematic calibration by now).
  const RobotModel design = LoadRobotModel(setup.sim_options.urdf);
  double flange_max = 0.0;
  RandomStream rng(1);
  for (int k = 0; k < 20; ++k) {
    Vector6d q = q_park;
    for (int i = 0; i < 6; ++i) q[i] += rng.Uniform(-0.5, 0.5);
    flange_max = std::max(flange_max, a.FlangeErrorAt(design, q));
  }
  return {{"world", "as-built"},
          {"brick_category", setup.tolerances.brick_category},
          {"brick_batch_mean_deviation_mm", mm3(a.brick_mean_size - site.brick.size)},
          {"brick_size_sigma_mm", mm3(a.brick_size_sigma)},
          {"brick_lean_sigma_deg", RadToDeg(a.brick_lean_sigma)},
          {"floor_worst_step_mm", {{"1m", 1e3 * a.floor_step_1m}, {"4m", 1e3 * a.floor_step_4m}}},
          {"floor_height_at_stack_mm", 1e3 * a.floor.Height(site.stack_origin.x, site.stack_origin.y)},
          {"base_compliance_deg_per_knm", RadToDeg(a.base_compliance) * 1e3},
          {"base_seat_sigma_deg", RadToDeg(a.base_seat_sigma)},
          {"arm_joint_offsets_deg", offsets_deg},
          {"arm_flange_error_mm", {{"park", 1e3 * a.FlangeErrorAt(design, q_park)}, {"max_of_20_poses", 1e3 * flange_max}}},
          {"arm_gravity_compliance_deg_per_knm", {RadToDeg(a.gravity_compliance[0]) * 1e3, RadToDeg(a.gravity_compliance[1]) * 1e3}},
          {"encoder_noise_deg", RadToDeg(a.encoder_noise)},
          {"calibration_cube_edge_error_mm", mm3(a.cube_size_error)},
          {"arm_laser", {{"walk_bias_at_0.4m_mm", 1e3 * unit.Bias(0.4, 0.0) - 1e3 * unit.Bias(10.0, 0.0)},
                         {"nominal_walk_bias_at_0.4m_mm", 1e3 * nominal.Bias(0.4, 0.0) - 1e3 * nominal.Bias(10.0, 0.0)},
                         {"bias_at_0.11m_mm", 1e3 * unit.Bias(0.11, 0.0)},
                         {"walk_bias_cos_power", unit.walk_bias_cos_power},
                         {"sigma_along_at_2m_mm", 1e3 * unit.SigmaAlong(2.0, 0.0)},
                         {"warmup_amplitude_mm", 1e3 * unit.warmup_amplitude}}},
          {"base_laser_mount_error", mount(a.base_laser_mount_error)},
          {"arm_laser_mount_error", mount(a.arm_laser_mount_error)},
          {"imu_mount_error_rpy_deg",
           {RadToDeg(a.imu_mount_error_rpy[0]), RadToDeg(a.imu_mount_error_rpy[1]), RadToDeg(a.imu_mount_error_rpy[2])}}};
}

}  // namespace

void CalibrateMount(Setup& setup, std::uint64_t seed, const RunContext& ctx, nlohmann::json* info) {
  const sequencer::LaserCalibrationPlan& plan = setup.calibration;
  RandomStream rng(seed + 7919);
  // Named draws, last argument first (gcc's order; C++ leaves a call's order open).
  const double yaw = DegToRad(rng.Normal(2.0)), y = rng.Normal(0.005), x = rng.Normal(0.005);
  const Pose3 T_base_cube_true = plan.T_base_cube() * PoseFromXyzRpy(x, y, 0, 0, 0, yaw);
  const Pose3 T_site_cube = PoseFromXyzRpy(0.0, 0.0, 0.5 * plan.cube_size, 0.0, 0.0, 0.0);
  const auto b = XyzRpyFromPose(T_site_cube * T_base_cube_true.inverse());
  sim::SimOptions sim_options = setup.sim_options;
  sim_options.seconds_since_power_on = plan.warmup_s;  // the operator switched the laser on this long ago
  sim::SimRobot sim(sim_options, Pose2(b[0], b[1], b[5]), plan.scan_posture, seed + 7919);
  // The cube stands on the floor as built (its height there; its tilt is the floor's slope of a
  // few hundredths of a degree, left out).
  // Its edges are as machined (the as-built draw), not the drawing's size the stack assumes.
  const Eigen::Vector3d cube_true = Eigen::Vector3d::Constant(plan.cube_size) + setup.sim_options.as_built.cube_size_error;
  Pose3 T_site_cube_true = T_site_cube;
  T_site_cube_true.translation().z() = sim.world().FloorHeight(0.0, 0.0) + 0.5 * cube_true.z();
  sim.mutable_world().AddBrick({"cube", T_site_cube_true, Box{cube_true}});
  const sequencer::ArmLaserCalibration cal = sequencer::CalibrateArmLaserAndRangeBias(
      sim, setup.parts.robot, setup.parts.arm, plan, plan.scan_posture, [&](const std::string& t) { ctx.Progress(t); });
  const CalibrationSummary& cs = cal.mount;
  if (!cs.IsUsable()) throw std::runtime_error("arm laser calibration failed: " + cs.message);
  if (cal.bias && !cal.bias->usable) throw std::runtime_error("arm laser range bias: " + cal.bias->message);
  setup.parts.assembly.range_bias = cal.compensation;
  Pose3 mount = cs.T_tool0_laser;
  // Scoring only: how far the calibrated mount is from the simulator's true one.
  const Pose3 e = sim.true_T_tool0_arm_laser().inverse() * cs.T_tool0_laser;
  const auto v = XyzRpyFromPose(e);
  *info = {{"source", "calibrated"},
           {"message", cs.message},
           {"error_vs_true_mm", {1e3 * v[0], 1e3 * v[1], 1e3 * v[2]}},
           {"error_vs_true_deg", {RadToDeg(v[3]), RadToDeg(v[4]), RadToDeg(v[5])}},
           {"sim_seconds", sim.Now()},
           {"laser_on_seconds", plan.warmup_s + sim.Now()}};
  if (cal.bias) {
    const sim::LrfOptions& unit =
        setup.sim_options.as_built.exact ? setup.sim_options.arm_laser : setup.sim_options.as_built.arm_laser;
    const double t_mid = plan.warmup_s + 0.5 * sim.Now();
    (*info)["range_bias"] = ScoreRangeBias(*cal.bias, cal.compensation, unit,
                                           unit.warmup_amplitude * std::exp(-t_mid / unit.warmup_tau));
    const auto u = XyzRpyFromPose(sim.true_T_tool0_arm_laser().inverse() * cal.mount_uncompensated.T_tool0_laser);
    (*info)["uncompensated_error_vs_true_mm"] = {1e3 * u[0], 1e3 * u[1], 1e3 * u[2]};
    (*info)["uncompensated_error_vs_true_deg"] = {RadToDeg(u[3]), RadToDeg(u[4]), RadToDeg(u[5])};
  }
  if (cal.ground_extent) {
    const GroundExtent& g = *cal.ground_extent;
    ctx.Progress("calibration: " + g.message);
    (*info)["ground_extent"] = GroundExtentToJson(g);
  }
  if (cal.kinematics) {
    const KinematicCalibration& k = *cal.kinematics;
    ctx.Progress(k.BriefReport());
    for (const auto& w : cal.views_left_out) ctx.Progress("  view left out: " + w);
    (*info)["arm_kinematics"] = {{"usable", k.usable},       {"message", k.message},
                                 {"views", k.views},         {"rms_design", k.rms_design},
                                 {"rms_fitted", k.rms_fitted}, {"view_rms_design", k.view_rms_design},
                                 {"view_rms_fitted", k.view_rms_fitted}};
    if (k.usable) {
      setup.parts.robot.arm_chain = ChainWithLinkErrors(setup.parts.robot.arm_chain, k.link_errors);
      mount = k.T_tool0_laser;
    }
  }
  setup.parts.T_tool0_arm_laser = mount;
}

namespace {

nlohmann::json RunBrickStack(const RunContext& ctx) {
  const auto wall_start = std::chrono::steady_clock::now();
  const ConfigNode& c = *ctx.config;
  Setup setup = LoadSetup(c);
  DrawWorld(setup, ctx.seed);
  nlohmann::json mount_info = {{"source", "design"}};
  if (setup.calibrate_mount) {
    CalibrateMount(setup, ctx.seed, ctx, &mount_info);
    // The same lasers, warmer by the warm-up and the calibration's time.
    setup.sim_options.seconds_since_power_on = mount_info["laser_on_seconds"].get<double>();
  }
  const sim::SimOptions& sim_options = setup.sim_options;
  const sequencer::MissionComponents& parts = setup.parts;
  const sequencer::MissionOptions& mission_options = setup.mission_options;
  const sequencer::BuildingPlan& plan = setup.plan;
  const Vector6d q0 = setup.q0;

  // The robot starts at the first building position; the site frame is the workpiece's, so the
  // start pose is known (the first brick defines where the stack is).
  const Pose2 start = plan.positions[static_cast<std::size_t>(plan.visits.front().position)].T_site_base;
  sim::SimRobot sim(sim_options, start, q0, ctx.seed);
  RecordingRobot robot(sim);
  ReplayRecorder replay;
  robot.replay = &replay;
  sequencer::Mission mission(robot, parts, mission_options, ctx.seed);
  std::size_t visits_done = 0;  // the share of the mission done, for the progress line
  std::vector<Pose3> true_T_site_base_at_end;  // per visit, for diagnosis (scoring only)
  mission.on_visit_end = [&](sequencer::VisitLog&) {
    ++visits_done;
    true_T_site_base_at_end.push_back(sim.true_T_site_base());
  };
  mission.on_progress = [&](const std::string& text) {
    ctx.Progress(text, static_cast<double>(visits_done) / static_cast<double>(plan.visits.size()));
  };
  mission.Start(start, q0);
  const std::vector<sequencer::VisitLog> logs = mission.Run(plan);

  // Score against the truth.
  const fs::path out(ctx.out_dir);
  const auto& placed = sim.world().bricks();
  Stats err_long, err_short, err_max;
  double away_sum = 0.0;
  // Where the robot stood (as planned) when it placed each brick: the scanning side.
  std::vector<Pose2> placed_from(placed.size(), Pose2());
  for (const auto& log : logs)
    for (int k : log.bricks_placed)
      if (k >= 0 && k < static_cast<int>(placed.size())) placed_from[static_cast<std::size_t>(k)] = log.desired;
  AtomicOfstream bricks_csv(out / "brick_errors.csv");
  bricks_csv << "brick,x_m,y_m,z_m,yaw_deg,error_long_mm,error_short_mm,error_z_mm,error_yaw_deg,error_away_mm,true_length_mm,true_width_mm,model_length_mm,model_width_mm,model_offset_long_mm,model_offset_short_mm\n";
  for (std::size_t k = 0; k < placed.size(); ++k) {
    const Pose3 design = mission.workpiece().DesignedBrickPose(static_cast<int>(k));
    const Eigen::Vector3d d = placed[k].T_site_box.translation() - design.translation();
    // The paper's effect: the range bias pushes bricks away from the side they were scanned from.
    const Eigen::Vector2d to_robot =
        (Eigen::Vector2d(placed_from[k].x, placed_from[k].y) - design.translation().head<2>()).normalized();
    const double e_away = -1000 * d.head<2>().dot(to_robot);
    away_sum += e_away;
    const double e_long = 1000 * d.dot(design.linear().col(0));
    const double e_short = 1000 * d.dot(design.linear().col(1));
    const auto v = XyzRpyFromPose(placed[k].T_site_box);
    // Yaw modulo 180 deg: the brick is symmetric and may be placed turned around.
    const double e_yaw = RadToDeg(0.5 * WrapAngle(2.0 * (v[5] - XyzRpyFromPose(design)[5])));
    err_long.Add(std::abs(e_long));
    err_short.Add(std::abs(e_short));
    err_max.Add(std::hypot(e_long, e_short));
    // The brick's true length and width beside the model's (designed, or measured: measure_footprint).
    const auto& model_bricks = mission.workpiece().bricks;
    const Eigen::Vector3d model_size = k < model_bricks.size() ? model_bricks[k].box.size : Eigen::Vector3d::Zero();
    // Where the model holds the brick against its design (moved by measure_first_brick, check_placement, ...).
    const Eigen::Vector3d model_d =
        k < model_bricks.size() ? Eigen::Vector3d(model_bricks[k].T_site_box.translation() - design.translation())
                                : Eigen::Vector3d::Zero();
    bricks_csv << fmt::format("{},{:.5f},{:.5f},{:.5f},{:.4f},{:.3f},{:.3f},{:.3f},{:.4f},{:.3f},{:.2f},{:.2f},{:.2f},{:.2f},{:.3f},{:.3f}\n",
                              k, v[0], v[1], v[2], RadToDeg(v[5]), e_long, e_short, 1000 * d.z(), e_yaw, e_away,
                              1e3 * placed[k].box.size.x(), 1e3 * placed[k].box.size.y(), 1e3 * model_size.x(),
                              1e3 * model_size.y(), 1e3 * model_d.dot(design.linear().col(0)),
                              1e3 * model_d.dot(design.linear().col(1)));
  }

  Stats end_m, end_deg, corr_m, corr_deg, after_m, after_deg, drift_m, drift_deg;
  AtomicOfstream planned_csv(out / "trajectory_planned.csv"), est_csv(out / "trajectory_estimated.csv"),
      visits_csv(out / "visits.csv");
  planned_csv << "visit,index,x,y,theta,v,omega\n";
  est_csv << "visit,t,x,y,theta\n";
  visits_csv << "visit,position,desired_x,desired_y,desired_theta,end_x,end_y,end_theta,localized,loc_x,loc_y,"
                "loc_theta,sweeps,reapproaches,failure,reg_z_mm,reg_roll_deg,reg_pitch_deg,true_z_mm,true_roll_deg,"
                "true_pitch_deg,placement_bias_x_mm,placement_bias_y_mm,placement_bias_std_x_mm,placement_bias_std_y_mm,"
                "check_offset_x_mm,check_offset_y_mm,check_std_x_mm,check_std_y_mm,top_offset_x_mm,top_offset_y_mm,true_x,true_y,"
                "true_theta\n";
  int repositionings = 0;
  for (const auto& log : logs) {
    for (std::size_t i = 0; i < log.plan.trajectory.points.size(); ++i) {
      const auto& p = log.plan.trajectory.points[i];
      planned_csv << fmt::format("{},{},{:.4f},{:.4f},{:.5f},{:.4f},{:.4f}\n", log.visit, i, p.pose.x, p.pose.y,
                                 p.pose.theta, p.v, p.omega);
    }
    for (const auto& s : log.estimated)
      est_csv << fmt::format("{},{:.3f},{:.4f},{:.4f},{:.5f}\n", log.visit, s.t, s.value.x, s.value.y, s.value.theta);
    visits_csv << fmt::format("{},{},{:.4f},{:.4f},{:.5f},{:.4f},{:.4f},{:.5f},{},{:.4f},{:.4f},{:.5f},{},{},\"{}\"",
                              log.visit, log.position, log.desired.x, log.desired.y, log.desired.theta,
                              log.end_estimate.x, log.end_estimate.y, log.end_estimate.theta, log.localized,
                              log.localized_pose.x, log.localized_pose.y, log.localized_pose.theta, log.sweeps,
                              log.reapproaches, log.failure);
    {
      // The full pose placing used, beside the true one at the visit's end (scoring only).
      const auto reg = XyzRpyFromPose(log.T_site_base_registered);
      const std::size_t k = static_cast<std::size_t>(&log - logs.data());
      const auto tru = XyzRpyFromPose(k < true_T_site_base_at_end.size() ? true_T_site_base_at_end[k] : Pose3::Identity());
      visits_csv << fmt::format(",{:.3f},{:.4f},{:.4f},{:.3f},{:.4f},{:.4f}", 1e3 * reg[2], RadToDeg(reg[3]),
                                RadToDeg(reg[4]), 1e3 * tru[2], RadToDeg(tru[3]), RadToDeg(tru[4]));
      // The arm's miss learned by this visit (mission.learn_placement_bias; base frame), or empty.
      const auto mm = [](double v) { return std::isfinite(v) ? fmt::format("{:.3f}", v) : std::string(); };
      visits_csv << fmt::format(",{},{},{},{}", mm(log.placement_bias_mm.x()), mm(log.placement_bias_mm.y()),
                                mm(log.placement_bias_std_mm.x()), mm(log.placement_bias_std_mm.y()));
      // Where the look after placing (mission.check_placement) put the visit's last brick, from
      // where it was meant to land (site frame), and its std, or empty.
      visits_csv << fmt::format(",{},{},{},{}", mm(log.placement_offset_mm.x()), mm(log.placement_offset_mm.y()),
                                mm(log.placement_offset_std_mm.x()), mm(log.placement_offset_std_mm.y()));
      // Where the localization saw the last visit's brick from where the model held it (along the
      // brick's x, y; measure_footprint), and the base's true pose at the visit's end (scoring only).
      visits_csv << fmt::format(",{},{},{:.5f},{:.5f},{:.6f}\n", mm(log.top_offset_mm.x()), mm(log.top_offset_mm.y()),
                                tru[0], tru[1], tru[5]);
    }
    if (log.visit == 0 || log.plan.trajectory.empty()) continue;
    ++repositionings;
    end_m.Add(TranslationDistance(log.end_estimate, log.desired));
    end_deg.Add(RadToDeg(AngleDistance(log.end_estimate, log.desired)));
    if (log.localized) {
      corr_m.Add(TranslationDistance(log.localized_pose, log.end_estimate));
      corr_deg.Add(RadToDeg(AngleDistance(log.localized_pose, log.end_estimate)));
      after_m.Add(TranslationDistance(log.localized_pose, log.desired));
      after_deg.Add(RadToDeg(AngleDistance(log.localized_pose, log.desired)));
    }
    if (!log.cloud.empty() && ctx.config->Get<bool>("write_clouds", true))
      WriteVisitCloud((out / fmt::format("cloud_visit_{:02d}.ply", log.visit)).string(), log);
  }
  robot.WriteTruthCsv((out / "trajectory_true.csv").string());
  replay.Write(out.string());
  WriteSceneJson(out.string(), parts, plan, mission.workpiece(), logs);

  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  nlohmann::json r;
  r["bricks_placed"] = static_cast<int>(placed.size());
  r["bricks_planned"] = plan.TotalBricks();
  r["repositionings"] = repositionings;
  r["brick_error_long_mm_mean"] = err_long.Mean();
  r["brick_error_short_mm_mean"] = err_short.Mean();
  r["brick_error_mm_max"] = err_max.max;
  r["brick_error_away_from_robot_mm_mean"] = placed.empty() ? 0.0 : away_sum / static_cast<double>(placed.size());
  r["base_end_error_vs_desired_m_mean"] = end_m.Mean();
  r["base_end_error_vs_desired_deg_mean"] = end_deg.Mean();
  r["localization_correction_m_mean"] = corr_m.Mean();
  r["localization_correction_deg_mean"] = corr_deg.Mean();
  r["after_localization_vs_desired_m_max"] = after_m.max;
  r["after_localization_vs_desired_deg_max"] = after_deg.max;
  r["sim_seconds"] = sim.Now();
  r["wall_seconds"] = wall;
  r["arm_laser_mount"] = mount_info;
  r["as_built"] = AsBuiltSummary(setup);
  {
    Stats tilt;
    for (const auto& log : logs)
      for (double d : log.tilt_change_deg) tilt.Add(d);
    r["tilt_change_measured_deg_mean"] = tilt.Mean();
    r["tilt_change_measured_deg_max"] = tilt.max;
  }
  for (auto it = logs.rbegin(); it != logs.rend(); ++it)  // the arm's miss as last learned (base frame)
    if (std::isfinite(it->placement_bias_mm.x())) {
      r["placement_bias_learned_mm"] = {it->placement_bias_mm.x(), it->placement_bias_mm.y()};
      r["placement_bias_learned_std_mm"] = {it->placement_bias_std_mm.x(), it->placement_bias_std_mm.y()};
      break;
    }
  r["failed"] = mission.stopped() || static_cast<int>(placed.size()) < plan.TotalBricks();
  if (mission.stopped()) {
    r["failure"] = mission.stop_reason();
    // Scoring only: did it stop safely? The arm at its park pose, the base standing still.
    const Pose2 before = sim.true_base_pose();
    sim.Wait(1.0);
    r["stop"] = {{"arm_parked", (sim.true_joint_angles() - mission_options.q_park).cwiseAbs().maxCoeff() < DegToRad(1.0)},
                 {"base_moved_m_in_1s", TranslationDistance(before, sim.true_base_pose())},
                 {"holding_brick", sim.holding_brick()}};
  }
  return r;
}

std::vector<std::vector<std::string>> BrickStackTable(const nlohmann::json& r) {
  auto f = [&](const char* key, int digits = 1) { return fmt::format("{:.{}f}", r[key].get<double>(), digits); };
  return {
      {"bricks placed", std::to_string(r["bricks_placed"].get<int>()), "26"},
      {"repositionings", std::to_string(r["repositionings"].get<int>()), "25"},
      {"brick error, long face [mm]", f("brick_error_long_mm_mean", 2), "4.6 (target 1)"},
      {"brick error, short face [mm]", f("brick_error_short_mm_mean", 2), "3.5 (target 1)"},
      {"brick error, worst [mm]", f("brick_error_mm_max", 2), ""},
      {"brick error away from the robot, mean [mm]", f("brick_error_away_from_robot_mm_mean", 2), "> 0 (range bias)"},
      {"end of maneuver vs desired [cm]", fmt::format("{:.1f}", 100 * r["base_end_error_vs_desired_m_mean"].get<double>()), "3"},
      {"end of maneuver vs desired [deg]", f("base_end_error_vs_desired_deg_mean", 2), "1.8"},
      {"localization correction [cm]", fmt::format("{:.1f}", 100 * r["localization_correction_m_mean"].get<double>()), "5"},
      {"localization correction [deg]", f("localization_correction_deg_mean", 2), "3.5"},
      {"after localization vs desired, max [cm]", fmt::format("{:.1f}", 100 * r["after_localization_vs_desired_m_max"].get<double>()), "< 8"},
      {"after localization vs desired, max [deg]", f("after_localization_vs_desired_deg_max", 2), "< 4"},
      {"simulated time [s]", f("sim_seconds", 0), ""},
      {"wall time [s]", f("wall_seconds", 1), ""},
  };
}

// `ifab run base-maneuvers` (issue 4): the base drives between the building positions with the
// planner, the controller and the estimator alone (no localization, no bricks). Per maneuver the
// estimator's drift is the error of its relative motion from start to end against the true one
// (Kuemmerle et al.'s relation metric), so no truth ever enters the mission.
nlohmann::json RunManeuvers(const RunContext& ctx) {
  const auto wall_start = std::chrono::steady_clock::now();
  Setup setup = LoadSetup(*ctx.config);
  DrawWorld(setup, ctx.seed);
  setup.mission_options.localize = false;
  setup.mission_options.place_bricks = false;
  const Pose2 start = setup.plan.positions[static_cast<std::size_t>(setup.plan.visits.front().position)].T_site_base;
  sim::SimRobot sim(setup.sim_options, start, setup.q0, ctx.seed);
  RecordingRobot robot(sim);
  robot.truth_period = setup.mission_options.control_period;  // every control step: for diagnosis
  sequencer::Mission mission(robot, setup.parts, setup.mission_options, ctx.seed);
  mission.on_progress = [&](const std::string& text) { ctx.Progress(text); };
  Pose2 true_start = sim.true_base_pose();
  std::vector<std::pair<Pose2, Pose2>> truth;  // true start and end of each visit
  mission.on_visit_end = [&](sequencer::VisitLog&) {
    truth.emplace_back(true_start, sim.true_base_pose());
    true_start = sim.true_base_pose();
  };
  mission.Start(start, setup.q0);
  const auto logs = mission.Run(setup.plan);

  Stats end_m, end_deg, drift_m, drift_deg, drift_deg_signed;
  AtomicOfstream csv(std::filesystem::path(ctx.out_dir) / "maneuvers.csv");
  AtomicOfstream est_csv(std::filesystem::path(ctx.out_dir) / "trajectory_estimated.csv");
  est_csv << "visit,t,x,y,theta\n";
  // Signed drift (dx, dy in the estimated end frame; dtheta = true - estimated turn) beside the
  // absolute values: a systematic error shows as one sign. The estimated trajectories and the
  // truth (every control period) go beside them, for diagnosis.
  csv << "visit,position,end_error_m,end_error_deg,drift_m,drift_deg,reapproaches,drift_x_m,drift_y_m,"
         "drift_theta_deg,true_turn_deg,true_distance_m\n";
  int reapproaches = 0;
  for (std::size_t k = 0; k < logs.size(); ++k) {
    const auto& log = logs[k];
    if (log.visit == 0 || log.plan.trajectory.empty()) continue;
    const Pose2 est_rel = log.start_estimate.inverse() * log.end_estimate;
    const Pose2 true_rel = truth[k].first.inverse() * truth[k].second;
    const Pose2 e = est_rel.inverse() * true_rel;
    const double em = TranslationDistance(log.end_estimate, log.desired);
    const double ed = RadToDeg(AngleDistance(log.end_estimate, log.desired));
    const double dm = std::hypot(e.x, e.y), dd = RadToDeg(std::abs(e.theta));
    end_m.Add(em);
    end_deg.Add(ed);
    drift_m.Add(dm);
    drift_deg.Add(dd);
    drift_deg_signed.Add(RadToDeg(e.theta));
    reapproaches += log.reapproaches;
    csv << fmt::format("{},{},{:.4f},{:.3f},{:.4f},{:.3f},{},{:.4f},{:.4f},{:.3f},{:.2f},{:.3f}\n", log.visit,
                       log.position, em, ed, dm, dd, log.reapproaches, e.x, e.y, RadToDeg(e.theta),
                       RadToDeg(true_rel.theta), std::hypot(true_rel.x, true_rel.y));
    for (const auto& s : log.estimated)
      est_csv << fmt::format("{},{:.4f},{:.5f},{:.5f},{:.6f}\n", log.visit, s.t, s.value.x, s.value.y, s.value.theta);
  }
  robot.WriteTruthCsv((std::filesystem::path(ctx.out_dir) / "trajectory_true.csv").string());
  nlohmann::json r;
  r["maneuvers"] = end_m.n;
  r["end_error_vs_desired_m_mean"] = end_m.Mean();
  r["end_error_vs_desired_deg_mean"] = end_deg.Mean();
  r["drift_m_mean"] = drift_m.Mean();
  r["drift_deg_mean"] = drift_deg.Mean();
  r["drift_m_max"] = drift_m.max;
  r["drift_deg_max"] = drift_deg.max;
  r["drift_deg_signed_mean"] = drift_deg_signed.Mean();  // true - estimated turn: a bias shows here
  r["end_error_vs_desired_m_max"] = end_m.max;
  r["end_error_vs_desired_deg_max"] = end_deg.max;
  r["reapproaches"] = reapproaches;
  r["sim_seconds"] = sim.Now();
  r["wall_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  r["failed"] = mission.stopped();
  return r;
}

std::vector<std::vector<std::string>> ManeuversTable(const nlohmann::json& r) {
  auto f = [&](const char* key, double scale, int digits) {
    return fmt::format("{:.{}f}", scale * r[key].get<double>(), digits);
  };
  return {{"maneuvers", std::to_string(r["maneuvers"].get<int>()), ""},
          {"end vs desired [cm]", f("end_error_vs_desired_m_mean", 100, 1), "3"},
          {"end vs desired [deg]", f("end_error_vs_desired_deg_mean", 1, 2), "1.8"},
          {"estimator drift [cm]", f("drift_m_mean", 100, 2), "5 (bar: 2.5)"},
          {"estimator drift [deg]", f("drift_deg_mean", 1, 2), "3.5 (bar: 1.75)"}};
}

}  // namespace

ExperimentInfo BaseManeuversExperiment() {
  return {"base-maneuvers", "issue 4: 20+ maneuvers with planner, controller and estimator; drift vs truth",
          RunManeuvers, ManeuversTable};
}

ExperimentInfo BrickStackExperiment() {
  return {"brick-stack", "paper Sec. VI-VII: 26 bricks, 25 repositionings around a stack (the default)", RunBrickStack, BrickStackTable};
}

}  // namespace ifab::experiments
