#include "ifab/app/perception_commands.h"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "ifab/core/config.h"
#include "ifab/core/data_path.h"
#include "ifab/core/error.h"
#include "ifab/core/parse.h"
#include "ifab/experiments/perception_json.h"
#include "ifab/model/robot_model.h"
#include "ifab/model/site.h"
#include "ifab/perception/calibration.h"
#include "ifab/experiments/ply_file.h"
#include "ifab/perception/ply.h"
#include "ifab/perception/registration.h"
#include "ifab/perception/scan_assembly.h"
#include "ifab/experiments/sweep_io.h"

namespace ifab {
namespace {

using nlohmann::json;

// The perception options: the shipped data/perception/perception.yaml with the user's file on
// top (a partial file changes only the keys it names).
struct PerceptionConfig {
  RegistrationOptions registration;
  CalibrationOptions calibration;
  ScanAssemblyOptions assembly;
  bool user_sets_gate{false};         // the user's file names registration.gate_sigmas
  bool user_sets_convergence{false};  // ... registration.convergence
};

PerceptionConfig ParsePerception(const ConfigNode& c) {
  PerceptionConfig out;
  c.ExpectKeys({"registration", "calibration", "scan_assembly"});
  if (auto r = c.Find("registration")) out.registration = RegistrationOptions::FromConfig(*r);
  // Calibration's registration options start from the registration section's.
  out.calibration.registration = out.registration;
  if (auto k = c.Find("calibration")) out.calibration = CalibrationOptions::FromConfig(*k, out.calibration);
  if (auto a = c.Find("scan_assembly")) out.assembly = ScanAssemblyOptions::FromConfig(*a);
  return out;
}

PerceptionConfig LoadPerceptionConfig(const std::string& path) {
  const std::string shipped = DataPath("perception/perception.yaml");
  ConfigNode c = ConfigNode::FromString("{}", "defaults");
  if (std::filesystem::exists(shipped)) c = ConfigNode::LoadFile(shipped);
  bool gate = false, convergence = false;
  if (!path.empty()) {
    const ConfigNode user = ConfigNode::LoadFile(path);
    ParsePerception(user);  // errors name the user's file and line
    auto names = [&](const ConfigNode& r) {
      gate = gate || r.Has("gate_sigmas");
      convergence = convergence || r.Has("convergence");
    };
    if (auto r = user.Find("registration")) names(*r);
    if (auto k = user.Find("calibration"))
      if (auto r = k->Find("registration")) names(*r);
    c = c.Overlay(user);
  }
  PerceptionConfig out = ParsePerception(c);
  out.user_sets_gate = gate;
  out.user_sets_convergence = convergence;
  return out;
}

// --sensor: a profile's noise (data/sensors/NAME.yaml or a file), "config", or none: estimated.
void ApplySensor(const std::string& sensor, const PerceptionConfig& config, RegistrationOptions& o) {
  // A user's cloud may hold a lone face: its in-plane motion must not keep the steps going.
  if (!config.user_sets_convergence) o.convergence = Convergence::kResiduals;
  if (sensor == "config") return;
  const bool user_sets_gate = config.user_sets_gate;
  if (!user_sets_gate) o.gate_sigmas = 3.0;  // a 3-sigma gate of whichever model is used
  if (sensor.empty()) {
    o.noise_source = NoiseSource::kEstimated;
    return;
  }
  std::string file = sensor;
  if (!std::filesystem::exists(file)) file = DataPath("sensors/" + sensor + ".yaml");
  if (!std::filesystem::exists(file))
    ThrowInputError("--sensor: '{}' is neither a file nor a profile in data/sensors/ (e.g. utm30lx, urg04lx, "
                    "sick_lms1xx, sick_lms2xx)",
                    sensor);
  const ConfigNode c = ConfigNode::LoadFile(file);
  const ConfigNode n = c["noise"];
  n.ExpectKeys({"name", "sigma_along", "sigma_along_slope", "sigma_along_offset", "sigma_across_slope",
                "sigma_across_offset"});
  for (const char* key : {"sigma_along", "sigma_across_offset"}) n[key];  // required in a profile
  // The numbers without the name (LaserNoiseModel knows only numbers); unset terms are zero.
  LaserNoiseModel m;
  m.sigma_along_slope = m.sigma_along_offset = m.sigma_across_slope = 0.0;
  n.ReadPositive("sigma_along", m.sigma_along);
  n.ReadNonNegative("sigma_along_slope", m.sigma_along_slope);
  n.Read("sigma_along_offset", m.sigma_along_offset);
  n.ReadNonNegative("sigma_across_slope", m.sigma_across_slope);
  n.ReadPositive("sigma_across_offset", m.sigma_across_offset);
  o.noise = m;
  o.noise_source = NoiseSource::kModel;
  o.noise_name = fmt::format("profile {} ({})", n.Get<std::string>("name", sensor), file);
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

// --crop: which points to keep.
struct Crop {
  enum class Kind { kNone, kBox, kRadius } kind{Kind::kNone};
  Eigen::Vector3d lo{Eigen::Vector3d::Zero()}, hi{Eigen::Vector3d::Zero()}, centre{Eigen::Vector3d::Zero()};
  double radius{0.0};
  bool Keeps(const Eigen::Vector3d& p) const {
    switch (kind) {
      case Kind::kNone: return true;
      case Kind::kBox: return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
      case Kind::kRadius: return (p - centre).norm() <= radius;
    }
    return true;
  }
};

Crop ParseCrop(const std::string& text) {
  Crop c;
  if (text.empty()) return c;
  std::istringstream in(text);
  std::string kind;
  in >> kind;
  std::string rest;
  std::getline(in, rest);
  if (kind == "box") {
    const auto v = ParseNumbers(rest, "--crop box", 6);
    c.kind = Crop::Kind::kBox;
    c.lo = Eigen::Vector3d(v[0], v[1], v[2]);
    c.hi = Eigen::Vector3d(v[3], v[4], v[5]);
    if ((c.hi.array() <= c.lo.array()).any())
      ThrowInputError("--crop box: expected x0 y0 z0 x1 y1 z1 with x1 > x0, y1 > y0, z1 > z0, got '{}'", text);
  } else if (kind == "radius") {
    std::vector<double> v;
    std::istringstream numbers(rest);
    for (double x; numbers >> x;) v.push_back(x);
    if (!numbers.eof()) ThrowInputError("--crop radius: expected R or R x y z (m), got '{}'", text);
    if (v.size() != 1 && v.size() != 4) ThrowInputError("--crop radius: expected R or R x y z (m), got '{}'", text);
    c.kind = Crop::Kind::kRadius;
    c.radius = v[0];
    if (!(c.radius > 0)) ThrowInputError("--crop radius: expected a positive radius, got '{}'", text);
    if (v.size() == 4) c.centre = Eigen::Vector3d(v[1], v[2], v[3]);
  } else {
    ThrowInputError("--crop: expected \"box x0 y0 z0 x1 y1 z1\" or \"radius R [x y z]\" (m), got '{}'", text);
  }
  return c;
}

// --fix BODY:x,y,z,rx,ry,rz (or BODY:z,tilt for z, rx, ry).
void ApplyFixes(const std::vector<std::string>& fixes, std::vector<RegistrationBody>& bodies) {
  for (const auto& f : fixes) {
    const auto colon = f.find(':');
    if (colon == std::string::npos)
      ThrowInputError("--fix: expected BODY:COMPONENTS (components x, y, z, rx, ry, rz, tilt), got '{}'", f);
    const std::string name = f.substr(0, colon);
    RegistrationBody* body = nullptr;
    std::string names;
    for (auto& b : bodies) {
      if (b.name == name) body = &b;
      names += (names.empty() ? "" : ", ") + b.name;
    }
    if (!body) ThrowInputError("--fix: no body '{}' (bodies: {})", name, names);
    std::stringstream ss(f.substr(colon + 1));
    std::string item;
    while (std::getline(ss, item, ',')) {
      static const char* kNames[6] = {"x", "y", "z", "rx", "ry", "rz"};
      bool known = false;
      for (int c = 0; c < 6; ++c)
        if (item == kNames[c]) body->fixed[static_cast<std::size_t>(c)] = known = true;
      if (item == "tilt") body->fixed[3] = body->fixed[4] = known = true;
      if (!known) ThrowInputError("--fix {}: unknown component '{}' (x, y, z, rx, ry, rz, tilt)", f, item);
    }
  }
}

}  // namespace

Pose3 ParsePoseArgument(const std::string& text, const std::string& what, bool radians) {
  const auto v = ParseNumbers(text, what, 6);
  const double k = radians ? 1.0 : M_PI / 180.0;
  return PoseFromXyzRpy(v[0], v[1], v[2], k * v[3], k * v[4], k * v[5]);
}

json RegisterCommand(const RegisterCommandOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  if (o.frame != "site" && o.frame != "sensor")
    ThrowInputError("--frame: expected site (cloud in the robot base frame) or sensor (objects in the cloud's frame), got '{}'",
                    o.frame);
  const bool sensor_frame = o.frame == "sensor";
  PerceptionConfig config = LoadPerceptionConfig(o.config_path);
  ApplySensor(o.sensor, config, config.registration);
  const Site site = LoadSite(o.site_path);
  if (!sensor_frame && o.guess.empty()) ThrowInputError("--guess: required with --frame site (the robot's pose in the site)");
  if (sensor_frame && !o.guess.empty())
    ThrowInputError("--guess: not used with --frame sensor (each object's guess is its pose in {})", o.site_path);
  const Crop crop = ParseCrop(o.crop);
  std::optional<Eigen::Vector3d> origin;
  if (!o.origin.empty()) {
    const auto v = ParseNumbers(o.origin, "--origin", 3);
    origin = Eigen::Vector3d(v[0], v[1], v[2]);
  }
  const PointCloud cloud = ReadPly(o.cloud_path);
  if (cloud.size() == 0) ThrowInputError("{}: the cloud has no points", o.cloud_path);
  const bool has_origins = cloud.Find("origin_x") != nullptr;
  if (sensor_frame && !origin && !has_origins) origin = Eigen::Vector3d::Zero();  // the sensor sits at its frame's origin
  const std::vector<RayPoint> all_rays = ToRayPoints(cloud, o.cloud_path, origin ? &*origin : nullptr);
  std::vector<RayPoint> rays;
  std::vector<std::size_t> kept;
  for (std::size_t i = 0; i < all_rays.size(); ++i)
    if (crop.Keeps(all_rays[i].p)) rays.push_back(all_rays[i]), kept.push_back(i);
  if (rays.empty()) ThrowInputError("--crop '{}': no point of {} lies inside", o.crop, o.cloud_path);
  MakeOutDir(o.out_dir);

  std::vector<RegistrationBody> bodies =
      sensor_frame ? SensorFrameBodies(site) : SiteBodies(site, ParsePoseArgument(o.guess, "--guess"), !o.one_body);
  if (bodies.empty()) ThrowInputError("{}: the site has no object to register", o.site_path);
  ApplyFixes(o.fix, bodies);
  const RegistrationOptions& ro = config.registration;
  const RegistrationSummary s = Register(rays, bodies, ro);

  json j = {{"cloud", o.cloud_path},
            {"site", o.site_path},
            {"frame", o.frame},
            {"status", ToString(s.status)},
            {"message", s.message},
            {"fit", FitToJson(s.fit)},
            {"covariance_convention",
             "[x y z rx ry rz]: position [m] and a rotation vector [rad] about the frame's axes (left perturbation), "
             "scaled by the a-posteriori variance factor"},
            {"points", s.num_points},
            {"points_cropped", all_rays.size() - rays.size()},
            {"inliers", s.num_inliers},
            {"shadow_points_flagged", s.num_shadow_flagged},
            {"shadow_points_removed", s.num_shadow_removed},
            {"outliers", s.num_outliers},
            {"grazing", s.num_grazing},
            {"rms_whitened", s.rms_whitened},
            {"iterations", s.iterations}};
  std::vector<std::string> warnings = s.warnings;
  if (!s.fit.consistent) warnings.push_back(s.fit.message);
  if (s.status != RegistrationStatus::kConverged) warnings.push_back("not converged: " + s.message);
  bool usable = s.IsUsable();
  json body_json = json::array();
  for (const auto& b : s.bodies) {
    const bool relevant = sensor_frame ? b.free : b.name == "site";
    if (relevant) usable = usable && b.Constrained();
    body_json.push_back(BodyToJson(b, s.IsUsable() && b.Constrained()));
  }
  j["bodies"] = body_json;
  if (sensor_frame) {
    json planes = json::array();
    for (const auto& p : RegisteredPlanes(s, bodies, ro.unconstrained_std))
      planes.push_back({{"body", p.body},
                        {"normal", {p.normal.x(), p.normal.y(), p.normal.z()}},
                        {"offset", p.offset},
                        {"offset_std_mm", 1e3 * p.offset_std},
                        {"tilt_std_deg", p.tilt_std * 180.0 / M_PI},
                        {"usable", s.IsUsable() && p.constrained}});
    j["planes"] = planes;
  } else {
    SiteLocalization loc;
    loc.registration = s;
    if (const RegisteredBody* site_body = s.Find("site")) {
      loc.T_site_base = site_body->T_base_body.inverse();
      loc.covariance = InverseCovariance(site_body->T_base_body, site_body->covariance);
      loc.unconstrained = site_body->unconstrained;
    } else {
      usable = false;
      warnings.push_back("the site has no object besides the ground: the robot's pose is not fixed");
    }
    j["T_site_base"] = PoseToJson(loc.T_site_base);
    j["covariance_site_base"] = MatrixToJson(loc.covariance);
    j["std_site_base"] = StdToJson(loc.covariance);
    j["unconstrained_site_base"] = loc.unconstrained;
  }
  j["usable"] = usable;
  j["warnings"] = warnings;

  PointCloud labelled = cloud;
  std::vector<double> label(cloud.size(), 5.0), body(cloud.size(), -1.0);
  for (std::size_t k = 0; k < kept.size(); ++k) {
    label[kept[k]] = static_cast<double>(s.labels[k]);
    body[kept[k]] = s.point_body[k];
  }
  labelled.SetField("label", std::move(label));
  labelled.SetField("body", std::move(body));
  SavePly((std::filesystem::path(o.out_dir) / "labelled.ply").string(), labelled);
  j["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  j["solve_seconds"] = s.seconds;
  WriteJson((std::filesystem::path(o.out_dir) / "registration.json").string(), j);
  return j;
}

CubeTarget LoadCubeTarget(const std::string& path) {
  const std::string target_path = path.empty() ? DataPath("perception/cube_target.yaml") : path;
  const ConfigNode target = ConfigNode::LoadFile(target_path);
  target.ExpectKeys({"cube", "ground_z_guess"});
  const ConfigNode cube = target["cube"];
  cube.ExpectKeys({"size", "pose_guess"});
  CubeTarget t;
  cube.ReadPositive("size", t.size);
  const auto p = cube["pose_guess"].AsNumbers(6);
  t.T_base_cube = PoseFromXyzRpy(p[0], p[1], p[2], p[3] * M_PI / 180, p[4] * M_PI / 180, p[5] * M_PI / 180);
  t.ground_z = target.Get<double>("ground_z_guess", 0.0);
  return t;
}

json CalibrateCommand(const CalibrateCommandOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  if (o.sweep_paths.empty()) ThrowInputError("calibrate: give at least one sweep file");
  PerceptionConfig config = LoadPerceptionConfig(o.config_path);
  ApplySensor(o.sensor, config, config.calibration.registration);
  const RobotModel robot = LoadRobotModel(o.robot_path.empty() ? DataPath("robots/insitu_fabricator.urdf") : o.robot_path);
  const CubeTarget target = LoadCubeTarget(o.target_path);
  const double size = target.size;
  const Pose3 T_base_cube = target.T_base_cube;
  const double ground_z = target.ground_z;
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
  for (const auto& b : s.bodies) bodies.push_back(BodyToJson(b, s.IsUsable() && b.Constrained()));
  std::vector<std::string> warnings = s.warnings;
  if (!s.fit.consistent) warnings.push_back(s.fit.message);
  if (s.status != RegistrationStatus::kConverged) warnings.push_back("not converged: " + s.message);
  json j = {{"status", ToString(s.status)},
            {"usable", s.IsUsable()},
            {"message", s.message},
            {"fit", FitToJson(s.fit)},
            {"T_tool0_laser", PoseToJson(s.T_tool0_laser)},
            {"mount_guess", PoseToJson(mount_guess)},
            {"covariance", MatrixToJson(s.covariance)},
            {"std", StdToJson(s.covariance)},
            {"unconstrained", s.unconstrained},
            {"bodies", bodies},
            {"sweeps", sweep_info},
            {"points", s.num_points},
            {"inliers", s.num_inliers},
            {"shadow_points_removed", s.num_shadow_removed},
            {"rms_whitened", s.rms_whitened},
            {"iterations", s.iterations},
            {"warnings", warnings}};
  const auto v = XyzRpyFromPose(s.T_tool0_laser);
  {
    std::ofstream yaml(std::filesystem::path(o.out_dir) / "arm_laser_mount.yaml");
    yaml << "# T_tool0_arm_laser from `ifab calibrate` (x y z m, roll pitch yaw rad), for a robot YAML's\n"
         << "# `mounts:` section (model/robot_model.h ApplyMountOverrides).\n"
         << (s.IsUsable() ? "" : "# NOT USABLE: see calibration.json's warnings before using this mount.\n")
         << fmt::format("mounts:\n  arm_laser: [{:.6f}, {:.6f}, {:.6f}, {:.7f}, {:.7f}, {:.7f}]\n", v[0], v[1], v[2],
                        v[3], v[4], v[5]);
  }
  j["seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  j["solve_seconds"] = s.seconds;
  WriteJson((std::filesystem::path(o.out_dir) / "calibration.json").string(), j);
  return j;
}

int ReportRegistration(const json& j, const std::string& out_dir, std::ostream& out) {
  out << "registration " << j["status"].get<std::string>() << " (" << j["message"].get<std::string>() << "), "
      << (j["usable"].get<bool>() ? "usable" : "NOT usable") << "\n"
      << "noise model: " << j["fit"]["noise_model"].get<std::string>() << "; " << j["fit"]["message"].get<std::string>()
      << "\n";
  if (j.contains("T_site_base")) {
    const auto& xyz = j["T_site_base"]["xyz"];
    const auto& rpy = j["T_site_base"]["rpy_deg"];
    out << "T_site_base: xyz [" << xyz[0] << ", " << xyz[1] << ", " << xyz[2] << "] m, rpy [" << rpy[0] << ", " << rpy[1]
        << ", " << rpy[2] << "] deg\n";
  }
  if (j.contains("planes"))
    for (const auto& p : j["planes"])
      out << fmt::format("plane of {}: normal [{:.5f}, {:.5f}, {:.5f}], offset {:.5f} m (std {:.2f} mm, {:.3f} deg){}\n",
                         p["body"].get<std::string>(), p["normal"][0].get<double>(), p["normal"][1].get<double>(),
                         p["normal"][2].get<double>(), p["offset"].get<double>(), p["offset_std_mm"].get<double>(),
                         p["tilt_std_deg"].get<double>(), p["usable"].get<bool>() ? "" : ", NOT usable");
  out << j["inliers"] << " of " << j["points"] << " points inliers, " << j["shadow_points_removed"]
      << " shadow points removed\n";
  for (const auto& w : j["warnings"]) out << "warning: " << w.get<std::string>() << "\n";
  out << "wrote " << out_dir << "/registration.json\n";
  return j["usable"].get<bool>() ? 0 : 1;
}

int ReportCalibration(const json& j, const std::string& out_dir, std::ostream& out) {
  const auto& xyz = j["T_tool0_laser"]["xyz"];
  const auto& rpy = j["T_tool0_laser"]["rpy_deg"];
  out << "calibration " << j["status"].get<std::string>() << " (" << j["message"].get<std::string>() << "), "
      << (j["usable"].get<bool>() ? "usable" : "NOT usable") << "\n"
      << "noise model: " << j["fit"]["noise_model"].get<std::string>() << "; " << j["fit"]["message"].get<std::string>()
      << "\n"
      << "T_tool0_laser: xyz [" << xyz[0] << ", " << xyz[1] << ", " << xyz[2] << "] m, rpy [" << rpy[0] << ", " << rpy[1]
      << ", " << rpy[2] << "] deg\n";
  for (const auto& w : j["warnings"]) out << "warning: " << w.get<std::string>() << "\n";
  out << "wrote " << out_dir << "/calibration.json and arm_laser_mount.yaml\n";
  return j["usable"].get<bool>() ? 0 : 1;
}

}  // namespace ifab
