#pragma once
/// \file
/// The arm as a rigid-body system: an immutable ArmModel (kinematic tree of the six revolute
/// joints with the link masses and inertias) read from the robot's KDL chain, and ArmData, the
/// reusable workspace of the dynamics algorithms (dynamics.h). Pinocchio's model/data split:
/// many ArmData may share one ArmModel, and no algorithm allocates.
///
/// Masses and inertias come from the URDF (data/robots/insitu_fabricator.urdf), where they are
/// documented as ESTIMATES (ABB publishes none: about 435 kg split over the links by housing
/// volume, each link a solid box or cylinder of its rough outer size). The URDF is the one
/// source of truth; data/arm/arm.yaml only points to it.

#include <Eigen/Core>
#include <array>
#include <limits>

#include "ifab/core/se3.h"
#include "ifab/model/robot_model.h"

namespace ifab::arm {

inline constexpr int kDof = 6;

template <typename T>
using Vec3 = Eigen::Matrix<T, 3, 1>;
template <typename T>
using Mat3 = Eigen::Matrix<T, 3, 3>;
template <typename T>
using Vec6 = Eigen::Matrix<T, 6, 1>;
template <typename T>
using Mat6 = Eigen::Matrix<T, 6, 6>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// One moving link: the joint that moves it and its inertia, all in the link's own frame.
struct ArmLink {
  /// Link frame at q = 0 in the parent link frame (the joint origin): rotation and position.
  Eigen::Matrix3d R_parent_link0{Eigen::Matrix3d::Identity()};
  Eigen::Vector3d p_parent_link{Eigen::Vector3d::Zero()};
  /// Unit joint axis in the link frame; the link frame is R_parent_link0 * Rot(axis, q).
  Eigen::Vector3d axis{Eigen::Vector3d::UnitZ()};
  double mass{0.0};                                            ///< [kg]
  Eigen::Vector3d com{Eigen::Vector3d::Zero()};                ///< centre of mass in the link frame [m]
  Eigen::Matrix3d inertia_com{Eigen::Matrix3d::Zero()};        ///< about the com, link axes [kg m^2]
  Eigen::Vector3d first_moment{Eigen::Vector3d::Zero()};       ///< mass * com
  Eigen::Matrix3d inertia_origin{Eigen::Matrix3d::Zero()};     ///< about the link frame origin
};

/// The immutable arm model: arm_base -> link_1 ... link_6 -> tool0.
struct ArmModel {
  static constexpr double kInf = std::numeric_limits<double>::infinity();

  std::array<ArmLink, kDof> links;
  Pose3 T_link6_tool0{Pose3::Identity()};  ///< fixed flange frame on the last link
  /// Gravity in arm_base [m/s^2] (the arm stands upright: -z).
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};
  Vector6d q_min{Vector6d::Constant(-kInf)};  ///< joint limits [rad]
  Vector6d q_max{Vector6d::Constant(kInf)};
  Vector6d qd_max{Vector6d::Constant(kInf)};  ///< joint speed limits [rad/s]
  Vector6d effort_max{Vector6d::Constant(kInf)};  ///< joint torque limits [N m]

  /// Build from the robot's KDL chain arm_base -> tool0 and its limits. Fixed segments are folded
  /// into their neighbours (their inertia into the link they hang on). Throws InputError if the
  /// chain is not six revolute joints.
  static ArmModel FromRobotModel(const RobotModel& robot);
  static ArmModel FromChain(const KDL::Chain& chain);

  /// Total mass of the moving links [kg].
  double MovingMass() const;
};

/// Rotation by angle about a unit axis (Rodrigues), templated for Jets.
template <typename T>
Mat3<T> AxisRotation(const Eigen::Vector3d& axis, const T& angle) {
  using std::cos;
  using std::sin;
  const T s = sin(angle);
  const T c = cos(angle);
  const T v = T(1.0) - c;
  const double x = axis.x(), y = axis.y(), z = axis.z();
  Mat3<T> r;
  r(0, 0) = c + v * (x * x);
  r(0, 1) = v * (x * y) - s * z;
  r(0, 2) = v * (x * z) + s * y;
  r(1, 0) = v * (x * y) + s * z;
  r(1, 1) = c + v * (y * y);
  r(1, 2) = v * (y * z) - s * x;
  r(2, 0) = v * (x * z) - s * y;
  r(2, 1) = v * (y * z) + s * x;
  r(2, 2) = c + v * (z * z);
  return r;
}

/// Reusable workspace of the dynamics algorithms for scalar T (double or ceres::Jet).
/// Fixed-size members only: creating and using it never allocates.
template <typename T>
struct ArmDataT {
  std::array<Mat3<T>, kDof> R;   ///< R_parent_link(q) of each link
  std::array<Vec3<T>, kDof> w;   ///< angular velocity of each link, link frame
  std::array<Vec3<T>, kDof> wd;  ///< angular acceleration, link frame
  std::array<Vec3<T>, kDof> vd;  ///< linear acceleration of the link origin (gravity included)
  std::array<Vec3<T>, kDof> f;   ///< force transmitted from the parent, link frame
  std::array<Vec3<T>, kDof> n;   ///< moment about the link origin, link frame
  // Composite-rigid-body quantities (mass, first moment, inertia about the link origin).
  std::array<T, kDof> mc;
  std::array<Vec3<T>, kDof> hc;
  std::array<Mat3<T>, kDof> Ic;
  Vec6<T> tau;  ///< result of InverseDynamics
  Mat6<T> M;    ///< joint-space inertia (MassMatrix)
  Mat6<T> L;    ///< its Cholesky factor (lower)
  Vec6<T> h;    ///< bias torque (Coriolis, centrifugal and gravity) in ForwardDynamics
  Vec6<T> qdd;  ///< result of ForwardDynamics
};
using ArmData = ArmDataT<double>;

}  // namespace ifab::arm
