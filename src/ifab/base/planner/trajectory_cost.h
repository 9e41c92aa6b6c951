#pragma once
/// \file
/// Cost and constraint terms of the STOMP base planner on a discretised trajectory.
///
/// A trajectory is a (N+2) x 3 matrix: row i is point i = (x, y, theta) in the site frame at
/// normalised time tau_i = i / (N+1); row 0 is the start and row N+1 the goal (both fixed), rows
/// 1..N are the N free points STOMP optimises. theta is unwrapped (continuous). Derivatives are
/// taken with respect to tau, so the costs do not depend on the maneuver's duration; the robot is
/// at rest before the start and after the goal (the trajectory is padded with copies of them).

#include <Eigen/Core>

namespace ifab::base {

using TrajectoryMatrix = Eigen::Matrix<double, Eigen::Dynamic, 3>;

/// Weights of the smoothness terms (paper Sec. III-A: "penalties on the acceleration and jerk").
struct SmoothnessWeights {
  double acceleration{1.0};  ///< weight of the integral of |d2q/dtau2|^2
  double jerk{0.01};         ///< weight of the integral of |d3q/dtau3|^2
  double heading_scale{0.5};  ///< length [m] that turns heading [rad] into distance in |.|^2
};

/// Adds each point's share of the acceleration and jerk integrals to per_point (size N+2).
/// The sum of per_point is w_a * integral |q''|^2 + w_j * integral |q'''|^2, discretised by finite
/// differences with |v|^2 = vx^2 + vy^2 + (heading_scale * vtheta)^2.
void AddSmoothnessCosts(const TrajectoryMatrix& q, const SmoothnessWeights& w, Eigen::VectorXd* per_point);

/// Finite-difference acceleration matrix A ((N+2) x N) on the free points for one coordinate,
/// rest-padded: row i holds the coefficients of q[i-1] - 2 q[i] + q[i+1] (without the 1/dtau^2
/// factor), so that theta_free^T A^T A theta_free is the sum of squared accelerations up to
/// terms fixed by the start and goal. STOMP's R = A^T A.
Eigen::MatrixXd AccelerationMatrix(int num_free);

/// Non-holonomic (no sideways motion) constraints, one per segment j = 0..N between points j and
/// j+1: the chord of an arc driven with constant curvature points along the mean heading, so
///   c_j = -sin(thetabar_j) (x_{j+1} - x_j) + cos(thetabar_j) (y_{j+1} - y_j) = 0,
///   thetabar_j = (theta_j + theta_{j+1}) / 2.
/// c_j [m] is the sideways displacement over the segment; c_j / dt is the lateral velocity.
Eigen::VectorXd LateralResiduals(const TrajectoryMatrix& q);

/// Sparse Jacobian of LateralResiduals with respect to the free points: for segment j,
///   dc_j/dx_j = s_j, dc_j/dx_{j+1} = -s_j, dc_j/dy_j = -k_j, dc_j/dy_{j+1} = k_j,
///   dc_j/dtheta_j = dc_j/dtheta_{j+1} = h_j,
/// with s = sin(thetabar), k = cos(thetabar), h = -(k dx + s dy) / 2. Entries of the fixed start
/// and goal are dropped.
struct LateralJacobian {
  Eigen::VectorXd s, k, h;  ///< size N+1 each

  int num_free() const { return static_cast<int>(s.size()) - 1; }
  /// Dense (N+1) x 3N matrix; columns [x_1..x_N, y_1..y_N, theta_1..theta_N].
  Eigen::MatrixXd Dense() const;
  /// C * v for a free-point displacement v (N x 3).
  Eigen::VectorXd Apply(const TrajectoryMatrix& v_free) const;
};
LateralJacobian LinearizeLateral(const TrajectoryMatrix& q);

/// Projection of free-point displacements onto the linearised constraints in the metric of the
/// noise covariance Sigma = blockdiag(sx^2 S, sy^2 S, st^2 S): the conditioned Gaussian of
/// STOMP with linear constraints. v -> v - Sigma C^T (C Sigma C^T)^-1 (C v + r).
class ConstraintProjector {
 public:
  /// S: N x N shape of the noise covariance; sigma: per-coordinate scales (x, y, theta).
  void Reset(const Eigen::MatrixXd& S, const Eigen::Vector3d& sigma, double damping);
  /// Linearise at trajectory q (re-factorises C Sigma C^T).
  void Linearize(const TrajectoryMatrix& q);
  /// v (N x 3) -> v - Sigma C^T K^-1 (C v + r); r may be empty (zero).
  void Project(TrajectoryMatrix* v, const Eigen::VectorXd* r = nullptr) const;
  const LateralJacobian& jacobian() const { return jac_; }

 private:
  Eigen::MatrixXd S_;
  Eigen::Vector3d var_{1, 1, 1};
  double damping_{1e-9};
  LateralJacobian jac_;
  Eigen::MatrixXd G_;  // Sigma C^T, 3N x (N+1)
  Eigen::MatrixXd K_factor_;
  Eigen::VectorXd tmp_;
};

}  // namespace ifab::base
