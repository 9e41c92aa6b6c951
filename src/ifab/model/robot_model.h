#pragma once
/// \file
/// The robot description: a URDF read with urdfdom and turned into KDL (no ROS needed).
/// Gives the arm chain (arm_base -> tool0) with joint limits, and the fixed mounts of the arm,
/// the lasers and the gripper.

#include <kdl/chain.hpp>
#include <kdl/tree.hpp>

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "ifab/core/se3.h"

namespace ifab {

class ConfigNode;

using Vector6d = Eigen::Matrix<double, 6, 1>;

struct RobotModel {
  std::string urdf_path;
  KDL::Tree tree;              ///< every link of the URDF
  KDL::Chain arm_chain;        ///< arm_base -> tool0, 6 revolute joints
  std::vector<std::string> joint_names;  ///< the chain's joints in order
  Vector6d q_min, q_max;       ///< joint limits [rad]
  Vector6d qd_max;             ///< joint speed limits [rad/s]
  Vector6d effort_max;         ///< joint effort limits [N m]
  Pose3 T_base_arm_base;       ///< arm foot on the base
  Pose3 T_base_base_laser;     ///< base laser on the base
  Pose3 T_tool0_arm_laser;     ///< arm laser on the flange (design value; calibration refines it)
  Pose3 T_tool0_gripper;       ///< vacuum gripper's contact point on the flange

  /// Flange pose in arm_base at joint angles q (KDL forward kinematics).
  Pose3 ArmForwardKinematics(const Vector6d& q) const;
  /// True if every joint lies within its limits (with a tolerance).
  bool WithinLimits(const Vector6d& q, double tolerance = 1e-9) const;
};

/// Read a URDF. Throws InputError naming the file and what is wrong (unparsable XML, a missing
/// link or joint, a chain that is not six revolute joints, missing limits).
RobotModel LoadRobotModel(const std::string& urdf_path);
/// The same from URDF text; `name` stands for the file in messages.
RobotModel ParseRobotModel(const std::string& urdf_text, const std::string& name);

/// Override mounts from a robot YAML section `mounts:` with keys base_laser, arm_laser,
/// arm_base, gripper, each `[x, y, z, roll, pitch, yaw]`.
void ApplyMountOverrides(const ConfigNode& mounts, RobotModel& model);

/// The chain with a pose error after each segment's frame to tip (tip = design tip * error; a
/// segment beyond `link_errors` keeps its design). The as-built arm of the simulator and the arm
/// as its kinematic calibration found it (perception/kinematic_calibration.h).
KDL::Chain ChainWithLinkErrors(const KDL::Chain& design, const std::vector<Pose3>& link_errors);

/// Convert between KDL frames and Pose3.
Pose3 ToPose3(const KDL::Frame& f);
KDL::Frame ToKdl(const Pose3& p);

}  // namespace ifab
