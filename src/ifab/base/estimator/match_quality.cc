#include "ifab/base/estimator/match_quality.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>

namespace ifab::base {

Eigen::Matrix3d StructureTrustedInformation(const Eigen::Matrix3d& info_scan, const Eigen::Matrix3d& S,
                                            double lever, double ratio) {
  const double l = std::max(lever, 1e-3);
  const Eigen::Vector3d scale(1.0, 1.0, 1.0 / l);  // (x, y, lever * theta) -> (x, y, theta)
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(scale.asDiagonal() * S * scale.asDiagonal());
  const double smax = es.eigenvalues()(2);
  Eigen::Matrix3d P = Eigen::Matrix3d::Identity();
  for (int i = 0; i < 3; ++i) {
    if (!(es.eigenvalues()(i) >= ratio * smax)) {
      P -= es.eigenvectors().col(i) * es.eigenvectors().col(i).transpose();
    }
  }
  const Eigen::Vector3d unscale = scale.cwiseInverse();
  const Eigen::Matrix3d H_scaled = scale.asDiagonal() * info_scan * scale.asDiagonal();
  return unscale.asDiagonal() * (P * H_scaled * P) * unscale.asDiagonal();
}

GateTable::GateTable(double probability) {
  for (int dof = 1; dof <= 3; ++dof) {
    median[static_cast<std::size_t>(dof)] = boost::math::median(boost::math::chi_squared(dof));
    quantile[static_cast<std::size_t>(dof)] =
        probability > 0.0 ? boost::math::quantile(boost::math::chi_squared(dof), probability)
                          : std::numeric_limits<double>::infinity();
  }
}

WindowGate::WindowGate(const EstimatorOptions& options)
    : o_(options), enabled_(options.window_gate_probability > 0.0) {
  if (enabled_) {
    ring_.resize(kCapacity);
    chi2_ = boost::math::quantile(boost::math::chi_squared(2), o_.window_gate_probability);
  }
}

void WindowGate::Clear() {
  count_ = 0;
  have_last_step_ = false;
}

void WindowGate::Push(const Pose2& pose, const Eigen::Matrix3d& cov, bool initialized, bool informative,
                      const MotionMeasurement* motion) {
  if (!enabled_) return;
  if (have_last_step_) {
    ring_[head_] = Entry{pose, cov, last_step_, last_step_cov_};
    head_ = (head_ + 1) % kCapacity;
    count_ = std::min(count_ + 1, kCapacity);
  } else if (initialized) {
    ring_[head_] = Entry{pose, cov, Pose2(), Eigen::Matrix3d::Zero()};
    head_ = (head_ + 1) % kCapacity;
    count_ = 1;
  }
  if (!informative) count_ = 0;
  have_last_step_ = informative;
  if (informative) {
    last_step_ = motion->step;
    last_step_cov_ = motion->covariance;
  }
}

double WindowGate::MahalanobisSq(const Pose2& solved, const Eigen::Matrix3d& cov_solved) const {
  if (!have_last_step_ || count_ < 1) return -1.0;
  // Back to window_gate_distance of travel, or to the chain's start when it is shorter.
  double travel = last_step_.translation().norm();
  std::size_t back = 0;  // the span starts at Back(back)
  while (travel < o_.window_gate_distance && back + 1 < count_) {
    travel += Back(back).step.translation().norm();
    ++back;
  }
  // Compound from the span's start: its pose and covariance, then each step's.
  const Entry& start = Back(back);
  Pose2 T = start.pose;
  Eigen::Matrix3d C = start.cov;
  auto compound = [&](const Pose2& step, const Eigen::Matrix3d& step_cov) {
    const Eigen::Vector2d arm = T.rotation() * step.translation();
    Eigen::Matrix3d J = Eigen::Matrix3d::Identity();
    J(0, 2) = -arm.y();
    J(1, 2) = arm.x();
    C = J * C * J.transpose() + StepCovarianceInWorld(T, step_cov);
    T = T * step;
  };
  for (std::size_t i = back; i-- > 0;) compound(Back(i).step, Back(i).step_cov);
  compound(last_step_, last_step_cov_);
  const Eigen::Vector2d d = solved.translation() - T.translation();
  const Eigen::Matrix2d S = (C + cov_solved).topLeftCorner<2, 2>();
  return d.dot(S.ldlt().solve(d));
}

PriorScale::PriorScale(const EstimatorOptions& options) : window_(options.prior_scale_window) {
  ring_.reserve(static_cast<std::size_t>(window_));
  scratch_.reserve(static_cast<std::size_t>(window_));
}

void PriorScale::Add(double m2, int dof, const std::array<double, 4>& chi2_median) {
  if (window_ <= 0 || dof <= 0) return;
  const double r = m2 * scale_ / chi2_median[static_cast<std::size_t>(dof)];
  if (ring_.size() < static_cast<std::size_t>(window_)) {
    ring_.push_back(r);
  } else {
    ring_[next_] = r;
    next_ = (next_ + 1) % ring_.size();
  }
  scratch_.assign(ring_.begin(), ring_.end());
  auto mid = scratch_.begin() + static_cast<std::ptrdiff_t>(scratch_.size() / 2);
  std::nth_element(scratch_.begin(), mid, scratch_.end());
  // Start from the given model until a tenth of the window is in.
  if (ring_.size() * 10 >= static_cast<std::size_t>(window_)) scale_ = std::max(1.0, *mid);
}

}  // namespace ifab::base
