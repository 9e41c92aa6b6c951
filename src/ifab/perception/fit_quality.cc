#include "ifab/perception/fit_quality.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace ifab {
namespace {

double NormalCdf(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

}  // namespace

// Inverse of the normal CDF on (0, 1) by bisection (called a few times per solve).
double NormalQuantile(double p) {
  double lo = -10.0, hi = 10.0;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (NormalCdf(mid) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double ChiSquareNormalScore(double x, double k) {
  return (std::cbrt(x / k) - (1.0 - 2.0 / (9.0 * k))) / std::sqrt(2.0 / (9.0 * k));
}

double ChiSquareQuantile(double k, double z) {
  const double a = 2.0 / (9.0 * k);
  return k * std::pow(1.0 - a + z * std::sqrt(a), 3);
}

double RobustScale(std::vector<double> a, double gate) {
  if (a.empty()) return 1.0;
  const auto mid = a.begin() + static_cast<std::ptrdiff_t>(a.size() / 2);
  std::nth_element(a.begin(), mid, a.end());
  const double median = *mid;
  // Median of |z| for z ~ N(0, 1) kept only within +-gate: P(|z| < m) = P(|z| < gate) / 2.
  const double m = gate > 0.0 ? NormalQuantile(0.5 + 0.25 * (2.0 * NormalCdf(gate) - 1.0)) : 0.674489750196;
  return median / m;
}

FitQuality AssessFit(const std::vector<double>& whitened, double cost, int num_residuals, int num_parameters,
                     double tolerance, bool estimated, double gate) {
  FitQuality f;
  f.degrees_of_freedom = std::max(1, num_residuals - num_parameters);
  const double sum_sq = 2.0 * cost;
  f.variance_factor = num_residuals > num_parameters ? sum_sq / f.degrees_of_freedom : 1.0;
  f.chi2_z = ChiSquareNormalScore(sum_sq, f.degrees_of_freedom);
  std::vector<double> a;
  a.reserve(whitened.size());
  int within = 0;
  for (double r : whitened) {
    a.push_back(std::abs(r));
    within += std::abs(r) < 1.0;
  }
  f.within_1sigma = whitened.empty() ? 0.0 : static_cast<double>(within) / static_cast<double>(whitened.size());
  f.robust_scale = RobustScale(std::move(a), gate);
  // The decision uses the robust spread, not the chi^2 score: with 10^4 and more residuals a chi^2
  // test rejects every real laser model (range bias, mixed pixels) at any significance level,
  // while a scale off by a factor means the gate and the loss cut at the wrong place.
  if (whitened.empty()) {
    f.consistent = false;
    f.message = "no inlier to test the fit";
  } else if (estimated) {
    f.consistent = tolerance <= 0.0 || std::abs(std::log(f.robust_scale)) < std::log(1.1);
    f.message = f.consistent ? "noise scale estimated from the residuals; it settled"
                             : fmt::format("the estimated noise scale did not settle (last step off by {:.2f}x)",
                                           f.robust_scale);
  } else {
    // One-sided: residuals wider than the model mean the gate and the loss cut too close and the
    // model's error bars are too tight (not usable). Narrower residuals (a unit or a range that
    // is less noisy than its profile) are safe: the covariance is scaled down to their spread by
    // s0^2, and the gate and the loss only cut later than they could.
    f.consistent = tolerance <= 0.0 || f.robust_scale < tolerance;
    if (!f.consistent)
      f.message = fmt::format("the noise model does not explain the residuals: their robust spread is "
                              "{:.2f} sigma of the model (tolerance {:.1f}x); give the --sensor profile "
                              "of this laser, or none to estimate the noise",
                              f.robust_scale, tolerance);
    else if (tolerance > 0.0 && f.robust_scale < 1.0 / tolerance)
      f.message = fmt::format("residuals narrower than the noise model (robust spread {:.2f} sigma): the "
                              "covariance is scaled to them (s0^2 = {:.2f})",
                              f.robust_scale, f.variance_factor);
    else
      f.message = fmt::format("residuals agree with the noise model (robust spread {:.2f} sigma)", f.robust_scale);
  }
  return f;
}

}  // namespace ifab
