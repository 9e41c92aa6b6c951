#pragma once
/// \file
/// Rigid-body algorithms of the arm, templated on the scalar so that ceres::Jet passes through:
/// forward kinematics, recursive Newton-Euler inverse dynamics (RNEA), the joint-space inertia by
/// the composite-rigid-body algorithm (CRBA), and forward dynamics (CRBA + Cholesky + RNEA).
/// Quantities are propagated in each link's own frame (Craig / Featherstone), so every link
/// needs one rotation per evaluation. All functions write into an ArmDataT workspace and never
/// allocate. Tested against Orocos KDL (ChainIdSolver_RNE, ChainDynParam) in
/// test/dynamics_test.cc.

#include <ceres/jet.h>

#include "ifab/arm/arm_model.h"

namespace ifab::arm {

/// Pose of a frame: rotation and position, for any scalar.
template <typename T>
struct FrameT {
  Mat3<T> R{Mat3<T>::Identity()};
  Vec3<T> p{Vec3<T>::Zero()};
};

namespace internal {

// Small products with a constant (double) operand, written out so that Jets only pay for
// scalar-times-Jet products where one factor is a constant.
template <typename T>
Vec3<T> MulCV(const Eigen::Matrix3d& a, const Vec3<T>& v) {  // constant matrix times v
  Vec3<T> r;
  for (int i = 0; i < 3; ++i) r[i] = a(i, 0) * v[0] + a(i, 1) * v[1] + a(i, 2) * v[2];
  return r;
}

template <typename T>
Vec3<T> Mul(const Mat3<T>& a, const Vec3<T>& v) {
  Vec3<T> r;
  for (int i = 0; i < 3; ++i) r[i] = a(i, 0) * v[0] + a(i, 1) * v[1] + a(i, 2) * v[2];
  return r;
}

template <typename T>
Vec3<T> MulT(const Mat3<T>& a, const Vec3<T>& v) {  // a^T v
  Vec3<T> r;
  for (int i = 0; i < 3; ++i) r[i] = a(0, i) * v[0] + a(1, i) * v[1] + a(2, i) * v[2];
  return r;
}

template <typename T>
Vec3<T> MulVC(const Mat3<T>& a, const Eigen::Vector3d& v) {  // a times a constant vector
  Vec3<T> r;
  for (int i = 0; i < 3; ++i) r[i] = a(i, 0) * v[0] + a(i, 1) * v[1] + a(i, 2) * v[2];
  return r;
}

template <typename T>
Mat3<T> MulCM(const Eigen::Matrix3d& a, const Mat3<T>& b) {  // constant matrix times b
  Mat3<T> r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r(i, j) = a(i, 0) * b(0, j) + a(i, 1) * b(1, j) + a(i, 2) * b(2, j);
  return r;
}

template <typename T>
Vec3<T> Cross(const Vec3<T>& a, const Vec3<T>& b) {
  return Vec3<T>(a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]);
}

template <typename T>
Vec3<T> CrossCV(const Eigen::Vector3d& a, const Vec3<T>& b) {  // constant a
  return Vec3<T>(a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]);
}

template <typename T>
Vec3<T> CrossVC(const Vec3<T>& a, const Eigen::Vector3d& b) {  // constant b
  return Vec3<T>(a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]);
}

template <typename T>
Vec3<T> Scale(const Eigen::Vector3d& a, const T& s) {
  return Vec3<T>(a[0] * s, a[1] * s, a[2] * s);
}

template <typename T>
T Dot(const Eigen::Vector3d& a, const Vec3<T>& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

}  // namespace internal

/// Fill data.R with each link's rotation in its parent frame at q.
template <typename T>
void ComputeLinkRotations(const ArmModel& model, ArmDataT<T>& data, const Vec6<T>& q) {
  for (int i = 0; i < kDof; ++i) {
    const ArmLink& link = model.links[i];
    data.R[i] = internal::MulCM(link.R_parent_link0, AxisRotation(link.axis, q[i]));
  }
}

/// Flange (tool0) pose in arm_base at joint angles q.
template <typename T>
FrameT<T> ForwardKinematics(const ArmModel& model, ArmDataT<T>& data, const Vec6<T>& q) {
  ComputeLinkRotations(model, data, q);
  FrameT<T> x;  // link i in arm_base
  for (int i = 0; i < kDof; ++i) {
    x.p += internal::MulVC(x.R, model.links[i].p_parent_link);
    x.R = (x.R * data.R[i]).eval();
  }
  FrameT<T> tool0;
  tool0.p = x.p + internal::MulVC(x.R, Eigen::Vector3d(model.T_link6_tool0.translation()));
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      tool0.R(r, c) = x.R(r, 0) * model.T_link6_tool0.linear()(0, c) +
                      x.R(r, 1) * model.T_link6_tool0.linear()(1, c) +
                      x.R(r, 2) * model.T_link6_tool0.linear()(2, c);
  return tool0;
}

/// Flange pose in arm_base (double convenience).
Pose3 ForwardKinematics(const ArmModel& model, const Vector6d& q);

