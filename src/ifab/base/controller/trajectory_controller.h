#pragma once
/// \file
/// Base trajectory controller (paper Sec. III-C, eq. 4): a P-controller that follows a planned
/// time-independent sequence of poses with nominal v and omega, fed with the estimated pose.
///
/// At each update the point of the trajectory closest to the current pose is found; its nominal
/// linear velocity v_k is used directly and the angular velocity is
///   omega_k = omega_nom_k + p_t * e_t + p_theta * e_theta,            (4)
/// where e_t and e_theta are the translational and angular displacements between the current pose
/// and the closest point. Track speeds follow from v_k and omega_k; if one would exceed its limit,
/// the linear speed is reduced (the robot slows down and turns back onto the path). The controller
/// is done when the end pose is reached within tolerance.
///
/// Details the paper leaves open, chosen here: the closest point is the nearest point on the
/// polyline through the poses, in a metric that counts heading (so turning on the spot advances
/// along the trajectory), searched in a window ahead of the previous one; e_t is the lateral
/// displacement of the closest point in its own frame, signed by the driving direction; and once
/// the closest point is the end, v is a P-law on the distance left along the end heading, then
/// the robot turns on the spot onto the end heading (end_approach_gain; 0 keeps the end's nominal
/// v and eq. 4 alone, which does not stop at the end). A tracked base cannot move sideways, so a
/// sideways offset left at the end by the tracking stays: `done` means reached along the end
/// heading and in heading; `end_reached` says whether the sideways offset is within tolerance too.

#include <array>
#include <optional>

#include "ifab/base/planner/base_trajectory.h"
#include "ifab/base/planner/planning_scene.h"
#include "ifab/core/config.h"
#include "ifab/core/se2.h"
#include "ifab/msgs/msgs.h"

namespace ifab::base {

struct BaseControllerOptions {
  double p_t{8.0};                ///< gain on the translational displacement e_t [rad/s per m]
  double p_theta{2.0};            ///< gain on the angular displacement e_theta [1/s]
  double track_gauge{1.0};        ///< distance between the track centre lines B [m]
  double max_track_speed{0.3};    ///< track speed limit [m/s]
  double goal_tolerance_xy{0.01};     ///< done when the end is this close along its heading [m]
  double goal_tolerance_theta{0.026};  ///< and the end heading this close [rad] (1.5 deg)
  double heading_scale{0.5};      ///< length [m] per radian of heading in the closest-point metric
  int search_ahead{8};            ///< closest point searched this many segments ahead of the last
  int search_behind{2};           ///< and this many behind
  double end_approach_gain{0.5};  ///< P-gain [1/s] on the distance to the end once it is closest (0: eq. 4 only)
  double min_end_speed{0.01};     ///< |v| floor of the end approach [m/s], so the robot arrives
  /// [s] Within tolerance the controller commands a stop and is done only if the pose stays
  /// within tolerance this long: a hydraulic base coasts on after a stop command (0.3 s lag at
  /// 0.3 rad/s is 5 deg), and coasting out of tolerance resumes control. 0: done at once (paper).
  double settle_hold{0.5};

  /// Read a `base_controller` YAML section; fields not named keep their defaults.
  static BaseControllerOptions FromConfig(const ConfigNode& node);
  /// Take the track gauge and the track speed limit from the robot's base geometry.
  BaseControllerOptions& SetTracks(const BaseGeometry& robot) {
    track_gauge = robot.track_gauge;
    max_track_speed = robot.max_track_speed;
    return *this;
  }
};

/// What one update computed (for logging and tests).
struct BaseControllerOutput {
  TrackCommand command;     ///< track speed references [m/s]
  double v{0.0};            ///< commanded linear velocity [m/s]
  double omega{0.0};        ///< commanded angular velocity [rad/s]
  double closest{0.0};      ///< closest point as segment index + fraction
  double e_t{0.0};          ///< translational displacement [m]
  double e_theta{0.0};      ///< angular displacement [rad]
  bool speed_limited{false};  ///< v was reduced to keep the tracks within their limit
  bool done{false};         ///< the end is reached along its heading and in heading (commands zero)
  bool end_reached{false};  ///< done and also within goal_tolerance_xy sideways (the full end pose)
  double end_distance{0.0};       ///< distance to the end position [m]
  double end_lateral_error{0.0};  ///< sideways offset of the end position in its own frame [m]
};

class BaseTrajectoryController {
 public:
  explicit BaseTrajectoryController(BaseControllerOptions options = {});

  /// Start following a new trajectory (at least one pose).
  void SetTrajectory(BaseTrajectory trajectory);
  /// One control step with the estimated pose T_site_base at host time t.
  BaseControllerOutput Update(const Pose2& T_site_base, double t);

  bool done() const { return done_; }
  const BaseTrajectory& trajectory() const { return trajectory_; }
  const BaseControllerOptions& options() const { return options_; }

  /// Track speeds for (v, omega), with v reduced if a track would exceed max_track_speed.
  /// Returns true if v was reduced.
  static bool ToTrackSpeeds(double v, double omega, double track_gauge, double max_track_speed, double* v_out,
                            double* omega_out, TrackCommand* command);

 private:
  BaseControllerOptions options_;
  BaseTrajectory trajectory_;
  double progress_{0.0};  // segment index + fraction of the last closest point
  bool done_{false};
  bool at_end_{false};  // the end has been the closest point
  double stop_time_{-1.0};  // when the stop within tolerance was commanded (< 0: not stopping)
};

/// A straight re-approach onto `goal` along its heading, for a sideways offset the tracking left
/// at the end (a tracked base cannot move sideways): two legs to follow one after the other,
/// first in reverse from `from` along the goal's line to `distance` behind the goal, then forward
/// onto it (or forward first to `distance` ahead, then in reverse: `reverse_first` false); eq. 4
/// steers the offset out on both. Poses every `step` [m] at nominal speed `speed` [m/s], all with
/// the goal's heading.
std::array<BaseTrajectory, 2> ReapproachTrajectories(const Pose2& from, const Pose2& goal, double distance,
                                                     double speed, bool reverse_first = true, double step = 0.05);

}  // namespace ifab::base
