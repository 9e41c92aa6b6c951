#pragma once
/// \file
/// Which directions of the pose a scan match constrains poorly, from the eigen-decomposition of
/// the match's information (Zhang, Kaess, Singh, "On degeneracy of optimization-based state
/// estimation problems", ICRA 2016), and the remapping of the solution that lets the prior
/// decide those directions only.
///
/// With an informative prior (odometry, commanded speeds) the threshold is not a tuned number:
/// the generalized eigenproblem Lambda_scan v = lambda Lambda_prior v gives, along each v_i, the
/// ratio lambda_i of what the scan knows to what the prior knows. A direction is degenerate when
/// lambda_i < 1: the prior is the better source there. Directions whose scaled eigenvalue is
/// below min_ratio of the scan's strongest are removed from the scan's information first: the
/// kernel sum keeps a little curvature along a featureless wall (the neighbour count truncates
/// it, chain ends are one-sided) that is no real information. Without a prior (gyro only), directions
/// are judged by the scan alone: eigenvalues of the information with theta scaled to metres at
/// the points' RMS lever arm, degenerate when below min_ratio of the largest.

#include <Eigen/Core>
#include <array>

namespace ifab::base {

struct DegeneracyAnalysis {
  int num_degenerate{0};
  /// lambda_i, ascending: with a prior the information ratio scan / prior along v_i; without,
  /// the scaled eigenvalues divided by the largest.
  Eigen::Vector3d eigenvalues{Eigen::Vector3d::Ones()};
  /// Columns v_i over (x, y, theta): with a prior, V^T Lambda_prior V = I; without, orthonormal
  /// in (x, y, lever * theta) coordinates.
  Eigen::Matrix3d eigenvectors{Eigen::Matrix3d::Identity()};
  std::array<bool, 3> degenerate{{false, false, false}};
  /// The degenerate directions as unit vectors over (x [m], y [m], lever * theta [m]), the
  /// first num_degenerate columns (the rest zero): what a user reads ("along the corridor").
  Eigen::Matrix3d directions{Eigen::Matrix3d::Zero()};
  double ratio{1.0};  ///< min / max eigenvalue of the scaled scan information (0: none)
  /// With a prior: the scan's information without the directions weaker than min_ratio of its
  /// strongest (scaled), which are not trusted whatever the prior (see AnalyseDegeneracy).
  Eigen::Matrix3d info_scan_trusted{Eigen::Matrix3d::Zero()};
  bool with_prior{false};
};

/// info_scan: the match's information (x, y, theta) in physical units (1/m^2, 1/rad^2);
/// info_prior: the prior's, or nullptr; lever [m]: RMS distance of the scan's points from the
/// base (scales theta to metres for the scan-only ratio and for reporting).
DegeneracyAnalysis AnalyseDegeneracy(const Eigen::Matrix3d& info_scan,
                                     const Eigen::Matrix3d* info_prior, double lever,
                                     double min_ratio);

/// Zhang et al.'s solution remapping: keep the solution's component along the well-constrained
/// directions and take the prior's along the degenerate ones. dx = x_solved - x_prior (theta
/// wrapped); returns the corrected offset from the prior. Requires an analysis with a prior.
Eigen::Vector3d RemapDegenerate(const DegeneracyAnalysis& analysis,
                                const Eigen::Matrix3d& info_prior, const Eigen::Vector3d& dx);

/// Squared Mahalanobis distance of the scan's innovation from the prior, over the
/// well-constrained directions only (the scan says nothing along the others), for a solution
/// dx = x_fused - x_prior of the fused problem (scan + prior): in the basis of the analysis the
/// fused offset along v_i is lambda_i / (1 + lambda_i) of the innovation, whose variance there
/// is 1 / lambda_i + 1. Sets *dof to the number of directions tested.
double InnovationMahalanobisSq(const DegeneracyAnalysis& analysis,
                               const Eigen::Matrix3d& info_prior, const Eigen::Vector3d& dx,
                               int* dof);

/// The same innovation's squared Mahalanobis distance over the translation alone (the heading
/// marginalised out): the match's scan-only translation offset from the prior against the
/// translation block of their combined covariance. A direction the prior alone decides counts
/// as unknown (its share of the translation is not tested). *dof: the translation directions
/// tested (0-2).
double InnovationTranslationMahalanobisSq(const DegeneracyAnalysis& analysis,
                                          const Eigen::Matrix3d& info_prior,
                                          const Eigen::Vector3d& dx, int* dof);

}  // namespace ifab::base
