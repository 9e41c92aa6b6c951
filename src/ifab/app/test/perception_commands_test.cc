#include "ifab/app/perception_commands.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "ifab/core/error.h"
#include "ifab/core/random.h"
#include "ifab/model/site.h"
#include "ifab/perception/calibration.h"
#include "ifab/experiments/ply_file.h"
#include "ifab/perception/ply.h"
#include "ifab/perception/registration.h"
#include "ifab/experiments/perception_json.h"
#include "ifab/experiments/sweep_io.h"
#include "ifab/perception/testing/synthetic.h"
#include "ifab/sync/clock_sync.h"

namespace ifab {
namespace {

namespace fs = std::filesystem;

fs::path TempDir(const std::string& name) {
  // The process id keeps parallel runs (other worktrees, ctest -j) apart.
  const fs::path d = fs::temp_directory_path() / ("ifab_app_perception_" + std::to_string(::getpid()) + "_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

void Write(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }

constexpr const char* kSite = R"(
ground_z: 0.0
boundary: [[-4, -3], [4, -3], [4, 3], [-4, 3]]
obstacles:
  - {name: feeder, size: [0.6, 0.4, 0.75], pose: [0.0, -2.3, 0.375, 0, 0, 0]}
brick: {size: [0.240, 0.115, 0.052]}
bricks:
  - {pose: [0.0, 0.0, 0.026, 0, 0, 0]}
  - {pose: [0.003, -0.002, 0.078, 0, 0, 0.01]}
  - {pose: [-0.002, 0.001, 0.130, 0, 0, -0.008]}
)";

TEST(RegisterCommand, LocalizesTheRobotFromAPlyCloudOfTheStack) {
  const fs::path dir = TempDir("register");
  Write(dir / "site.yaml", kSite);
  const Site site = LoadSite((dir / "site.yaml").string());
  // The robot stands 1.6 m from the stack, seeing two of its sides, its arm laser sweeping across.
  const Pose3 T_site_base = PoseFromXyzRpy(-1.25, 1.0, 0.0, 0.0, 0.0, -0.7);
  std::vector<RegistrationBody> world_bodies{{"site", Pose3::Identity(), site.Objects(), true}};
  const Scene world(world_bodies);
  testing::SyntheticLaser laser;
  RandomStream rng(9);
  auto laser_in_site = [&](double t) {
    Pose3 T = Pose3::Identity();
    T.translation() = Eigen::Vector3d(0.35, 0.0, 0.8);
    T.linear() = RotationFromRpy(M_PI / 2, 0.0, -0.35 + 0.3 * t);
    return T_site_base * T;
  };
  std::vector<RayPoint> cloud_site = testing::SynthesizeCloud(world, laser_in_site, 0.0, 2.3, laser, rng);
  std::vector<RayPoint> cloud_base;
  for (const auto& p : cloud_site) cloud_base.push_back({T_site_base.inverse() * p.p, T_site_base.inverse() * p.origin});
  SavePly((dir / "cloud.ply").string(), ToPointCloud(cloud_base));

  RegisterCommandOptions o;
  o.cloud_path = (dir / "cloud.ply").string();
  o.site_path = (dir / "site.yaml").string();
  o.guess = "-1.235 1.02 0.0 0 0 -38.9";  // 2.5 cm and 1 deg off
  o.out_dir = (dir / "out").string();
  // The stack stands on the floor: one rigid body with the ground fixes its roll and pitch (seen
  // from one side, the stack alone leaves them to a 0.115 m wide top face).
  o.one_body = true;
  const nlohmann::json j = RegisterCommand(o);
  ASSERT_TRUE(j["usable"].get<bool>()) << j.dump(2);
  const auto xyz = j["T_site_base"]["xyz"].get<std::vector<double>>();
  const auto rpy = j["T_site_base"]["rpy_deg"].get<std::vector<double>>();
  const Pose3 found = PoseFromXyzRpy(xyz[0], xyz[1], xyz[2], rpy[0] * M_PI / 180, rpy[1] * M_PI / 180, rpy[2] * M_PI / 180);
  // The error that matters: the workpiece seen from the robot, at the stack.
  const Pose3 error = T_site_base * found.inverse();
  EXPECT_LT(error.translation().norm(), 0.002) << j.dump(2);
  // Yaw rests on faces 0.115 and 0.24 m wide under 18 mm range noise: std about 0.45 deg here.
  EXPECT_LT(RotationAngle(found, T_site_base), 1.5 * M_PI / 180) << j.dump(2);
  EXPECT_TRUE(fs::exists(dir / "out" / "registration.json"));
  const PointCloud labelled = ReadPly((dir / "out" / "labelled.ply").string());
  EXPECT_EQ(labelled.size(), cloud_base.size());
  EXPECT_NE(labelled.Find("label"), nullptr);
  EXPECT_EQ(j["covariance_site_base"].size(), 6u);

  o.guess = "1 2 3 4 5";
  try {
    RegisterCommand(o);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--guess: expected 6 numbers, got 5"), std::string::npos) << e.what();
  }
}

// A partial --config changes only the keys it names: the shipped restarts: 2 stays.
TEST(RegisterCommand, APartialConfigKeepsTheOtherDefaults) {
  const fs::path dir = TempDir("register_partial");
  Write(dir / "site.yaml", "boxes:\n  - {name: crate, size: [0.5, 0.4, 0.3], xyz: [1.5, 0.1, 0.0], rpy_deg: [0, 0, 25]}\n");
  const Site site = LoadSite((dir / "site.yaml").string());
  const Scene world(SensorFrameBodies(site));
  testing::SyntheticLaser laser;
  laser.noise.sigma_along = 0.005;
  RandomStream rng(4);
  auto at = [](double t) {
    Pose3 T = Pose3::Identity();
    T.translation() = Eigen::Vector3d(0.3, -1.2, 0.8);  // seeing two side faces and the top
    T.linear() = RotationFromRpy(0.0, 0.25 + 0.4 * t, 0.82);
    return T;
  };
  const std::vector<RayPoint> cloud = testing::SynthesizeCloud(world, at, 0.0, 1.0, laser, rng);
  SavePly((dir / "cloud.ply").string(), ToPointCloud(cloud));
  Write(dir / "partial.yaml", "registration: {max_iterations: 40}\n");
  Write(dir / "guess.yaml", "boxes:\n  - {name: crate, size: [0.5, 0.4, 0.3], xyz: [1.52, 0.09, 0.01], rpy_deg: [1, 0, 27]}\n");
  RegisterCommandOptions o;
  o.cloud_path = (dir / "cloud.ply").string();
  o.site_path = (dir / "guess.yaml").string();
  o.frame = "sensor";
  o.config_path = (dir / "partial.yaml").string();
  o.out_dir = (dir / "out").string();
  const nlohmann::json j = RegisterCommand(o);
  EXPECT_NE(j["message"].get<std::string>().find("restarts"), std::string::npos) << j.dump(2);
  EXPECT_TRUE(j["usable"].get<bool>()) << j.dump(2);
  EXPECT_NE(j["fit"]["noise_model"].get<std::string>().find("estimated"), std::string::npos);
  std::ostringstream out;
  EXPECT_EQ(ReportRegistration(j, o.out_dir, out), 0);

  // Stopped at max_iterations: not usable, exit code 1.
  Write(dir / "one_step.yaml", "registration: {max_iterations: 1}\n");
  o.config_path = (dir / "one_step.yaml").string();
  const nlohmann::json k = RegisterCommand(o);
  EXPECT_EQ(k["status"].get<std::string>(), "max_iterations");
  EXPECT_FALSE(k["usable"].get<bool>());
  EXPECT_EQ(ReportRegistration(k, o.out_dir, out), 1);

  // A sensor profile is named in the output; --crop keeps what it says.
  o.config_path.clear();
  o.sensor = "sick_lms2xx";
  o.crop = "radius 3";
  const nlohmann::json p = RegisterCommand(o);
  EXPECT_NE(p["fit"]["noise_model"].get<std::string>().find("SICK LMS-2xx"), std::string::npos) << p.dump(2);
  o.crop = "sphere 3";
  EXPECT_THROW(RegisterCommand(o), InputError);
  o.crop.clear();
  o.sensor = "no_such_laser";
  EXPECT_THROW(RegisterCommand(o), InputError);
}

// Sweeps saved with raw device stamps and sync pulses: the loader syncs the clocks (TICSync
// style) before eq. 6, and calibration recovers the mount.
TEST(CalibrateCommand, CalibratesFromSweepFilesWithRawClockStamps) {
  const fs::path dir = TempDir("calibrate");
  const RobotModel robot = LoadRobotModel(std::string(IFAB_DATA_DIR) + "/robots/insitu_fabricator.urdf");
  const Pose3 T_true = robot.T_tool0_arm_laser * PoseFromXyzRpy(0.004, -0.003, 0.006, 0.01, -0.008, 0.015);
  const Pose3 T_cube = PoseFromXyzRpy(1.8, -0.05, 0.125, 0.0, 0.0, 0.25);
  const Scene world(CubeOnGroundBodies(0.25, T_cube));
  testing::SyntheticLaser laser;
  RandomStream rng(2);
  const Vector6d down = (Vector6d() << 0.0, 0.3, 0.3, 0.0, 1.2, 0.0).finished();
  std::vector<std::string> files;
  int k = 0;
  for (auto [joint, from, to] : {std::tuple{4, 1.0, 1.45}, {5, -0.7, 0.7}, {3, -0.5, 0.5}, {1, 0.15, 0.45}}) {
    Vector6d q0 = down, q1 = down;
    q0[joint] = from;
    q1[joint] = to;
    auto sweep = testing::SynthesizeArmSweep(world, robot, T_true, q0, q1, 1.5, laser, rng);
    SweepRecording rec;
    rec.name = "joint " + std::to_string(joint + 1);
    // Device clocks: offsets, skews, pulses late by up to 1 ms; sequence numbers tie them.
    std::uint64_t seq = 0;
    for (auto& s : sweep.scans) {
      s.stamp.sequence = seq++;
      s.stamp.t_device = (s.stamp.t - 100.0) / (1 + 30e-6);
      rec.sync_pulses.push_back({DeviceId::kArmLaser, s.stamp.sequence, s.stamp.t + rng.Uniform(0, 1e-3)});
    }
    for (auto& js : sweep.joints) {
      js.stamp.sequence = seq++;
      js.stamp.t_device = (js.stamp.t + 55.0) / (1 - 12e-6);
      rec.sync_pulses.push_back({DeviceId::kArm, js.stamp.sequence, js.stamp.t + rng.Uniform(0, 1e-3)});
    }
    rec.scans = sweep.scans;
    rec.joint_states = sweep.joints;
    files.push_back((dir / ("sweep" + std::to_string(k++) + ".json")).string());
    SaveSweep(files.back(), rec, /*raw_stamps=*/true);
  }
  Write(dir / "target.yaml", "cube: {size: 0.25, pose_guess: [1.78, -0.03, 0.12, 0, 0, 16]}\nground_z_guess: 0.005\n");
  // Four sweeps at every 4th beam: the face assignments at the cube's edges keep the steps
  // alternating by about 2e-5 m at the smallest relaxation; accept that as settled.
  Write(dir / "perception.yaml",
        "scan_assembly: {beam_stride: 4}\ncalibration: {registration: {translation_tolerance: 3.0e-5, rotation_tolerance: 1.0e-4}}\n");
  CalibrateCommandOptions o;
  o.sweep_paths = files;
  o.target_path = (dir / "target.yaml").string();
  o.robot_path = std::string(IFAB_DATA_DIR) + "/robots/insitu_fabricator.urdf";
  o.config_path = (dir / "perception.yaml").string();
  o.out_dir = (dir / "out").string();
  const nlohmann::json j = CalibrateCommand(o);
  ASSERT_TRUE(j["usable"].get<bool>()) << j.dump(2);
  const auto xyz = j["T_tool0_laser"]["xyz"].get<std::vector<double>>();
  EXPECT_LT((Eigen::Vector3d(xyz[0], xyz[1], xyz[2]) - T_true.translation()).norm(), 0.004) << j.dump(2);
  EXPECT_TRUE(fs::exists(dir / "out" / "arm_laser_mount.yaml"));

  // A broken sweep file names the file and the field.
  Write(dir / "bad.json", R"({"format": "ifab-sweep", "version": 1, "scans": [{"t": 0}], "joint_states": []})");
  o.sweep_paths = {(dir / "bad.json").string()};
  try {
    CalibrateCommand(o);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.json: scans[0]: missing field 'angle_min'"), std::string::npos) << e.what();
  }
}

TEST(SweepIo, RoundTripsHostTimes) {
  const fs::path dir = TempDir("sweep_io");
  SweepRecording rec;
  rec.name = "test";
  LaserScan scan;
  scan.stamp.t = 1.5;
  scan.angle_min = -1;
  scan.angle_increment = 0.5;
  scan.time_increment = 1e-4;
  scan.ranges = {1.0, LaserScan::kNoReturn, 2.5};
  rec.scans = {scan};
  rec.joint_states.resize(2);
  rec.joint_states[1].stamp.t = 0.004;
  rec.joint_states[1].q[2] = 0.3;
  SaveSweep((dir / "s.json").string(), rec);
  const SweepRecording back = LoadSweep((dir / "s.json").string());
  ASSERT_EQ(back.scans.size(), 1u);
  EXPECT_EQ(back.scans[0].stamp.t, 1.5);
  EXPECT_TRUE(std::isnan(back.scans[0].ranges[1]));
  EXPECT_EQ(back.joint_states[1].q[2], 0.3);
  Write(dir / "not.json", "{\"format\": \"other\"}");
  EXPECT_THROW(LoadSweep((dir / "not.json").string()), InputError);
  Write(dir / "broken.json", "{");
  EXPECT_THROW(LoadSweep((dir / "broken.json").string()), InputError);
}

}  // namespace
}  // namespace ifab

