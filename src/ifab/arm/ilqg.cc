#include "ifab/arm/ilqg.h"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "ifab/core/angles.h"
#include "ifab/core/config.h"
#include "ifab/core/error.h"

namespace ifab::arm {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Cost changes below this are numerical noise (a motion of zero length costs exactly 0).
constexpr double kCostFloor = 1e-12;

Vector6d ReadVector6(const ConfigNode& node, const char* key, const Vector6d& fallback, bool positive) {
  auto c = node.Find(key);
  if (!c) return fallback;
  const auto v = c->AsNumbers(6);
  Vector6d out;
  for (int i = 0; i < 6; ++i) {
    if (positive ? !(v[i] > 0.0) : !(v[i] >= 0.0)) c->Fail(positive ? "6 positive numbers" : "6 non-negative numbers");
    out[i] = v[i];
  }
  return out;
}

// Quintic from (q0, v0, a = 0) to (q1, 0, 0) over duration T: position and velocity at tau.
void Quintic(const Vector6d& q0, const Vector6d& v0, const Vector6d& q1, double T, double tau,
             Vector6d& q, Vector6d& qd) {
  const double s = std::clamp(tau / T, 0.0, 1.0);
  const Vector6d d = q1 - q0 - v0 * T;
  const Vector6d a3 = 10.0 * d + 4.0 * T * v0;
  const Vector6d a4 = -15.0 * d - 7.0 * T * v0;
  const Vector6d a5 = 6.0 * d + 3.0 * T * v0;
  const double s2 = s * s, s3 = s2 * s, s4 = s3 * s, s5 = s4 * s;
  q = q0 + v0 * (s * T) + a3 * s3 + a4 * s4 + a5 * s5;
  qd = v0 + (3.0 * a3 * s2 + 4.0 * a4 * s3 + 5.0 * a5 * s4) / T;
}

}  // namespace

// Per joint, the optimum of the decoupled problem min int (w_v v^2 + w_e (m a / s)^2) dt of a
// double integrator with the joint's own inertia m (the diagonal of M(q) halfway): the 4th
// derivative of p is k^2 times its 2nd, k = s sqrt(w_v / w_e) / m, so
// p(t) = c0 + c1 t + c2 cosh(k (t - T/2)) + c3 sinh(k (t - T/2)) (a cubic when k T is tiny),
// from (q0, v0) to (q1, 0) in time T.
void IlqgPlanner::WarmStartProfile::Fit(const Vector6d& q0, const Vector6d& v0, const Vector6d& q1, double T_in,
                                        const Vector6d& k_in) {
  T = T_in;
  k = k_in;
  for (int i = 0; i < 6; ++i) {
    k[i] = std::min(k[i], 60.0 / T);  // beyond this the profile is a ramp anyway; keeps cosh finite
    Eigen::Matrix4d A;
    const Eigen::Vector4d b(q0[i], v0[i], q1[i], 0.0);
    if (k[i] * T < 1e-3) {
      k[i] = 0.0;  // cubic basis 1, t, t^2, t^3
      A << 1, 0, 0, 0,  //
          0, 1, 0, 0,   //
          1, T, T * T, T * T * T, 0, 1, 2 * T, 3 * T * T;
    } else {
      const double h = 0.5 * T, ch = std::cosh(k[i] * h), sh = std::sinh(k[i] * h);
      A << 1, 0, ch, -sh,              //
          0, 1, -k[i] * sh, k[i] * ch,  //
          1, T, ch, sh,                 //
          0, 1, k[i] * sh, k[i] * ch;
    }
    c.row(i) = A.colPivHouseholderQr().solve(b).transpose();
  }
}

void IlqgPlanner::WarmStartProfile::Eval(double t, Vector6d& q, Vector6d& qd) const {
  t = std::clamp(t, 0.0, T);
  for (int i = 0; i < 6; ++i) {
    if (k[i] == 0.0) {
      q[i] = c(i, 0) + t * (c(i, 1) + t * (c(i, 2) + t * c(i, 3)));
      qd[i] = c(i, 1) + t * (2.0 * c(i, 2) + 3.0 * t * c(i, 3));
    } else {
      const double tau = t - 0.5 * T, ch = std::cosh(k[i] * tau), sh = std::sinh(k[i] * tau);
      q[i] = c(i, 0) + c(i, 1) * t + c(i, 2) * ch + c(i, 3) * sh;
      qd[i] = c(i, 1) + k[i] * (c(i, 2) * sh + c(i, 3) * ch);
    }
  }
}

