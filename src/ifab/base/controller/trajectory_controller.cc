#include "ifab/base/controller/trajectory_controller.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ifab/core/angles.h"
#include "ifab/core/error.h"

namespace ifab::base {

BaseControllerOptions BaseControllerOptions::FromConfig(const ConfigNode& node) {
  BaseControllerOptions o;
  node.ExpectKeys({"p_t", "p_theta", "track_gauge", "max_track_speed", "goal_tolerance_xy", "goal_tolerance_theta",
                   "heading_scale", "search_ahead", "search_behind", "end_approach_gain", "min_end_speed", "settle_hold"});
  node.ReadNonNegative("p_t", o.p_t);
  node.ReadNonNegative("p_theta", o.p_theta);
  node.ReadPositive("track_gauge", o.track_gauge);
  node.ReadPositive("max_track_speed", o.max_track_speed);
  node.ReadPositive("goal_tolerance_xy", o.goal_tolerance_xy);
  node.ReadPositive("goal_tolerance_theta", o.goal_tolerance_theta);
  node.ReadPositive("heading_scale", o.heading_scale);
  node.ReadPositive("search_ahead", o.search_ahead);
  node.ReadNonNegative("search_behind", o.search_behind);
  node.ReadNonNegative("end_approach_gain", o.end_approach_gain);
  node.ReadNonNegative("min_end_speed", o.min_end_speed);
  node.ReadNonNegative("settle_hold", o.settle_hold);
  return o;
}

BaseTrajectoryController::BaseTrajectoryController(BaseControllerOptions options) : options_(options) {}

void BaseTrajectoryController::SetTrajectory(BaseTrajectory trajectory) {
  IFAB_THROW_UNLESS(!trajectory.empty(), "base trajectory controller: expected a trajectory with at least one pose");
  trajectory_ = std::move(trajectory);
  progress_ = 0.0;
  done_ = false;
  at_end_ = false;
  stop_time_ = -1.0;
}

bool BaseTrajectoryController::ToTrackSpeeds(double v, double omega, double track_gauge, double max_track_speed,
                                             double* v_out, double* omega_out, TrackCommand* command) {
  const double half = 0.5 * track_gauge;
  bool limited = false;
  // Turning alone may not exceed the limit; then the linear speed takes what is left.
  const double omega_max = max_track_speed / half;
  if (std::abs(omega) > omega_max) omega = std::copysign(omega_max, omega);
  const double v_max = max_track_speed - half * std::abs(omega);
  if (std::abs(v) > v_max) {
    v = std::copysign(v_max, v);
    limited = true;
  }
  *v_out = v;
  *omega_out = omega;
  command->v_left = v - half * omega;
  command->v_right = v + half * omega;
  return limited;
}

BaseControllerOutput BaseTrajectoryController::Update(const Pose2& pose, double t) {
  IFAB_THROW_UNLESS(!trajectory_.empty(), "base trajectory controller: Update() before SetTrajectory()");
  BaseControllerOutput out;
  out.command.t = t;
  const auto& pts = trajectory_.points;
  const int segments = static_cast<int>(pts.size()) - 1;
  const double rho = options_.heading_scale;

  // Closest point on the polyline through the poses, in (x, y, rho * theta).
  double best_d2 = std::numeric_limits<double>::infinity();
  int best_j = segments > 0 ? 0 : -1;
  double best_s = 1.0;
  const int j0 = std::max(0, static_cast<int>(progress_) - options_.search_behind);
  const int j1 = std::min(segments - 1, static_cast<int>(progress_) + options_.search_ahead);
  for (int j = j0; j <= j1; ++j) {
    const Pose2& a = pts[j].pose;
    const Pose2& b = pts[j + 1].pose;
    const Eigen::Vector3d za(a.x, a.y, 0.0);
    const Eigen::Vector3d zb(b.x, b.y, rho * WrapAngle(b.theta - a.theta));
    const Eigen::Vector3d zr(pose.x, pose.y, rho * WrapAngle(pose.theta - a.theta));
    const Eigen::Vector3d ab = zb - za;
    const double l2 = ab.squaredNorm();
    const double s = l2 > 0.0 ? std::clamp((zr - za).dot(ab) / l2, 0.0, 1.0) : 0.0;
    const double d2 = (za + s * ab - zr).squaredNorm();
    if (d2 < best_d2) {
      best_d2 = d2;
      best_j = j;
      best_s = s;
    }
  }
  Pose2 ref;
  double v_ref = 0.0, omega_ref = 0.0;
  if (best_j < 0) {
    ref = pts[0].pose;
    out.closest = 0.0;
  } else {
    const auto& a = pts[best_j];
    const auto& b = pts[best_j + 1];
    ref = Interpolate(a.pose, b.pose, best_s);
    v_ref = a.v + best_s * (b.v - a.v);
    omega_ref = a.omega + best_s * (b.omega - a.omega);
    out.closest = best_j + best_s;
    progress_ = out.closest;
  }

  const Pose2& end = pts.back().pose;
  const double e_theta_end = WrapAngle(end.theta - pose.theta);
  const double along_end = std::cos(end.theta) * (end.x - pose.x) + std::sin(end.theta) * (end.y - pose.y);
  out.end_lateral_error = -std::sin(end.theta) * (end.x - pose.x) + std::cos(end.theta) * (end.y - pose.y);
  out.end_distance = TranslationDistance(pose, end);
  // Once the end has been the closest point, it stays the target (no chattering at its edge).
  at_end_ = at_end_ || segments == 0 || out.closest >= segments - 1e-9;
  const bool within = (at_end_ || out.closest >= segments - 1) && std::abs(along_end) <= options_.goal_tolerance_xy &&
                      std::abs(e_theta_end) <= options_.goal_tolerance_theta;
  if (!done_ && !within) stop_time_ = -1.0;  // (coasted) out of tolerance: control again
  if (!done_ && within) {
    if (stop_time_ < 0.0) stop_time_ = t;
    if (t - stop_time_ < options_.settle_hold) return out;  // stopped (zero command), watching it settle
    done_ = true;
  }
  if (done_) {
    out.done = true;
    out.end_reached = out.end_distance <= options_.goal_tolerance_xy;
    return out;
  }

  // Displacements from the current pose to the closest point (eq. 4).
  const Eigen::Vector2d d(ref.x - pose.x, ref.y - pose.y);
  const double lateral = -std::sin(ref.theta) * d.x() + std::cos(ref.theta) * d.y();
  out.e_theta = WrapAngle(ref.theta - pose.theta);
  const bool at_end = at_end_;
  double v = v_ref;
  double omega_nom = omega_ref;
  bool turn_onto_end = false;
  if (at_end && options_.end_approach_gain > 0.0) {
    // The end is the closest point: a P-law on the distance left along the end heading brings the
    // robot onto the end (eq. 4 still steers it onto the end's line), then it turns on the spot
    // onto the end heading. A lateral offset left by the tracking stays: it is reported.
    const double cap = std::max(std::abs(v_ref), options_.min_end_speed);
    v = std::abs(along_end) > 0.5 * options_.goal_tolerance_xy
            ? std::clamp(options_.end_approach_gain * along_end, -cap, cap)
            : 0.0;
    if (v != 0.0 && std::abs(v) < options_.min_end_speed) v = std::copysign(options_.min_end_speed, v);
    omega_nom = 0.0;
    turn_onto_end = v == 0.0;
  }
  // Reversing steers the other way round.
  const double direction = v < 0.0 ? -1.0 : 1.0;
  out.e_t = direction * lateral;
  const double omega = turn_onto_end ? options_.p_theta * e_theta_end
                                     : omega_nom + options_.p_t * out.e_t + options_.p_theta * out.e_theta;
  out.speed_limited =
      ToTrackSpeeds(v, omega, options_.track_gauge, options_.max_track_speed, &out.v, &out.omega, &out.command);
  return out;
}

std::array<BaseTrajectory, 2> ReapproachTrajectories(const Pose2& from, const Pose2& goal, double distance,
                                                     double speed, bool reverse_first, double step) {
  IFAB_THROW_UNLESS(distance > 0.0 && speed > 0.0 && step > 0.0, "re-approach: expected positive lengths");
  const Eigen::Vector2d dir(std::cos(goal.theta), std::sin(goal.theta));
  auto at = [&](double s) { return Pose2(goal.x + s * dir.x(), goal.y + s * dir.y(), goal.theta); };
  // A straight leg along the goal's line from s0 to s1 (s: signed distance ahead of the goal).
  auto leg = [&](const Pose2& start, double s0, double s1) {
    const double v = s1 < s0 ? -speed : speed;
    const int n = std::max(1, static_cast<int>(std::ceil(std::abs(s1 - s0) / step)));
    BaseTrajectory t;
    t.points.push_back({start, v, 0.0});
    for (int k = 1; k <= n; ++k) t.points.push_back({at(s0 + (s1 - s0) * k / n), v, 0.0});
    t.duration = std::abs(s1 - s0) / speed;
    return t;
  };
  const double s_from = dir.dot(Eigen::Vector2d(from.x - goal.x, from.y - goal.y));
  const double s_turn = reverse_first ? std::min(s_from, 0.0) - distance : std::max(s_from, 0.0) + distance;
  return {leg(from, s_from, s_turn), leg(at(s_turn), s_turn, 0.0)};
}

}  // namespace ifab::base
