#pragma once
/// \file
/// Does a solved pose problem (registration or calibration) agree with its noise model, and how
/// far can its covariance be trusted? The a-posteriori variance factor s0^2 = sum r^2 / (n - p)
/// of the whitened residuals scales the covariance to the residuals' actual spread (so a laser
/// noisier than its profile gives wider, not falsely tight, error bars), and the inliers' robust
/// spread is tested against the model: the gate and the robust loss are set in sigmas, and mean
/// nothing when sigma is off by more than a small factor.

#include <string>
#include <vector>

#include "ifab/perception/laser_model.h"

namespace ifab {

struct FitQuality {
  std::string noise_source{"model"};  ///< "profile NAME" or "estimated from the residuals"
  LaserNoiseModel noise;              ///< the model the final weights used (estimated: scaled)
  double noise_scale{1.0};            ///< estimated: the factor applied to the given shape
  double variance_factor{1.0};        ///< s0^2 = sum r^2 / (n - p); the covariance is scaled by it
  int degrees_of_freedom{0};          ///< n - p
  double chi2_z{0.0};                 ///< normal score of sum r^2 under chi^2(n - p) (Wilson-Hilferty)
  double robust_scale{1.0};           ///< 1.4826 median |r| of the inliers, gate-corrected (1: fits)
  double within_1sigma{0.0};          ///< fraction of inliers with |r| < 1 (0.68 if the model fits)
  bool consistent{true};              ///< robust_scale below the tolerance (a wider model is safe)
  std::string message;
};

/// The standard normal distribution's quantile at probability p in (0, 1).
double NormalQuantile(double p);
/// Wilson and Hilferty (1931): (X / k)^(1/3) of X ~ chi^2(k) is about normal with mean
/// 1 - 2 / (9k) and variance 2 / (9k). The normal score of x under chi^2(k), and the quantile of
/// chi^2(k) at the normal score z (its inverse; within about 1 % for k >= 2 in the upper tail).
double ChiSquareNormalScore(double x, double k);
double ChiSquareQuantile(double k, double z);

/// Robust scale of whitened residuals: 1.4826 median |r|, corrected for the gate that cut them
/// at `gate` sigmas (0: no gate): the median of a normal truncated at +-g is smaller.
double RobustScale(std::vector<double> abs_whitened, double gate);

/// The fit test. `whitened` are the inliers' errors whitened by the final noise model, `cost` is
/// 0.5 sum r^2 over `num_residuals` with `num_parameters` free; `tolerance` the factor the robust
/// spread may be off by (0: no test); `estimated`: the scale was fitted to these residuals (then
/// the test only checks that the fit settled).
FitQuality AssessFit(const std::vector<double>& whitened, double cost, int num_residuals, int num_parameters,
                     double tolerance, bool estimated, double gate);

}  // namespace ifab
