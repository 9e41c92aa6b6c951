#pragma once
/// \file
/// The options of the base state estimator (one struct, one YAML section `estimator:`), grouped
/// by the part that reads them: scan preprocessing (scan_preprocessing.h), eq. 1 and its
/// association (association.h), the reference set (keyframe_map.h), eq. 2 and the solve
/// (eq3_solver.h), and the quality check (match_quality.h, degeneracy.h).

#include <string>
#include <vector>

#include "ifab/base/estimator/commanded_motion.h"
#include "ifab/core/config.h"

namespace ifab::base {

/// How a measurement point is compared with the reference points.
enum class MatchResidual {
  kKernel,       ///< eq. 1 as written: Gaussian kernels over reference points within a radius
  kPointToLine,  ///< improvement (off by default): distance to the reference scan's local line
};

/// How reference points count in eq. 1's sum.
enum class ReferenceWeighting {
  kNone,       ///< eq. 1 as written: every reference point counts once
  kArcLength,  ///< improvement: each counts by the length of surface it samples, so the sum
               ///< approximates the kernel integrated along the surface and no longer pulls
               ///< measurement points towards where the reference happens to be denser
};

/// How a scan's points are thinned to about min_point_spacing (reference_point_spacing) apart,
/// walking along the scan.
enum class Thinning {
  /// Keep each point that lies at least the spacing from the last kept one. Under range noise
  /// this keeps points whose noise carried them forward along the scan, and on a wall seen
  /// obliquely that noise also moves them off the wall with a sign that flips at the foot of the
  /// perpendicular: the kept points show the wall turned, by an amount that depends on the
  /// spacing, so a scan matched against a reference thinned at another spacing (or seen from
  /// another place) comes out turned too, by ~0.01 deg per match, always the same way. Chained
  /// over keyframes that is a heading drift of ~0.5 deg per maneuver.
  kNearestBeyondSpacing,
  /// Keep a point when the previous one plus one more step reaches the spacing: whether a point
  /// is kept depends only on the points before it, never on its own noise, so the kept points
  /// are unbiased. (Their spacing still follows the noise; over raw reference points that leaves
  /// ~0.002 deg per match, which interpolate_reference removes.) The paper does not say how it
  /// thins; this is the default because the other one is biased.
  kNoiseIndependent,
};

/// How the translation of the initial guess is predicted when no motion hint is given (the
/// rotation comes from the gyro).
enum class MotionPrior {
  kNone,              ///< start from the previous pose
  kConstantVelocity,  ///< previous pose + last velocity * dt
};

struct EstimatorOptions {
  // Scan preprocessing.
  double min_range{0.1};           ///< [m] beams shorter than this are dropped
  double max_range{29.0};          ///< [m] beams longer than this are dropped
  double min_point_spacing{0.05};  ///< [m] consecutive kept points are about this far apart
  Thinning thinning{Thinning::kNoiseIndependent};  ///< how points are picked (both scan kinds)
  /// Improvement: move each beam to the base pose at the scan's middle time with the twist of
  /// the base (gyro rate, last velocity) and the beam times (LaserScan::time_increment), instead
  /// of the paper's scan "rigid at the time of the middle point". While turning, a rigid scan is
  /// stretched in angle by omega * sweep time / field of view, and the estimated turn with it
  /// (~0.1 % of every turn, one sign per turning sense). No effect when time_increment is 0.
  bool deskew{false};
  int max_points{400};             ///< measurement points kept per scan (evenly thinned beyond)
  int max_beams{1081};             ///< buffers are sized for scans of this many beams
  int min_points{40};              ///< fewer valid points than this: the scan is not matched

  // Eq. 1.
  MatchResidual residual{MatchResidual::kKernel};  ///< eq. 1 or the point-to-line variant
  double sigma{0.05};  ///< [m] kernel scale sigma: G(p_M - p_R, 2 sigma^2 I)
  /// [m] larger sigmas solved first (coarse to fine, widens the basin); empty = paper (one sigma)
  std::vector<double> coarse_sigmas{};
  double search_radius_sigmas{4.0};  ///< reference points within this many sqrt(2)*sigma count
  int neighbors_per_reference{8};    ///< at most this many nearest points per reference scan

  // Reference scans (receding horizon of keyframes).
  int num_reference_scans{3};           ///< keyframes matched against (the reference set)
  /// Improvement: keyframes kept (within the horizon); when more than num_reference_scans, each
  /// scan is matched against the num_reference_scans nearest to its predicted pose, and
  /// revisiting a place reuses its keyframes instead of adding new ones (a keyframe map without
  /// graph optimisation). 0: keep num_reference_scans (the paper's receding set).
  int keyframe_capacity{0};
  double keyframe_distance{0.15};       ///< [m] a new keyframe when every kept one is this far
  double keyframe_angle_deg{5.0};       ///< [deg] ... or turned this much from the pose
  double keyframe_interval{1e9};        ///< [s] ... or this much time while moving
  double horizon{60.0};                 ///< [s] keyframes older than this are dropped (not the newest)
  double reference_point_spacing{0.04};  ///< [m] spacing of the points kept in a keyframe
  /// Reference points whose nearer neighbour along the scan is farther than this many sigma are
  /// dropped: samples sparser than the kernel (grazing walls, far range, lone mixed pixels)
  /// make eq. 1 lumpy and hold the pose at the reference. 0 keeps every point.
  double max_reference_gap_sigmas{4.0};
  /// Measurement points whose nearest reference point lies within this many (final) sigma of the end of
  /// its chain (depth jump, occlusion, range or density cut-off) skip that reference: the kernel
  /// sum is one-sided there and would pin the pose to the reference's. 0 keeps every point.
  double end_margin_sigmas{4.0};
  ReferenceWeighting reference_weighting{ReferenceWeighting::kNone};  ///< eq. 1 or arc length
  /// Improvement: sample each reference scan as a polyline (consecutive points within
  /// max_reference_gap_sigmas linked, not across depth jumps) every reference_point_spacing,
  /// instead of keeping its raw (thinned) points. Sparse far or grazing samples otherwise make
  /// eq. 1 lumpy and hold the pose at the reference (motion is underestimated).
  bool interpolate_reference{false};

