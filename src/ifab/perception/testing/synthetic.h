#pragma once
/// \file
/// Synthetic laser data for perception's own tests and benchmark: beams ray-cast against a Scene
/// of known bodies, with range noise along the ray, beam-width noise across it (as a jitter of
/// the beam direction) and optional mixed pixels at depth edges. Not the simulator (src/ifab/sim
/// owns ground truth for the experiments); perception never includes that.

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <vector>

#include "ifab/core/data_path.h"
#include "ifab/core/random.h"
#include "ifab/model/robot_model.h"
#include "ifab/msgs/msgs.h"
#include "ifab/perception/cloud.h"
#include "ifab/perception/laser_model.h"
#include "ifab/perception/scene.h"

namespace ifab::testing {

/// The design robot (data/robots/insitu_fabricator.urdf) that the tests scan from.
inline RobotModel DesignRobot() { return LoadRobotModel(DataPath("robots/insitu_fabricator.urdf")); }

/// A Hokuyo UTM-30LX-like scanner.
struct SyntheticLaser {
  int beams{1081};
  double angle_min{-0.75 * M_PI};
  double angle_increment{0.25 * M_PI / 180.0};
  double scan_period{0.025};               ///< [s] 40 Hz
  double time_increment{0.025 / 1440.0};   ///< [s] between beams
  double range_min{0.1};
  double range_max{30.0};
  LaserNoiseModel noise;
  bool noisy{true};
  bool mixed_pixels{false};  ///< beams straddling a depth edge return a range between the surfaces
  double mixed_gap{0.03};    ///< [m] range difference across the beam that makes a mixed pixel
  /// Range bias b(range, incidence) added to every return (positive: reads long); unset: none.
  std::function<double(double, double)> range_bias;
  /// Noise along the ray sigma(range, incidence) [m] (e.g. a simulated unit's range- and
  /// incidence-dependent law); unset: noise.sigma_along at every range.
  std::function<double(double, double)> sigma_along_at;
};

/// One beam from the laser pose along angle a (laser frame x-y plane). NaN if nothing is hit.
/// Sets *mixed if the return is a mixed pixel. `edge_range`: the nearest range among the beam and
/// its neighbours (SynthesizeScan), where a footprint straddling a depth edge meets it; NaN: the
/// beam's own.
inline double CastBeam(const Scene& world, const Pose3& T_base_laser, double a, const SyntheticLaser& laser,
                       RandomStream& rng, bool* mixed = nullptr,
                       double edge_range = std::numeric_limits<double>::quiet_NaN()) {
  if (mixed) *mixed = false;
  const Eigen::Vector3d o = T_base_laser.translation();
  auto cast = [&](double angle, double tilt) {
    const Eigen::Vector3d d_laser(std::cos(angle) * std::cos(tilt), std::sin(angle) * std::cos(tilt), std::sin(tilt));
    const auto hit = world.CastRay(o, T_base_laser.linear() * d_laser, laser.range_max);
    return hit ? hit->t : std::numeric_limits<double>::quiet_NaN();
  };
  // The beam's own ray, kept whole: its face's normal gives the incidence for the bias and noise.
  const Eigen::Vector3d d0 = T_base_laser.linear() * Eigen::Vector3d(std::cos(a), std::sin(a), 0.0);
  const auto hit0 = world.CastRay(o, d0, laser.range_max);
  if (!hit0) return std::numeric_limits<double>::quiet_NaN();
  const double r0 = hit0->t;
  // The angular beam-width sigma, where the beam meets an edge beside it (the nearer surface's
  // range): a beam passing the edge to the floor is as wide there, and jitters as far, as its
  // neighbour ending on the edge's face; so it mixes, and crosses the edge, as often.
  const double r_edge = std::isfinite(edge_range) ? std::min(r0, edge_range) : r0;
  const double beam = laser.noise.SigmaAcross(r_edge) / r_edge;
  if (laser.mixed_pixels) {
    const double r1 = cast(a - 2.0 * beam, 0.0), r2 = cast(a + 2.0 * beam, 0.0);
    if (std::isfinite(r1) && std::isfinite(r2) && std::abs(r1 - r2) > laser.mixed_gap) {
      if (mixed) *mixed = true;
      return std::min(r1, r2) + rng.Uniform(0.15, 0.85) * std::abs(r1 - r2);
    }
  }
  double bias = 0.0, incidence = 0.0;
  if (laser.range_bias || laser.sigma_along_at) {
    incidence = std::acos(std::min(1.0, std::abs(hit0->normal.dot(d0))));
    if (laser.range_bias) bias = laser.range_bias(r0, incidence);
  }
  if (!laser.noisy) return r0 + bias;
  // Elevation noise first, then azimuth: gcc's order of the call's arguments (C++ leaves it open).
  const double de = rng.Normal(beam), da = rng.Normal(beam);
  double r = cast(a + da, de);
  if (!std::isfinite(r)) r = r0;
  return r + bias + rng.Normal(laser.sigma_along_at ? laser.sigma_along_at(r0, incidence) : laser.noise.sigma_along);
}

/// A scan starting at t0; the laser pose is evaluated at each beam's own time.
inline LaserScan SynthesizeScan(const Scene& world, const std::function<Pose3(double)>& T_base_laser_at, double t0,
                                const SyntheticLaser& laser, RandomStream& rng, std::vector<char>* mixed = nullptr) {
  LaserScan scan;
  scan.stamp.t = t0;
  scan.angle_min = laser.angle_min;
  scan.angle_increment = laser.angle_increment;
  scan.time_increment = laser.time_increment;
  scan.range_min = laser.range_min;
  scan.range_max = laser.range_max;
  scan.ranges.resize(static_cast<std::size_t>(laser.beams));
  // With mixed pixels: each beam's nominal range first, for the neighbours' nearer surface.
  std::vector<double> nominal;
  if (laser.mixed_pixels) {
    nominal.resize(static_cast<std::size_t>(laser.beams), std::numeric_limits<double>::infinity());
    for (int i = 0; i < laser.beams; ++i) {
      const auto k = static_cast<std::size_t>(i);
      const Pose3 T = T_base_laser_at(scan.BeamTime(k));
      const double a = scan.Angle(k);
      const auto hit = world.CastRay(T.translation(), T.linear() * Eigen::Vector3d(std::cos(a), std::sin(a), 0.0),
                                     laser.range_max);
      if (hit) nominal[k] = hit->t;
    }
  }
  for (int i = 0; i < laser.beams; ++i) {
    bool m = false;
    const auto k = static_cast<std::size_t>(i);
    double edge_range = std::numeric_limits<double>::quiet_NaN();
    // Two beams each side: a beam's jitter and footprint (about 2.5 mrad at 0.8 m) reach past
    // its neighbour (4.4 mrad away) to an edge beyond it.
    for (int j = std::max(0, i - 2); !nominal.empty() && j <= std::min(laser.beams - 1, i + 2); ++j)
      edge_range = std::isfinite(edge_range) ? std::min(edge_range, nominal[static_cast<std::size_t>(j)])
                                             : nominal[static_cast<std::size_t>(j)];
    scan.ranges[k] = CastBeam(world, T_base_laser_at(scan.BeamTime(k)), scan.Angle(k), laser, rng, &m, edge_range);
    if (mixed) mixed->push_back(m);
  }
  return scan;
}

/// The cloud (base frame) of a laser moving along T_base_laser_at from t0 to t1. `mixed` (if
/// given) receives one flag per returned point.
inline std::vector<RayPoint> SynthesizeCloud(const Scene& world, const std::function<Pose3(double)>& T_base_laser_at,
                                             double t0, double t1, const SyntheticLaser& laser, RandomStream& rng,
                                             std::vector<char>* mixed = nullptr) {
  std::vector<RayPoint> cloud;
  for (double t = t0; t < t1; t += laser.scan_period) {
    std::vector<char> m;
    const LaserScan scan = SynthesizeScan(world, T_base_laser_at, t, laser, rng, &m);
    for (std::size_t i = 0; i < scan.size(); ++i) {
      if (!scan.IsValid(i)) continue;
      const Pose3 T = T_base_laser_at(scan.BeamTime(i));
      cloud.push_back({T * scan.Point(i), T.translation()});
      if (mixed) mixed->push_back(m[i]);
    }
  }
  return cloud;
}

/// Scans and joint states of an arm moving linearly in joint space from q0 to q1 over `duration`
/// (host times from t = 0), the laser on the flange at T_tool0_laser.
struct SyntheticSweep {
  std::vector<LaserScan> scans;
  std::vector<JointState> joints;
};

inline SyntheticSweep SynthesizeArmSweep(const Scene& world, const RobotModel& robot, const Pose3& T_tool0_laser,
                                         const Vector6d& q0, const Vector6d& q1, double duration,
                                         const SyntheticLaser& laser, RandomStream& rng, double joint_rate = 250.0) {
  SyntheticSweep sweep;
  auto q_at = [&](double t) -> Vector6d { return q0 + std::clamp(t / duration, 0.0, 1.0) * (q1 - q0); };
  auto laser_at = [&](double t) {
    return robot.T_base_arm_base * robot.ArmForwardKinematics(q_at(t)) * T_tool0_laser;
  };
  const double dt = 1.0 / joint_rate;
  for (double t = -dt; t <= duration + laser.scan_period + dt; t += dt) {
    JointState j;
    j.stamp.t = t;
    j.q = q_at(t);
    sweep.joints.push_back(j);
  }
  for (double t = 0.0; t + laser.scan_period <= duration; t += laser.scan_period)
    sweep.scans.push_back(SynthesizeScan(world, laser_at, t, laser, rng));
  return sweep;
}

}  // namespace ifab::testing
