#include "ifab/perception/commands.h"

#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "ifab/core/config.h"
#include "ifab/core/data_path.h"
#include "ifab/core/error.h"
#include "ifab/core/parse.h"
#include "ifab/model/robot_model.h"
#include "ifab/model/site.h"
#include "ifab/perception/calibration.h"
#include "ifab/perception/ply.h"
#include "ifab/perception/registration.h"
#include "ifab/perception/scan_assembly.h"
#include "ifab/perception/sweep_io.h"

namespace ifab {
namespace {

using nlohmann::json;

json Matrix(const Eigen::MatrixXd& m) {
  json rows = json::array();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    std::vector<double> row(static_cast<std::size_t>(m.cols()));
    for (Eigen::Index c = 0; c < m.cols(); ++c) row[static_cast<std::size_t>(c)] = m(r, c);
    rows.push_back(row);
  }
  return rows;
}

json StdJson(const Matrix6d& cov) {
  return {{"xyz_mm", {1e3 * std::sqrt(cov(0, 0)), 1e3 * std::sqrt(cov(1, 1)), 1e3 * std::sqrt(cov(2, 2))}},
          {"rotation_deg",
           {std::sqrt(cov(3, 3)) * 180 / M_PI, std::sqrt(cov(4, 4)) * 180 / M_PI, std::sqrt(cov(5, 5)) * 180 / M_PI}}};
}

json BodyJson(const RegisteredBody& b) {
  return {{"name", b.name},
          {"free", b.free},
          {"T_base_body", PoseToJson(b.T_base_body)},
          {"covariance", Matrix(b.covariance)},
          {"std", StdJson(b.covariance)},
          {"inliers", b.inliers},
          {"unconstrained", b.unconstrained}};
}

// The optional perception config: a YAML file with registration:, calibration:, scan_assembly:.
struct PerceptionConfig {
  RegistrationOptions registration;
  CalibrationOptions calibration;
  ScanAssemblyOptions assembly;
};

PerceptionConfig LoadPerceptionConfig(const std::string& path) {
  PerceptionConfig out;
  const std::string file = path.empty() ? DataPath("perception/perception.yaml") : path;
  if (path.empty() && !std::filesystem::exists(file)) return out;
  const ConfigNode c = ConfigNode::LoadFile(file);
  c.ExpectKeys({"registration", "calibration", "scan_assembly"});
  if (auto r = c.Find("registration")) out.registration = RegistrationOptions::FromConfig(*r);
  if (auto k = c.Find("calibration")) out.calibration = CalibrationOptions::FromConfig(*k);
  if (auto a = c.Find("scan_assembly")) out.assembly = ScanAssemblyOptions::FromConfig(*a);
  return out;
}

void MakeOutDir(const std::string& dir) {
  if (dir.empty()) ThrowInputError("--out: an output folder is required");
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) ThrowInputError("--out: cannot create '{}': {}", dir, ec.message());
}

void WriteJson(const std::string& path, const json& j) {
  std::ofstream out(path);
  if (!out) ThrowInputError("{}: cannot open for writing", path);
  out << j.dump(2) << "\n";
}

}  // namespace

Pose3 ParsePoseArgument(const std::string& text, const std::string& what, bool radians) {
  const auto v = ParseNumbers(text, what, 6);
  const double k = radians ? 1.0 : M_PI / 180.0;
  return PoseFromXyzRpy(v[0], v[1], v[2], k * v[3], k * v[4], k * v[5]);
}

json PoseToJson(const Pose3& pose) {
  const auto v = XyzRpyFromPose(pose);
  return {{"xyz", {v[0], v[1], v[2]}},
          {"rpy_deg", {v[3] * 180 / M_PI, v[4] * 180 / M_PI, v[5] * 180 / M_PI}},
          {"matrix", Matrix(pose.matrix())}};
}

json RegisterCommand(const RegisterCommandOptions& o) {
  const PerceptionConfig config = LoadPerceptionConfig(o.config_path);
  const Site site = LoadSite(o.site_path);
  const Pose3 guess = ParsePoseArgument(o.guess, "--guess");
  std::optional<Eigen::Vector3d> origin;
  if (!o.origin.empty()) {
    const auto v = ParseNumbers(o.origin, "--origin", 3);
    origin = Eigen::Vector3d(v[0], v[1], v[2]);
  }
  const PointCloud cloud = ReadPly(o.cloud_path);
  if (cloud.size() == 0) ThrowInputError("{}: the cloud has no points", o.cloud_path);
  const std::vector<RayPoint> rays = ToRayPoints(cloud, o.cloud_path, origin ? &*origin : nullptr);
  MakeOutDir(o.out_dir);

  const SiteLocalization loc = LocalizeInSite(rays, site, guess, config.registration, !o.one_body);
  const RegistrationSummary& s = loc.registration;
  json bodies = json::array();
  for (const auto& b : s.bodies) bodies.push_back(BodyJson(b));
  const json j = {{"cloud", o.cloud_path},
                  {"site", o.site_path},
                  {"status", ToString(s.status)},
                  {"usable", s.IsUsable()},
                  {"message", s.message},
                  {"T_site_base", PoseToJson(loc.T_site_base)},
                  {"covariance_site_base", Matrix(loc.covariance)},
                  {"std_site_base", StdJson(loc.covariance)},
                  {"covariance_convention",
                   "[x y z rx ry rz]: position [m] and a rotation vector [rad] about the frame's axes (left perturbation)"},
                  {"bodies", bodies},
                  {"points", s.num_points},
                  {"inliers", s.num_inliers},
                  {"shadow_points_flagged", s.num_shadow_flagged},
                  {"shadow_points_removed", s.num_shadow_removed},
                  {"outliers", s.num_outliers},
                  {"grazing", s.num_grazing},
                  {"rms_whitened", s.rms_whitened},
                  {"iterations", s.iterations},
                  {"seconds", s.seconds},
                  {"warnings", s.warnings}};
  WriteJson((std::filesystem::path(o.out_dir) / "registration.json").string(), j);

  PointCloud labelled = cloud;
  std::vector<double> label(cloud.size()), body(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    label[i] = static_cast<double>(s.labels[i]);
    body[i] = s.point_body[i];
  }
  labelled.SetField("label", std::move(label));
  labelled.SetField("body", std::move(body));
  WritePly((std::filesystem::path(o.out_dir) / "labelled.ply").string(), labelled);
  return j;
}

