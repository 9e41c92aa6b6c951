#include "ifab/base/estimator/keyframe_map.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ifab/core/angles.h"

namespace ifab::base {

int NumLevels(const EstimatorOptions& o) { return static_cast<int>(o.coarse_sigmas.size()) + 1; }

double LevelSigma(const EstimatorOptions& o, int level) {
  return level + 1 < NumLevels(o) ? o.coarse_sigmas[static_cast<std::size_t>(level)] : o.sigma;
}

double ReferenceSpacing(const EstimatorOptions& o, int level) {
  return level + 1 < NumLevels(o) ? std::max(o.reference_point_spacing, LevelSigma(o, level))
                                  : o.reference_point_spacing;
}

double MeasurementSpacing(const EstimatorOptions& o, int level) {
  return level + 1 < NumLevels(o) ? std::max(o.min_point_spacing, LevelSigma(o, level))
                                  : o.min_point_spacing;
}

KeyframeMap::KeyframeMap(const EstimatorOptions& options) : o_(options), num_levels_(NumLevels(options)) {
  const auto beams = static_cast<std::size_t>(o_.max_beams);
  const int capacity = std::max(o_.num_reference_scans, o_.keyframe_capacity);
  keyframes_.reserve(static_cast<std::size_t>(capacity));
  for (int k = 0; k < capacity; ++k) {
    auto kf = std::make_unique<Keyframe>();
    kf->levels.resize(static_cast<std::size_t>(num_levels_));
    for (auto& level : kf->levels) {
      level.ref.points.reserve(beams);
      level.ref.normals.reserve(beams);
      level.ref.near_end.reserve(beams);
      level.ref.weight.reserve(beams);
    }
    keyframes_.push_back(std::move(kf));
  }
  candidates_.reserve(static_cast<std::size_t>(capacity));
}

int KeyframeMap::NumActive() const {
  int n = 0;
  for (const auto& kf : keyframes_) n += kf->active ? 1 : 0;
  return n;
}

const Keyframe* KeyframeMap::Newest() const {
  const Keyframe* best = nullptr;
  for (const auto& kf : keyframes_) {
    if (kf->active && (!best || kf->order > best->order)) best = kf.get();
  }
  return best;
}

void KeyframeMap::Clear() {
  for (auto& kf : keyframes_) kf->active = false;
}

void KeyframeMap::MoveRigidly(const Pose2& correction) {
  for (auto& kf : keyframes_) {
    if (kf->active) kf->T_world_base = correction * kf->T_world_base;
  }
}

void KeyframeMap::Add(const Pose2& T_world_base, Seconds t, ScanPreprocessor* points) {
  // Reuse an inactive slot, else the oldest.
  Keyframe* slot = nullptr;
  for (auto& kf : keyframes_) {
    if (!kf->active) {
      slot = kf.get();
      break;
    }
  }
  if (!slot) {
    for (auto& kf : keyframes_) {
      if (!slot || kf->order < slot->order) slot = kf.get();
    }
  }
  slot->active = true;
  slot->order = ++counter_;
  slot->t = t;
  slot->T_world_base = T_world_base;
  for (int l = 0; l < num_levels_; ++l) {
    ReferenceLevel& level = slot->levels[static_cast<std::size_t>(l)];
    const double max_gap = o_.max_reference_gap_sigmas > 0.0
                               ? o_.max_reference_gap_sigmas * LevelSigma(o_, l)
                               : std::numeric_limits<double>::infinity();
    if (o_.interpolate_reference) {
      points->Densify(ReferenceSpacing(o_, l), max_gap, o_.end_margin_sigmas * o_.sigma, &level.ref);
    } else {
      points->Thin(ReferenceSpacing(o_, l), max_gap, o_.max_beams, &level.ref.points,
                   o_.end_margin_sigmas * o_.sigma, &level.ref.near_end);
      ArcLengthWeights(level.ref.points, ReferenceSpacing(o_, l), max_gap, o_.reference_weighting,
                       &level.ref.weight);
      if (o_.residual == MatchResidual::kPointToLine) {
        points->ComputeNormals(level.ref.points,
                               std::max(3.0 * ReferenceSpacing(o_, l), 2.0 * LevelSigma(o_, l)),
                               &level.ref.normals);
      } else if (o_.structure_degeneracy_ratio > 0.0) {
        points->ComputeNormals(level.ref.points, o_.structure_normal_radius, &level.ref.normals);
      } else {
        level.ref.normals.clear();
      }
    }
    // Cells of the level's search radius (Eq3Solver's): a query then visits about 3 x 3 cells.
    level.grid.Build(level.ref.points, o_.search_radius_sigmas * std::sqrt(2.0) * LevelSigma(o_, l));
  }
}

namespace {
// Distance used to pick keyframes: translation plus 1 m per radian of turn.
double KeyframeDistance(const Pose2& a, const Pose2& b) {
  const double dx = a.x - b.x, dy = a.y - b.y;
  return std::sqrt(dx * dx + dy * dy) + std::abs(std::remainder(a.theta - b.theta, 2.0 * kPi));
}
}  // namespace

void KeyframeMap::Select(const Pose2& T_world_base) {
  candidates_.clear();
  for (auto& kf : keyframes_) {
    kf->selected = false;
    if (kf->active) candidates_.emplace_back(KeyframeDistance(kf->T_world_base, T_world_base), kf.get());
  }
  const auto n = std::min(candidates_.size(), static_cast<std::size_t>(o_.num_reference_scans));
  std::nth_element(candidates_.begin(), candidates_.begin() + static_cast<std::ptrdiff_t>(n) -
                                            (n > 0 ? 1 : 0),
                   candidates_.end());
  for (std::size_t k = 0; k < n; ++k) candidates_[k].second->selected = true;
}

bool KeyframeMap::NeedsKeyframe(const Pose2& T_world_base, Seconds t) const {
  const Keyframe* newest = Newest();
  if (newest == nullptr) return true;
  if (t - newest->t >= o_.keyframe_interval && TranslationDistance(T_world_base, newest->T_world_base) > 0.0) {
    return true;
  }
  const double d2 = o_.keyframe_distance * o_.keyframe_distance;
  const double angle = DegToRad(o_.keyframe_angle_deg);
  for (const auto& kf : keyframes_) {
    if (!kf->active) continue;
    const double dx = T_world_base.x - kf->T_world_base.x, dy = T_world_base.y - kf->T_world_base.y;
    if (dx * dx + dy * dy < d2 &&
        std::abs(std::remainder(T_world_base.theta - kf->T_world_base.theta, 2.0 * kPi)) < angle) {
      return false;
    }
  }
  return true;
}

void KeyframeMap::DropOld(Seconds t) {
  const Keyframe* newest = Newest();
  for (auto& kf : keyframes_) {
    if (kf->active && kf.get() != newest && t - kf->t > o_.horizon) kf->active = false;
  }
}

}  // namespace ifab::base
