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
  double height{0.0};  ///< [m] of the top face above the floor around the box
  double std{0.0};     ///< [m] standard error of `height`
  int points{0};       ///< points on the face
  int floor_points{0}; ///< points on the floor around it
};

/// How high `box`'s top face stands above the floor it stands on, both seen in one sweep
/// (`cloud` in the base frame, `T_site_base` the registered pose). The face: the points inside
/// the box's footprint, 2 cm in from its edges (so no side face counts) and within 3 cm of its
/// modelled top (nothing else lies there: the box is solid below it); their median. The floor: a
/// plane fitted to the points 0.25-0.6 m around the box within 3 cm of `ground_z`, evaluated
/// under the box. Measured against the floor in the same sweep, the height does not depend on
/// the registered height or tilt (which a small workpiece pins only loosely): an error there
/// moves the face and the floor alike. Nothing with fewer than 30 points on either.
std::optional<TopFaceMeasurement> MeasureTopFace(const std::vector<RayPoint>& cloud, const Pose3& T_site_base,
                                                 const SiteBox& box, double ground_z);

}  // namespace ifab::sequencer
