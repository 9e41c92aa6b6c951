#pragma once
/// \file
/// The as-built world and machine (DESIGN.md "The world and the model"): per seed the simulator
/// draws, from published tolerances (data/sim/as_built.yaml), what a real lab has and a drawing
/// does not: brick sizes and lean, an uneven floor, a base that tilts on its tracks with the
/// arm's posture, an arm with its own kinematic errors and gravity deflection, lasers each with
/// their own bias, noise and warm-up drift, a gripper whose release depends on the brick.
/// Ground truth: only sim and the experiments' scoring see it.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "ifab/core/random.h"
#include "ifab/model/robot_model.h"
#include "ifab/model/site.h"
#include "ifab/sim/lrf_model.h"
#include "ifab/sim/world.h"

namespace ifab {
class ConfigNode;
}

namespace ifab::sim {

/// The distributions of data/sim/as_built.yaml (units SI, angles as the keys say).
struct AsBuiltTolerances {
  // Bricks (EN 771-1).
  std::string brick_category{"T1"};           ///< T1 or T2
  double brick_mean_limit_factor{0.40};       ///< mean deviation limit [mm per sqrt(mm)] of the category
  double brick_mean_sigma_of_limit{0.333};    ///< a batch mean's sigma as a fraction of the limit
  double brick_range_factor{0.6};             ///< R1 range [mm per sqrt(mm)] = 4 sigma of single bricks
  double brick_lean_sigma_deg{0.15};          ///< out of square: how a brick leans
  // Floor (DIN 18202 Table 3).
  std::vector<double> floor_limit_distance_m{0.1, 1.0, 4.0};
  std::vector<double> floor_limit_mm{2.0, 4.0, 10.0};
  int floor_waves{8};
  double floor_wavelength_min{1.2}, floor_wavelength_max{9.0};  ///< [m]
  double floor_fraction_min{0.4}, floor_fraction_max{1.0};      ///< of the limits
  // Base on its tracks.
  double base_seat_sigma_deg{0.03};
  double base_compliance_min{2e-7}, base_compliance_max{6e-7};  ///< [rad / (N m)]
  double arm_mass_kg{435.0};
  double arm_com_fraction{0.4};
  double payload_kg{2.6};
  double track_contact_length_m{1.6};
  // Arm.
  double joint_offset_sigma_deg{0.02};
  double link_length_sigma_m{0.0008};
  double link_angle_sigma_deg{0.01};
  double gravity_compliance_min{5e-8}, gravity_compliance_max{1.5e-7};  ///< [rad / (N m)]
  double encoder_noise_deg{0.0005};
  // Lasers.
  LrfUnitTolerances laser;
  double mount_sigma_m{0.003};
  double mount_sigma_deg{0.3};
  // The IMU on the chassis: its sensor frame against the base frame.
  double imu_mount_sigma_deg{0.07};
  // Gripper.
  double release_sigma_xy_m{0.0003};
  double release_sigma_per_lean_deg_m{0.001};
  double release_sigma_yaw_deg{0.05};
  // The calibration cube (ISO 2768-1 general tolerances).
  double cube_size_limit_m{0.0005};
  double cube_size_sigma_of_limit{0.333};

  /// Read data/sim/as_built.yaml (every section required, unknown keys rejected).
  static AsBuiltTolerances FromConfig(const ConfigNode& root);
  static AsBuiltTolerances Load(const std::string& path);
};

/// One draw: the machine and world of one seed. Default-constructed = the exact world.
struct AsBuilt {
  bool exact{true};
  // Bricks: each brick's size is normal around the batch mean.
  Eigen::Vector3d brick_mean_size{Eigen::Vector3d::Zero()};   ///< [m] this batch's mean
  Eigen::Vector3d brick_size_sigma{Eigen::Vector3d::Zero()};  ///< [m] single bricks about it
  double brick_lean_sigma{0.0};                               ///< [rad]
  FloorField floor;
  double floor_step_1m{0.0}, floor_step_4m{0.0};              ///< [m] its worst step measures
  // Base.
  double base_seat_sigma{0.0};       ///< [rad]
  double base_compliance{0.0};       ///< [rad / (N m)]
  double arm_mass_kg{0.0}, arm_com_fraction{0.4}, payload_kg{0.0};
  double track_contact_length{1.6};  ///< [m]
  // Arm.
  Vector6d joint_offsets{Vector6d::Zero()};         ///< [rad] physical = reported + offset
  std::vector<Pose3> link_errors;                   ///< per chain segment: true tip = design tip * error
  Eigen::Vector2d gravity_compliance{Eigen::Vector2d::Zero()};  ///< joints 2 and 3 [rad / (N m)]
  double encoder_noise{0.0};                        ///< [rad]
  // Lasers (each unit its own options: bias curve, noise, warm-up) and mounts.
  LrfOptions base_laser, arm_laser;
  std::array<double, 6> base_laser_mount_error{}, arm_laser_mount_error{};
  Eigen::Vector3d imu_mount_error_rpy{Eigen::Vector3d::Zero()};  ///< [rad] sensor frame = base frame turned by this
  // Gripper.
  double release_sigma_xy{0.0}, release_sigma_per_lean{0.0}, release_sigma_yaw{0.0};
  // The calibration cube: its edges' deviation from the drawing's size (x, y, z of its box).
  Eigen::Vector3d cube_size_error{Eigen::Vector3d::Zero()};  ///< [m]

  /// The flange's error at a pose from the kinematic errors alone (offsets and links) [m].
  double FlangeErrorAt(const RobotModel& design, const Vector6d& q) const;
  /// The robot's true kinematic chain: the design chain with the link errors applied.
  RobotModel TrueRobot(const RobotModel& design) const;
};

/// Draw the as-built world for `seed` around the design (robot, site, the nominal laser model).
AsBuilt DrawAsBuilt(const AsBuiltTolerances& tolerances, const RobotModel& design_robot, const Site& design_site,
                    const LrfOptions& nominal_laser, std::uint64_t seed);

}  // namespace ifab::sim
