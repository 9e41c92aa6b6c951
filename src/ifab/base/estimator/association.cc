#include "ifab/base/estimator/association.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ifab/base/estimator/kernel_residual.h"

namespace ifab::base {

namespace {

// k nearest neighbours within a radius, into caller-owned arrays (no allocation).
class RadiusKnnResultSet {
 public:
  using DistanceType = double;
  using IndexType = std::uint32_t;
  RadiusKnnResultSet(int capacity, double radius_sq, IndexType* indices, double* dists)
      : capacity_(capacity), radius_sq_(radius_sq), indices_(indices), dists_(dists) {}
  std::size_t size() const { return static_cast<std::size_t>(count_); }
  bool full() const { return count_ == capacity_; }
  bool addPoint(double dist, IndexType index) {
    if (dist >= radius_sq_) return true;
    int i = count_;
    for (; i > 0 && dists_[i - 1] > dist; --i) {
      if (i < capacity_) {
        dists_[i] = dists_[i - 1];
        indices_[i] = indices_[i - 1];
      }
    }
    if (i < capacity_) {
      dists_[i] = dist;
      indices_[i] = index;
    }
    if (count_ < capacity_) ++count_;
    return true;
  }
  double worstDist() const { return full() ? dists_[capacity_ - 1] : radius_sq_; }

