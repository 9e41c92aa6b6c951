#include "ifab/sequencer/placement_bias.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>

#include "ifab/core/error.h"

namespace ifab::sequencer {

PlacementBiasFilter::PlacementBiasFilter(PlacementBiasOptions options)
    : o_(options), covariance_(Eigen::Matrix2d::Identity() * options.prior_std * options.prior_std) {
  IFAB_CHECK(o_.prior_std > 0.0 && o_.scatter >= 0.0 && o_.walk >= 0.0);  // MissionOptions reads them so
}

void PlacementBiasFilter::Predict() { covariance_ += Eigen::Matrix2d::Identity() * o_.walk * o_.walk; }

void PlacementBiasFilter::AdaptNoise(double nis, int dof) {
  // The first two looks meet the wide prior (their innovation is mostly the bias itself); from
  // the third on, the innovations are mostly the looks' noise.
  if (!o_.adapt_noise || looks_ < 2) return;
  nis_sum_ += nis;
  nis_dof_ += dof;
  noise_scale_ = std::max(1.0, nis_sum_ / nis_dof_);
}

void PlacementBiasFilter::Update(const Eigen::Vector2d& u, double z, double std) {
  const double r2 = std * std + o_.scatter * o_.scatter;
  const Eigen::Vector2d Pu = covariance_ * u;
  const double innovation = z - u.dot(bias_);
  AdaptNoise(innovation * innovation / (u.dot(Pu) + r2), 1);
  const double s = u.dot(Pu) + noise_scale_ * r2;
  bias_ += Pu * ((z - u.dot(bias_)) / s);
  covariance_ -= Pu * Pu.transpose() / s;
  covariance_ = 0.5 * (covariance_ + covariance_.transpose());
  ++looks_;
}

void PlacementBiasFilter::Update(const Eigen::Vector2d& z, const Eigen::Matrix2d& covariance) {
  const Eigen::Matrix2d R = covariance + Eigen::Matrix2d::Identity() * o_.scatter * o_.scatter;
  const Eigen::Vector2d innovation = z - bias_;
  AdaptNoise(innovation.dot((covariance_ + R).ldlt().solve(innovation)), 2);
  const Eigen::Matrix2d S = covariance_ + noise_scale_ * R;
  const Eigen::Matrix2d K = covariance_ * S.inverse();
  bias_ += K * (z - bias_);
  covariance_ = (Eigen::Matrix2d::Identity() - K) * covariance_;
  covariance_ = 0.5 * (covariance_ + covariance_.transpose());
  ++looks_;
}

Eigen::Vector2d PlacementBiasFilter::FusedMiss(const Eigen::Vector2d& z, const Eigen::Matrix2d& covariance) const {
  const Eigen::Matrix2d scatter = Eigen::Matrix2d::Identity() * o_.scatter * o_.scatter;
  const Eigen::Matrix2d expected = covariance_ + scatter;               // this placement's miss, before the look
  const Eigen::Matrix2d look = noise_scale_ * (covariance + scatter) - scatter;  // the look's own noise, as Update scales it
  return bias_ + expected * (expected + look).ldlt().solve(z - bias_);
}

bool ArmCanExplainMiss(const Eigen::Vector2d& miss, const Eigen::Matrix2d& look_covariance,
                       const PlacementBiasOptions& options, double* mahalanobis2) {
  const double arm = options.prior_std * options.prior_std + options.scatter * options.scatter;
  const Eigen::Matrix2d expected = look_covariance + arm * Eigen::Matrix2d::Identity();
  const double d2 = miss.dot(expected.ldlt().solve(miss));
  if (mahalanobis2) *mahalanobis2 = d2;
  return d2 <= kChi2Dof2P999;  // false for a NaN
}

PlacementBiasLearner::PlacementBiasLearner(PlacementBiasOptions options, bool per_position)
    : o_(options), per_position_(per_position), shared_(options) {}

PlacementBiasFilter& PlacementBiasLearner::For(const std::string& position) {
  if (!per_position_) return shared_;
  return by_position_.try_emplace(position, o_).first->second;
}

void PlacementBiasLearner::Predict() {
  shared_.Predict();
  for (auto& [name, filter] : by_position_) filter.Predict();
}

}  // namespace ifab::sequencer
