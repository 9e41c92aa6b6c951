#pragma once
/// \file
/// Running the base state estimator over a recorded CARMEN log and scoring it against reference
/// relations with the metric of Kuemmerle et al. 2009: for each relation (t1, t2, delta*),
/// E = (P(t1)^-1 * P(t2)) * delta*^-1; translational error |t(E)| [m], rotational |angle(E)| [deg].
/// This is the runner of `ifab estimate LOG [--relations FILE] [--config FILE] --out DIR`; it
/// lives in experiments/ because it scores against reference data and writes files (the
/// estimator itself, base/estimator/, does neither).
///
/// One config for every recorded log (data/estimator/carmen.yaml): what differs between robots
/// comes from the log (carmen_log.h's LogGeometry: beams, field of view, resolution, no-return
/// code and maximum range, scan rate, the laser's mount from ROBOTLASER1's laser pose).
///
/// The odometry (`log.odometry`):
///  - `factor` (default): the odometry step since the previous scan is a factor of eq. 3 with
///    the noise model of motion_prior.h (growing with distance and turn), weighed against the
///    match by the match's information; it is the prior of the Mahalanobis gate and decides
///    the directions the scan leaves degenerate. No gyro term (the heading is in the factor).
///  - `gyro`: the paper's eq. 2 with the odometry's heading change per scan as the gyro (one
///    rate sample per scan); the odometry step seeds the initial guess only.
/// A scan whose odometry pose repeats the previous one exactly (x, y and theta) carries no new
/// odometry (a robot at rest, or an odometry message that did not arrive: MIT CSAIL's freezes
/// for up to five scans, then jumps 0.9 m). Its prior is the constant-velocity prediction,
/// with the same noise model applied to that predicted step, and the next scan with new
/// odometry takes the odometry's motion since the last updated scan.
///
/// Time stamps: a log's stamps may go backwards (intel.clf: 631 times, where a scan's stamp is
/// late by up to ~0.9 s while the odometry shows the file order is the true order). Scans are
/// processed in file order on a repaired, increasing clock: a stamp later than any following
/// stamp is replaced by interpolation between its nearest trustworthy neighbours (by index),
/// and consecutive scans are kept at least 1 ms apart. The original stamps are kept for the
/// relations (which refer to them) and are written to the trajectory beside the repaired ones.

#include <array>
#include <nlohmann/json.hpp>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "ifab/base/estimator/base_state_estimator.h"
#include "ifab/base/estimator/carmen_log.h"
#include "ifab/core/angles.h"

namespace ifab::experiments {

using base::CarmenReadOptions;
using base::EstimatorOptions;
using base::Relation;

/// How the log's odometry enters (see the file comment).
enum class LogOdometry { kFactor, kGyro };

/// Everything `ifab estimate` reads from its YAML config.
struct EstimateLogOptions {
  EstimatorOptions estimator;     ///< section `estimator`
  CarmenReadOptions reader;       ///< section `log`: reader overrides (none needed for CARMEN logs)
  LogOdometry odometry{LogOdometry::kFactor};  ///< `log.odometry`: factor | gyro
  base::OdometryNoise odometry_noise;          ///< `log.odometry_noise` (motion_prior.h)
  double short_span{20.0};        ///< [s] relations spanning at most this go under short_span
  double false_ok_span{5.0};      ///< [s] false_ok_rate looks at relations spanning at most this
  double false_ok_error{0.2};     ///< [m] ... whose translation error exceeds this
  double stamp_tolerance{1e-3};   ///< [s] a relation's time matches a scan's stamp within this

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

/// Among the relations spanning at most max_span, the fraction whose translation error exceeds
/// max_error while every scan from the one at t1 to the one at t2 (in processing order) was
/// usable (status ok, degenerate or reference): the estimator claimed ok and was wrong.
struct FalseOk {
  int relations{0};  ///< relations spanning at most max_span that were scored
  int false_ok{0};   ///< of those, wrong while all scans between were ok
  double rate{0.0};
};
FalseOk FalseOkRate(const std::vector<Seconds>& stamps, const std::vector<Pose2>& poses,
                    const std::vector<char>& usable, const std::vector<Relation>& relations,
                    double max_span, double max_error, double tolerance = 1e-3);

/// Run the estimator over the log; if out_dir is non-empty write out_dir/trajectory.csv and
/// out_dir/metrics.json. relations_path may be empty: then "<log without .clf>.relations" is
/// used if it exists, else no errors are computed. Returns the metrics JSON. Throws InputError
/// on unreadable or broken input.
nlohmann::json RunEstimateOnLog(const std::string& log_path, const std::string& relations_path,
                                const EstimateLogOptions& options, const std::string& out_dir);

}  // namespace ifab::experiments