 private:
  int capacity_;
  double radius_sq_;
  IndexType* indices_;
  double* dists_;
  int count_{0};
};

}  // namespace

Association::Association(const EstimatorOptions& options) : o_(options) {
  const auto beams = static_cast<std::size_t>(o_.max_beams);
  const int capacity = std::max(o_.num_reference_scans, o_.keyframe_capacity);
  const int k = o_.neighbors_per_reference;
  meas_base.reserve(beams);
  pairs_.reserve(static_cast<std::size_t>(o_.max_points) *
                 static_cast<std::size_t>(o_.num_reference_scans * k));
  pair_begin_.reserve(beams + 1);
  kf_frames_.reserve(static_cast<std::size_t>(capacity));
  knn_index_.resize(static_cast<std::size_t>(k));
  knn_dist_.resize(static_cast<std::size_t>(k));
}

double Association::Associate(const KeyframeMap& map, const Pose2& T_world_base, int level_index,
                              double radius) {
  pairs_.clear();
  pair_begin_.clear();
  kf_frames_.clear();
  for (const auto& kf : map.keyframes()) {
    if (!kf->active || !kf->selected) continue;
    const ReferenceLevel& level = kf->levels[static_cast<std::size_t>(level_index)];
    if (level.ref.points.empty()) continue;
    const Pose2 T_kf_base = kf->T_world_base.inverse() * T_world_base;
    kf_frames_.push_back({&level, T_kf_base.rotation(), T_kf_base.translation(),
                          kf->T_world_base.rotation(), kf->T_world_base.translation()});
  }
  const double r2 = radius * radius;
  const bool line = o_.residual == MatchResidual::kPointToLine;
  int matched = 0;
  for (std::size_t i = 0; i < meas_base.size(); ++i) {
    pair_begin_.push_back(static_cast<int>(pairs_.size()));
    for (const KeyframeFrame& f : kf_frames_) {
      const Eigen::Vector2d q_kf = f.R_kf_base * meas_base[i] + f.t_kf_base;
      RadiusKnnResultSet result(o_.neighbors_per_reference, r2, knn_index_.data(), knn_dist_.data());
      f.level->grid.RadiusSearch(q_kf, radius, result);
      const ReferencePoints& ref = f.level->ref;
      // Nearest to the end of a reference chain: the kernel sum there is one-sided and would
      // pull the point along the surface towards the reference's pose. Skip this reference.
      if (result.size() > 0 && ref.near_end[knn_index_[0]]) continue;
      for (std::size_t k = 0; k < result.size() && pairs_.size() < pairs_.capacity(); ++k) {
        const std::uint32_t j = knn_index_[k];
        Pair pr;
        pr.point = static_cast<int>(i);
        pr.p_ref_world = f.R_world_kf * ref.points[j] + f.t_world_kf;
        pr.weight = ref.weight[j];
        if (line) {
          pr.n_world = f.R_world_kf * ref.normals[j];
          if (pr.n_world.squaredNorm() == 0.0) continue;  // no line here
        } else if (j < ref.normals.size()) {
          pr.n_world = f.R_world_kf * ref.normals[j];  // for StructureInformation only
        } else {
          pr.n_world.setZero();
        }
        pairs_.push_back(pr);
      }
    }
    matched += static_cast<int>(pairs_.size()) > pair_begin_.back() ? 1 : 0;
  }
  pair_begin_.push_back(static_cast<int>(pairs_.size()));
  return meas_base.empty() ? 0.0
                           : static_cast<double>(matched) / static_cast<double>(meas_base.size());
}

double Association::MatchedFraction() const {
  int matched = 0;
  for (std::size_t i = 0; i + 1 < pair_begin_.size(); ++i) {
    matched += pair_begin_[i + 1] > pair_begin_[i] ? 1 : 0;
  }
  return meas_base.empty() ? 0.0 : static_cast<double>(matched) / static_cast<double>(meas_base.size());
}

NormalEquations Association::Accumulate(const Pose2& T_world_base, double sigma) const {
  NormalEquations ne;
  const Eigen::Matrix2d R = T_world_base.rotation();
  const Eigen::Vector2d t = T_world_base.translation();
  const bool line = o_.residual == MatchResidual::kPointToLine;
  for (std::size_t i = 0; i < meas_base.size(); ++i) {
    const int begin = pair_begin_[i], end = pair_begin_[i + 1];
    if (begin == end) continue;
    const Eigen::Vector2d p = R * meas_base[i] + t;
    PointKernelSum sum;
    for (int k = begin; k < end; ++k) {
      const Pair& pr = pairs_[static_cast<std::size_t>(k)];
      if (line) {
        sum.AddLine(p - pr.p_ref_world, pr.n_world, sigma, pr.weight);
      } else {
        sum.AddPoint(p - pr.p_ref_world, sigma, pr.weight);
      }
    }
    const Eigen::Matrix<double, 2, 3> J = PointJacobian(t, p);
    ne.H.noalias() += J.transpose() * sum.PsdHessian() * J;
    ne.g.noalias() += J.transpose() * sum.gradient;
    ne.sum_sq += 2.0 * sum.cost;
    ne.rows += end - begin;
  }
  return ne;
}

Eigen::Matrix3d Association::StructureInformation(const Pose2& T_world_base) const {
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  const Eigen::Vector2d t = T_world_base.translation();
  for (std::size_t i = 0; i + 1 < pair_begin_.size(); ++i) {
    const int begin = pair_begin_[i], end = pair_begin_[i + 1];
    if (begin == end) continue;
    const Eigen::Vector2d p = T_world_base * meas_base[i];
    int best_k = begin;
    double best = std::numeric_limits<double>::infinity();
    for (int k = begin; k < end; ++k) {
      const double d2 = (p - pairs_[static_cast<std::size_t>(k)].p_ref_world).squaredNorm();
      if (d2 < best) {
        best = d2;
        best_k = k;
      }
    }
    const Eigen::Vector2d& n = pairs_[static_cast<std::size_t>(best_k)].n_world;
    if (n.squaredNorm() == 0.0) continue;  // not line-like there (a corner, clutter)
    const Eigen::RowVector3d j = n.transpose() * PointJacobian(t, p);
    H.noalias() += j.transpose() * j;
  }
  return H;
}

double Association::InlierFraction(const Pose2& T_world_base, double sigma) const {
  const double r2 = 4.0 * sigma * sigma;
  int matched = 0, inliers = 0;
  for (std::size_t i = 0; i + 1 < pair_begin_.size(); ++i) {
    const int begin = pair_begin_[i], end = pair_begin_[i + 1];
    if (begin == end) continue;
    ++matched;
    const Eigen::Vector2d p = T_world_base * meas_base[i];
    double best = std::numeric_limits<double>::infinity();
    for (int k = begin; k < end; ++k) {
      best = std::min(best, (p - pairs_[static_cast<std::size_t>(k)].p_ref_world).squaredNorm());
    }
    inliers += best <= r2 ? 1 : 0;
  }
  return matched > 0 ? static_cast<double>(inliers) / static_cast<double>(matched) : 0.0;
}

double Association::Score(const Pose2& T_world_base, double sigma) const {
  double sum = 0.0;
  for (const Pair& pr : pairs_) {
    sum += KernelScore(T_world_base * meas_base[static_cast<std::size_t>(pr.point)] - pr.p_ref_world,
                       sigma);
  }
  return meas_base.empty() ? 0.0 : sum / static_cast<double>(meas_base.size());
}

double Association::Lever() const {
  double lever_sq = 0.0;
  for (const auto& q : meas_base) lever_sq += q.squaredNorm();
  return std::sqrt(std::max(lever_sq / static_cast<double>(meas_base.size()), 1e-6));
}

}  // namespace ifab::base
