#pragma once
/// \file
/// The scan-matching error of eq. 1 written as a least-squares residual.
///
/// The paper scores measurement point i by e_mi = sum_j G(p_Mi - p_Rj, 2 sigma^2 I), a sum of
/// Gaussian kernels that is largest when the scans overlap, and calls eq. 3 a
/// "pseudo-maximum-likelihood" problem. A least-squares solver needs something to minimise, so
/// each pair (i, j) gets the 2-vector residual
///
///   r_ij = d * h(|d|^2),   d = p_Mi - p_Rj,   h(s) = sqrt((1 - exp(-s / (4 sigma^2))) / s),
///
/// whose squared norm is |r_ij|^2 = 1 - exp(-|d|^2 / (4 sigma^2)) = 1 - G_ij / G(0), the kernel
/// normalised to peak 1 and subtracted from 1 (the Welsch / Leclerc robust loss). Hence
///
///   sum_ij |r_ij|^2 = (number of pairs) - sum_i e_mi / G(0),
///
/// so minimising the squares over a fixed set of pairs is exactly maximising eq. 1. The vector
/// form (rather than the scalar sqrt(1 - G)) keeps the residual smooth at d = 0, where it
/// behaves like point-to-point ICP scaled by 1 / (2 sigma); far pairs saturate at |r| -> 1 and
/// stop pulling, which is the kernel's robustness. The Gaussian's normalising constant is
/// dropped: it only scales the cost, and c_G of eq. 2 is expressed against this scale.

#include <Eigen/Core>
#include <cmath>

#include "ifab/core/se2.h"

