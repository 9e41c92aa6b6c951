#pragma once
/// \file
/// The commanded track speeds as a weak motion prior (issue 11, Deliver 2). The IF has no usable
/// wheel odometry: its tracks slip (DESIGN.md). What a real robot does know is the command its
/// controller sent; integrated with the skid-steer kinematics of the design (v = (v_l + v_r) / 2,
/// omega = (v_r - v_l) / B, no slip), it says roughly how the base moved between two scans, and
/// with a noise as large as the slip it becomes the odometry factor of eq. 3 (motion_prior.h):
/// the scan decides every direction it observes, the commanded motion only those it does not (a
/// featureless corridor's axis), where gyro-only eq. 2 has nothing and slides.
///
/// The commands are the controller's, stamped by the host clock when sent (the mission records
/// every TrackCommand it hands to hal::Robot); never the simulator's truth.

#include <cstddef>
#include <string>
#include <vector>

#include "ifab/base/estimator/motion_prior.h"
#include "ifab/core/config.h"
#include "ifab/core/se2.h"
#include "ifab/msgs/msgs.h"

namespace ifab::base {

/// Noise of the commanded motion: the slip of a skid-steered tracked base, from the published
/// ICR model's sizes (Martinez et al. 2005, "Approximating kinematics for tracked mobile
/// robots", IJRR; the ranges are in DESIGN.md), not from the simulator.
inline OdometryNoise CommandedSpeedNoise() {
  OdometryNoise n;
  n.translation_per_m = 0.10;   // speed factor 0.90-0.95: the tracks cover 5-10 % less than commanded
  n.lateral_per_m = 0.05;       // a tracked base moves sideways only by slip: half the above
  n.translation_per_rad = 0.10; // the ICR's offset along x follows the load (arm posture): ~0.1 gauge per rad
  n.rotation_per_m = 0.035;     // 2 deg per metre, as for wheel odometry
  n.rotation_per_rad = 0.30;    // steering efficiency 0.70-0.76: the base turns 24-30 % less than commanded
  n.translation_floor = 0.005;  // hydraulic drives follow the command with lag: a step of one scan
                                // period (25 ms at the 0.3 m/s limit: 7.5 mm) may not have happened yet
  n.rotation_floor = 0.002;     // 0.1 deg a step
  return n;
}

/// Options of the commanded-speed prior (EstimatorOptions::commanded_speeds, YAML
/// `estimator.commanded_speeds`).
struct CommandedSpeedOptions {
  bool use{false};  ///< off: the paper's gyro-only eq. 2
  OdometryNoise noise{CommandedSpeedNoise()};  ///< see CommandedSpeedNoise()

  /// Reads `use` and `noise` (an OdometryNoise map; keys it does not name keep the slip defaults).
  static CommandedSpeedOptions FromConfig(const ConfigNode& node);
};

/// The track commands sent, in time order; each holds until the next (none before the first:
/// the base stands). A fixed-size ring: the oldest commands are dropped when it is full.
class TrackCommandHistory {
 public:
  /// track_gauge [m]: the design distance between the track centre lines (BaseGeometry).
  explicit TrackCommandHistory(double track_gauge, std::size_t capacity = 4096);

  /// A command as sent (command.t: host time). Throws InputError if it is older than the last.
  void Add(const TrackCommand& command);
  /// T_prev_current: the motion from ta to tb under the commands, with the no-slip skid-steer
  /// kinematics (each constant-command piece an exact arc).
  Pose2 Step(Seconds ta, Seconds tb) const;
  /// The step with its covariance by the noise model: a motion measurement for AddScan.
  MotionMeasurement Measure(Seconds ta, Seconds tb, const OdometryNoise& noise) const;
  /// Forget the commands superseded before t (the one in force at t is kept).
  void DropBefore(Seconds t);
  std::size_t size() const { return commands_.size(); }

 private:
  double gauge_;
  std::size_t capacity_;
  std::vector<TrackCommand> commands_;
};

}  // namespace ifab::base
