#pragma once
/// \file
/// Scan preprocessing: from a laser scan to the points eq. 1 compares. The range filter (beams
/// outside [min_range, max_range] and the laser's own limits are dropped), the deskew (each beam
/// moved to the base pose at the scan's middle time with the base's twist, an improvement on the
/// paper's rigid scan), the thinning of the measurement scan, and the sampling of a reference
/// scan (thinned points with their end-of-chain flags, or a polyline; normals for point-to-line
/// and for the structure degeneracy check). Buffers are sized once (max_beams) and reused.

#include <Eigen/Core>
#include <vector>

#include "ifab/base/estimator/estimator_options.h"
#include "ifab/core/se2.h"
#include "ifab/msgs/msgs.h"

namespace ifab::base {

/// A reference scan's points at one spacing, in the base frame of the scan.
struct ReferencePoints {
  std::vector<Eigen::Vector2d> points;
  std::vector<Eigen::Vector2d> normals;  ///< unit normals, zero where not line-like; may be empty
  std::vector<char> near_end;            ///< within the end margin of its chain's end
  std::vector<double> weight;            ///< arc-length weight (1 unless weighting is on)
};

class ScanPreprocessor {
 public:
  /// T_base_laser: the laser's planar mount on the base.
  ScanPreprocessor(const EstimatorOptions& options, const Pose2& T_base_laser);

  /// Valid beam endpoints of the scan in the base frame. With a base twist (v_base [m/s] in the
  /// base frame, omega [rad/s]) and beam times, each beam is moved from the base pose at its own
  /// time to the pose at the scan's middle time (constant twist over the sweep); a zero twist
  /// leaves the scan rigid.
  void Extract(const LaserScan& scan, const Eigen::Vector2d& v_base = Eigen::Vector2d::Zero(),
               double omega = 0.0);
  /// The valid points of the last Extract, in scan order.
  const std::vector<Eigen::Vector2d>& valid() const { return valid_base_; }

  /// Keep points about `spacing` apart in scan order (Options::thinning; skipping points whose
  /// nearer scan neighbour is farther than max_gap), then at most `max_out` (evenly). With
  /// `near_end`, also flag the kept points lying within end_margin (along the scan) of the end
  /// of their chain: a chain ends where consecutive points are more than max_gap apart (a depth
  /// jump, an occlusion, sparse sampling) or at the scan's ends.
  void Thin(double spacing, double max_gap, int max_out, std::vector<Eigen::Vector2d>* out,
            double end_margin = 0.0, std::vector<char>* near_end = nullptr);

  /// The reference as a polyline (Options::interpolate_reference): consecutive valid points are
  /// linked when at most max_link apart and the link is not nearly parallel to the beam (a depth
  /// jump); each chain is sampled every `spacing`, with the chain's normal, and samples within
  /// end_margin of a chain's end are flagged. Points on no link are dropped.
  void Densify(double spacing, double max_link, double end_margin, ReferencePoints* out);

  /// Normals of `points` (a subset of the valid points, in the same order) by PCA of the valid
  /// points within `radius`, walking along the scan; zero where the neighbourhood is not
  /// line-like (smaller eigenvalue above a tenth of the larger).
  void ComputeNormals(const std::vector<Eigen::Vector2d>& points, double radius,
                      std::vector<Eigen::Vector2d>* normals) const;

 private:
  const EstimatorOptions& o_;
  Pose2 T_base_laser_;
  std::vector<Eigen::Vector2d> valid_base_;  // every valid beam endpoint, base frame
  std::vector<double> valid_gap_;            // distance to the nearer neighbour along the scan
  std::vector<double> chain_before_, chain_after_;  // arc length to the chain's ends (scratch)
};

/// Weight of each reference point: the arc length it stands for (half the way to each
/// neighbour within max(max_gap, 2 spacing)) over the nominal spacing; 1 everywhere unless
/// weighting is kArcLength.
void ArcLengthWeights(const std::vector<Eigen::Vector2d>& points, double spacing, double max_gap,
                      ReferenceWeighting weighting, std::vector<double>* weight);

}  // namespace ifab::base