void IlqgPlanner::FitWarmStart(const Vector6d& q_from, const Vector6d& qd_from, const Vector6d& q_goal, double T) {
  if (options_.warm_start == IlqgOptions::WarmStart::kQuintic) return;
  ArmData data;
  const Vector6d q_mid = 0.5 * (q_from + q_goal);
  const Vector6d m = MassMatrix<double>(model_, data, q_mid).diagonal();
  Vector6d k;
  for (int i = 0; i < 6; ++i) {
    const double we = options_.effort_weight / (options_.effort_scale[i] * options_.effort_scale[i]);
    k[i] = we > 0.0 ? std::sqrt(options_.velocity_weight[i] / we) / m[i] : 60.0 / T;
  }
  profile_.Fit(q_from, qd_from, q_goal, T, k);
}

void IlqgPlanner::WarmStartAt(const Vector6d& q_from, const Vector6d& qd_from, const Vector6d& q_goal, double T,
                              double t, Vector6d& q, Vector6d& qd) const {
  if (options_.warm_start == IlqgOptions::WarmStart::kQuintic) {
    Quintic(q_from, qd_from, q_goal, T, t, q, qd);
  } else {
    profile_.Eval(t, q, qd);
  }
}

namespace {
}  // namespace

const char* ToString(PlanStatus status) {
  switch (status) {
    case PlanStatus::kConverged: return "converged";
    case PlanStatus::kMaxIterations: return "max_iterations";
    case PlanStatus::kLimitViolation: return "limit_violation";
    case PlanStatus::kFailed: return "failed";
  }
  return "?";
}

std::string PlanSummary::BriefReport() const {
  return fmt::format(
      "iLQG: {} after {} iterations, cost {:.6g} (warm start {:.6g}), {:.1f} ms; duration {:.2f} s in {} "
      "steps; final error {:.2e} deg, final speed {:.2e} deg/s; {}{}{}",
      ToString(status), iterations, cost, initial_cost, 1e3 * seconds, duration, steps,
      RadToDeg(final_position_error), RadToDeg(final_speed),
      within_limits ? "within limits" : "OUTSIDE LIMITS", message.empty() ? "" : "; ", message);
}

IlqgOptions IlqgOptions::FromConfig(const ConfigNode& node, const IlqgOptions& base) {
  node.ExpectMap();
  node.ExpectKeys({"dt", "duration_per_rad", "min_duration", "warm_start", "warm_start_speed_fraction",
                   "effort_relative_to_gravity", "velocity_weight", "effort_scale", "effort_weight",
                   "terminal_position_weight", "terminal_velocity_weight", "limit_weight",
                   "position_limit_margin", "velocity_limit_fraction", "max_iterations", "tolerance_cost",
                   "tolerance_gradient", "mu_init", "mu_min", "mu_max", "mu_factor", "line_search_steps",
                   "min_reduction_ratio", "goal_tolerance", "goal_speed_tolerance"});
  IlqgOptions o = base;
  node.ReadPositive("dt", o.dt);
  node.ReadPositive("duration_per_rad", o.duration_per_rad);
  node.ReadPositive("min_duration", o.min_duration);
  if (auto w = node.Find("warm_start")) {
    const std::string v = w->As<std::string>();
    if (v == "quintic") o.warm_start = WarmStart::kQuintic;
    else if (v == "lq") o.warm_start = WarmStart::kLq;
    else w->Fail("quintic or lq");
  }
  node.ReadInRange("warm_start_speed_fraction", o.warm_start_speed_fraction, 1e-3, 1.0);
  node.Read("effort_relative_to_gravity", o.effort_relative_to_gravity);
  o.velocity_weight = ReadVector6(node, "velocity_weight", o.velocity_weight, false);
  o.effort_scale = ReadVector6(node, "effort_scale", o.effort_scale, true);
  node.ReadNonNegative("effort_weight", o.effort_weight);
  node.ReadPositive("terminal_position_weight", o.terminal_position_weight);
  node.ReadNonNegative("terminal_velocity_weight", o.terminal_velocity_weight);
  node.ReadNonNegative("limit_weight", o.limit_weight);
  node.ReadNonNegative("position_limit_margin", o.position_limit_margin);
  node.ReadInRange("velocity_limit_fraction", o.velocity_limit_fraction, 1e-3, 1.0);
  node.ReadPositive("max_iterations", o.max_iterations);
  node.ReadNonNegative("tolerance_cost", o.tolerance_cost);
  node.ReadNonNegative("tolerance_gradient", o.tolerance_gradient);
  node.ReadNonNegative("mu_init", o.mu_init);
  node.ReadNonNegative("mu_min", o.mu_min);
  node.ReadPositive("mu_max", o.mu_max);
  node.ReadInRange("mu_factor", o.mu_factor, 1.0 + 1e-6, 100.0);
  node.ReadPositive("line_search_steps", o.line_search_steps);
  node.Read("min_reduction_ratio", o.min_reduction_ratio);
  node.ReadPositive("goal_tolerance", o.goal_tolerance);
  node.ReadPositive("goal_speed_tolerance", o.goal_speed_tolerance);
  const std::string why = o.Validate();
  if (!why.empty()) ThrowInputError("{}: {}", node.Where(), why);
  return o;
}