/// Inverse dynamics by recursive Newton-Euler: the joint torques that give accelerations qdd
/// at (q, qd) under gravity `gravity` (in arm_base; pass zero for none). Result in data.tau.
template <typename T>
const Vec6<T>& InverseDynamics(const ArmModel& model, ArmDataT<T>& data, const Vec6<T>& q,
                               const Vec6<T>& qd, const Vec6<T>& qdd,
                               const Eigen::Vector3d& gravity) {
  using internal::Cross;
  using internal::Mul;
  using internal::MulT;
  ComputeLinkRotations(model, data, q);
  // Gravity enters as an upward acceleration of the base (Luh, Walker and Paul).
  Vec3<T> w_prev = Vec3<T>::Zero();
  Vec3<T> wd_prev = Vec3<T>::Zero();
  Vec3<T> vd_prev(T(-gravity.x()), T(-gravity.y()), T(-gravity.z()));
  for (int i = 0; i < kDof; ++i) {
    const ArmLink& link = model.links[i];
    const Mat3<T>& R = data.R[i];
    // Origin acceleration of link i, still in the parent frame.
    const Vec3<T> vd_parent = vd_prev + internal::CrossVC(wd_prev, link.p_parent_link) +
                              Cross(w_prev, internal::CrossVC(w_prev, link.p_parent_link));
    const Vec3<T> w_in = MulT(R, w_prev);
    const Vec3<T> w_joint = internal::Scale(link.axis, qd[i]);
    data.w[i] = w_in + w_joint;
    data.wd[i] = MulT(R, wd_prev) + internal::Scale(link.axis, qdd[i]) + Cross(w_in, w_joint);
    data.vd[i] = MulT(R, vd_parent);
    w_prev = data.w[i];
    wd_prev = data.wd[i];
    vd_prev = data.vd[i];
  }
  for (int i = kDof - 1; i >= 0; --i) {
    const ArmLink& link = model.links[i];
    const Vec3<T>& w = data.w[i];
    const Vec3<T>& wd = data.wd[i];
    const Vec3<T>& vd = data.vd[i];
    // Net force and moment (about the link origin) of the link's own inertia.
    Vec3<T> f = vd * link.mass + internal::CrossVC(wd, link.first_moment) +
                Cross(w, internal::CrossVC(w, link.first_moment));
    Vec3<T> n = internal::MulCV(link.inertia_origin, wd) +
                Cross(w, internal::MulCV(link.inertia_origin, w)) +
                internal::CrossCV(link.first_moment, vd);
    if (i + 1 < kDof) {
      const Vec3<T> f_child = Mul(data.R[i + 1], data.f[i + 1]);
      n += Mul(data.R[i + 1], data.n[i + 1]) + internal::CrossCV(model.links[i + 1].p_parent_link, f_child);
      f += f_child;
    }
    data.f[i] = f;
    data.n[i] = n;
    data.tau[i] = internal::Dot(link.axis, n);
  }
  return data.tau;
}

/// Joint-space inertia M(q) by the composite-rigid-body algorithm. Result in data.M.
template <typename T>
const Mat6<T>& MassMatrix(const ArmModel& model, ArmDataT<T>& data, const Vec6<T>& q) {
  using internal::Cross;
  using internal::Mul;
  ComputeLinkRotations(model, data, q);
  for (int i = 0; i < kDof; ++i) {
    data.mc[i] = T(model.links[i].mass);
    data.hc[i] = model.links[i].first_moment.cast<T>();
    data.Ic[i] = model.links[i].inertia_origin.cast<T>();
  }
  // Accumulate each subtree into its parent (frame of the parent, about its origin).
  for (int i = kDof - 1; i >= 1; --i) {
    const Mat3<T>& R = data.R[i];
    const Eigen::Vector3d& p = model.links[i].p_parent_link;
    const Vec3<T> h = Mul(R, data.hc[i]);
    const T& m = data.mc[i];
    Mat3<T> I = R * data.Ic[i] * R.transpose();
    const T pp = T(p.dot(p));
    const T ph = internal::Dot(p, h);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        // Parallel-axis with a first moment: -m [p]x[p]x - [p]x[h]x - [h]x[p]x.
        T shift = -(m * (p[r] * p[c])) - (h[r] * p[c] + p[r] * h[c]);
        if (r == c) shift += m * pp + T(2.0) * ph;
        I(r, c) += shift;
      }
    }
    data.mc[i - 1] += m;
    data.hc[i - 1] += h + internal::Scale(p, m);
    data.Ic[i - 1] += I;
  }
  for (int i = 0; i < kDof; ++i) {
    const Eigen::Vector3d& a = model.links[i].axis;
    // Wrench (about the link origin) that a unit acceleration of joint i needs from the subtree.
    Vec3<T> n = internal::MulVC(data.Ic[i], a);
    Vec3<T> f = internal::CrossCV(a, data.hc[i]);
    data.M(i, i) = internal::Dot(a, n);
    for (int j = i - 1; j >= 0; --j) {
      const Mat3<T>& R = data.R[j + 1];
      const Vec3<T> f_parent = Mul(R, f);
      n = Mul(R, n) + internal::CrossCV(model.links[j + 1].p_parent_link, f_parent);
      f = f_parent;
      data.M(j, i) = internal::Dot(model.links[j].axis, n);
      data.M(i, j) = data.M(j, i);
    }
  }
  return data.M;
}

