#pragma once
/// \file
/// Point-to-point arm motion planning with iLQG (Todorov & Li 2005), paper Sec. IV, eq. (5):
///
///   J = h(x_N) + sum_{k<N} l(x_k, u_k),   x = (q, qd) in R^12,   u = joint torques in R^6.
///
/// - Dynamics: the arm's rigid-body dynamics (dynamics.h), discretised with semi-implicit Euler
///   (qd' = qd + dt qdd, q' = q + dt qd'); derivatives from one Jet pass through RNEA per knot and
///   iteration (DynamicsDerivatives).
/// - Terminal cost h: deviation from the desired joint position and from zero velocity.
/// - Running cost l, "dominated by joint velocity and control effort penalties":
///     dt * (1/2 sum_i w_v,i qd_i^2 + 1/2 w_e sum_i (e_i / s_i)^2) + joint-limit penalties,
///   where the effort e is the torque beyond gravity compensation, e = tau - g(q)
///   (effort_relative_to_gravity, the default; holding the arm still then costs nothing). With
///   that option the planner's control variable is e itself (tau = e + g(q)): the same optimal
///   control problem under a change of variables, with simpler dynamics (gravity cancels).
///   With the option off, e = tau, the paper read literally.
/// - Duration: proportional to the Euclidean norm of the joint change (paper), at least
///   min_duration, lengthened if the warm start would come near a joint speed limit.
/// - Joint position and speed limits: quadratic penalties beyond soft limits just inside the hard
///   ones; the result is checked against the hard limits.
/// - Solver: backward pass with the regularisation of Tassa, Erez & Todorov (IROS 2012): mu is
///   added to V'_xx (not to Q_uu) and adapted with their quadratic schedule; backtracking line
///   search on the feedforward step accepted on the ratio of actual to expected cost reduction.
/// - Warm start: a joint interpolation whose inverse-dynamics torques reproduce it exactly under
///   the discrete dynamics, so the first rollout already ends at the goal and iLQG only reshapes
///   it: per joint the optimum of the decoupled problem (warm_start: lq, default) or minimum
///   jerk (quintic).
///
/// The result is the joint position (and velocity) trajectory for the arm's own controller
/// (as in the paper), plus the torques and the feedback gains.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "ifab/arm/arm_model.h"
#include "ifab/arm/dynamics.h"
#include "ifab/msgs/msgs.h"

namespace ifab {
class ConfigNode;
}

namespace ifab::arm {

struct IlqgOptions {
  // The problem.
  double dt{0.04};                       ///< time step [s]
  double duration_per_rad{0.8};          ///< movement duration per radian of joint change (Euclidean norm) [s/rad]
  double min_duration{0.6};              ///< shortest movement [s]
  /// Initial trajectory: kQuintic = minimum jerk; kLq = per joint the optimum of the decoupled
  /// problem (double integrator with the joint's own inertia, same weights), closer to the answer.
  enum class WarmStart { kQuintic, kLq };
  WarmStart warm_start{WarmStart::kLq};
  double warm_start_speed_fraction{0.8}; ///< lengthen the movement so the warm start's joint speeds stay below this fraction of the limits
  bool effort_relative_to_gravity{true}; ///< penalise tau - g(q) (true) or tau itself (false)
  Vector6d velocity_weight{Vector6d::Ones()};  ///< w_v: running cost per (rad/s)^2 per second
  /// s: effort penalty scale per joint [N m]; roughly the joint's inertia over the acceleration
  /// time constant wanted (about M_ii / 0.3 s at a typical pose).
  Vector6d effort_scale{(Vector6d() << 600.0, 900.0, 300.0, 12.0, 6.0, 0.5).finished()};
  double effort_weight{1.0};             ///< w_e
  double terminal_position_weight{1e6};  ///< per rad^2 of final position error
  double terminal_velocity_weight{1e4};  ///< per (rad/s)^2 of final speed
  double limit_weight{1e4};              ///< quadratic penalty weight beyond the soft limits
  double position_limit_margin{0.005};   ///< soft position limits this far inside the hard ones [rad]
  double velocity_limit_fraction{0.95};  ///< soft speed limits as a fraction of the hard ones