std::string IlqgOptions::Validate() const {
  if (!(dt > 0.0)) return "dt must be positive";
  if (!(duration_per_rad > 0.0) || !(min_duration > 0.0)) return "durations must be positive";
  if (min_duration < 2.0 * dt) return "min_duration must span at least two time steps";
  if ((velocity_weight.array() < 0.0).any()) return "velocity_weight must be non-negative";
  if (!(effort_scale.array() > 0.0).all()) return "effort_scale must be positive";
  if (!(terminal_position_weight > 0.0)) return "terminal_position_weight must be positive";
  if (max_iterations < 1 || line_search_steps < 1) return "max_iterations and line_search_steps must be >= 1";
  if (!(mu_factor > 1.0)) return "mu_factor must exceed 1";
  if (!(mu_max > mu_min)) return "mu_max must exceed mu_min";
  return {};
}

IlqgOptions LoadIlqgOptions(const std::string& path) {
  const ConfigNode root = ConfigNode::LoadFile(path);
  root.ExpectKeys({"ilqg", "ik", "primitives"});  // the arm file (primitives.cc)
  auto section = root.Find("ilqg");
  return section ? IlqgOptions::FromConfig(*section) : IlqgOptions{};
}

IlqgPlanner::IlqgPlanner(const ArmModel& model, IlqgOptions options)
    : model_(model), options_(std::move(options)) {
  const std::string why = options_.Validate();
  if (!why.empty()) ThrowInputError("iLQG options: {}", why);
  gravity_dynamics_ = options_.effort_relative_to_gravity ? Eigen::Vector3d::Zero() : model_.gravity;
  const Vector6d margin = Vector6d::Constant(options_.position_limit_margin);
  soft_q_min_ = model_.q_min + margin;
  soft_q_max_ = model_.q_max - margin;
  soft_qd_max_ = options_.velocity_limit_fraction * model_.qd_max;
  effort_weight_ = options_.effort_weight * options_.effort_scale.array().square().inverse().matrix();
}

double IlqgPlanner::Duration(const Vector6d& q_from, const Vector6d& q_goal, const Vector6d& qd_from) {
  // The paper: proportional to the Euclidean norm of the joint change.
  double T = std::max(options_.min_duration, options_.duration_per_rad * (q_goal - q_from).norm());
  // Lengthen if the warm start would come near a speed limit (only for large or fast starts).
  const Vector6d speed_cap = options_.warm_start_speed_fraction * model_.qd_max;
  for (int round = 0; round < 4; ++round) {
    FitWarmStart(q_from, qd_from, q_goal, T);
    double ratio = 0.0;
    Vector6d q, qd;
    for (int j = 0; j <= 40; ++j) {
      WarmStartAt(q_from, qd_from, q_goal, T, T * j / 40.0, q, qd);
      ratio = std::max(ratio, (qd.cwiseAbs().array() / speed_cap.array()).maxCoeff());
    }
    if (ratio <= 1.0) break;
    T *= ratio * 1.01;
  }
  return T;
}