/// Cholesky factorisation of data.M into data.L (lower). False if M is not positive definite.
template <typename T>
bool FactorMassMatrix(ArmDataT<T>& data) {
  using std::sqrt;
  data.L.setZero();
  for (int j = 0; j < kDof; ++j) {
    T d = data.M(j, j);
    for (int k = 0; k < j; ++k) d -= data.L(j, k) * data.L(j, k);
    if (!(d > T(0.0))) return false;
    data.L(j, j) = sqrt(d);
    for (int i = j + 1; i < kDof; ++i) {
      T s = data.M(i, j);
      for (int k = 0; k < j; ++k) s -= data.L(i, k) * data.L(j, k);
      data.L(i, j) = s / data.L(j, j);
    }
  }
  return true;
}

/// Solve M x = b with the factor in data.L.
template <typename T>
Vec6<T> SolveMassMatrix(const ArmDataT<T>& data, const Vec6<T>& b) {
  Vec6<T> y;
  for (int i = 0; i < kDof; ++i) {
    T s = b[i];
    for (int k = 0; k < i; ++k) s -= data.L(i, k) * y[k];
    y[i] = s / data.L(i, i);
  }
  Vec6<T> x;
  for (int i = kDof - 1; i >= 0; --i) {
    T s = y[i];
    for (int k = i + 1; k < kDof; ++k) s -= data.L(k, i) * x[k];
    x[i] = s / data.L(i, i);
  }
  return x;
}

/// Forward dynamics: joint accelerations under torques tau at (q, qd), as
/// qdd = M(q)^-1 (tau - RNEA(q, qd, 0)). Result in data.qdd (data.M, data.L, data.h filled too).
/// Returns false if M is not positive definite (cannot happen for a valid model).
template <typename T>
bool ForwardDynamics(const ArmModel& model, ArmDataT<T>& data, const Vec6<T>& q, const Vec6<T>& qd,
                     const Vec6<T>& tau, const Eigen::Vector3d& gravity) {
  MassMatrix(model, data, q);
  if (!FactorMassMatrix(data)) return false;
  data.h = InverseDynamics(model, data, q, qd, Vec6<T>::Zero().eval(), gravity);
  data.qdd = SolveMassMatrix(data, (tau - data.h).eval());
  return true;
}

/// Gravity-compensating torque g(q) (RNEA at rest).
template <typename T>
Vec6<T> GravityTorque(const ArmModel& model, ArmDataT<T>& data, const Vec6<T>& q) {
  return InverseDynamics(model, data, q, Vec6<T>::Zero().eval(), Vec6<T>::Zero().eval(),
                         model.gravity);
}

/// Derivatives of the dynamics for the planner, computed analytically from one forward-mode
/// (ceres::Jet) pass through RNEA: since RNEA(q, qd, FD(q, qd, tau)) = tau,
///   d qdd/d q = -M^-1 dRNEA/dq,  d qdd/d qd = -M^-1 dRNEA/dqd,  d qdd/d tau = M^-1.
struct DynamicsDerivatives {
  Vector6d qdd{Vector6d::Zero()};        ///< forward dynamics
  Matrix6d dtau_dq{Matrix6d::Zero()};    ///< d RNEA / d q at (q, qd, qdd)
  Matrix6d dtau_dqd{Matrix6d::Zero()};   ///< d RNEA / d qd
  Matrix6d M_inv{Matrix6d::Zero()};      ///< = d qdd / d tau
  Matrix6d dqdd_dq{Matrix6d::Zero()};
  Matrix6d dqdd_dqd{Matrix6d::Zero()};
};

using Jet12 = ceres::Jet<double, 12>;

/// Workspace for the derivatives (double and Jet data).
struct DerivativeData {
  ArmData data;
  ArmDataT<Jet12> jet;
};

/// Inverse-dynamics derivatives d tau/d q, d tau/d qd at (q, qd, qdd) into out.dtau_*.
void InverseDynamicsDerivatives(const ArmModel& model, DerivativeData& work, const Vector6d& q,
                                const Vector6d& qd, const Vector6d& qdd,
                                const Eigen::Vector3d& gravity, DynamicsDerivatives& out);

/// Forward dynamics and all of its derivatives at (q, qd, tau). False if M is singular.
bool ForwardDynamicsDerivatives(const ArmModel& model, DerivativeData& work, const Vector6d& q,
                                const Vector6d& qd, const Vector6d& tau,
                                const Eigen::Vector3d& gravity, DynamicsDerivatives& out);

}  // namespace ifab::arm
