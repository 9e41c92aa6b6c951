#include "ifab/arm/primitives.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "ifab/arm/dynamics.h"
#include "ifab/core/angles.h"
#include "ifab/core/config.h"
#include "ifab/core/error.h"

namespace ifab::arm {
namespace {

double MinimumJerk(double s) {
  s = std::clamp(s, 0.0, 1.0);
  return s * s * s * (10.0 + s * (-15.0 + 6.0 * s));
}

Pose3 Translation(const Eigen::Vector3d& t) {
  Pose3 p = Pose3::Identity();
  p.translation() = t;
  return p;
}

PrimitiveResult Failure(std::string message, const Vector6d& q) {
  PrimitiveResult r;
  r.ok = false;
  r.message = std::move(message);
  r.q_end = q;
  return r;
}

}  // namespace

PrimitiveOptions PrimitiveOptions::FromConfig(const ConfigNode& node) {
  node.ExpectMap();
  node.ExpectKeys({"approach_height", "line_speed", "line_angular_speed", "line_min_duration", "sample_dt",
                   "gripper_settle", "release_height", "max_joint_step", "allow_brick_yaw_flip"});
  PrimitiveOptions o;
  node.ReadNonNegative("approach_height", o.approach_height);
  node.ReadPositive("line_speed", o.line_speed);
  node.ReadPositive("line_angular_speed", o.line_angular_speed);
  node.ReadPositive("line_min_duration", o.line_min_duration);
  node.ReadPositive("sample_dt", o.sample_dt);
  node.ReadNonNegative("gripper_settle", o.gripper_settle);
  node.ReadNonNegative("release_height", o.release_height);
  node.ReadPositive("max_joint_step", o.max_joint_step);
  node.Read("allow_brick_yaw_flip", o.allow_brick_yaw_flip);
  return o;
}

ArmOptions ArmOptions::FromConfig(const ConfigNode& root) {
  root.ExpectMap();
  root.ExpectKeys({"ilqg", "ik", "primitives"});
  ArmOptions o;
  if (auto s = root.Find("ilqg")) o.ilqg = IlqgOptions::FromConfig(*s);
  if (auto s = root.Find("ik")) o.ik = IkOptions::FromConfig(*s);
  if (auto s = root.Find("primitives")) o.primitives = PrimitiveOptions::FromConfig(*s);
  return o;
}

ArmOptions ArmOptions::Load(const std::string& path) { return FromConfig(ConfigNode::LoadFile(path)); }

void PrimitiveResult::Append(PrimitiveResult&& next) {
  ok = ok && next.ok;
  if (!next.message.empty()) message += (message.empty() ? "" : "; ") + next.message;
  for (ArmStep& s : next.steps) steps.push_back(std::move(s));
  for (PlanSummary& p : next.plans) plans.push_back(std::move(p));
  q_end = next.q_end;
}

Seconds PrimitiveResult::Duration() const {
  Seconds t = 0.0;
  for (const ArmStep& s : steps) t += s.trajectory.Duration() + s.settle;
  return t;
}

ArmPrimitives::ArmPrimitives(const RobotModel& robot, const ArmOptions& options)
    : robot_(robot),
      options_(options),
      ik_(robot, options.ik),
      planner_(ArmModel::FromRobotModel(robot), options.ilqg) {}

PrimitiveResult ArmPrimitives::MoveToJoints(const Vector6d& q_current, const Vector6d& q_goal) {
  const ArmPlan plan = planner_.Plan(q_current, q_goal);
  PrimitiveResult r;
  r.plans.push_back(plan.summary);
  r.q_end = plan.trajectory.points.back().q;
  if (!plan.summary.IsUsable()) {
    r.ok = false;
    r.message = "move to joints: " + plan.summary.BriefReport();
    return r;
  }
  r.steps.push_back({"move to joints", plan.trajectory, GripperAction::kNone, 0.0});
  return r;
}

PrimitiveResult ArmPrimitives::SweepJoint(const Vector6d& q_current, int joint, double from, double to,
                                          double speed) {
  IFAB_THROW_UNLESS(joint >= 0 && joint < kDof, "sweep: joint index {} outside 0..5", joint);
  IFAB_THROW_UNLESS(std::isfinite(from) && std::isfinite(to) && from >= robot_.q_min[joint] &&
                        from <= robot_.q_max[joint] && to >= robot_.q_min[joint] && to <= robot_.q_max[joint],
                    "sweep: joint {} range [{:.4f}, {:.4f}] rad outside its limits [{:.4f}, {:.4f}]", joint + 1,
                    from, to, robot_.q_min[joint], robot_.q_max[joint]);
  IFAB_THROW_UNLESS(speed > 0.0 && speed <= robot_.qd_max[joint],
                    "sweep: speed {:.4f} rad/s must be positive and at most joint {}'s limit {:.4f} rad/s", speed,
                    joint + 1, robot_.qd_max[joint]);
  PrimitiveResult result;
  result.q_end = q_current;
  Vector6d q_start = q_current;
  q_start[joint] = from;
  if ((q_start - q_current).cwiseAbs().maxCoeff() > 1e-6) {
    result = MoveToJoints(q_current, q_start);
    if (!result.ok) return result;
  }
  // Start from where the move really ended (within the planner's goal tolerance).
  q_start = result.q_end;
  const double span = to - q_start[joint];
  const double duration = std::abs(span) / speed;
  const int n = std::max(1, static_cast<int>(std::ceil(duration / options_.primitives.sample_dt - 1e-9)));
  ArmStep step{fmt::format("sweep joint {}", joint + 1), {}, GripperAction::kNone, 0.0};
  step.trajectory.points.resize(n + 1);
  for (int k = 0; k <= n; ++k) {
    JointTrajectory::Point& p = step.trajectory.points[k];
    p.t = duration * k / n;
    p.q = q_start;
    p.q[joint] = q_start[joint] + span * k / n;
    p.qd.setZero();
    if (k < n && duration > 0.0) p.qd[joint] = span / duration;  // constant speed; at rest at the end
  }
  result.q_end = step.trajectory.points.back().q;
  result.steps.push_back(std::move(step));
  return result;
}

PrimitiveResult ArmPrimitives::MoveGripperLinear(const Vector6d& q_current, const Pose3& T_arm_base_gripper,
                                                 const std::string& name) {
  const PrimitiveOptions& o = options_.primitives;
  const Pose3 T_gripper_tool0 = robot_.T_tool0_gripper.inverse();
  const Pose3 start = ForwardKinematics(planner_.model(), q_current) * robot_.T_tool0_gripper;
  const double distance = TranslationDistance(start, T_arm_base_gripper);
  const double angle = RotationAngle(start, T_arm_base_gripper);
  // Minimum jerk peaks at 1.875 times the mean speed.
  const double duration = std::max({o.line_min_duration, 1.875 * distance / o.line_speed,
                                    1.875 * angle / o.line_angular_speed});
  const int n = std::max(2, static_cast<int>(std::ceil(duration / o.sample_dt - 1e-9)));
  ArmStep step{name, {}, GripperAction::kNone, 0.0};
  std::vector<JointTrajectory::Point>& pts = step.trajectory.points;
  pts.resize(n + 1);
  pts[0].q = q_current;
  Vector6d q_prev = q_current;
  for (int k = 1; k <= n; ++k) {
    const Pose3 T_arm_base_tool0 = Interpolate(start, T_arm_base_gripper, MinimumJerk(static_cast<double>(k) / n)) *
                                   T_gripper_tool0;
    IkResult r = ik_.SolveFrom(T_arm_base_tool0, q_prev);
    if (!r.ok()) r = ik_.Solve(T_arm_base_tool0, q_prev);
    if (!r.ok()) return Failure(fmt::format("{}: knot {}/{} unreachable: {}", name, k, n, r.message), q_current);
    const double jump = (r.q - q_prev).cwiseAbs().maxCoeff();
    if (jump > o.max_joint_step) {
      return Failure(fmt::format("{}: knot {}/{} needs a joint jump of {:.1f} deg (singularity or wrist flip)", name,
                                 k, n, RadToDeg(jump)),
                     q_current);
    }
    pts[k].t = duration * k / n;
    pts[k].q = r.q;
    q_prev = r.q;
  }
  for (int k = 1; k < n; ++k) pts[k].qd = (pts[k + 1].q - pts[k - 1].q) / (pts[k + 1].t - pts[k - 1].t);
  pts[0].qd.setZero();
  pts[n].qd.setZero();
  PrimitiveResult result;
  result.q_end = pts[n].q;
  result.steps.push_back(std::move(step));
  return result;
}

Pose3 ArmPrimitives::GripperPoseOnBrick(const Pose3& T_site_brick, const Box& brick, bool yaw_flip) {
  // Top face centre, gripper z down into the brick, gripper x along the brick's x (or against it).
  Pose3 T_brick_gripper = Translation(Eigen::Vector3d(0.0, 0.0, 0.5 * brick.size.z()));
  T_brick_gripper.linear() = (Eigen::AngleAxisd(yaw_flip ? kPi : 0.0, Eigen::Vector3d::UnitZ()) *
                              Eigen::AngleAxisd(kPi, Eigen::Vector3d::UnitX()))
                                 .toRotationMatrix();
  return T_site_brick * T_brick_gripper;
}

Pose3 ArmPrimitives::FlangePoseInArmBase(const Pose3& T_site_base, const Pose3& T_site_gripper) const {
  const Pose3 T_arm_base_site = (T_site_base * robot_.T_base_arm_base).inverse();
  return T_arm_base_site * T_site_gripper * robot_.T_tool0_gripper.inverse();
}

PrimitiveResult ArmPrimitives::GripSequence(const Vector6d& q_current, const Pose3& T_site_base,
                                            const Pose3& T_site_brick, const Box& brick, double action_height,
                                            GripperAction action, const std::string& what) {
  const PrimitiveOptions& o = options_.primitives;
  const Pose3 T_arm_base_site = (T_site_base * robot_.T_base_arm_base).inverse();
  // Choose the brick's grip (as is or turned by 180 deg) whose approach pose is nearest.
  Pose3 T_site_grip = Pose3::Identity();
  IkResult best;
  double best_distance = std::numeric_limits<double>::infinity();
  for (int flip = 0; flip < (o.allow_brick_yaw_flip ? 2 : 1); ++flip) {
    const Pose3 grip = Translation(Eigen::Vector3d(0, 0, action_height)) * GripperPoseOnBrick(T_site_brick, brick, flip);
    const Pose3 above = Translation(Eigen::Vector3d(0, 0, o.approach_height)) * grip;
    IkResult r = ik_.Solve(FlangePoseInArmBase(T_site_base, above), q_current);
    if (!r.ok()) {
      if (flip == 0) best = r;
      continue;
    }
    const double d = (r.q - q_current).norm();
    if (d < best_distance) {
      best_distance = d;
      best = r;
      T_site_grip = grip;
    }
  }
  if (!best.ok()) return Failure(fmt::format("{}: approach pose: {}", what, best.message), q_current);

  PrimitiveResult result = MoveToJoints(q_current, best.q);
  if (!result.ok) return result;
  result.steps.back().name = "move above " + what;

  const Pose3 T_arm_base_grip = T_arm_base_site * T_site_grip;
  const Pose3 T_arm_base_above = T_arm_base_site * Translation(Eigen::Vector3d(0, 0, o.approach_height)) * T_site_grip;
  PrimitiveResult descend = MoveGripperLinear(result.q_end, T_arm_base_grip, "descend onto " + what);
  if (!descend.ok) {
    result.Append(std::move(descend));
    return result;
  }
  descend.steps.back().gripper = action;
  descend.steps.back().settle = o.gripper_settle;
  result.Append(std::move(descend));
  result.Append(MoveGripperLinear(result.q_end, T_arm_base_above, "lift from " + what));
  return result;
}

PrimitiveResult ArmPrimitives::PickBrick(const Vector6d& q_current, const Pose3& T_site_base, const Pose3& T_site_brick,
                                         const Box& brick) {
  return GripSequence(q_current, T_site_base, T_site_brick, brick, 0.0, GripperAction::kGrip, "brick to pick");
}

PrimitiveResult ArmPrimitives::PlaceBrick(const Vector6d& q_current, const Pose3& T_site_base,
                                          const Pose3& T_site_brick_goal, const Box& brick) {
  return GripSequence(q_current, T_site_base, T_site_brick_goal, brick, options_.primitives.release_height,
                      GripperAction::kRelease, "brick goal");
}

ExecuteResult ExecuteSteps(hal::Robot& robot, const std::vector<ArmStep>& steps, const ExecuteOptions& options) {
  ExecuteResult result;
  const Seconds t0 = robot.Now();
  bool holding = options.holding;
  for (const ArmStep& step : steps) {
    if (!step.trajectory.points.empty()) {
      robot.SendJointTrajectory(step.trajectory);
      if (const std::string why = robot.ArmRejection(); !why.empty()) {
        result.ok = false;
        result.rejected = true;
        result.message = fmt::format("step '{}': the arm controller rejected the trajectory: {}", step.name, why);
        break;
      }
      const Seconds deadline = robot.Now() + step.trajectory.Duration() + options.timeout_margin;
      do {
        robot.Wait(options.poll);
      } while (robot.ArmBusy() && robot.Now() < deadline);
      if (robot.ArmBusy()) {
        result.ok = false;
        result.message = fmt::format("step '{}': the arm is still busy {:.1f} s after the trajectory should have "
                                     "ended",
                                     step.name, options.timeout_margin);
        break;
      }
    }
    if (step.gripper != GripperAction::kNone) robot.SetGripper(step.gripper == GripperAction::kGrip);
    if (step.settle > 0.0) robot.Wait(step.settle);
    if (step.gripper != GripperAction::kNone) holding = step.gripper == GripperAction::kGrip;
    // A brick that should be held but is not (a failed grip or a drop) ends the motion here:
    // carrying on would "place" nothing.
    if (holding && robot.VacuumHolding() == false) {
      result.ok = false;
      result.lost_grip = true;
      result.message = fmt::format("after step '{}': the vacuum sensor reports no brick", step.name);
      ++result.steps_done;
      break;
    }
    ++result.steps_done;
  }
  result.elapsed = robot.Now() - t0;
  return result;
}

}  // namespace ifab::arm