void IlqgPlanner::Resize(int n) {
  n_ = n;
  x_.resize(n + 1);
  x_new_.resize(n + 1);
  u_.resize(n);
  u_new_.resize(n);
  fx_.resize(n);
  fu_.resize(n);
  k_.resize(n);
  K_.resize(n);
}

bool IlqgPlanner::Step(const Vector12d& x, const Vector6d& u, double dt, Vector12d& x_next) {
  const Vector6d q = x.head<6>();
  const Vector6d qd = x.tail<6>();
  if (!ForwardDynamics<double>(model_, data_, q, qd, u, gravity_dynamics_)) return false;
  const Vector6d qd_next = qd + dt * data_.qdd;
  x_next.head<6>() = q + dt * qd_next;
  x_next.tail<6>() = qd_next;
  return x_next.allFinite();
}

void IlqgPlanner::LimitPenaltyGradient(const Vector12d& x, double weight, Vector12d& lx,
                                       Vector12d& lxx_diag) const {
  for (int i = 0; i < 6; ++i) {
    double d = 0.0;
    if (x[i] > soft_q_max_[i]) d = x[i] - soft_q_max_[i];
    else if (x[i] < soft_q_min_[i]) d = x[i] - soft_q_min_[i];
    if (d != 0.0) {
      lx[i] += weight * d;
      lxx_diag[i] += weight;
    }
    const double v = x[6 + i];
    double e = 0.0;
    if (v > soft_qd_max_[i]) e = v - soft_qd_max_[i];
    else if (v < -soft_qd_max_[i]) e = v + soft_qd_max_[i];
    if (e != 0.0) {
      lx[6 + i] += weight * e;
      lxx_diag[6 + i] += weight;
    }
  }
}

namespace {
double LimitPenalty(const Eigen::Matrix<double, 12, 1>& x, const Vector6d& q_min, const Vector6d& q_max,
                    const Vector6d& qd_max) {
  double c = 0.0;
  for (int i = 0; i < 6; ++i) {
    const double d = std::max(0.0, x[i] - q_max[i]) + std::min(0.0, x[i] - q_min[i]);
    const double e = std::max(0.0, std::abs(x[6 + i]) - qd_max[i]);
    c += 0.5 * (d * d + e * e);
  }
  return c;
}
}  // namespace

double IlqgPlanner::RunningCost(const Vector12d& x, const Vector6d& u) const {
  const double velocity = 0.5 * (options_.velocity_weight.array() * x.tail<6>().array().square()).sum();
  const double effort = 0.5 * (effort_weight_.array() * u.array().square()).sum();
  const double limits = options_.limit_weight * LimitPenalty(x, soft_q_min_, soft_q_max_, soft_qd_max_);
  return dt_ * (velocity + effort + limits);
}

double IlqgPlanner::TerminalCost(const Vector12d& x) const {
  return 0.5 * options_.terminal_position_weight * (x.head<6>() - q_goal_).squaredNorm() +
         0.5 * options_.terminal_velocity_weight * x.tail<6>().squaredNorm() +
         options_.limit_weight * LimitPenalty(x, soft_q_min_, soft_q_max_, soft_qd_max_);
}

void IlqgPlanner::WarmStart(const Vector6d& q_from, const Vector6d& qd_from, const Vector6d& q_goal) {
  // Discrete reference: positions on the profile, velocities and accelerations as the
  // semi-implicit Euler step implies them; RNEA gives the controls that reproduce it. The
  // profile is run over the first N - 1 steps so that the last knot repeats the goal: the
  // discrete trajectory then ends at rest (a profile that brakes late would otherwise leave a
  // last-step velocity for the terminal cost to punish).
  const double T = dt_ * n_;
  FitWarmStart(q_from, qd_from, q_goal, T);
  const double time_scale = static_cast<double>(n_) / (n_ - 1);
  Vector6d q_k = q_from, qd_k = qd_from, q_next, unused;
  for (int k = 0; k < n_; ++k) {
    WarmStartAt(q_from, qd_from, q_goal, T, std::min(T, dt_ * (k + 1) * time_scale), q_next, unused);
    if (k + 2 >= n_) q_next = q_goal;
    const Vector6d qd_next = (q_next - q_k) / dt_;
    const Vector6d qdd = (qd_next - qd_k) / dt_;
    u_[k] = InverseDynamics<double>(model_, data_, q_k, qd_k, qdd, gravity_dynamics_);
    q_k = q_next;
    qd_k = qd_next;
  }
}

