#include "ifab/arm/dynamics.h"

namespace ifab::arm {

Pose3 ForwardKinematics(const ArmModel& model, const Vector6d& q) {
  ArmData data;
  const FrameT<double> x = ForwardKinematics<double>(model, data, q);
  Pose3 pose = Pose3::Identity();
  pose.linear() = x.R;
  pose.translation() = x.p;
  return pose;
}

void InverseDynamicsDerivatives(const ArmModel& model, DerivativeData& work, const Vector6d& q,
                                const Vector6d& qd, const Vector6d& qdd,
                                const Eigen::Vector3d& gravity, DynamicsDerivatives& out) {
  // One forward-mode pass: directions 0-5 seed q, 6-11 seed qd.
  Vec6<Jet12> qj, qdj, qddj;
  for (int i = 0; i < kDof; ++i) {
    qj[i] = Jet12(q[i], i);
    qdj[i] = Jet12(qd[i], kDof + i);
    qddj[i] = Jet12(qdd[i]);
  }
  const Vec6<Jet12>& tau = InverseDynamics(model, work.jet, qj, qdj, qddj, gravity);
  for (int i = 0; i < kDof; ++i) {
    out.dtau_dq.row(i) = tau[i].v.head<kDof>().transpose();
    out.dtau_dqd.row(i) = tau[i].v.tail<kDof>().transpose();
  }
}

bool ForwardDynamicsDerivatives(const ArmModel& model, DerivativeData& work, const Vector6d& q,
                                const Vector6d& qd, const Vector6d& tau,
                                const Eigen::Vector3d& gravity, DynamicsDerivatives& out) {
  if (!ForwardDynamics<double>(model, work.data, q, qd, tau, gravity)) return false;
  out.qdd = work.data.qdd;
  for (int j = 0; j < kDof; ++j) out.M_inv.col(j) = SolveMassMatrix<double>(work.data, Vector6d::Unit(j));
  out.M_inv = (0.5 * (out.M_inv + out.M_inv.transpose())).eval();
  InverseDynamicsDerivatives(model, work, q, qd, out.qdd, gravity, out);
  out.dqdd_dq.noalias() = -out.M_inv * out.dtau_dq;
  out.dqdd_dqd.noalias() = -out.M_inv * out.dtau_dqd;
  return true;
}

}  // namespace ifab::arm
