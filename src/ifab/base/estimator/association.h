#pragma once
/// \file
/// Data association for eq. 1: each measurement point of the scan, at a pose, is paired with the
/// nearest reference points (at most neighbors_per_reference per keyframe of the reference set,
/// within the kernel's search radius), skipping a keyframe whose nearest point lies at the end
/// of its chain. Over the pairs it sums eq. 1's kernel terms (kernel_residual.h) into the normal
/// equations of the solve, and gives the match's quality figures: the matched fraction
/// (coverage), the inlier fraction and the mean score (eq. 1's e_mi), and the scene's
/// point-to-line structure (for the degeneracy check). No allocation per scan.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "ifab/base/estimator/estimator_options.h"
#include "ifab/base/estimator/keyframe_map.h"
#include "ifab/core/se2.h"

namespace ifab::base {

/// One measurement point paired with one reference point.
struct Pair {
  int point{0};        ///< measurement point index
  double weight{1.0};  ///< the reference point's weight
  Eigen::Vector2d p_ref_world;
  Eigen::Vector2d n_world;  ///< the reference point's normal (zero if none)
};

/// Sums over terms of eq. 3 at one pose, in least-squares form (cost = |r|^2 / 2): the
/// (positive semi-definite) Hessian H, the gradient g = J^T r of the cost, and |r|^2.
struct NormalEquations {
  Eigen::Matrix3d H{Eigen::Matrix3d::Zero()};
  Eigen::Vector3d g{Eigen::Vector3d::Zero()};
  double sum_sq{0.0};
  int rows{0};
};

class Association {
 public:
  explicit Association(const EstimatorOptions& options);

  /// The measurement points (base frame) of the current sigma level; the caller fills them
  /// (ScanPreprocessor::Thin) before Associate.
  std::vector<Eigen::Vector2d> meas_base;

  /// Pair the measurement points at the pose with the selected keyframes' points of a level
  /// within `radius`; returns the fraction of measurement points with a pair.
  double Associate(const KeyframeMap& map, const Pose2& T_world_base, int level, double radius);
  /// The fraction of measurement points with a pair in the current association.
  double MatchedFraction() const;
  const std::vector<Pair>& pairs() const { return pairs_; }
  bool Empty() const { return pairs_.empty(); }

  /// H, g and |r|^2 of eq. 1's terms over the current pairs at the pose.
  NormalEquations Accumulate(const Pose2& T_world_base, double sigma) const;
  /// The scene's structure as point-to-line information (Zhang, Kaess, Singh 2016): each paired
  /// point constrains the pose along the normal of its nearest reference point only. Unlike the
  /// kernel sum's Hessian it has no curvature along a wall, however its points are spaced. Unit
  /// weights: only its directions and their ratios are meaningful.
  Eigen::Matrix3d StructureInformation(const Pose2& T_world_base) const;
  /// Of the paired measurement points, the fraction whose nearest reference point lies within
  /// 2 sigma (kernel >= exp(-1)).
  double InlierFraction(const Pose2& T_world_base, double sigma) const;
  /// Mean e_mi over the measurement points (kernels of peak 1).
  double Score(const Pose2& T_world_base, double sigma) const;
  /// RMS distance of the measurement points from the base: the lever that scales theta to metres.
  double Lever() const;

 private:
  struct KeyframeFrame {
    const ReferenceLevel* level;
    Eigen::Matrix2d R_kf_base;
    Eigen::Vector2d t_kf_base;
    Eigen::Matrix2d R_world_kf;
    Eigen::Vector2d t_world_kf;
  };
  const EstimatorOptions& o_;
  std::vector<Pair> pairs_;       // grouped by measurement point
  std::vector<int> pair_begin_;   // pairs of point i: [pair_begin_[i], pair_begin_[i + 1])
  std::vector<KeyframeFrame> kf_frames_;
  std::vector<std::uint32_t> knn_index_;
  std::vector<double> knn_dist_;
};

}  // namespace ifab::base
