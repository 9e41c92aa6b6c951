#pragma once
/// \file
/// The base's tilt from the IMU's accelerometers (paper Sec. VII's "the floor isn't perfectly
/// flat"; cf. Kindle et al., RA-L 2025, who compensate deflection with accelerometers). At rest an
/// accelerometer measures +g along the up direction, so the mean specific force over a window
/// gives the base's roll and pitch in its own frame. The stack compares the attitude when it
/// scanned the workpiece with the attitude when it is about to place a brick: the arm reaching
/// out with a brick tilts the base on its tracks, and the registered pose no longer holds.
/// A constant accelerometer bias or mounting error cancels in this change (to first order).

#include <optional>
#include <vector>

#include "ifab/core/se3.h"
#include "ifab/msgs/msgs.h"
#include "ifab/perception/cloud.h"

namespace ifab::sequencer {

/// Mean up direction (unit vector, sensor = base frame) of the samples with host time in
/// [t0, t1]; nullopt with fewer than `min_samples` samples there.
std::optional<Eigen::Vector3d> MeanUp(const std::vector<AccelSample>& samples, Seconds t0, Seconds t1,
                                      int min_samples = 20);

/// The rotation R (in the base frame at the reference) that the base turned through between the
/// reference and now, from the up directions then and now: R_site_base(now) = R_site_base(ref) R.
/// The turn about the vertical is not observable and taken as zero (the smallest rotation).
Eigen::Matrix3d TiltChange(const Eigen::Vector3d& up_ref, const Eigen::Vector3d& up_now);

/// The base's pose now from its pose at the reference and the tilt change. The base turns about
/// its origin (the footprint centre on the floor): tracks on an elastic floor turn about the
/// centroid of their contact area.
Pose3 CompensateTilt(const Pose3& T_site_base_ref, const Eigen::Vector3d& up_ref, const Eigen::Vector3d& up_now);

/// The planar pose `T_site_base` (x, y, heading; its height kept) tilted so that the base's
/// measured up direction `up_base` (base frame) maps to the site's vertical: the site is plumb
/// (a designed stack stands vertical), so gravity gives the base's absolute roll and pitch.
Pose3 LevelledPose(const Pose3& T_site_base, const Eigen::Vector3d& up_base);

/// Covariance of T_site_base ([x y z rx ry rz] as in perception/registration.h) from a
/// registration that held the workpiece's roll and pitch (base axes, through its origin) at the
/// IMU's: the held directions get the IMU's tilt variance `tilt_sigma`^2 [rad^2] instead of zero.
Eigen::Matrix<double, 6, 6> WithHeldTiltCovariance(const Pose3& T_base_site, Eigen::Matrix<double, 6, 6> covariance,
                                                   double tilt_sigma);

/// Puts a sweep's flange poses into the base frame at attitude `up_ref`, from the accelerometer at each scan's
/// time (the mean up over +-half_window): the arm's weight tilts the base on its tracks as the arm
/// moves, by hundredths of a degree between the postures of one calibration, which is millimetres
/// at the laser's range. The base turns about its origin, as in CompensateTilt; its heading is
/// kept. Returns false (and leaves the points) when the samples do not cover every scan.
/// `up_ref`: the up direction (base frame) of the attitude the points are put into (+z: level).
bool LevelSweepPoints(std::vector<SweepPoint>& points, const std::vector<AccelSample>& accel,
                      const Eigen::Vector3d& up_ref = Eigen::Vector3d::UnitZ(), double half_window = 0.25);

/// Angle between two up directions [rad].
double TiltAngle(const Eigen::Vector3d& up_a, const Eigen::Vector3d& up_b);

}  // namespace ifab::sequencer
