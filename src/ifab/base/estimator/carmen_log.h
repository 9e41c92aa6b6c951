#pragma once
/// \file
/// Readers for recorded 2D laser logs: CARMEN logs (FLASER, ROBOTLASER1 and ODOM lines) and
/// the reference relations of the Freiburg SLAM benchmark (Kuemmerle et al. 2009).
///
/// CARMEN lines (whitespace separated; comments start with '#'; other message types are
/// skipped):
///   FLASER n r_1..r_n x y theta odom_x odom_y odom_theta timestamp [hostname logger_timestamp]
///   ROBOTLASER1 type start_angle fov resolution max_range accuracy remission_mode n r_1..r_n
///               m rem_1..rem_m laser_x laser_y laser_theta robot_x robot_y robot_theta
///               tv rv forward_safety side_safety turn_axis timestamp [hostname logger_timestamp]
///   ODOM x y theta tv rv accel timestamp [hostname logger_timestamp]
/// A line of a known type that cannot be parsed throws InputError naming the file and line.
///
/// FLASER lines carry no beam angles: n beams cover `flaser_fov_deg` starting at -fov/2, with
/// step fov/(n-1) when n is odd (181, 361: both ends included, as the SICK LMS delivers) and
/// fov/n when n is even (180: the last beam one step short of +fov/2).

#include <iosfwd>
#include <string>
#include <vector>

#include "ifab/core/se2.h"
#include "ifab/msgs/msgs.h"

namespace ifab::base {

struct CarmenReadOptions {
  double flaser_fov_deg{180.0};  ///< [deg] field of view of FLASER lines (they carry no angles)
  /// [deg] if set (> 0), FLASER beam i is at flaser_first_deg + i * flaser_step_deg instead of
  /// the rule above (flaser_first_deg is then required too).
  double flaser_step_deg{0.0};
  double flaser_first_deg{-90.0};  ///< [deg] used with flaser_step_deg
  double range_max{1000.0};      ///< [m] LaserScan::range_max cap (the log's own maximum applies below it)
  double range_min{0.0};         ///< [m] LaserScan::range_min
};

/// One laser scan of a log with the poses its line carries.
struct LogScan {
  LaserScan scan;      ///< stamp.t = the line's timestamp field; time_increment 0 (unknown)
  Pose2 odom;          ///< robot odometry pose at the scan (FLASER odom_*, ROBOTLASER1 robot_*)
  Pose2 laser_pose;    ///< laser pose of the line (FLASER x y theta, ROBOTLASER1 laser_*)
  int line{0};         ///< line number in the file (1-based)
};

/// One ODOM line.
struct LogOdometry {
  Seconds t{0.0};
  Pose2 pose;
  int line{0};
};

/// The laser's geometry as the log itself tells it (see DeriveLogGeometry); nothing here comes
/// from a config.
struct LogGeometry {
  std::string message;        ///< "FLASER" or "ROBOTLASER1" (the first laser message type)
  int beams{0};               ///< beams per scan (the most common count)
  double fov{0.0};            ///< [rad] field of view: (beams - 1) * resolution
  double angle_min{0.0};      ///< [rad] first beam
  double resolution{0.0};     ///< [rad] angle between beams
  /// [m] the no-return code: a reading this large repeated far more often than any reading
  /// within a metre below it (SICK: 81.83 / 81.91 in 80 m mode, 50.00 in some drivers; CARMEN
  /// writes max_range for no return). 0 if none was found. Such readings are set to NaN.
  double no_return_code{0.0};
  double max_range{0.0};      ///< [m] the largest real return (below the code)
  double scan_rate{0.0};      ///< [Hz] from the median interval between scan stamps
  /// The laser's mount on the robot: T_robot_laser from each line's laser pose and robot pose
  /// (the median over the lines; identity when the log does not distinguish them).
  Pose2 T_base_laser;
  bool laser_offset_in_log{false};  ///< the laser and robot poses of the lines differ
};


struct CarmenLog {
  std::string file;
  LogGeometry geometry;                ///< from the log alone (DeriveLogGeometry)
  std::vector<LogScan> scans;          ///< in file order
  std::vector<LogOdometry> odometry;   ///< ODOM lines, in file order
  int skipped_lines{0};                ///< comments, empty lines and other message types
};

/// Derive the geometry from the scans and apply it to them: readings at the no-return code
/// become NaN and every scan's range_max becomes the largest real return. Called by the
/// readers below.
LogGeometry DeriveLogGeometry(std::vector<LogScan>* scans, const std::string& message);

/// Read a CARMEN log; throws InputError if the file cannot be opened or a line is broken.
CarmenLog ReadCarmenLog(const std::string& path, const CarmenReadOptions& options = {});
/// Same from a stream; `name` stands for the file in messages.
CarmenLog ParseCarmenLog(std::istream& in, const std::string& name,
                         const CarmenReadOptions& options = {});

/// A reference relation: the pose at t2 expressed in the frame of the pose at t1.
struct Relation {
  Seconds t1{0.0};
  Seconds t2{0.0};
  Pose2 delta;   ///< (x, y, yaw) of "t1 t2 x y z roll pitch yaw"; z, roll, pitch must be ~0
  int line{0};
};

/// Read a relations file ("t1 t2 x y z roll pitch yaw" per line; one header line allowed,
/// '#' comments and empty lines skipped). Throws InputError naming the file and line.
std::vector<Relation> ReadRelations(const std::string& path);
std::vector<Relation> ParseRelations(std::istream& in, const std::string& name);

}  // namespace ifab::base
