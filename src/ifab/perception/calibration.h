#pragma once
/// \file
/// Extrinsic calibration of the arm laser (paper Sec. V-C): the mount T_tool0_laser is solved
/// together with the poses of a known object and the ground from several sweeps, by putting
/// eq. 6 inside the error of eq. 7 (Ceres autodiff through both; the closest point enters with
/// its analytic derivative, closest_point.h). The paper's target: a wooden cube of about 0.25 m
/// on a flat floor, 6 to 8 sweeps of different joints.

#include <string>
#include <vector>

#include "ifab/perception/cloud.h"
#include "ifab/perception/registration.h"

namespace ifab {

class ConfigNode;

/// One arm sweep, assembled (scan_assembly.h) but not yet put through the laser mount.
struct CalibrationSweep {
  std::string name;
  std::vector<SweepPoint> points;
};

struct CalibrationOptions {
  RegistrationOptions registration;  ///< noise model, residual, shadows, iterations, tolerances
  double laser_extent{1.0};          ///< [m] lever arm for the mount's unconstrained-direction test
  bool autodiff{false};              ///< Jacobians by Ceres autodiff through eq. 6 and 7 (the paper's
                                     ///< way); false: the hand-derived ones (same values, checked in
                                     ///< the tests, about 5x faster)

  /// Reads a `calibration:` section over `base`: {registration: {...}, laser_extent, autodiff}.
  static CalibrationOptions FromConfig(const ConfigNode& config, CalibrationOptions base);
  static CalibrationOptions FromConfig(const ConfigNode& config) { return FromConfig(config, CalibrationOptions{}); }
};

struct CalibrationSummary {
  RegistrationStatus status{RegistrationStatus::kNoPoints};
  std::string message;
  int iterations{0};
  double cost{0.0};
  double seconds{0.0};
  Pose3 T_tool0_laser{Pose3::Identity()};
  /// Covariance of the mount's [x y z rx ry rz] (tool0 origin of the laser, rotation vector about
  /// tool0 axes; left perturbation as in RegisteredBody).
  Matrix6d covariance{Matrix6d::Zero()};
  std::vector<std::string> unconstrained;  ///< directions of the mount the sweeps do not fix
  std::vector<RegisteredBody> bodies;      ///< target poses in base
  std::vector<int> sweep_inliers;          ///< per sweep
  int num_points{0};
  int num_inliers{0};
  int num_shadow_removed{0};
  double rms_whitened{0.0};
  FitQuality fit;                          ///< noise model used, variance factor, fit test
  std::vector<std::string> warnings;

  /// Converged, the residuals agree with the noise model, and the sweeps fix every direction of
  /// the mount (a mount with a free direction is no calibration).
  bool IsUsable() const {
    return status == RegistrationStatus::kConverged && fit.consistent && unconstrained.empty();
  }
  std::string BriefReport() const;
};

/// Solve the laser mount and the free bodies' poses from the sweeps, starting from the guesses.
CalibrationSummary CalibrateLaserMount(const std::vector<CalibrationSweep>& sweeps,
                                       const std::vector<RegistrationBody>& bodies,
                                       const Pose3& T_tool0_laser_guess, const CalibrationOptions& options = {});

/// The paper's target as bodies: "ground" (plane z = 0 of a frame at ground_z in base) and
/// "cube" (a box of edge `size` whose centre is at T_base_cube).
std::vector<RegistrationBody> CubeOnGroundBodies(double size, const Pose3& T_base_cube, double ground_z = 0.0);

/// How far about the cube the calibration may take the ground as one plane. A finished floor bows
/// by millimetres over a metre (DIN 18202 allows 4 mm under a 1 m straightedge), and a plane fitted
/// over a wider patch than is flat leans the mount by as much. Measured from the ground's own
/// returns: rings about the cube, from the inside out, are accepted while the ring's height above
/// the plane fitted to the rings inside it stays within `significance` standard errors. The ring is
/// tested sector by sector: a floor that waves or twists lies above the plane on one side of the
/// cube and below it on the other, which a whole ring's mean averages away.
struct GroundExtentOptions {
  bool enabled{true};
  double ring_width{0.1};      ///< [m]
  /// Standard errors that mark a ring off the plane: with one sector, its mean height beyond this
  /// many; with several, the sum of the sectors' squared z-scores beyond the chi-square quantile
  /// of the same tail probability (two-sided normal at `significance`).
  double significance{3.0};
  /// Equal angles about the cube's centre; 1: the ring's mean alone. 8 (45 deg each): a twist
  /// puts two sectors above the plane and two below, and each sector of a 0.1 m ring still holds
  /// thousands of returns (a geometric choice, not one read off any floor's error).
  int sectors{8};
  double max_height{0.03};     ///< [m] a return farther off the ground plane is not the ground's
  int min_ring_points{30};     ///< a ring with fewer returns carries no evidence and is accepted

  /// Reads {enabled, ring_width_m, significance, sectors, max_height_m, min_ring_points}.
  static GroundExtentOptions FromConfig(const ConfigNode& config);
};

struct GroundExtent {
  double radius{0.0};  ///< [m] horizontally about the cube's centre (base frame)
  bool limited{false};  ///< a ring departed from the plane before `max_radius`
  struct Ring {
    double outer{0.0};    ///< [m] its outer radius
    int points{0};
    double mean_mm{0.0};  ///< its mean height above the plane of the rings inside
    double se_mm{0.0};    ///< the mean's standard error
    double chi2{0.0};     ///< sum over its sectors of (sector mean / its standard error)^2
    int sectors{0};       ///< sectors with enough returns to be tested
    double bound{0.0};    ///< the chi-square quantile chi2 was held against
    double worst_sector_mm{0.0};  ///< the sector mean farthest off the plane
  };
  std::vector<Ring> rings;  ///< tested rings, inside out (the last departed when `limited`)
  std::string message;
};

/// The ground's planar extent (GroundExtentOptions) from the sweeps through `T_tool0_laser`, with
/// the ground and cube where a solve put them; rings out to `max_radius`.
GroundExtent MeasureGroundExtent(const std::vector<CalibrationSweep>& sweeps, const Pose3& T_tool0_laser,
                                 const Pose3& T_base_ground, const Pose3& T_base_cube, double cube_size,
                                 double max_radius, const GroundExtentOptions& options = {});

/// Drops every return farther than `radius` horizontally from `center` (base frame).
void CropSweeps(std::vector<CalibrationSweep>& sweeps, const Pose3& T_tool0_laser, const Eigen::Vector2d& center,
                double radius);

/// Mean of poses: mean translation, rotation the chordal L2 mean (projected mean of matrices).
/// Used to average calibration trials from random initial guesses (Sec. V-C).
Pose3 AveragePoses(const std::vector<Pose3>& poses);

}  // namespace ifab
