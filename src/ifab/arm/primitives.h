#pragma once
/// \file
/// Manipulation primitives (paper Sec. IV): "whole sequences of arm motion and object
/// manipulation are created by combining the planned trajectories with a library of
/// pre-programmed manipulation primitives, such as picking up a brick from the brick feeder, and
/// moving a joint at constant velocity."
///
/// Every primitive returns a list of ArmSteps (a joint trajectory for the arm's own controller,
/// then an optional gripper action), starting at the configuration it is given and ending at
/// `q_end`, so primitives chain: pass one's q_end as the next one's start. ExecuteSteps runs a
/// list on any hal::Robot (the simulator or a real machine).
///
/// Frames: the robot's base pose in the site is T_site_base (from localization); the arm foot on
/// the base T_base_arm_base and the gripper's contact point on the flange T_tool0_gripper come
/// from the RobotModel. A brick is gripped at the centre of its top face with the gripper's z
/// axis pointing down into it and the gripper's x along the brick's long (x) axis, or turned
/// by 180 deg about the vertical if that is nearer (the brick is symmetric).

#include <string>
#include <vector>

#include "ifab/arm/ik.h"
#include "ifab/arm/ilqg.h"
#include "ifab/core/se3.h"
#include "ifab/hal/robot.h"
#include "ifab/model/geometry.h"
#include "ifab/model/robot_model.h"
#include "ifab/msgs/msgs.h"

namespace ifab {
class ConfigNode;
}

namespace ifab::arm {

enum class GripperAction { kNone, kGrip, kRelease };

/// One step: move along `trajectory` (if any), then act with the gripper and wait `settle`.
struct ArmStep {
  std::string name;                             ///< what the step does, for logs
  JointTrajectory trajectory;                   ///< empty for a gripper-only step
  GripperAction gripper{GripperAction::kNone};  ///< after the trajectory
  Seconds settle{0.0};                          ///< wait after the gripper action [s]
};

struct PrimitiveOptions {
  double approach_height{0.15};      ///< approach and retreat this far above the grip, along site z [m]
  double line_speed{0.10};           ///< peak gripper speed on straight descents and lifts [m/s]
  double line_angular_speed{0.5};    ///< peak gripper turn rate on straight moves [rad/s]
  double line_min_duration{0.5};     ///< shortest straight move [s]
  double sample_dt{0.02};            ///< knot spacing of straight moves and sweeps [s]
  double gripper_settle{0.5};        ///< wait after switching the vacuum [s]
  double release_height{0.0};        ///< release a brick this far above its goal pose [m]
  double max_joint_step{0.05};       ///< largest joint change between two knots of a straight move [rad]
  bool allow_brick_yaw_flip{true};   ///< grip a brick turned by 180 deg if that is nearer

  /// Read the `primitives:` section (every key optional; unknown keys rejected).
  static PrimitiveOptions FromConfig(const ConfigNode& node);
};

/// All options of the arm module, read from one file (data/arm/arm.yaml: ilqg, ik, primitives).
struct ArmOptions {
  IlqgOptions ilqg;
  IkOptions ik;
  PrimitiveOptions primitives;

  static ArmOptions FromConfig(const ConfigNode& root);
  static ArmOptions Load(const std::string& path);
};

/// What a primitive produced: ok() or a message saying what failed (unreachable pose, failed
/// plan); the steps up to the failure are kept for inspection but should not be executed.
struct PrimitiveResult {
  bool ok{true};
  std::string message;
  std::vector<ArmStep> steps;
  Vector6d q_end{Vector6d::Zero()};   ///< configuration after the last step
  std::vector<PlanSummary> plans;     ///< summaries of the iLQG plans used

  /// Append another primitive's result (which must start at this one's q_end).
  void Append(PrimitiveResult&& next);
  /// Total duration of the trajectories and settle times [s].
  Seconds Duration() const;
};

class ArmPrimitives {
 public:
  ArmPrimitives(const RobotModel& robot, const ArmOptions& options);

