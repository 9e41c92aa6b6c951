#pragma once
/// \file
/// The reference set of eq. 1: keyframes (earlier scans, sampled as reference points with a
/// neighbour grid each, one resolution per sigma level) spaced in distance and angle and kept over a
/// receding time horizon. With Options::keyframe_capacity above num_reference_scans it is a
/// keyframe map: each scan is matched against the num_reference_scans keyframes nearest to its
/// predicted pose, and revisiting a place reuses them. Slots are allocated once; adding a
/// keyframe builds its grids (which keep their buffers).

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "ifab/base/estimator/estimator_options.h"
#include "ifab/base/estimator/point_grid.h"
#include "ifab/base/estimator/scan_preprocessing.h"
#include "ifab/core/se2.h"
#include "ifab/core/time.h"

namespace ifab::base {

/// The kernel scale of sigma level `level` (coarse levels first, the last is Options::sigma).
double LevelSigma(const EstimatorOptions& o, int level);
/// Spacing of a level's reference points: coarse levels keep points about sigma apart, so the
/// kernel sum over them is as smooth as over a continuous wall (ripple ~exp(-2 pi^2 (sqrt(2)
/// sigma / spacing)^2)).
double ReferenceSpacing(const EstimatorOptions& o, int level);
/// Spacing of a level's measurement points (likewise).
double MeasurementSpacing(const EstimatorOptions& o, int level);
/// Number of sigma levels (coarse_sigmas + 1).
int NumLevels(const EstimatorOptions& o);

/// One resolution of a keyframe's points (one per sigma level, coarse levels sparser).
struct ReferenceLevel {
  ReferencePoints ref;  ///< in the keyframe's base frame
  PointGrid grid;       ///< over ref.points, cells of the level's search radius
};

struct Keyframe {
  bool active{false};
  bool selected{false};    ///< in this scan's reference set
  std::uint64_t order{0};  ///< insertion counter: larger is newer
  Seconds t{0.0};
  Pose2 T_world_base;
  std::vector<ReferenceLevel> levels;
};

class KeyframeMap {
 public:
  explicit KeyframeMap(const EstimatorOptions& options);

  int NumActive() const;
  /// The newest active keyframe, or nullptr.
  const Keyframe* Newest() const;
  const std::vector<std::unique_ptr<Keyframe>>& keyframes() const { return keyframes_; }

  /// Forget every keyframe.
  void Clear();
  /// Move every keyframe rigidly: T_world_kf <- correction * T_world_kf.
  void MoveRigidly(const Pose2& correction);
  /// A keyframe at the pose from the preprocessor's valid points (the last extracted scan), in
  /// an inactive slot, else the oldest one's.
  void Add(const Pose2& T_world_base, Seconds t, ScanPreprocessor* points);
  /// The reference set for a scan at the predicted pose: every kept keyframe, or the
  /// num_reference_scans nearest (translation plus 1 m per radian of turn) when more are kept.
  void Select(const Pose2& T_world_base);
  /// True if no kept keyframe lies within the keyframe spacing (distance and angle) of the
  /// pose, or keyframe_interval has passed since the newest while moving.
  bool NeedsKeyframe(const Pose2& T_world_base, Seconds t) const;
  /// Drop keyframes older than the horizon (never the newest).
  void DropOld(Seconds t);

 private:
  const EstimatorOptions& o_;
  int num_levels_{1};
  std::uint64_t counter_{0};
  std::vector<std::unique_ptr<Keyframe>> keyframes_;
  std::vector<std::pair<double, Keyframe*>> candidates_;  // scratch, reserved
};

}  // namespace ifab::base
