#pragma once
/// \file
/// Noise model of a 2D laser range finder point (paper Sec. V-B): anisotropic, with the largest
/// standard deviation along the ray (UTM-30LX: 18 mm) and a beam-width term across it that grows
/// with range (DESIGN.md: 0.0006 r + 0.0015 m, about 2.5 mm at 2 m as in the paper). Along the
/// ray, sigma = max(a, b r + c) as Pomerleau et al. 2012 model their lasers (b = c = 0: constant).

#include <Eigen/Core>

namespace ifab {

class ConfigNode;

struct LaserNoiseModel {
  double sigma_along{0.018};           ///< [m] standard deviation along the ray (range noise), a
  double sigma_along_slope{0.0};       ///< [m/m] b: along the ray sigma = max(a, b * range + c)
  double sigma_along_offset{0.0};      ///< [m] c
  double sigma_across_slope{0.0006};   ///< [m/m] across the ray: slope * range + offset
  double sigma_across_offset{0.0015};  ///< [m]

  double SigmaAcross(double range) const { return sigma_across_slope * range + sigma_across_offset; }
  double SigmaAlong(double range) const {
    const double linear = sigma_along_slope * range + sigma_along_offset;
    return linear > sigma_along ? linear : sigma_along;
  }
  /// Every standard deviation times k (a noise scale estimated from residuals).
  LaserNoiseModel Scaled(double k) const;

  /// S with S^T S = Sigma^-1 for a point measured along unit `ray` at `range`: rows are the ray
  /// over sigma_along and two perpendiculars over sigma_across. S e is the whitened error.
  Eigen::Matrix3d SqrtInformation(const Eigen::Vector3d& ray, double range) const;
  /// Variance of the point's displacement along a unit surface normal n: n^T Sigma n.
  double NormalVariance(const Eigen::Vector3d& ray, double range, const Eigen::Vector3d& n) const;

  /// Reads {sigma_along, sigma_along_slope, sigma_along_offset, sigma_across_slope,
  /// sigma_across_offset} over `base`; sigma_along and sigma_across_offset must be positive.
  static LaserNoiseModel FromConfig(const ConfigNode& config, LaserNoiseModel base);
  static LaserNoiseModel FromConfig(const ConfigNode& config) { return FromConfig(config, LaserNoiseModel{}); }
};

/// A unit vector perpendicular to u (u unit), chosen continuously away from the axes.
Eigen::Vector3d AnyPerpendicular(const Eigen::Vector3d& u);

}  // namespace ifab
