#pragma once
/// \file
/// The quality check of a match, after the solve: the parts that decide whether the status is
/// ok, degenerate or flagged, beside degeneracy.h (the eigen-analysis against the prior, the
/// remapping and the per-scan Mahalanobis gate).
///
/// - the structure check: directions the scene's point-to-line structure leaves (nearly)
///   unconstrained are removed from the match's information (StructureTrustedInformation);
/// - the gate thresholds: chi-square quantiles of Options::gate_probability by dof (GateTable);
/// - the window gate: the match against the estimate a span of odometry travel back chained
///   with the motion steps since (WindowGate);
/// - the prior's scale identified from the innovations (PriorScale).
/// Coverage (matched fraction) and score (inlier fraction) come from association.h.

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <limits>
#include <vector>

#include "ifab/base/estimator/estimator_options.h"
#include "ifab/base/estimator/motion_prior.h"
#include "ifab/core/se2.h"

namespace ifab::base {

/// info_scan (x, y, theta) without the directions along which the structure information S
/// (Association::StructureInformation) is weaker than `ratio` of its strongest, both scaled with
/// theta in metres at `lever`: the kernel sum's curvature there is no real information.
Eigen::Matrix3d StructureTrustedInformation(const Eigen::Matrix3d& info_scan, const Eigen::Matrix3d& S,
                                            double lever, double ratio);

/// Chi-square quantiles of a probability (infinite for probability 0: the gate is off) and
/// medians, by degrees of freedom 1-3.
struct GateTable {
  explicit GateTable(double probability);
  std::array<double, 4> quantile{};
  std::array<double, 4> median{};
};

/// The window gate (Options::window_gate_probability): a fixed ring of the last scans' final
/// poses and covariances with the motion step that led to each (no allocation per scan).
class WindowGate {
 public:
  explicit WindowGate(const EstimatorOptions& options);
  bool enabled() const { return enabled_; }
  /// Chi-square (2 dof) quantile of the gate's probability.
  double threshold() const { return chi2_; }
  /// Start over (a reset: no chain).
  void Clear();
  /// Before each scan: the previous scan's outcome (pose and covariance) joins the ring, and
  /// this scan's motion step is kept (with an informative step only; a scan without one breaks
  /// the chain). `initialized`: the estimator had a pose before this scan.
  void Push(const Pose2& pose, const Eigen::Matrix3d& cov, bool initialized, bool informative,
            const MotionMeasurement* motion);
  /// The squared Mahalanobis distance (translation) of a pose for the current scan from the
  /// pose window_gate_distance of odometry travel back (or the chain's start) chained with the
  /// steps since; -1 without a chain.
  double MahalanobisSq(const Pose2& solved, const Eigen::Matrix3d& cov_solved) const;

 private:
  struct Entry {
    Pose2 pose;
    Eigen::Matrix3d cov;
    Pose2 step;  // from the previous entry's pose
    Eigen::Matrix3d step_cov;
  };
  static constexpr std::size_t kCapacity = 256;
  const Entry& Back(std::size_t i) const {  // i = 0: the newest
    return ring_[(head_ + kCapacity - 1 - i) % kCapacity];
  }
  const EstimatorOptions& o_;
  bool enabled_{false};
  double chi2_{std::numeric_limits<double>::infinity()};
  std::vector<Entry> ring_;
  std::size_t count_{0}, head_{0};  // head: the slot the next entry goes to
  bool have_last_step_{false};
  Pose2 last_step_;
  Eigen::Matrix3d last_step_cov_{Eigen::Matrix3d::Zero()};
};

/// The identified scale of the motion covariance (Options::prior_scale_window): over the last
/// window matches, the median of the squared Mahalanobis distance per direction times the scale
/// it was computed with, over the chi-square median; never below 1.
class PriorScale {
 public:
  explicit PriorScale(const EstimatorOptions& options);
  double scale() const { return scale_; }
  /// A match's innovation m2 over dof directions; chi2_median: GateTable::median.
  void Add(double m2, int dof, const std::array<double, 4>& chi2_median);

 private:
  int window_{0};
  double scale_{1.0};
  std::vector<double> ring_, scratch_;
  std::size_t next_{0};
};

}  // namespace ifab::base