double IlqgPlanner::Rollout(double alpha) {
  // alpha < 0: plain rollout of u_ into x_ (the warm start); else the feedback law into *_new_.
  const bool plain = alpha < 0.0;
  std::vector<Vector12d>& xs = plain ? x_ : x_new_;
  std::vector<Vector6d>& us = plain ? u_ : u_new_;
  xs[0] = x_[0];
  double cost = 0.0;
  for (int k = 0; k < n_; ++k) {
    if (!plain) us[k] = u_[k] + alpha * k_[k] + K_[k] * (xs[k] - x_[k]);
    cost += RunningCost(xs[k], us[k]);
    if (!Step(xs[k], us[k], dt_, xs[k + 1])) return kInf;
  }
  cost += TerminalCost(xs[n_]);
  return std::isfinite(cost) ? cost : kInf;
}

bool IlqgPlanner::Linearize(const Vector12d& x, const Vector6d& u, double dt, Matrix12d& fx, Matrix12x6d& fu) {
  const double dt2 = dt * dt;
  const Vector6d q = x.head<6>();
  const Vector6d qd = x.tail<6>();
  if (!ForwardDynamicsDerivatives(model_, derivative_data_, q, qd, u, gravity_dynamics_, derivatives_)) return false;
  const DynamicsDerivatives& d = derivatives_;
  // q' = q + dt qd + dt^2 qdd(q, qd, u),  qd' = qd + dt qdd(q, qd, u).
  fx.topLeftCorner<6, 6>() = dt2 * d.dqdd_dq;
  fx.topLeftCorner<6, 6>().diagonal().array() += 1.0;
  fx.topRightCorner<6, 6>() = dt2 * d.dqdd_dqd;
  fx.topRightCorner<6, 6>().diagonal().array() += dt;
  fx.bottomLeftCorner<6, 6>() = dt * d.dqdd_dq;
  fx.bottomRightCorner<6, 6>() = dt * d.dqdd_dqd;
  fx.bottomRightCorner<6, 6>().diagonal().array() += 1.0;
  fu.topRows<6>() = dt2 * d.M_inv;
  fu.bottomRows<6>() = dt * d.M_inv;
  return true;
}

bool IlqgPlanner::ComputeDerivatives() {
  for (int k = 0; k < n_; ++k) {
    if (!Linearize(x_[k], u_[k], dt_, fx_[k], fu_[k])) return false;
  }
  return true;
}

