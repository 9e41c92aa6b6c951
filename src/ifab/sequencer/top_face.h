#pragma once
/// \file
/// The workpiece as built: how high a placed brick's top face really is, measured from a
/// registered sweep. Bricks vary in height (EN 771-1 category T1 allows +-2.9 mm on the mean of
/// a 52 mm brick), so the designed top of a stack drifts from the real one brick by brick.

#include <array>
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

/// A placed brick's length and width as built, from one registered sweep.
struct FootprintMeasurement {
  Eigen::Vector2d size{Eigen::Vector2d::Zero()};  ///< [m] along the box's x and y
  Eigen::Vector2d std{Eigen::Vector2d::Zero()};   ///< [m] standard error of each
  /// [m] the brick's centre from the model's, along the box's x and y (midway between the near
  /// face and the far edge); its standard error is half the size's
  Eigen::Vector2d centre_offset{Eigen::Vector2d::Zero()};
  std::array<bool, 2> measured{};                 ///< whether each axis had enough rays at its far edge
  std::array<int, 2> edge_rays{};                 ///< rays used at each far edge
};

/// The length and width of `box` (the stack's top brick) as built. A sweep sees one end face and
/// one long face; a brick ΔL longer than designed is then registered ΔL/2 towards the laser,
/// and the next brick goes there. The far edges are what the sweep adds. Every ray is cut with
/// the top face's plane (its height the median of the points on it) and weighted by where it
/// returned: on that plane 1, on the floor 0, in between 1/2 (a mixed pixel: a beam straddling
/// the edge, as often before it as past it). The edge is where the weight missing before it
/// equals the weight found past it, which is unbiased for a beam jitter and mixed pixels
/// symmetric about the edge, and uses each ray's direction (precise) rather than its range (10-18
/// mm of noise along the ray). The near faces are taken where the registration put them, so the
/// size is the far edge's distance from the model's near face; alternated with the registration
/// it moves towards the size that fits both (`T_site_base` the registered pose, `cloud` in the
/// base frame). Nothing for an axis with fewer than 10 rays well inside or well past its edge.
/// `edge_cloud`: the rays for the far edges, if not `cloud` (a cloud cropped around a tall stack
/// loses the floor that the rays past its far edges reach).
std::optional<FootprintMeasurement> MeasureTopFootprint(const std::vector<RayPoint>& cloud, const Pose3& T_site_base,
                                                        const SiteBox& box, double ground_z,
                                                        const std::vector<RayPoint>* edge_cloud = nullptr);

}  // namespace ifab::sequencer
