#pragma once
/// \file
/// Noise model of a 2D laser range finder point (paper Sec. V-B): anisotropic, with the largest
/// standard deviation along the ray (UTM-30LX: 18 mm) and a beam-width term across it that grows
/// with range (DESIGN.md: 0.0006 r + 0.0015 m, about 2.5 mm at 2 m as in the paper).

#include <Eigen/Core>

namespace ifab {

class ConfigNode;

struct LaserNoiseModel {
  double sigma_along{0.018};           ///< [m] standard deviation along the ray (range noise)
  double sigma_across_slope{0.0006};   ///< [m/m] across the ray: slope * range + offset
  double sigma_across_offset{0.0015};  ///< [m]

  double SigmaAcross(double range) const { return sigma_across_slope * range + sigma_across_offset; }

  /// S with S^T S = Sigma^-1 for a point measured along unit `ray` at `range`: rows are the ray
  /// over sigma_along and two perpendiculars over sigma_across. S e is the whitened error.
  Eigen::Matrix3d SqrtInformation(const Eigen::Vector3d& ray, double range) const;
  /// Variance of the point's displacement along a unit surface normal n: n^T Sigma n.
  double NormalVariance(const Eigen::Vector3d& ray, double range, const Eigen::Vector3d& n) const;

  /// Reads {sigma_along, sigma_across_slope, sigma_across_offset}; all must be positive.
  static LaserNoiseModel FromConfig(const ConfigNode& config);
};

/// A unit vector perpendicular to u (u unit), chosen continuously away from the axes.
Eigen::Vector3d AnyPerpendicular(const Eigen::Vector3d& u);

}  // namespace ifab