  /// Move to a joint configuration (iLQG). Throws InputError if q_goal violates the limits.
  PrimitiveResult MoveToJoints(const Vector6d& q_current, const Vector6d& q_goal);

  /// The scan sweep: joint `joint` (0-based) from `from` to `to` [rad] at constant `speed`
  /// [rad/s], the other joints held at q_current; an iLQG move to the sweep's start comes first
  /// when the arm is not there. Throws InputError for a bad joint, range or speed.
  PrimitiveResult SweepJoint(const Vector6d& q_current, int joint, double from, double to, double speed);

  /// Move the gripper's contact point along a straight line (slerp in orientation) to
  /// T_arm_base_gripper, with a minimum-jerk time law (the robot's "move linear").
  PrimitiveResult MoveGripperLinear(const Vector6d& q_current, const Pose3& T_arm_base_gripper,
                                    const std::string& name = "linear");

  /// Pick the brick at T_site_brick (its centre): iLQG move above it, descend, grip, lift.
  PrimitiveResult PickBrick(const Vector6d& q_current, const Pose3& T_site_base, const Pose3& T_site_brick,
                            const Box& brick);

  /// Pick the brick the on-board feeder presents at T_base_brick (robot YAML feeder_in_base):
  /// the same sequence in the base frame, independent of where the robot stands.
  PrimitiveResult PickBrickFromFeeder(const Vector6d& q_current, const Pose3& T_base_brick, const Box& brick) {
    return PickBrick(q_current, Pose3::Identity(), T_base_brick, brick);
  }

  /// Place the held brick so that its centre lands at T_site_brick_goal: iLQG move above the
  /// goal, descend, release, lift.
  PrimitiveResult PlaceBrick(const Vector6d& q_current, const Pose3& T_site_base, const Pose3& T_site_brick_goal,
                             const Box& brick);

  /// The gripper pose that grips a brick at T_site_brick (top face centre, z down).
  static Pose3 GripperPoseOnBrick(const Pose3& T_site_brick, const Box& brick, bool yaw_flip = false);
  /// Flange pose in arm_base that puts the gripper at T_site_gripper when the base is at T_site_base.
  Pose3 FlangePoseInArmBase(const Pose3& T_site_base, const Pose3& T_site_gripper) const;

  const RobotModel& robot() const { return robot_; }
  IkSolver& ik() { return ik_; }
  IlqgPlanner& planner() { return planner_; }
  const ArmOptions& options() const { return options_; }

 private:
  // Approach, descend, act, lift at a gripper pose in the site frame.
  PrimitiveResult GripSequence(const Vector6d& q_current, const Pose3& T_site_base, const Pose3& T_site_brick,
                               const Box& brick, double lift_before_action, GripperAction action,
                               const std::string& what);

  RobotModel robot_;
  ArmOptions options_;
  IkSolver ik_;
  IlqgPlanner planner_;
};

struct ExecuteOptions {
  Seconds poll{0.02};            ///< how often ArmBusy() is checked [s]
  Seconds timeout_margin{5.0};   ///< give up this long after a trajectory should have ended [s]
  bool holding{false};           ///< the gripper holds a brick at the start (checked by the vacuum sensor)
};

struct ExecuteResult {
  bool ok{true};
  std::string message;
  int steps_done{0};             ///< steps completed (the failed one not counted)
  bool rejected{false};          ///< the arm controller refused step steps_done (the arm did not move)
  bool lost_grip{false};         ///< the vacuum sensor says the brick is gone (or the grip did not take)
  Seconds elapsed{0.0};  ///< host time spent [s]
};

/// Run steps on a robot: send each trajectory, wait until the arm is no longer busy, then switch
/// the gripper and wait its settle time.
ExecuteResult ExecuteSteps(hal::Robot& robot, const std::vector<ArmStep>& steps, const ExecuteOptions& options = {});

}  // namespace ifab::arm
