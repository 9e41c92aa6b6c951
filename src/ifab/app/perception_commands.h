#pragma once
/// \file
/// The work behind `ifab register` and `ifab calibrate`, so the subcommands only parse flags.
/// Both throw InputError for bad input (named file, field, what was expected) and return the
/// JSON they wrote.
///
///   ifab register CLOUD.ply --site SITE.yaml [--frame site|sensor] [--guess "x y z r p y"]
///                 [--sensor NAME|FILE] [--crop ...] [--fix BODY:x,y,z,rx,ry,rz] --out DIR
///     --frame site (default): CLOUD.ply in the robot base frame; the guess is the robot's pose in
///     the site (m, deg); the result is T_site_base. --frame sensor: the site YAML gives every
///     object's pose guess in the cloud's own frame and each object is solved apart; the result
///     is each object's pose and each plane's normal and offset in that frame.
///     Points carry laser origins (origin_x/y/z, as written by ifab) or one --origin for all
///     (default: the cloud frame's origin with --frame sensor).
///     Writes DIR/registration.json and DIR/labelled.ply (fields label: 0 inlier, 1 shadow,
///     2 outlier, 3 fixed, 4 grazing, 5 cropped; body: index or -1).
///
///   ifab calibrate SWEEP.json... --out DIR [--target TARGET.yaml] [--mount "x y z r p y"]
///     sweep files as in sweep_io.h; the target (default data/perception/cube_target.yaml) gives
///     the cube's size and a guess of its pose; the mount guess defaults to the URDF's.
///     Writes DIR/calibration.json and DIR/arm_laser_mount.yaml (a `mounts:` section).
///
/// Options: --config FILE overlays data/perception/perception.yaml (only the keys it names
/// change). --sensor NAME (data/sensors/NAME.yaml) or FILE takes the noise model from a sensor
/// profile's `noise:` section; without it the noise scale is estimated from the residuals
/// (`--sensor config` keeps the config's noise settings as they are). Unless the config sets
/// gate_sigmas, points more than 3 sigmas of the noise model off count as outliers.

#include <nlohmann/json.hpp>

#include <iosfwd>
#include <string>
#include <vector>

#include "ifab/core/se3.h"

namespace ifab {

/// "x y z roll pitch yaw" (spaces or commas; metres and degrees unless `radians`).
Pose3 ParsePoseArgument(const std::string& text, const std::string& what, bool radians = false);

/// The calibration target file (`data/perception/cube_target.yaml`): the cube's size, its pose
/// guess in the base frame (degrees in the file) and the floor height guess.
struct CubeTarget {
  double size{0.25};
  Pose3 T_base_cube{Pose3::Identity()};
  double ground_z{0.0};
};
/// Reads `path`, or the shipped cube_target.yaml when it is empty.
CubeTarget LoadCubeTarget(const std::string& path);

struct RegisterCommandOptions {
  std::string cloud_path;   ///< PLY
  std::string site_path;    ///< site YAML
  std::string frame{"site"};  ///< site: cloud in the robot base frame, solve T_site_base; sensor: objects in the cloud's frame
  std::string guess;        ///< --frame site: T_site_base guess, "x y z roll pitch yaw" [m, deg]
  std::string out_dir;      ///< created if missing
  std::string config_path;  ///< optional YAML overlaid on data/perception/perception.yaml
  std::string sensor;       ///< profile name or file; empty: estimate the noise; "config": as configured
  std::string origin;       ///< "x y z": one laser origin for clouds without origin fields
  std::string crop;         ///< "box x0 y0 z0 x1 y1 z1" or "radius R [x y z]" (cloud frame, m)
  std::vector<std::string> fix;  ///< "BODY:z,rx,ry": components held at the guess
  bool one_body{false};     ///< --frame site: ground and site as one rigid body
};
nlohmann::json RegisterCommand(const RegisterCommandOptions& options);

struct CalibrateCommandOptions {
  std::vector<std::string> sweep_paths;
  std::string target_path;  ///< default data/perception/cube_target.yaml
  std::string robot_path;   ///< default data/robots/insitu_fabricator.urdf
  std::string mount_guess;  ///< "x y z roll pitch yaw" [m, deg]; default the URDF's tool0 -> arm_laser
  std::string out_dir;
  std::string config_path;  ///< optional YAML with `calibration:` and `scan_assembly:` sections (overlay)
  std::string sensor;       ///< as for register
};
nlohmann::json CalibrateCommand(const CalibrateCommandOptions& options);

/// Print a registration / calibration result's summary; returns the exit code (0 usable, 1 not).
int ReportRegistration(const nlohmann::json& j, const std::string& out_dir, std::ostream& out);
int ReportCalibration(const nlohmann::json& j, const std::string& out_dir, std::ostream& out);

}  // namespace ifab
