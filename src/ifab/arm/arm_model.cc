#include "ifab/arm/arm_model.h"

#include <kdl/chain.hpp>
#include <kdl/rigidbodyinertia.hpp>

#include "ifab/core/error.h"

namespace ifab::arm {
namespace {

Eigen::Matrix3d ToEigen(const KDL::Rotation& r) {
  Eigen::Matrix3d m;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m(i, j) = r(i, j);
  return m;
}

Eigen::Vector3d ToEigen(const KDL::Vector& v) { return {v.x(), v.y(), v.z()}; }

void SetInertia(const KDL::RigidBodyInertia& inertia, ArmLink& link) {
  link.mass = inertia.getMass();
  link.com = ToEigen(inertia.getCOG());
  link.first_moment = link.mass * link.com;
  const KDL::RotationalInertia& io = inertia.getRotationalInertia();  // about the link origin
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) link.inertia_origin(i, j) = io.data[3 * i + j];
  // Back to the centre of mass: I_c = I_o + m [c]x [c]x.
  link.inertia_com = link.inertia_origin + link.mass * Skew(link.com) * Skew(link.com);
}

}  // namespace

ArmModel ArmModel::FromChain(const KDL::Chain& chain) {
  ArmModel model;
  KDL::Frame pending = KDL::Frame::Identity();  // fixed transforms since the last moving link
  KDL::RigidBodyInertia pending_inertia = KDL::RigidBodyInertia::Zero();  // fixed bodies on it
  int n = 0;
  for (const KDL::Segment& segment : chain.segments) {
    const KDL::Joint& joint = segment.getJoint();
    if (joint.getType() == KDL::Joint::Fixed) {
      pending = pending * segment.pose(0.0);
      // A fixed body rides on the last moving link; one before the first joint never moves.
      if (n > 0) pending_inertia = pending_inertia + pending * segment.getInertia();
      continue;
    }
    if (joint.getType() != KDL::Joint::RotAxis && joint.getType() != KDL::Joint::RotX &&
        joint.getType() != KDL::Joint::RotY && joint.getType() != KDL::Joint::RotZ) {
      ThrowInputError("arm chain: joint '{}' is not revolute", joint.getName());
    }
    if (n >= kDof) ThrowInputError("arm chain: more than {} moving joints", kDof);
    if (n > 0 && pending_inertia.getMass() > 0.0) {
      // Fold fixed bodies into the previous link.
      KDL::RigidBodyInertia merged = pending_inertia;
      ArmLink& prev = model.links[n - 1];
      merged = merged + KDL::RigidBodyInertia(prev.mass, KDL::Vector(prev.com.x(), prev.com.y(), prev.com.z()),
                                              KDL::RotationalInertia(prev.inertia_com(0, 0), prev.inertia_com(1, 1),
                                                                     prev.inertia_com(2, 2), prev.inertia_com(0, 1),
                                                                     prev.inertia_com(0, 2), prev.inertia_com(1, 2)));
      SetInertia(merged, prev);
    }
    const KDL::Frame at_zero = segment.pose(0.0);
    const KDL::Frame parent_link0 = pending * at_zero;
    ArmLink& link = model.links[n];
    link.R_parent_link0 = ToEigen(parent_link0.M);
    link.p_parent_link = ToEigen(parent_link0.p);
    // KDL rotates about the axis given in the joint's parent frame; express it in the link frame.
    link.axis = (ToEigen(at_zero.M).transpose() * ToEigen(joint.JointAxis())).normalized();
    SetInertia(segment.getInertia(), link);
    pending = KDL::Frame::Identity();
    pending_inertia = KDL::RigidBodyInertia::Zero();
    ++n;
  }
  if (n != kDof) ThrowInputError("arm chain: {} moving joints, expected {}", n, kDof);
  if (pending_inertia.getMass() > 0.0) {
    ArmLink& last = model.links[kDof - 1];
    KDL::RigidBodyInertia merged =
        pending_inertia + KDL::RigidBodyInertia(last.mass, KDL::Vector(last.com.x(), last.com.y(), last.com.z()),
                                                KDL::RotationalInertia(last.inertia_com(0, 0), last.inertia_com(1, 1),
                                                                       last.inertia_com(2, 2), last.inertia_com(0, 1),
                                                                       last.inertia_com(0, 2), last.inertia_com(1, 2)));
    SetInertia(merged, last);
  }
  model.T_link6_tool0 = ToPose3(pending);
  return model;
}

ArmModel ArmModel::FromRobotModel(const RobotModel& robot) {
  ArmModel model = FromChain(robot.arm_chain);
  model.q_min = robot.q_min;
  model.q_max = robot.q_max;
  model.qd_max = robot.qd_max;
  model.effort_max = robot.effort_max;
  return model;
}

double ArmModel::MovingMass() const {
  double m = 0.0;
  for (const ArmLink& link : links) m += link.mass;
  return m;
}

}  // namespace ifab::arm
