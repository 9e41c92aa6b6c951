#include "ifab/sim/as_built.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "ifab/core/angles.h"
#include "ifab/core/config.h"

namespace ifab::sim {
namespace {

void ReadRange(const ConfigNode& c, const char* key, double& lo, double& hi) {
  if (auto n = c.Find(key)) {
    const auto v = n->AsNumbers(2);
    if (!(v[0] >= 0.0 && v[1] >= v[0])) n->Fail("[min, max] with 0 <= min <= max");
    lo = v[0];
    hi = v[1];
  }
}

double ClippedNormal(RandomStream& rng, double sigma, double limit) {
  return std::clamp(rng.Normal(sigma), -limit, limit);
}

}  // namespace

AsBuiltTolerances AsBuiltTolerances::FromConfig(const ConfigNode& root) {
  root.ExpectKeys({"bricks", "floor", "base", "arm", "lasers", "imu", "gripper", "calibration_cube"});
  AsBuiltTolerances t;
  {
    const ConfigNode b = root["bricks"];
    b.ExpectKeys({"category", "mean_limit_factor", "mean_sigma_of_limit", "range_factor", "lean_sigma_deg"});
    b.Read("category", t.brick_category);
    if (t.brick_category != "T1" && t.brick_category != "T2") b["category"].Fail("T1 or T2");
    if (auto f = b.Find("mean_limit_factor")) {
      f->ExpectKeys({"T1", "T2"});
      f->ReadPositive(t.brick_category, t.brick_mean_limit_factor);
    }
    b.ReadNonNegative("mean_sigma_of_limit", t.brick_mean_sigma_of_limit);
    b.ReadNonNegative("range_factor", t.brick_range_factor);
    b.ReadNonNegative("lean_sigma_deg", t.brick_lean_sigma_deg);
  }
  {
    const ConfigNode f = root["floor"];
    f.ExpectKeys({"limits_distance_m", "limits_mm", "waves", "wavelength_m", "fraction_of_limit"});
    if (f.Has("limits_distance_m") || f.Has("limits_mm")) {
      t.floor_limit_distance_m = f["limits_distance_m"].AsNumbers();
      t.floor_limit_mm = f["limits_mm"].AsNumbers();
      if (t.floor_limit_mm.size() != t.floor_limit_distance_m.size() || t.floor_limit_mm.empty())
        f["limits_mm"].Fail("as many limits as limits_distance_m");
    }
    f.ReadNonNegative("waves", t.floor_waves);
    ReadRange(f, "wavelength_m", t.floor_wavelength_min, t.floor_wavelength_max);
    if (t.floor_waves > 0 && !(t.floor_wavelength_min > 0.0)) f["wavelength_m"].Fail("positive wavelengths");
    ReadRange(f, "fraction_of_limit", t.floor_fraction_min, t.floor_fraction_max);
  }
  {
    const ConfigNode b = root["base"];
    b.ExpectKeys({"seat_sigma_deg", "compliance_rad_per_nm", "arm_mass_kg", "arm_com_fraction", "payload_kg",
                  "track_contact_length_m"});
    b.ReadNonNegative("seat_sigma_deg", t.base_seat_sigma_deg);
    ReadRange(b, "compliance_rad_per_nm", t.base_compliance_min, t.base_compliance_max);
    b.ReadNonNegative("arm_mass_kg", t.arm_mass_kg);
    b.ReadInRange("arm_com_fraction", t.arm_com_fraction, 0.0, 1.0);
    b.ReadNonNegative("payload_kg", t.payload_kg);
    b.ReadPositive("track_contact_length_m", t.track_contact_length_m);
  }
  {
    const ConfigNode a = root["arm"];
    a.ExpectKeys({"joint_offset_sigma_deg", "link_length_sigma_m", "link_angle_sigma_deg",
                  "gravity_compliance_rad_per_nm", "encoder_noise_deg"});
    a.ReadNonNegative("joint_offset_sigma_deg", t.joint_offset_sigma_deg);
    a.ReadNonNegative("link_length_sigma_m", t.link_length_sigma_m);
    a.ReadNonNegative("link_angle_sigma_deg", t.link_angle_sigma_deg);
    ReadRange(a, "gravity_compliance_rad_per_nm", t.gravity_compliance_min, t.gravity_compliance_max);
    a.ReadNonNegative("encoder_noise_deg", t.encoder_noise_deg);
  }
  {
    const ConfigNode l = root["lasers"];
    l.ExpectKeys({"walk_bias_scale_sigma", "walk_bias_cos_power_sigma", "near_bias_shift_sigma_m",
                  "sigma_along_range_m", "sigma_along_m", "sigma_incidence_gain", "sigma_unit_scale_sigma",
                  "warmup_amplitude_sigma_m", "warmup_tau_s", "mount_sigma_m", "mount_sigma_deg"});
    t.laser = LrfUnitTolerances::FromConfig(l);
    l.ReadNonNegative("mount_sigma_m", t.mount_sigma_m);
    l.ReadNonNegative("mount_sigma_deg", t.mount_sigma_deg);
  }
  {
    const ConfigNode i = root["imu"];
    i.ExpectKeys({"mount_sigma_deg"});
    i.ReadNonNegative("mount_sigma_deg", t.imu_mount_sigma_deg);
  }
  {
    const ConfigNode g = root["gripper"];
    g.ExpectKeys({"release_sigma_xy_m", "release_sigma_per_lean_deg_m", "release_sigma_yaw_deg"});
    g.ReadNonNegative("release_sigma_xy_m", t.release_sigma_xy_m);
    g.ReadNonNegative("release_sigma_per_lean_deg_m", t.release_sigma_per_lean_deg_m);
    g.ReadNonNegative("release_sigma_yaw_deg", t.release_sigma_yaw_deg);
  }
  {
    const ConfigNode c = root["calibration_cube"];
    c.ExpectKeys({"size_limit_m", "sigma_of_limit"});
    c.ReadNonNegative("size_limit_m", t.cube_size_limit_m);
    c.ReadNonNegative("sigma_of_limit", t.cube_size_sigma_of_limit);
  }
  return t;
}

AsBuiltTolerances AsBuiltTolerances::Load(const std::string& path) { return FromConfig(ConfigNode::LoadFile(path)); }

RobotModel AsBuilt::TrueRobot(const RobotModel& design) const {
  if (exact || link_errors.empty()) return design;
  RobotModel r = design;
  // A segment past the drawn errors takes the last one (as drawn: one per segment).
  std::vector<Pose3> errors;
  for (unsigned i = 0; i < design.arm_chain.getNrOfSegments(); ++i)
    errors.push_back(link_errors[std::min<std::size_t>(i, link_errors.size() - 1)]);
  r.arm_chain = ChainWithLinkErrors(design.arm_chain, errors);
  return r;
}

double AsBuilt::FlangeErrorAt(const RobotModel& design, const Vector6d& q) const {
  const RobotModel truth = TrueRobot(design);
  return (truth.ArmForwardKinematics(q + joint_offsets).translation() - design.ArmForwardKinematics(q).translation())
      .norm();
}

AsBuilt DrawAsBuilt(const AsBuiltTolerances& t, const RobotModel& design_robot, const Site& design_site,
                    const LrfOptions& nominal_laser, std::uint64_t seed) {
  RandomStream root(seed);
  root = root.Derive("as_built");
  AsBuilt a;
  a.exact = false;

  // Bricks: the batch's mean within its category, single bricks about it (EN 771-1).
  {
    RandomStream rng = root.Derive("bricks");
    for (int k = 0; k < 3; ++k) {
      const double d_mm = 1000.0 * design_site.brick.size[k];
      const double limit = 1e-3 * t.brick_mean_limit_factor * std::sqrt(d_mm);
      a.brick_mean_size[k] = design_site.brick.size[k] + ClippedNormal(rng, t.brick_mean_sigma_of_limit * limit, limit);
      a.brick_size_sigma[k] = 1e-3 * t.brick_range_factor * std::sqrt(d_mm) / 4.0;
    }
    a.brick_lean_sigma = DegToRad(t.brick_lean_sigma_deg);
  }

  // Floor: smooth waves, scaled so the worst step measure is a drawn fraction of DIN 18202's limit.
  {
    RandomStream rng = root.Derive("floor");
    for (int k = 0; k < t.floor_waves; ++k) {
      FloorField::Wave w;
      // Log-uniform wavelengths; amplitude growing with wavelength (long waves dominate a floor).
      const double lambda =
          t.floor_wavelength_min * std::pow(t.floor_wavelength_max / t.floor_wavelength_min, rng.Uniform());
      const double dir = rng.Uniform(0.0, 2 * EIGEN_PI);
      w.k = 2 * EIGEN_PI / lambda * Eigen::Vector2d(std::cos(dir), std::sin(dir));
      w.amplitude = lambda * rng.Uniform(0.5, 1.0);
      w.phase = rng.Uniform(0.0, 2 * EIGEN_PI);
      a.floor.waves.push_back(w);
    }
    if (!a.floor.waves.empty()) {
      Eigen::Vector2d lo(1e9, 1e9), hi(-1e9, -1e9);
      for (const auto& p : design_site.boundary) {
        lo = lo.cwiseMin(p);
        hi = hi.cwiseMax(p);
      }
      double scale = 1e9;
      for (std::size_t i = 0; i < t.floor_limit_mm.size(); ++i) {
        const double step = a.floor.WorstStep(t.floor_limit_distance_m[i], lo, hi);
        if (step > 0.0) scale = std::min(scale, 1e-3 * t.floor_limit_mm[i] / step);
      }
      scale *= rng.Uniform(t.floor_fraction_min, t.floor_fraction_max);
      for (auto& w : a.floor.waves) w.amplitude *= scale;
      a.floor_step_1m = a.floor.WorstStep(1.0, lo, hi);
      a.floor_step_4m = a.floor.WorstStep(4.0, lo, hi);
    }
  }

  // Base on its tracks.
  {
    RandomStream rng = root.Derive("base");
    a.base_seat_sigma = DegToRad(t.base_seat_sigma_deg);
    a.base_compliance = rng.Uniform(t.base_compliance_min, t.base_compliance_max);
    a.arm_mass_kg = t.arm_mass_kg;
    a.arm_com_fraction = t.arm_com_fraction;
    a.payload_kg = t.payload_kg;
    a.track_contact_length = t.track_contact_length_m;
  }

  // Arm: joint zero offsets, link errors, gravity deflection, encoder noise.
  {
    RandomStream rng = root.Derive("arm");
    for (int i = 0; i < 6; ++i) a.joint_offsets[i] = DegToRad(rng.Normal(t.joint_offset_sigma_deg));
    for (unsigned i = 0; i < design_robot.arm_chain.getNrOfSegments(); ++i) {
      const double s = t.link_length_sigma_m, r = DegToRad(t.link_angle_sigma_deg);
      // Named draws, last coordinate first: C++ leaves the order of a call's arguments open, and
      // this is the order gcc used for the recorded worlds (clang drew them the other way round).
      const double yaw = rng.Normal(r), pitch = rng.Normal(r), roll = rng.Normal(r);
      const double z = rng.Normal(s), y = rng.Normal(s), x = rng.Normal(s);
      a.link_errors.push_back(PoseFromXyzRpy(x, y, z, roll, pitch, yaw));
    }
    a.gravity_compliance = {rng.Uniform(t.gravity_compliance_min, t.gravity_compliance_max),
                            rng.Uniform(t.gravity_compliance_min, t.gravity_compliance_max)};
    a.encoder_noise = DegToRad(t.encoder_noise_deg);
  }

  // Lasers: each unit its own, each bracket its own.
  {
    RandomStream rng = root.Derive("lasers");
    a.base_laser = DrawLrfUnit(nominal_laser, t.laser, rng);
    a.arm_laser = DrawLrfUnit(nominal_laser, t.laser, rng);
    for (auto* m : {&a.base_laser_mount_error, &a.arm_laser_mount_error}) {
      for (int k = 0; k < 3; ++k) (*m)[static_cast<std::size_t>(k)] = rng.Normal(t.mount_sigma_m);
      for (int k = 3; k < 6; ++k) (*m)[static_cast<std::size_t>(k)] = DegToRad(rng.Normal(t.mount_sigma_deg));
    }
  }

  // The IMU as mounted (its own stream: the other draws stay as they were).
  {
    RandomStream rng = root.Derive("imu");
    const double roll = DegToRad(rng.Normal(t.imu_mount_sigma_deg));
    const double pitch = DegToRad(rng.Normal(t.imu_mount_sigma_deg));
    const double yaw = DegToRad(rng.Normal(t.imu_mount_sigma_deg));
    a.imu_mount_error_rpy = {roll, pitch, yaw};
  }

  // The calibration cube as machined: each edge its own, within its general tolerance.
  {
    RandomStream rng = root.Derive("calibration_cube");
    const double limit = t.cube_size_limit_m;
    for (int k = 0; k < 3; ++k)
      a.cube_size_error[k] = std::clamp(rng.Normal(t.cube_size_sigma_of_limit * limit), -limit, limit);
  }

  a.release_sigma_xy = t.release_sigma_xy_m;
  a.release_sigma_per_lean = t.release_sigma_per_lean_deg_m / DegToRad(1.0);
  a.release_sigma_yaw = DegToRad(t.release_sigma_yaw_deg);
  return a;
}

}  // namespace ifab::sim
