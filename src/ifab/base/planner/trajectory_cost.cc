#include "ifab/base/planner/trajectory_cost.h"

#include <Eigen/Cholesky>
#include <cmath>

#include "ifab/core/error.h"

namespace ifab::base {

void AddSmoothnessCosts(const TrajectoryMatrix& q, const SmoothnessWeights& w, Eigen::VectorXd* per_point) {
  const int n = static_cast<int>(q.rows());  // N + 2
  IFAB_CHECK(n >= 2 && per_point->size() == n);
  const double inv_dtau = n - 1;  // 1 / dtau = N + 1
  const double dtau = 1.0 / inv_dtau;
  const Eigen::Vector3d scale(1.0, 1.0, w.heading_scale);
  // Rest-padded point access.
  const auto point = [&](int i) -> Eigen::Vector3d {
    const int c = i < 0 ? 0 : (i >= n ? n - 1 : i);
    return q.row(c).transpose();
  };
  const auto accel = [&](int i) -> Eigen::Vector3d {
    if (i < 0 || i >= n) return Eigen::Vector3d::Zero();
    return (point(i - 1) - 2.0 * point(i) + point(i + 1)).cwiseProduct(scale) * (inv_dtau * inv_dtau);
  };
  Eigen::Vector3d a_prev = Eigen::Vector3d::Zero();  // accel(-1)
  for (int i = 0; i <= n; ++i) {
    const Eigen::Vector3d a = accel(i);
    const Eigen::Vector3d j = (a - a_prev) * inv_dtau;
    const int at = i < n ? i : n - 1;
    if (i < n) (*per_point)[at] += w.acceleration * a.squaredNorm() * dtau;
    (*per_point)[at] += w.jerk * j.squaredNorm() * dtau;
    a_prev = a;
  }
}

Eigen::MatrixXd AccelerationMatrix(int num_free) {
  const int n = num_free;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n + 2, n);
  // Row i: q[i-1] - 2 q[i] + q[i+1] with q[-1] = q[0], q[N+2] = q[N+1]; free q[i] is column i-1.
  for (int i = 0; i < n + 2; ++i) {
    const auto add = [&](int p, double c) {
      if (p < 0) p = 0;
      if (p > n + 1) p = n + 1;
      if (p >= 1 && p <= n) A(i, p - 1) += c;
    };
    add(i - 1, 1.0);
    add(i, -2.0);
    add(i + 1, 1.0);
  }
  return A;
}

Eigen::VectorXd LateralResiduals(const TrajectoryMatrix& q) {
  const int segments = static_cast<int>(q.rows()) - 1;
  Eigen::VectorXd c(segments);
  for (int j = 0; j < segments; ++j) {
    const double tb = 0.5 * (q(j, 2) + q(j + 1, 2));
    c[j] = -std::sin(tb) * (q(j + 1, 0) - q(j, 0)) + std::cos(tb) * (q(j + 1, 1) - q(j, 1));
  }
  return c;
}

LateralJacobian LinearizeLateral(const TrajectoryMatrix& q) {
  const int segments = static_cast<int>(q.rows()) - 1;
  LateralJacobian J;
  J.s.resize(segments);
  J.k.resize(segments);
  J.h.resize(segments);
  for (int j = 0; j < segments; ++j) {
    const double tb = 0.5 * (q(j, 2) + q(j + 1, 2));
    const double s = std::sin(tb), k = std::cos(tb);
    const double dx = q(j + 1, 0) - q(j, 0), dy = q(j + 1, 1) - q(j, 1);
    J.s[j] = s;
    J.k[j] = k;
    J.h[j] = -0.5 * (k * dx + s * dy);
  }
  return J;
}

