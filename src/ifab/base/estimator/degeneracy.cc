#include "ifab/base/estimator/degeneracy.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace ifab::base {

DegeneracyAnalysis AnalyseDegeneracy(const Eigen::Matrix3d& info_scan,
                                     const Eigen::Matrix3d* info_prior, double lever,
                                     double min_ratio) {
  DegeneracyAnalysis a;
  const double l = std::max(lever, 1e-3);
  const Eigen::Vector3d scale(1.0, 1.0, 1.0 / l);  // (x, y, lever * theta) -> (x, y, theta)
  const Eigen::Matrix3d H_scaled = scale.asDiagonal() * info_scan * scale.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(H_scaled);
  const double lmax = es.eigenvalues()(2);
  a.ratio = lmax > 0.0 ? std::max(0.0, es.eigenvalues()(0)) / lmax : 0.0;
  if (info_prior != nullptr) {
    a.with_prior = true;
    // Directions far weaker than the scan's best are not trusted at all, whatever the prior: the
    // kernel sum's residual curvature along a wall (neighbour truncation, chain ends) is an
    // artefact, not information. Project them out before comparing with the prior.
    Eigen::Matrix3d H_trusted = H_scaled;
    for (int i = 0; i < 3; ++i) {
      if (lmax > 0.0 && es.eigenvalues()(i) < min_ratio * lmax) {
        H_trusted -= es.eigenvalues()(i) * es.eigenvectors().col(i) * es.eigenvectors().col(i).transpose();
      }
    }
    const Eigen::Vector3d unscale = scale.cwiseInverse();
    a.info_scan_trusted = unscale.asDiagonal() * H_trusted * unscale.asDiagonal();
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::Matrix3d> ges(
        a.info_scan_trusted, *info_prior, Eigen::ComputeEigenvectors | Eigen::Ax_lBx);
    a.eigenvalues = ges.eigenvalues().cwiseMax(0.0);
    a.eigenvectors = ges.eigenvectors();
    for (int i = 0; i < 3; ++i) a.degenerate[static_cast<std::size_t>(i)] = a.eigenvalues(i) < 1.0;
  } else {
    a.eigenvalues = lmax > 0.0 ? Eigen::Vector3d(es.eigenvalues().cwiseMax(0.0) / lmax)
                               : Eigen::Vector3d::Zero();
    a.eigenvectors = scale.asDiagonal() * es.eigenvectors();
    for (int i = 0; i < 3; ++i) a.degenerate[static_cast<std::size_t>(i)] = a.eigenvalues(i) < min_ratio;
  }
  for (int i = 0; i < 3; ++i) {
    if (!a.degenerate[static_cast<std::size_t>(i)]) continue;
    Eigen::Vector3d d = a.eigenvectors.col(i).cwiseQuotient(scale);  // to (x, y, lever * theta)
    const double n = d.norm();
    if (n > 0.0) d /= n;
    // A sign convention so a direction reads the same from scan to scan.
    int k = 0;
    d.cwiseAbs().maxCoeff(&k);
    if (d(k) < 0.0) d = -d;
    a.directions.col(a.num_degenerate++) = d;
  }
  return a;
}

Eigen::Vector3d RemapDegenerate(const DegeneracyAnalysis& a, const Eigen::Matrix3d& info_prior,
                                const Eigen::Vector3d& dx) {
  // dx = V c with c = V^T Lambda_prior dx (V^T Lambda_prior V = I); zero c_i where degenerate.
  Eigen::Vector3d c = a.eigenvectors.transpose() * info_prior * dx;
  for (int i = 0; i < 3; ++i) {
    if (a.degenerate[static_cast<std::size_t>(i)]) c(i) = 0.0;
  }
  return a.eigenvectors * c;
}

double InnovationMahalanobisSq(const DegeneracyAnalysis& a, const Eigen::Matrix3d& info_prior,
                               const Eigen::Vector3d& dx, int* dof) {
  const Eigen::Vector3d c = a.eigenvectors.transpose() * info_prior * dx;
  double m2 = 0.0;
  int n = 0;
  for (int i = 0; i < 3; ++i) {
    if (a.degenerate[static_cast<std::size_t>(i)]) continue;
    const double lambda = a.eigenvalues(i);
    m2 += c(i) * c(i) * (1.0 + lambda) / lambda;
    ++n;
  }
  if (dof) *dof = n;
  return m2;
}

double InnovationTranslationMahalanobisSq(const DegeneracyAnalysis& a,
                                          const Eigen::Matrix3d& info_prior,
                                          const Eigen::Vector3d& dx, int* dof) {
  // In the generalised eigenbasis (dx = V c, V^T Lambda_prior V = I) the scan-only offset is
  // u_i = c_i (1 + lambda_i) / lambda_i with combined variance (1 + lambda_i) / lambda_i.
  // Degenerate directions: the scan says nothing, infinite variance, i.e. they drop out of the
  // information of the translation marginal below.
  const Eigen::Vector3d c = a.eigenvectors.transpose() * info_prior * dx;
  Eigen::Vector3d y = Eigen::Vector3d::Zero();
  Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
  constexpr double kUnknown = 1e12;  // [m^2]: a variance no laser match comes near
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d v = a.eigenvectors.col(i);
    if (a.degenerate[static_cast<std::size_t>(i)]) {
      const Eigen::Vector3d u = v.normalized();
      S += kUnknown * u * u.transpose();
      continue;
    }
    const double s = (1.0 + a.eigenvalues(i)) / a.eigenvalues(i);
    y += c(i) * s * v;
    S += s * v * v.transpose();
  }
  const Eigen::Matrix2d S_tt = S.topLeftCorner<2, 2>();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(S_tt);
  const Eigen::Vector2d z = es.eigenvectors().transpose() * y.head<2>();
  double m2 = 0.0;
  int n = 0;
  for (int i = 0; i < 2; ++i) {
    if (!(es.eigenvalues()(i) < 1e-3 * kUnknown)) continue;  // a direction the scan leaves open
    m2 += z(i) * z(i) / es.eigenvalues()(i);
    ++n;
  }
  if (dof) *dof = n;
  return m2;
}

}  // namespace ifab::base
