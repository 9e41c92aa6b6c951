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

void LookNoiseScale::Add(bool enabled, int looks, double nis, int dof) {
  if (!enabled || looks < 2) return;
  nis_sum_ += nis;
  nis_dof_ += dof;
  scale_ = std::max(1.0, nis_sum_ / nis_dof_);
}

void PlacementBiasFilter::Update(const Eigen::Vector2d& u, double z, double std) {
  const double r2 = std * std + o_.scatter * o_.scatter;
  const Eigen::Vector2d Pu = covariance_ * u;
  const double innovation = z - u.dot(bias_);
  noise_.Add(o_.adapt_noise, looks_, innovation * innovation / (u.dot(Pu) + r2), 1);
  const double s = u.dot(Pu) + noise_.scale() * r2;
  bias_ += Pu * ((z - u.dot(bias_)) / s);
  covariance_ -= Pu * Pu.transpose() / s;
  covariance_ = 0.5 * (covariance_ + covariance_.transpose());
  ++looks_;
}

void PlacementBiasFilter::Update(const Eigen::Vector2d& z, const Eigen::Matrix2d& covariance) {
  const Eigen::Matrix2d R = covariance + Eigen::Matrix2d::Identity() * o_.scatter * o_.scatter;
  const Eigen::Vector2d innovation = z - bias_;
  noise_.Add(o_.adapt_noise, looks_, innovation.dot((covariance_ + R).ldlt().solve(innovation)), 2);
  const Eigen::Matrix2d S = covariance_ + noise_.scale() * R;
  const Eigen::Matrix2d K = covariance_ * S.inverse();
  bias_ += K * (z - bias_);
  covariance_ = (Eigen::Matrix2d::Identity() - K) * covariance_;
  covariance_ = 0.5 * (covariance_ + covariance_.transpose());
  ++looks_;
}

Eigen::Vector2d PlacementBiasFilter::FusedMiss(const Eigen::Vector2d& z, const Eigen::Matrix2d& covariance) const {
  const Eigen::Matrix2d scatter = Eigen::Matrix2d::Identity() * o_.scatter * o_.scatter;
  const Eigen::Matrix2d expected = covariance_ + scatter;               // this placement's miss, before the look
  const Eigen::Matrix2d look = noise_.scale() * (covariance + scatter) - scatter;  // the look's own noise, as Update scales it
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

PlacementBiasLearner::PlacementBiasLearner(PlacementBiasOptions options, PlacementBiasScope scope)
    : o_(options), scope_(scope), shared_(options) {
  if (scope_ == PlacementBiasScope::kRobotAndPosition) {
    x_ = Eigen::VectorXd::Zero(2);
    P_ = Eigen::MatrixXd::Identity(2, 2) * o_.prior_std * o_.prior_std;
  }
}

PlacementBiasFilter& PlacementBiasLearner::For(const std::string& position) {
  if (scope_ == PlacementBiasScope::kRobot) return shared_;
  return by_position_.try_emplace(position, o_).first->second;
}

int PlacementBiasLearner::Block(const std::string& position) {
  const auto it = blocks_.find(position);
  if (it != blocks_.end()) return it->second;
  // A new stand: its own part enters with the arm's prior, uncorrelated with what is known.
  const int n = static_cast<int>(x_.size());
  x_.conservativeResize(n + 2);
  x_.tail<2>().setZero();
  P_.conservativeResize(n + 2, n + 2);
  P_.rightCols<2>().setZero();
  P_.bottomRows<2>().setZero();
  P_.bottomRightCorner<2, 2>() = Eigen::Matrix2d::Identity() * o_.prior_std * o_.prior_std;
  blocks_[position] = n;
  return n;
}

Eigen::MatrixXd PlacementBiasLearner::H(int block) const {
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(2, x_.size());
  h.leftCols<2>().setIdentity();
  h.block<2, 2>(0, block).setIdentity();
  return h;
}

Eigen::Vector2d PlacementBiasLearner::Bias(const std::string& position) {
  if (scope_ != PlacementBiasScope::kRobotAndPosition) return For(position).bias();
  return H(Block(position)) * x_;
}

Eigen::Matrix2d PlacementBiasLearner::Covariance(const std::string& position) {
  if (scope_ != PlacementBiasScope::kRobotAndPosition) return For(position).covariance();
  const Eigen::MatrixXd h = H(Block(position));
  return h * P_ * h.transpose();
}

void PlacementBiasLearner::UpdateJoint(const Eigen::MatrixXd& Hm, const Eigen::VectorXd& z, const Eigen::MatrixXd& R) {
  const Eigen::VectorXd innovation = z - Hm * x_;
  const Eigen::MatrixXd HP = Hm * P_;
  const Eigen::MatrixXd prior = HP * Hm.transpose();
  noise_.Add(o_.adapt_noise, looks_, innovation.dot((prior + R).ldlt().solve(innovation)), static_cast<int>(z.size()));
  const Eigen::MatrixXd S = prior + noise_.scale() * R;
  const Eigen::MatrixXd K = S.ldlt().solve(HP).transpose();  // P H^T S^-1 (S symmetric)
  x_ += K * innovation;
  P_ -= K * HP;
  P_ = 0.5 * (P_ + P_.transpose());
  ++looks_;
}

void PlacementBiasLearner::Update(const std::string& position, const Eigen::Vector2d& u, double z, double std) {
  if (scope_ != PlacementBiasScope::kRobotAndPosition) return For(position).Update(u, z, std);
  const int b = Block(position);
  const Eigen::MatrixXd Hm = u.transpose() * H(b);
  UpdateJoint(Hm, Eigen::VectorXd::Constant(1, z),
              Eigen::MatrixXd::Constant(1, 1, std * std + o_.scatter * o_.scatter));
}

void PlacementBiasLearner::Update(const std::string& position, const Eigen::Vector2d& z,
                                  const Eigen::Matrix2d& covariance) {
  if (scope_ != PlacementBiasScope::kRobotAndPosition) return For(position).Update(z, covariance);
  const int b = Block(position);
  UpdateJoint(H(b), z, covariance + Eigen::Matrix2d::Identity() * o_.scatter * o_.scatter);
}

Eigen::Vector2d PlacementBiasLearner::FusedMiss(const std::string& position, const Eigen::Vector2d& z,
                                                const Eigen::Matrix2d& covariance) {
  if (scope_ != PlacementBiasScope::kRobotAndPosition) return For(position).FusedMiss(z, covariance);
  const Eigen::Matrix2d scatter = Eigen::Matrix2d::Identity() * o_.scatter * o_.scatter;
  const Eigen::Matrix2d expected = Covariance(position) + scatter;
  const Eigen::Matrix2d look = noise_.scale() * (covariance + scatter) - scatter;
  const Eigen::Vector2d bias = Bias(position);
  return bias + expected * (expected + look).ldlt().solve(z - bias);
}

void PlacementBiasLearner::Predict() {
  shared_.Predict();
  for (auto& [name, filter] : by_position_) filter.Predict();
  if (scope_ == PlacementBiasScope::kRobotAndPosition)
    P_.diagonal().array() += 0.5 * o_.walk * o_.walk;  // each part half: a stand's miss walks by `walk`
}

}  // namespace ifab::sequencer