bool IlqgPlanner::BackwardPass(double mu, double& dv_linear, double& dv_quadratic) {
  // Terminal cost derivatives.
  Vector12d vx = Vector12d::Zero();
  Vector12d vxx_diag = Vector12d::Zero();
  vx.head<6>() = options_.terminal_position_weight * (x_[n_].head<6>() - q_goal_);
  vx.tail<6>() = options_.terminal_velocity_weight * x_[n_].tail<6>();
  vxx_diag.head<6>().setConstant(options_.terminal_position_weight);
  vxx_diag.tail<6>().setConstant(options_.terminal_velocity_weight);
  LimitPenaltyGradient(x_[n_], options_.limit_weight, vx, vxx_diag);
  Matrix12d vxx = vxx_diag.asDiagonal();
  dv_linear = 0.0;
  dv_quadratic = 0.0;

  Eigen::LLT<Matrix6d> llt;
  for (int k = n_ - 1; k >= 0; --k) {
    const Matrix12d& fx = fx_[k];
    const Matrix12x6d& fu = fu_[k];
    // Running cost derivatives (diagonal weights; no cross term).
    Vector12d lx = Vector12d::Zero(), lxx_diag = Vector12d::Zero();
    lx.tail<6>() = options_.velocity_weight.cwiseProduct(x_[k].tail<6>());
    lxx_diag.tail<6>() = options_.velocity_weight;
    LimitPenaltyGradient(x_[k], options_.limit_weight, lx, lxx_diag);
    lx *= dt_;
    lxx_diag *= dt_;
    const Vector6d lu = dt_ * effort_weight_.cwiseProduct(u_[k]);

    const Vector12d qx = lx + fx.transpose() * vx;
    const Vector6d qu = lu + fu.transpose() * vx;
    const Matrix12d vxx_fx = vxx * fx;
    Matrix12d qxx = fx.transpose() * vxx_fx;
    qxx.diagonal() += lxx_diag;
    const Matrix12x6d vxx_fu = vxx * fu;
    Matrix6d quu = fu.transpose() * vxx_fu;
    quu.diagonal() += dt_ * effort_weight_;
    Matrix6x12d qux = vxx_fu.transpose() * fx;
    // Tassa et al. 2012: regularise V'_xx, which keeps the step's effect on the state small.
    Matrix6d quu_reg = quu;
    Matrix6x12d qux_reg = qux;
    if (mu > 0.0) {
      quu_reg.noalias() += mu * fu.transpose() * fu;
      qux_reg.noalias() += mu * fu.transpose() * fx;
    }
    llt.compute(quu_reg);
    if (llt.info() != Eigen::Success) return false;
    k_[k] = -llt.solve(qu);
    K_[k] = -llt.solve(qux_reg);
    const Vector6d& kk = k_[k];
    const Matrix6x12d& KK = K_[k];
    if (!kk.allFinite() || !KK.allFinite()) return false;
    dv_linear += kk.dot(qu);
    dv_quadratic += 0.5 * kk.dot(quu * kk);
    const Matrix12x6d kt_quu = KK.transpose() * quu;
    vx = qx + kt_quu * kk + KK.transpose() * qu + qux.transpose() * kk;
    vxx = qxx + kt_quu * KK + KK.transpose() * qux + qux.transpose() * KK;
    vxx = (0.5 * (vxx + vxx.transpose())).eval();
  }
  return true;
}