json CalibrateCommand(const CalibrateCommandOptions& o) {
  if (o.sweep_paths.empty()) ThrowInputError("calibrate: give at least one sweep file");
  const PerceptionConfig config = LoadPerceptionConfig(o.config_path);
  const RobotModel robot = LoadRobotModel(o.robot_path.empty() ? DataPath("robots/insitu_fabricator.urdf") : o.robot_path);
  const std::string target_path = o.target_path.empty() ? DataPath("perception/cube_target.yaml") : o.target_path;
  const ConfigNode target = ConfigNode::LoadFile(target_path);
  target.ExpectKeys({"cube", "ground_z_guess"});
  const ConfigNode cube = target["cube"];
  cube.ExpectKeys({"size", "pose_guess"});
  double size = 0.25;
  cube.ReadPositive("size", size);
  const auto p = cube["pose_guess"].AsNumbers(6);
  const Pose3 T_base_cube = PoseFromXyzRpy(p[0], p[1], p[2], p[3] * M_PI / 180, p[4] * M_PI / 180, p[5] * M_PI / 180);
  const double ground_z = target.Get<double>("ground_z_guess", 0.0);
  const Pose3 mount_guess = o.mount_guess.empty() ? robot.T_tool0_arm_laser : ParsePoseArgument(o.mount_guess, "--mount");

  std::vector<CalibrationSweep> sweeps;
  json sweep_info = json::array();
  for (const auto& path : o.sweep_paths) {
    const SweepRecording rec = LoadSweep(path);
    const AssembledSweep a = AssembleSweep(rec.scans, rec.joint_states, robot, config.assembly);
    if (a.points.empty()) ThrowInputError("{}: no laser beam falls within the joint states' times", path);
    sweeps.push_back({rec.name, a.points});
    sweep_info.push_back({{"file", path}, {"name", rec.name}, {"points", a.points.size()},
                          {"untimed_beams", a.untimed_beams}});
  }
  MakeOutDir(o.out_dir);
  const CalibrationSummary s =
      CalibrateLaserMount(sweeps, CubeOnGroundBodies(size, T_base_cube, ground_z), mount_guess, config.calibration);
  for (std::size_t k = 0; k < sweeps.size(); ++k) sweep_info[k]["inliers"] = s.sweep_inliers[k];
  json bodies = json::array();
  for (const auto& b : s.bodies) bodies.push_back(BodyJson(b));
  const json j = {{"status", ToString(s.status)},
                  {"usable", s.IsUsable()},
                  {"message", s.message},
                  {"T_tool0_laser", PoseToJson(s.T_tool0_laser)},
                  {"mount_guess", PoseToJson(mount_guess)},
                  {"covariance", Matrix(s.covariance)},
                  {"std", StdJson(s.covariance)},
                  {"unconstrained", s.unconstrained},
                  {"bodies", bodies},
                  {"sweeps", sweep_info},
                  {"points", s.num_points},
                  {"inliers", s.num_inliers},
                  {"shadow_points_removed", s.num_shadow_removed},
                  {"rms_whitened", s.rms_whitened},
                  {"iterations", s.iterations},
                  {"seconds", s.seconds},
                  {"warnings", s.warnings}};
  WriteJson((std::filesystem::path(o.out_dir) / "calibration.json").string(), j);
  const auto v = XyzRpyFromPose(s.T_tool0_laser);
  std::ofstream yaml(std::filesystem::path(o.out_dir) / "arm_laser_mount.yaml");
  yaml << "# T_tool0_arm_laser from `ifab calibrate` (x y z m, roll pitch yaw rad), for a robot YAML's\n"
       << "# `mounts:` section (model/robot_model.h ApplyMountOverrides).\n"
       << fmt::format("mounts:\n  arm_laser: [{:.6f}, {:.6f}, {:.6f}, {:.7f}, {:.7f}, {:.7f}]\n", v[0], v[1], v[2], v[3],
                      v[4], v[5]);
  return j;
}

}  // namespace ifab
