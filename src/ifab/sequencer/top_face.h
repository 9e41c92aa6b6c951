#pragma once
/// \file
/// The workpiece as built: how high a placed brick's top face really is, measured from a
/// registered sweep. Bricks vary in height (EN 771-1 category T1 allows +-2.9 mm on the mean of
/// a 52 mm brick), so the designed top of a stack drifts from the real one brick by brick.

#include <optional>
#include <vector>

#include "ifab/core/se3.h"
#include "ifab/model/site.h"
#include "ifab/perception/cloud.h"

namespace ifab::sequencer {

struct TopFaceMeasurement {
  double offset{0.0};  ///< [m] measured minus modelled height of the top face
  double std{0.0};     ///< [m] standard error of `offset`
  int points{0};       ///< points on the face
};

/// The points of `cloud` (base frame) that land inside `box`'s footprint, 2 cm in from its edges
/// (so no side face counts), and within 3 cm of its modelled top face (nothing else lies there:
/// the box is solid below it). Returns how far their median lies above the modelled face, or
/// nothing with fewer than 30 such points.
std::optional<TopFaceMeasurement> MeasureTopFace(const std::vector<RayPoint>& cloud, const Pose3& T_site_base,
                                                 const SiteBox& box);

}  // namespace ifab::sequencer