  // Eq. 2.
  double gyro_weight{1e6};  ///< c_G [1/rad^2]: weight of the squared gyro error against sum(1 - G)
  MotionPrior motion_prior{MotionPrior::kConstantVelocity};  ///< translation of the initial guess
  /// [1/m^2, 1/rad^2] weak quadratic pull to the predicted pose, added to eq. 3 so that a
  /// direction the scan does not observe stays at the prediction (negligible elsewhere: the
  /// scan's information is ~1e4-1e6). 0 = eq. 3 as written.
  double prior_weight{1.0};

  // Solver.
  int max_associations{4};      ///< data-association rounds per sigma level
  int max_iterations{10};       ///< LM iterations per association round
  double converged_step{1e-4};  ///< [m or rad] stop re-associating when the pose moved less

  // Failure detection.
  double min_matched_fraction{0.3};  ///< fewer points with a reference neighbour: failed
  double degeneracy_ratio{0.02};     ///< min/max eigenvalue of the (scaled) information below: degenerate
  /// With an informative prior only (0: off). Degeneracy from the scene's structure rather than
  /// the kernel sum's curvature (which ripples along a wall of discrete reference points and
  /// fakes information along it): the point-to-line information of the matched points, each
  /// with the local normal of its nearest reference point (Zhang, Kaess, Singh 2016). Its
  /// (scaled) directions weaker than this fraction of its strongest are removed from the match's
  /// information, so the prior alone decides them, and they are reported as degenerate.
  double structure_degeneracy_ratio{0.0};
  /// [m] radius of the PCA that gives the reference points' normals for the above.
  double structure_normal_radius{0.3};
  double max_rotation_jump_deg{5.0}; ///< [deg] match disagrees with the gyro by more: failed
  double max_translation_jump{0.3};  ///< [m] match farther from the prediction: failed
  /// This many scans in a row with too few matched points (the robot left the mapped area)
  /// restart the references from the prior's pose (0: never). Gate rejections do not: the
  /// prior's covariance grows with every flagged scan until a good match fits again.
  int reseed_after_failures{5};
  /// Score check: of the matched points, at least this fraction must have their nearest
  /// reference point within 2 sigma (kernel >= exp(-1)), else kPoorScore. 0: off.
  double min_inlier_fraction{0.0};
  /// Mahalanobis gate (only with an informative motion prior, e.g. the odometry factor): the
  /// match is flagged when its innovation from the prior, over the directions the scan
  /// constrains, exceeds the chi-square quantile of this probability (their combined
  /// covariance: the match's inverse information and the prior's). 0: off.
  double gate_probability{0.999};
  /// The gate tests the translation only (heading marginalised out, 2 dof): a laser line's
  /// odometry heading may lag the scan on fast turns, so the heading innovation is not a
  /// sign of a wrong match there; a match sliding along a corridor shows in the translation.
  bool gate_translation_only{false};
  /// Window gate (only with an informative motion prior): the match's position against the
  /// estimate window_gate_distance of odometry travel back chained with the motion steps since
  /// (their covariance compounded over the span, plus both ends' own), translation only,
  /// flagged beyond the chi-square (2 dof) quantile of this probability. A match that clings to
  /// a keyframe while the robot moves falls behind the chain by the whole span's travel, while a
  /// per-scan jitter or heading lag of the odometry averages out over the span instead of
  /// rejecting right matches (a per-scan gate does not tell the two apart). 0: off.
  double window_gate_probability{0.0};
  /// [m] The window gate's span in odometry travel (at most 256 scans back).
  double window_gate_distance{1.0};
  /// With an informative prior: the prior alone decides the directions the scan constrains
  /// less than the prior does (Zhang et al.'s solution remapping, see degeneracy.h).
  bool remap_degenerate{true};
  /// Identify the scale of the motion measurement's covariance from the log itself: over the
  /// last this many matches (that passed coverage and score), the median of the squared
  /// Mahalanobis distance per direction, times the scale it was computed with, over the
  /// chi-square median: the scale that makes the innovations consistent (never below 1: the
  /// given noise model is the least a caller claims). 0: the covariance as given.
  int prior_scale_window{0};

  /// For the caller that feeds the estimator (the mission): hand the commanded track speeds to
  /// AddScan as a weak motion prior (commanded_motion.h). Off: the paper's gyro-only eq. 2.
  CommandedSpeedOptions commanded_speeds{};

  /// Read the fields a YAML map names (unknown keys are rejected); defaults stay otherwise.
  static EstimatorOptions FromConfig(const ConfigNode& node);
  /// Empty if valid, else what is wrong.
  std::string Validate() const;
};

}  // namespace ifab::base