namespace ifab::base {

/// Residual of one measurement/reference pair and its derivatives.
struct KernelPairResidual {
  Eigen::Vector2d r{Eigen::Vector2d::Zero()};      ///< r_ij, |r_ij|^2 = 1 - exp(-|d|^2/(4 sigma^2))
  Eigen::Matrix<double, 2, 3> J{Eigen::Matrix<double, 2, 3>::Zero()};  ///< dr / d(x, y, theta)
};

/// f(u) = (1 - exp(-u)) / u and its derivative, accurate near u = 0.
inline void KernelShape(double u, double* f, double* df_du) {
  if (u < 1e-4) {
    // Taylor series: f = 1 - u/2 + u^2/6 - u^3/24, f' = -1/2 + u/3 - u^2/8.
    *f = 1.0 - u * (0.5 - u * (1.0 / 6.0 - u / 24.0));
    *df_du = -0.5 + u * (1.0 / 3.0 - u / 8.0);
    return;
  }
  const double one_minus_e = -std::expm1(-u);
  *f = one_minus_e / u;
  *df_du = (std::exp(-u) * u - one_minus_e) / (u * u);
}

/// Residual r(d) = d * h(|d|^2) and dr/dd for a pair difference d (see the file comment).
inline void KernelResidualOfDifference(const Eigen::Vector2d& d, double sigma, Eigen::Vector2d* r,
                                       Eigen::Matrix2d* dr_dd) {
  const double inv_4s2 = 1.0 / (4.0 * sigma * sigma);
  const double s = d.squaredNorm();
  double f = 0.0, df_du = 0.0;
  KernelShape(s * inv_4s2, &f, &df_du);
  // h(s) = sqrt(f(u) * inv_4s2), u = s * inv_4s2.
  const double sqrt_f = std::sqrt(f);
  const double h = sqrt_f * std::sqrt(inv_4s2);
  *r = h * d;
  if (dr_dd) {
    // dh/ds = sqrt(inv_4s2) * f'(u) / (2 sqrt f) * inv_4s2; dr/dd = h I + 2 dh/ds d d^T.
    const double dh_ds = std::sqrt(inv_4s2) * df_du / (2.0 * sqrt_f) * inv_4s2;
    *dr_dd = h * Eigen::Matrix2d::Identity() + 2.0 * dh_ds * d * d.transpose();
  }
}

/// Pair residual for the measurement point q_base (in the base frame) placed at the pose
/// T_world_base, against the reference point p_ref_world; derivatives with respect to the
/// pose parameters (x, y, theta) of T_world_base.
inline KernelPairResidual KernelPair(const Pose2& T_world_base, const Eigen::Vector2d& q_base,
                                     const Eigen::Vector2d& p_ref_world, double sigma);

/// Same, given the base position t_world and the measurement point already in the world
/// (p_world = T_world_base * q_base), so a caller transforms each point once per evaluation.
inline KernelPairResidual KernelPairAt(const Eigen::Vector2d& t_world, const Eigen::Vector2d& p_world,
                                       const Eigen::Vector2d& p_ref_world, double sigma) {
  KernelPairResidual out;
  const Eigen::Vector2d d = p_world - p_ref_world;
  Eigen::Matrix2d dr_dd;
  KernelResidualOfDifference(d, sigma, &out.r, &dr_dd);
  // dp/d(x, y) = I; dp/dtheta = perp(R q) = (-(p - t)_y, (p - t)_x).
  out.J.leftCols<2>() = dr_dd;
  out.J.col(2) = dr_dd * Eigen::Vector2d(-(p_world.y() - t_world.y()), p_world.x() - t_world.x());
  return out;
}

inline KernelPairResidual KernelPair(const Pose2& T_world_base, const Eigen::Vector2d& q_base,
                                     const Eigen::Vector2d& p_ref_world, double sigma) {
  return KernelPairAt(T_world_base.translation(), T_world_base * q_base, p_ref_world, sigma);
}

/// Point-to-line variant (off by default, MatchResidual::kPointToLine): the same kernel applied
/// to the signed distance e = n^T (p_M - p_R) from the reference point's local line (normal n),
/// so that |r|^2 = 1 - exp(-e^2 / (4 sigma^2)) lives on the same scale as eq. 1's residual and
/// c_G keeps its meaning. Returns r and dr/d(x, y, theta).
inline void KernelLinePairAt(const Eigen::Vector2d& t_world, const Eigen::Vector2d& p_world,
                             const Eigen::Vector2d& p_ref_world, const Eigen::Vector2d& n_world,
                             double sigma, double* r, Eigen::Matrix<double, 1, 3>* J) {
  const double e = n_world.dot(p_world - p_ref_world);
  const double inv_4s2 = 1.0 / (4.0 * sigma * sigma);
  double f = 0.0, df_du = 0.0;
  KernelShape(e * e * inv_4s2, &f, &df_du);
  const double sqrt_f = std::sqrt(f);
  const double h = sqrt_f * std::sqrt(inv_4s2);
  *r = h * e;
  if (J) {
    const double dh_ds = std::sqrt(inv_4s2) * df_du / (2.0 * sqrt_f) * inv_4s2;
    const double dr_de = h + 2.0 * dh_ds * e * e;
    const Eigen::Vector2d lever(-(p_world.y() - t_world.y()), p_world.x() - t_world.x());
    *J << dr_de * n_world.x(), dr_de * n_world.y(), dr_de * n_world.dot(lever);
  }
}

inline void KernelLinePair(const Pose2& T_world_base, const Eigen::Vector2d& q_base,
                           const Eigen::Vector2d& p_ref_world, const Eigen::Vector2d& n_world,
                           double sigma, double* r, Eigen::Matrix<double, 1, 3>* J) {
  KernelLinePairAt(T_world_base.translation(), T_world_base * q_base, p_ref_world, n_world, sigma,
                   r, J);
}

/// What the solver uses: one measurement point's share of the cost, (1/2) sum_j rho(s_ij) with
/// rho(s) = 1 - exp(-s / (4 sigma^2)) = |r_ij|^2 above (the Welsch robust loss of the pair
/// difference d_ij = p_M - p_Rj), with its exact gradient and exact Hessian with respect to the
/// point position p_M. The Hessian of the sum is projected onto the positive semi-definite cone
/// (negative eigenvalues clipped) before it enters the pose's Gauss-Newton matrix
/// J_p^T H_p J_p. Why not the plain Gauss-Newton matrix of the residuals: it counts every
/// pair's curvature even along a wall, where the sum over the wall's points is flat, so
/// Levenberg-Marquardt crawls (linear convergence) and a corridor never looks degenerate. The
/// summed Hessian is flat along the wall and curved across it, like point-to-line ICP, which is
/// what the kernel sum of eq. 1 really is near a surface.
struct PointKernelSum {
  double cost{0.0};                                   ///< (1/2) sum_j rho(s_ij)
  Eigen::Vector2d gradient{Eigen::Vector2d::Zero()};  ///< d cost / d p_M
  Eigen::Matrix2d hessian{Eigen::Matrix2d::Zero()};   ///< d^2 cost / d p_M^2 (exact)