Eigen::MatrixXd LateralJacobian::Dense() const {
  const int n = num_free();
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(n + 1, 3 * n);
  for (int j = 0; j <= n; ++j) {
    // Point j is free column j-1 (if 1 <= j <= N); point j+1 is free column j.
    if (j >= 1) {
      C(j, j - 1) += s[j];
      C(j, n + j - 1) += -k[j];
      C(j, 2 * n + j - 1) += h[j];
    }
    if (j + 1 <= n) {
      C(j, j) += -s[j];
      C(j, n + j) += k[j];
      C(j, 2 * n + j) += h[j];
    }
  }
  return C;
}

Eigen::VectorXd LateralJacobian::Apply(const TrajectoryMatrix& v) const {
  const int n = num_free();
  Eigen::VectorXd out(n + 1);
  for (int j = 0; j <= n; ++j) {
    double r = 0.0;
    if (j >= 1) r += s[j] * v(j - 1, 0) - k[j] * v(j - 1, 1) + h[j] * v(j - 1, 2);
    if (j + 1 <= n) r += -s[j] * v(j, 0) + k[j] * v(j, 1) + h[j] * v(j, 2);
    out[j] = r;
  }
  return out;
}

void ConstraintProjector::Reset(const Eigen::MatrixXd& S, const Eigen::Vector3d& sigma, double damping) {
  S_ = S;
  var_ = sigma.cwiseProduct(sigma);
  damping_ = damping;
}

void ConstraintProjector::Linearize(const TrajectoryMatrix& q) {
  jac_ = LinearizeLateral(q);
  const int n = jac_.num_free();
  IFAB_CHECK(S_.rows() == n);
  // G = Sigma C^T: column j mixes at most two columns of S per coordinate.
  G_.setZero(3 * n, n + 1);
  for (int j = 0; j <= n; ++j) {
    const double c_lo[3] = {jac_.s[j], -jac_.k[j], jac_.h[j]};   // point j (free col j-1)
    const double c_hi[3] = {-jac_.s[j], jac_.k[j], jac_.h[j]};   // point j+1 (free col j)
    for (int d = 0; d < 3; ++d) {
      auto col = G_.col(j).segment(d * n, n);
      if (j >= 1) col += (var_[d] * c_lo[d]) * S_.col(j - 1);
      if (j + 1 <= n) col += (var_[d] * c_hi[d]) * S_.col(j);
    }
  }
  // K = C G (+ damping), symmetric positive definite.
  Eigen::MatrixXd K(n + 1, n + 1);
  for (int j = 0; j <= n; ++j) {
    const double* g = G_.col(j).data();  // stacked [x; y; theta]
    for (int i = 0; i <= n; ++i) {
      double r = 0.0;
      if (i >= 1) r += jac_.s[i] * g[i - 1] - jac_.k[i] * g[n + i - 1] + jac_.h[i] * g[2 * n + i - 1];
      if (i + 1 <= n) r += -jac_.s[i] * g[i] + jac_.k[i] * g[n + i] + jac_.h[i] * g[2 * n + i];
      K(i, j) = r;
    }
  }
  K = 0.5 * (K + K.transpose()).eval();
  const double scale = K.diagonal().maxCoeff();
  K.diagonal().array() += damping_ * (scale > 0 ? scale : 1.0);
  Eigen::LLT<Eigen::MatrixXd> llt(K);
  K_factor_ = llt.matrixLLT();
  tmp_.resize(n + 1);
}

void ConstraintProjector::Project(TrajectoryMatrix* v, const Eigen::VectorXd* r) const {
  const int n = jac_.num_free();
  Eigen::VectorXd rhs = jac_.Apply(*v);
  if (r) rhs += *r;
  // Solve K lambda = rhs with the stored Cholesky factor.
  const auto L = K_factor_.triangularView<Eigen::Lower>();
  L.solveInPlace(rhs);
  L.transpose().solveInPlace(rhs);
  const Eigen::VectorXd delta = G_ * rhs;
  for (int d = 0; d < 3; ++d) v->col(d) -= delta.segment(d * n, n);
}

}  // namespace ifab::base
