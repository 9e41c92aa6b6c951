#pragma once
/// \file
/// Running the base state estimator over a recorded CARMEN log and scoring it against reference
/// relations with the metric of Kuemmerle et al. 2009: for each relation (t1, t2, delta*),
/// E = (P(t1)^-1 * P(t2)) * delta*^-1; translational error |t(E)| [m], rotational |angle(E)| [deg].
/// This is the library side of `ifab estimate LOG [--relations FILE] [--config FILE] --out DIR`.
///
/// CARMEN logs have no gyro. The rotation input of eq. 2 is the wheel odometry's heading change
/// between consecutive scans, fed to the estimator as one GyroSample per scan (rate = change /
/// interval); metrics.json says so under "rotation_input". The odometry step also seeds the
/// initial guess (configurable, see EstimateLogOptions). Where the odometry stalled (the same
/// pose repeated, then a jump), the jump is replaced by interpolation (see RepairOdometryStalls).
///
/// Time stamps: a log's stamps may go backwards (intel.clf: 631 times, where a scan's stamp is
/// late by up to ~0.9 s while the odometry shows the file order is the true order). Scans are
/// processed in file order on a repaired, increasing clock: a stamp later than any following
/// stamp is replaced by interpolation between its nearest trustworthy neighbours (by index),
/// and consecutive scans are kept at least 1 ms apart (intel.clf: 999 stamps interpolated,
/// 1470 moved by less than 1 ms). The original stamps are kept for the relations (which refer
/// to them) and are written to the trajectory beside the repaired ones. The repaired clock only
/// drives the horizon, the gyro interval and the constant-velocity prior; the rotation input is
/// the odometry's heading change per scan, whatever the stamps.

#include <array>
#include <nlohmann/json.hpp>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "ifab/base/estimator/base_state_estimator.h"
#include "ifab/base/estimator/carmen_log.h"
#include "ifab/core/angles.h"

namespace ifab::base {

/// Everything `ifab estimate` reads from its YAML config.
struct EstimateLogOptions {
  EstimatorOptions estimator;     ///< section `estimator`
  CarmenReadOptions reader;       ///< section `log` (flaser_fov_deg, range_max, range_min)
  Pose2 T_base_laser;             ///< `log.T_base_laser: [x, y, theta_deg]` (identity: laser = base)
  double short_span{20.0};        ///< [s] relations spanning at most this go under short_span
  double stamp_tolerance{1e-3};   ///< [s] a relation's time matches a scan's stamp within this
  /// A stalled odometry (the same pose over several scans, then a heading jump larger than
  /// this) has its jump spread evenly over the stalled scans (`log.odometry_stall_jump_deg`).
  double odometry_stall_jump_rad{DegToRad(10.0)};
  double odometry_stall_jump_m{0.4};  ///< `log.odometry_stall_jump_m`
  /// Seed each scan's initial guess with the odometry step (`log.odometry_translation_hint`).
  /// Only the initial guess: eq. 3 has no odometry term.
  bool odometry_translation_hint{true};

  /// Read a config file of the form {estimator: {...}, log: {...}, evaluation: {...}}.
  static EstimateLogOptions FromConfig(const ConfigNode& node);
};

/// mean, std (population) and max of a list of errors; all 0 for an empty list.
struct ErrorStats {
  double mean{0.0};
  double std{0.0};
  double max{0.0};
  static ErrorStats Of(const std::vector<double>& values);
};

struct RelationErrors {
  int relations{0};            ///< relations scored
  int unmatched{0};            ///< relations whose t1 or t2 matched no scan stamp (not scored)
  ErrorStats translation_m;
  ErrorStats rotation_deg;
  /// Every scored relation: t1, t2 [s], translation error [m], rotation error [deg] (the report
  /// page draws them over time).
  std::vector<std::array<double, 4>> each;
};

/// Score a trajectory (stamps[i], poses[i]) against relations, using those with
/// |t2 - t1| <= max_span. Relation times are looked up among the stamps within `tolerance`.
RelationErrors EvaluateRelations(const std::vector<Seconds>& stamps, const std::vector<Pose2>& poses,
                                 const std::vector<Relation>& relations,
                                 double max_span = std::numeric_limits<double>::infinity(),
                                 double tolerance = 1e-3);

/// The repaired processing clock for a log's stamps (see the file comment); reports how many
/// late stamps were interpolated and how many were moved forward to keep 1 ms steps.
std::vector<Seconds> RepairStamps(const std::vector<Seconds>& stamps, int* interpolated = nullptr,
                                  int* nudged = nullptr);

/// Odometry with stalls repaired: where the position (or the heading) repeats exactly over a
/// run of scans and then jumps by more than stall_jump_m (stall_jump_rad), the run is replaced
/// by interpolation up to the sample after the jump. MIT CSAIL's odometry freezes for up to
/// five scans, then catches up with 0.8-0.9 m steps (4 m/s).
std::vector<Pose2> RepairOdometryStalls(const std::vector<Pose2>& odom, double stall_jump_m,
                                        double stall_jump_rad, int* repaired = nullptr);

/// Run the estimator over the log; if out_dir is non-empty write out_dir/trajectory.csv and
/// out_dir/metrics.json. relations_path may be empty: then "<log without .clf>.relations" is
/// used if it exists, else no errors are computed. Returns the metrics JSON. Throws InputError
/// on unreadable or broken input.
nlohmann::json RunEstimateOnLog(const std::string& log_path, const std::string& relations_path,
                                const EstimateLogOptions& options, const std::string& out_dir);

}  // namespace ifab::base