ArmPlan IlqgPlanner::Plan(const Vector6d& q_from, const Vector6d& q_goal_in, const Vector6d& qd_from) {
  const auto start = std::chrono::steady_clock::now();
  IFAB_THROW_UNLESS(q_from.allFinite() && q_goal_in.allFinite() && qd_from.allFinite(),
                    "iLQG: start and goal must be finite");
  for (int i = 0; i < 6; ++i) {
    IFAB_THROW_UNLESS(q_goal_in[i] >= model_.q_min[i] - kGoalLimitSlack && q_goal_in[i] <= model_.q_max[i] + kGoalLimitSlack,
                      "iLQG: goal joint {} = {:.4f} rad lies outside its limits [{:.4f}, {:.4f}]", i + 1,
                      q_goal_in[i], model_.q_min[i], model_.q_max[i]);
  }
  // A goal a rounding error outside a limit (e.g. 180 deg against a limit written 3.14159265)
  // is moved onto it.
  const Vector6d q_goal = q_goal_in.cwiseMax(model_.q_min).cwiseMin(model_.q_max);
  ArmPlan plan;
  PlanSummary& s = plan.summary;
  const double T = Duration(q_from, q_goal, qd_from);
  const int n = std::max(2, static_cast<int>(std::ceil(T / options_.dt - 1e-9)));
  Resize(n);
  dt_ = T / n;
  q_goal_ = q_goal;
  s.duration = T;
  s.steps = n;

  x_[0].head<6>() = q_from;
  x_[0].tail<6>() = qd_from;
  WarmStart(q_from, qd_from, q_goal);
  double cost = Rollout(-1.0);
  s.initial_cost = cost;
  bool failed = !std::isfinite(cost);
  if (failed) s.message = "the warm start's rollout is not finite";

  const double ln_factor = options_.mu_factor;
  double mu = options_.mu_init, dmu = 1.0;
  bool converged = false, changed = true;
  auto increase_mu = [&]() {
    dmu = std::max(dmu * ln_factor, ln_factor);
    mu = std::max(mu * dmu, options_.mu_min);
  };
  int iter = 0;
  while (!failed && !converged && iter < options_.max_iterations) {
    ++iter;
    if (changed) {
      if (!ComputeDerivatives()) {
        failed = true;
        s.message = "singular mass matrix";
        break;
      }
      changed = false;
    }
    double dv1 = 0.0, dv2 = 0.0;
    bool backward_ok = false;
    while (true) {
      backward_ok = BackwardPass(mu, dv1, dv2);
      if (backward_ok) break;
      increase_mu();
      if (mu > options_.mu_max) break;
    }
    if (!backward_ok) {
      failed = true;
      s.message = "backward pass: regularisation exceeded mu_max";
      break;
    }
    double g_norm = 0.0;
    for (int k = 0; k < n_; ++k)
      g_norm += (k_[k].cwiseAbs().array() / (u_[k].cwiseAbs().array() + 1.0)).maxCoeff();
    g_norm /= n_;
    if (g_norm < options_.tolerance_gradient && mu < 1e-5) {
      converged = true;
      s.message = "gradient below tolerance";
      break;
    }
    bool accepted = false;
    double new_cost = kInf, reduction = 0.0;
    for (int j = 0; j < options_.line_search_steps; ++j) {
      const double alpha =
          options_.line_search_steps == 1 ? 1.0 : std::pow(10.0, -3.0 * j / (options_.line_search_steps - 1));
      new_cost = Rollout(alpha);
      if (!std::isfinite(new_cost)) continue;
      reduction = cost - new_cost;
      const double expected = -alpha * (dv1 + alpha * dv2);
      const double z = expected > 0.0 ? reduction / expected : (reduction > 0.0 ? 1.0 : -1.0);
      if (z > options_.min_reduction_ratio) {
        accepted = true;
        break;
      }
    }
    if (accepted) {
      dmu = std::min(dmu / ln_factor, 1.0 / ln_factor);
      mu = mu * dmu;
      if (mu < options_.mu_min) mu = 0.0;
      std::swap(x_, x_new_);
      std::swap(u_, u_new_);
      cost = new_cost;
      changed = true;
      if (reduction <= options_.tolerance_cost * cost + kCostFloor) {
        converged = true;
        s.message = "cost change below tolerance";
      }
    } else {
      // Nothing left to gain at the full step: converged; else regularise more.
      if (-(dv1 + dv2) <= options_.tolerance_cost * cost + kCostFloor) {
        converged = true;
        s.message = "expected cost change below tolerance";
        break;
      }
      increase_mu();
      if (mu > options_.mu_max) {
        failed = true;
        s.message = "line search failed and regularisation exceeded mu_max";
      }
    }
  }
  s.iterations = iter;
  s.cost = cost;

  // The result: the trajectory, the torques and the gains, checked against the hard limits.
  plan.trajectory.points.resize(n_ + 1);
  plan.torques.resize(n_);
  plan.feedback_gains.assign(K_.begin(), K_.end());
  bool within = true;
  for (int k = 0; k <= n_; ++k) {
    JointTrajectory::Point& p = plan.trajectory.points[k];
    p.t = dt_ * k;
    p.q = x_[k].head<6>();
    p.qd = x_[k].tail<6>();
    within = within && ((p.q - model_.q_min).array() >= -kGoalLimitSlack).all() &&
             ((model_.q_max - p.q).array() >= -kGoalLimitSlack).all() &&
             (p.qd.cwiseAbs().array() <= model_.qd_max.array() + 1e-9).all();
    if (k < n_) {
      Vector6d tau = u_[k];
      if (options_.effort_relative_to_gravity) tau += GravityTorque<double>(model_, data_, p.q);
      plan.torques[k] = tau;
      within = within && (tau.cwiseAbs().array() <= model_.effort_max.array()).all();
    }
  }
  s.within_limits = within;
  s.final_position_error = (x_[n_].head<6>() - q_goal).cwiseAbs().maxCoeff();
  s.final_speed = x_[n_].tail<6>().cwiseAbs().maxCoeff();
  s.reached_goal = s.final_position_error <= options_.goal_tolerance && s.final_speed <= options_.goal_speed_tolerance;
  if (failed) {
    s.status = PlanStatus::kFailed;
  } else if (!converged) {
    s.status = PlanStatus::kMaxIterations;
    s.message = fmt::format("no convergence in {} iterations", options_.max_iterations);
  } else if (!within || !s.reached_goal) {
    s.status = PlanStatus::kLimitViolation;
    s.message += !within ? "; violates a joint limit" : "; misses the goal tolerance";
  } else {
    s.status = PlanStatus::kConverged;
  }
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return plan;
}

}  // namespace ifab::arm