  // The solver (Tassa et al. 2012).
  int max_iterations{30};                ///< outer iterations (backward + forward pass)
  double tolerance_cost{1e-6};           ///< converged when an accepted step lowers the cost by less than this fraction
  double tolerance_gradient{1e-5};       ///< converged when max_i |k_i| / (|u_i| + 1), averaged over time, falls below
  double mu_init{1e-3};                  ///< initial regularisation
  double mu_min{1e-6};                   ///< below this mu is set to 0
  double mu_max{1e10};                   ///< give up above this
  double mu_factor{1.6};                 ///< Delta_0 of the regularisation schedule
  int line_search_steps{11};             ///< step sizes 10^(-3 j / (steps - 1)), j = 0 .. steps - 1
  double min_reduction_ratio{0.0};       ///< accept a step if actual / expected reduction exceeds this
  double goal_tolerance{1e-4};           ///< a plan reaches the goal if every joint ends this close [rad]
  double goal_speed_tolerance{1e-3};     ///< ... and every joint speed is below this [rad/s]

  /// Read the `ilqg:` section over `base` (every key optional; unknown keys rejected).
  static IlqgOptions FromConfig(const ConfigNode& node, const IlqgOptions& base);
  static IlqgOptions FromConfig(const ConfigNode& node) { return FromConfig(node, IlqgOptions{}); }
  /// Empty if usable, else what is wrong.
  std::string Validate() const;
};

enum class PlanStatus {
  kConverged,       ///< converged; within limits and at the goal
  kMaxIterations,   ///< iteration limit reached (the trajectory is the best found)
  kLimitViolation,  ///< converged, but violates a joint limit or misses the goal tolerance
  kFailed,          ///< numerical failure (regularisation exhausted or non-finite values)
};
const char* ToString(PlanStatus status);

struct PlanSummary {
  PlanStatus status{PlanStatus::kFailed};
  std::string message;
  int iterations{0};              ///< outer iterations run
  double cost{0.0};               ///< final cost J
  double initial_cost{0.0};       ///< cost of the warm start
  double seconds{0.0};            ///< wall time of Plan()
  double duration{0.0};           ///< movement duration [s]
  int steps{0};                   ///< time steps N
  double final_position_error{0.0};  ///< max_i |q_N,i - q_goal,i| [rad]
  double final_speed{0.0};        ///< max_i |qd_N,i| [rad/s]
  bool within_limits{false};      ///< positions (to kGoalLimitSlack), speeds and torques within the hard limits
  bool reached_goal{false};       ///< final error and speed within the goal tolerances

  /// The trajectory may be executed: within limits and at the goal.
  bool IsUsable() const { return status != PlanStatus::kFailed && within_limits && reached_goal; }
  std::string BriefReport() const;
};

struct ArmPlan {
  PlanSummary summary;
  /// Knots k = 0..N at t = k dt: positions and velocities for the arm's own controller.
  JointTrajectory trajectory;
  /// Joint torques applied over [t_k, t_k+1), k = 0..N-1 [N m].
  std::vector<Vector6d> torques;
  /// Feedback gains: the control correction for a state error (q - q_k, qd - qd_k). The control is
  /// tau - g(q) with effort_relative_to_gravity, else tau.
  std::vector<Eigen::Matrix<double, 6, 12>> feedback_gains;
};

/// Plans point-to-point motions. Holds its workspace (reused between plans: after the longest
/// plan so far nothing is allocated); not thread-safe, use one per thread.
class IlqgPlanner {
 public:
  /// [rad] goals this close outside a position limit are moved onto it; trajectories may touch
  /// the limits within it (limits in the URDF are rounded to 1e-8 rad).
  static constexpr double kGoalLimitSlack = 1e-6;