  /// Add the pair with difference d = p_M - p_Rj (eq. 1's kernel), optionally weighted.
  void AddPoint(const Eigen::Vector2d& d, double sigma, double weight = 1.0) {
    const double a = 1.0 / (4.0 * sigma * sigma);
    const double e = weight * std::exp(-d.squaredNorm() * a);
    // (1/2) rho = (1 - e) / 2; gradient rho' d; Hessian rho' I + 2 rho'' d d^T.
    cost += 0.5 * (weight - e);
    gradient += a * e * d;
    hessian += a * e * (Eigen::Matrix2d::Identity() - 2.0 * a * d * d.transpose());
  }
  /// Point-to-line variant: the kernel of the signed distance n^T d to the line through p_Rj.
  void AddLine(const Eigen::Vector2d& d, const Eigen::Vector2d& n, double sigma,
               double weight = 1.0) {
    const double a = 1.0 / (4.0 * sigma * sigma);
    const double dist = n.dot(d);
    const double e = weight * std::exp(-dist * dist * a);
    cost += 0.5 * (weight - e);
    gradient += a * e * dist * n;
    hessian += a * e * (1.0 - 2.0 * a * dist * dist) * n * n.transpose();
  }
  /// The Hessian with negative eigenvalues clipped to zero.
  Eigen::Matrix2d PsdHessian() const {
    // Closed-form symmetric 2x2 eigen decomposition.
    const double h00 = hessian(0, 0), h11 = hessian(1, 1), h01 = 0.5 * (hessian(0, 1) + hessian(1, 0));
    const double mean = 0.5 * (h00 + h11);
    const double diff = 0.5 * (h00 - h11);
    const double rad = std::sqrt(diff * diff + h01 * h01);
    const double l1 = mean + rad, l2 = mean - rad;
    if (l2 >= 0.0) return hessian;
    if (l1 <= 0.0) return Eigen::Matrix2d::Zero();
    // Eigenvector of l1.
    Eigen::Vector2d v = std::abs(diff) + rad > 0.0
                            ? (h00 >= h11 ? Eigen::Vector2d(l1 - h11, h01) : Eigen::Vector2d(h01, l1 - h00))
                            : Eigen::Vector2d(1.0, 0.0);
    const double n2 = v.squaredNorm();
    if (n2 == 0.0) v = Eigen::Vector2d(1.0, 0.0); else v /= std::sqrt(n2);
    return l1 * v * v.transpose();
  }
};

/// d p_M / d(x, y, theta) for the point p_world of a base at t_world.
inline Eigen::Matrix<double, 2, 3> PointJacobian(const Eigen::Vector2d& t_world,
                                                 const Eigen::Vector2d& p_world) {
  Eigen::Matrix<double, 2, 3> J;
  J << 1.0, 0.0, -(p_world.y() - t_world.y()), 0.0, 1.0, p_world.x() - t_world.x();
  return J;
}

/// The paper's e_mi contribution of one pair: the kernel G(d, 2 sigma^2 I) normalised to peak 1.
inline double KernelScore(const Eigen::Vector2d& d, double sigma) {
  return std::exp(-d.squaredNorm() / (4.0 * sigma * sigma));
}

}  // namespace ifab::base
