#pragma once
/// \file
/// The work behind `ifab register` and `ifab calibrate`, so the app's wrappers only parse flags.
/// Both throw InputError for bad input (named file, field, what was expected) and return the
/// JSON they wrote.
///
///   ifab register CLOUD.ply --site SITE.yaml --guess "x y z roll pitch yaw" --out DIR
///     CLOUD.ply in the robot base frame, with per-point laser origins (origin_x/y/z, as written
///     by ifab) or one --origin for all; the guess is the robot's pose in the site (m, deg).
///     Writes DIR/registration.json (T_site_base, its covariance, every body's pose, covariance,
///     inliers and unconstrained directions, shadow points, warnings) and DIR/labelled.ply
///     (fields label: 0 inlier, 1 shadow, 2 outlier, 3 fixed, 4 grazing; body: index or -1).
///
///   ifab calibrate SWEEP.json... --out DIR [--target TARGET.yaml] [--mount "x y z r p y"]
///     sweep files as in sweep_io.h; the target (default data/perception/cube_target.yaml) gives
///     the cube's size and a guess of its pose; the mount guess defaults to the URDF's.
///     Writes DIR/calibration.json and DIR/arm_laser_mount.yaml (a `mounts:` section).

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

#include "ifab/core/se3.h"

namespace ifab {

/// "x y z roll pitch yaw" (spaces or commas; metres and degrees unless `radians`).
Pose3 ParsePoseArgument(const std::string& text, const std::string& what, bool radians = false);

/// A pose as JSON: {"xyz": [m], "rpy_deg": [deg], "matrix": 4 rows of 4}.
nlohmann::json PoseToJson(const Pose3& pose);

struct RegisterCommandOptions {
  std::string cloud_path;   ///< PLY, robot base frame
  std::string site_path;    ///< site YAML
  std::string guess;        ///< T_site_base guess, "x y z roll pitch yaw" [m, deg]
  std::string out_dir;      ///< created if missing
  std::string config_path;  ///< optional YAML with `registration:` (default data/perception/perception.yaml)
  std::string origin;       ///< "x y z": one laser origin for clouds without origin fields
  bool one_body{false};     ///< ground and site as one rigid body (else the ground apart, as the paper)
};
nlohmann::json RegisterCommand(const RegisterCommandOptions& options);

struct CalibrateCommandOptions {
  std::vector<std::string> sweep_paths;
  std::string target_path;  ///< default data/perception/cube_target.yaml
  std::string robot_path;   ///< default data/robots/insitu_fabricator.urdf
  std::string mount_guess;  ///< "x y z roll pitch yaw" [m, deg]; default the URDF's tool0 -> arm_laser
  std::string out_dir;
  std::string config_path;  ///< optional YAML with `calibration:` and `scan_assembly:` sections
};
nlohmann::json CalibrateCommand(const CalibrateCommandOptions& options);

}  // namespace ifab