  explicit IlqgPlanner(const ArmModel& model, IlqgOptions options = {});

  /// Plan from (q_from, qd_from) to q_goal at rest. Throws InputError if q_goal lies outside the
  /// joint limits (by more than kGoalLimitSlack; closer goals are moved onto the limit) or an
  /// input is not finite; numerical outcomes are in the summary.
  ArmPlan Plan(const Vector6d& q_from, const Vector6d& q_goal,
               const Vector6d& qd_from = Vector6d::Zero());

  /// Movement duration the planner uses for this joint change [s].
  double Duration(const Vector6d& q_from, const Vector6d& q_goal, const Vector6d& qd_from);

  const IlqgOptions& options() const { return options_; }
  const ArmModel& model() const { return model_; }

  using Vector12d = Eigen::Matrix<double, 12, 1>;
  using Matrix12d = Eigen::Matrix<double, 12, 12>;
  using Matrix12x6d = Eigen::Matrix<double, 12, 6>;
  using Matrix6x12d = Eigen::Matrix<double, 6, 12>;

  /// The planner's discrete dynamics x_next = F(x, u) over one step dt (semi-implicit Euler;
  /// u is tau - g(q) with effort_relative_to_gravity, else tau). False if the dynamics fail.
  bool Step(const Vector12d& x, const Vector6d& u, double dt, Vector12d& x_next);
  /// Its Jacobians F_x (12 x 12) and F_u (12 x 6), as the backward pass uses them.
  bool Linearize(const Vector12d& x, const Vector6d& u, double dt, Matrix12d& fx, Matrix12x6d& fu);

 private:
  struct WarmStartProfile {
    Eigen::Matrix<double, 6, 4> c{Eigen::Matrix<double, 6, 4>::Zero()};
    Vector6d k{Vector6d::Zero()};
    double T{1.0};
    void Fit(const Vector6d& q0, const Vector6d& v0, const Vector6d& q1, double T, const Vector6d& k);
    void Eval(double t, Vector6d& q, Vector6d& qd) const;
  };

  void Resize(int n);
  void FitWarmStart(const Vector6d& q_from, const Vector6d& qd_from, const Vector6d& q_goal, double T);
  void WarmStartAt(const Vector6d& q_from, const Vector6d& qd_from, const Vector6d& q_goal, double T, double t,
                   Vector6d& q, Vector6d& qd) const;
  void WarmStart(const Vector6d& q_from, const Vector6d& qd_from, const Vector6d& q_goal);
  double RunningCost(const Vector12d& x, const Vector6d& u) const;
  double TerminalCost(const Vector12d& x) const;
  // Roll out u (with the feedback law when alpha > 0) into xs/us_new; returns the cost or +inf.
  double Rollout(double alpha);
  bool ComputeDerivatives();
  bool BackwardPass(double mu, double& dv_linear, double& dv_quadratic);
  void LimitPenaltyGradient(const Vector12d& x, double weight, Vector12d& lx, Vector12d& lxx_diag) const;

  ArmModel model_;
  IlqgOptions options_;
  Eigen::Vector3d gravity_dynamics_;  // gravity inside the planner's dynamics
  Vector6d soft_q_min_, soft_q_max_, soft_qd_max_;
  Vector6d effort_weight_;             // w_e / s_i^2

  WarmStartProfile profile_;
  int n_{0};
  double dt_{0.0};
  Vector6d q_goal_;
  std::vector<Vector12d> x_, x_new_;
  std::vector<Vector6d> u_, u_new_;
  std::vector<Matrix12d> fx_;
  std::vector<Matrix12x6d> fu_;
  std::vector<Vector6d> k_;
  std::vector<Matrix6x12d> K_;
  ArmData data_;
  DerivativeData derivative_data_;
  DynamicsDerivatives derivatives_;
};

/// Read the `ilqg:` section of a file (e.g. data/arm/arm.yaml).
IlqgOptions LoadIlqgOptions(const std::string& path);

}  // namespace ifab::arm
