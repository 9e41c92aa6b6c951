#include "ifab/base/planner/stomp_planner.h"

#include <fmt/format.h>
#include <oneapi/tbb/parallel_for.h>
#include <oneapi/tbb/task_arena.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <limits>
#include <numeric>

#include "ifab/core/angles.h"
#include "ifab/core/error.h"
#include "ifab/core/log.h"

namespace ifab::base {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

void ReadPhase(const ConfigNode& node, StompPhaseOptions* p) {
  node.ExpectKeys({"max_iterations", "min_iterations", "noise_stddev_xy", "noise_stddev_theta", "noise_decay",
                   "min_noise_fraction", "hold_noise_until_valid", "cost_window", "convergence_tolerance"});
  node.ReadPositive("max_iterations", p->max_iterations);
  node.ReadNonNegative("min_iterations", p->min_iterations);
  node.ReadPositive("noise_stddev_xy", p->noise_stddev_xy);
  node.ReadPositive("noise_stddev_theta", p->noise_stddev_theta);
  node.ReadInRange("noise_decay", p->noise_decay, 0.0, 1.0);
  node.ReadInRange("min_noise_fraction", p->min_noise_fraction, 0.0, 1.0);
  node.Read("hold_noise_until_valid", p->hold_noise_until_valid);
  node.ReadNonNegative("cost_window", p->cost_window);
  node.ReadNonNegative("convergence_tolerance", p->convergence_tolerance);
}

}  // namespace

const char* PlanStatusName(PlanStatus s) {
  switch (s) {
    case PlanStatus::kSuccess: return "success";
    case PlanStatus::kStartInCollision: return "start_in_collision";
    case PlanStatus::kGoalOutsideBoundary: return "goal_outside_boundary";
    case PlanStatus::kGoalInCollision: return "goal_in_collision";
    case PlanStatus::kUnreachable: return "unreachable";
    case PlanStatus::kNotConverged: return "not_converged";
  }
  return "unknown";
}

std::string PlanResult::BriefReport() const {
  if (iterations == 0 && trajectory.empty()) {
    return fmt::format("STOMP base planner: {} ({}), {:.1f} ms", PlanStatusName(status), message, seconds * 1e3);
  }
  return fmt::format(
      "STOMP base planner: {} ({}); iterations {} (phase 1: {}, phase 2: {}), cost {:.4g}, {:.1f} ms; "
      "min clearance {:.3f} m, max lateral velocity {:.2e} m/s, max track speed {:.3f} m/s, "
      "{} poses, length {:.2f} m, duration {:.1f} s",
      PlanStatusName(status), message, iterations, phase1_iterations, phase2_iterations, cost, seconds * 1e3,
      min_clearance, max_lateral_velocity, max_track_speed, trajectory.size(), trajectory.Length(),
      trajectory.duration);
}

StompPlannerOptions StompPlannerOptions::FromConfig(const ConfigNode& node) {
  StompPlannerOptions o;
  node.ExpectKeys({"num_time_steps", "num_rollouts", "num_reused_rollouts", "exponent_h", "acceleration_weight",
                   "jerk_weight", "heading_scale", "obstacle_weight", "obstacle_margin", "collision_penalty", "obstacle_substeps", "obstacle_substep_length",
                   "required_clearance", "phase1_clearance", "collision_check_step", "duration_slack", "track_speed_fraction", "per_segment_timing",
                   "constraint_tolerance", "constraint_projection_steps", "constraint_damping",
                   "phase2_initialization", "phase2_attempts", "check_reachability", "reachability_cell", "num_threads", "phase1",
                   "phase2"});
  node.ReadPositive("num_time_steps", o.num_time_steps);
  node.ReadPositive("num_rollouts", o.num_rollouts);
  node.ReadNonNegative("num_reused_rollouts", o.num_reused_rollouts);
  node.ReadPositive("exponent_h", o.exponent_h);
  node.ReadNonNegative("acceleration_weight", o.smoothness.acceleration);
  node.ReadNonNegative("jerk_weight", o.smoothness.jerk);
  node.ReadPositive("heading_scale", o.smoothness.heading_scale);
  node.ReadNonNegative("obstacle_weight", o.obstacle_weight);
  node.ReadPositive("obstacle_margin", o.obstacle_margin);
  node.ReadNonNegative("collision_penalty", o.collision_penalty);
  node.ReadNonNegative("obstacle_substeps", o.obstacle_substeps);
  node.ReadPositive("obstacle_substep_length", o.obstacle_substep_length);
  node.ReadNonNegative("required_clearance", o.required_clearance);
  node.ReadNonNegative("phase1_clearance", o.phase1_clearance);
  node.ReadPositive("collision_check_step", o.collision_check_step);
  node.ReadPositive("duration_slack", o.duration_slack);
  node.ReadInRange("track_speed_fraction", o.track_speed_fraction, 0.01, 1.0);
  node.Read("per_segment_timing", o.per_segment_timing);
  node.ReadPositive("constraint_tolerance", o.constraint_tolerance);
  node.ReadNonNegative("constraint_projection_steps", o.constraint_projection_steps);
  node.ReadNonNegative("constraint_damping", o.constraint_damping);
  if (auto c = node.Find("phase2_initialization")) {
    o.phase2_initialization = c->As<std::string>();
    if (o.phase2_initialization != "phase1" && o.phase2_initialization != "tangent" &&
        o.phase2_initialization != "best") {
      c->Fail("'phase1', 'tangent' or 'best'");
    }
  }
  node.ReadPositive("phase2_attempts", o.phase2_attempts);
  node.Read("check_reachability", o.check_reachability);
  // A cell under 1 mm is no use to a 1.4 t base and its grid would not fit memory.
  node.ReadInRange("reachability_cell", o.reachability_cell, 1e-3, 10.0);
  node.ReadNonNegative("num_threads", o.num_threads);
  if (auto c = node.Find("phase1")) ReadPhase(*c, &o.phase1);
  if (auto c = node.Find("phase2")) ReadPhase(*c, &o.phase2);
  std::string why;
  if (!o.IsValid(&why)) node.Fail(why);
  return o;
}

bool StompPlannerOptions::IsValid(std::string* why) const {
  const auto fail = [&](const std::string& w) {
    if (why) *why = w;
    return false;
  };
  if (num_time_steps < 3) return fail("num_time_steps >= 3");
  if (num_rollouts < 2) return fail("num_rollouts >= 2");
  if (num_reused_rollouts < 0 || num_reused_rollouts > num_rollouts) return fail("0 <= num_reused_rollouts <= num_rollouts");
  if (!(exponent_h > 0)) return fail("exponent_h > 0");
  if (!(obstacle_margin > 0) || required_clearance < 0 || required_clearance >= obstacle_margin) {
    return fail("0 <= required_clearance < obstacle_margin");
  }
  if (phase2_initialization != "phase1" && phase2_initialization != "tangent" && phase2_initialization != "best") {
    return fail("phase2_initialization 'phase1', 'tangent' or 'best'");
  }
  if (phase2_attempts < 1) return fail("phase2_attempts >= 1");
  for (const auto* p : {&phase1, &phase2}) {
    if (p->max_iterations < 1 || p->min_iterations < 0) return fail("phase max_iterations >= 1, min_iterations >= 0");
  }
  return true;
}

// Per-Plan() buffers; sized once, reused by every iteration of both phases.
struct StompBasePlanner::Workspace {
  int K{0};
  std::vector<TrajectoryMatrix> traj;   // rollout trajectories (N+2 x 3)
  std::vector<TrajectoryMatrix> eps;    // rollout noise on the free points (N x 3)
  std::vector<Eigen::VectorXd> cost;    // per-point costs (N+2)
  std::vector<Eigen::Matrix<double, Eigen::Dynamic, 3>> z;  // standard normal draws
  std::vector<RandomStream> streams;    // one per rollout index, never shared between threads
  std::vector<double> total;            // total cost per rollout
  std::vector<Eigen::VectorXd> prefix;  // prefix sums of the per-point costs
  std::vector<int> order;
  std::vector<TrajectoryMatrix> reused;  // best rollouts of the previous iteration
  std::vector<Eigen::VectorXd> reused_cost;
  Eigen::MatrixXd weights;              // N x (K + reused)
  ConstraintProjector projector;
  std::unique_ptr<oneapi::tbb::task_arena> arena;
};

StompBasePlanner::StompBasePlanner(PlanningScene scene, BaseGeometry robot, StompPlannerOptions options)
    : options_(std::move(options)), checker_(std::move(scene), std::move(robot)) {
  std::string why;
  IFAB_THROW_UNLESS(options_.IsValid(&why), "STOMP base planner options: expected {}", why);
  n_ = options_.num_time_steps;
  const Eigen::MatrixXd A = AccelerationMatrix(n_);
  const Eigen::MatrixXd R = A.transpose() * A;
  const Eigen::MatrixXd Rinv = R.inverse();
  S_ = Rinv / Rinv.maxCoeff();
  L_ = Eigen::LLT<Eigen::MatrixXd>(S_).matrixL();
  M_ = Rinv;
  for (int c = 0; c < n_; ++c) M_.col(c) *= (1.0 / n_) / Rinv.col(c).cwiseAbs().maxCoeff();

  // Reachability grid: a cell is open if the footprint's inscribed disc could be centred in it.
  const auto& boundary = checker_.scene().boundary;
  if (options_.check_reachability && !boundary.empty()) {
    Eigen::Vector2d lo = boundary[0], hi = boundary[0];
    for (const auto& p : boundary) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    const double cell = options_.reachability_cell;
    grid_origin_ = lo;
    // The cell count in double first: a tiny cell would overflow int (and the allocation).
    const double nx = std::ceil((hi.x() - lo.x()) / cell) + 1, ny = std::ceil((hi.y() - lo.y()) / cell) + 1;
    constexpr double kMaxCells = 1e7;  // 80 MB of labels; a 1 cm grid over a 30 x 30 m site
    if (!(cell > 0) || !(nx * ny <= kMaxCells))
      ThrowInputError("stomp.reachability_cell: {} m gives {:.3g} x {:.3g} cells over the site's {:.1f} x {:.1f} m "
                      "boundary; expected a cell giving at most {:.0g} cells",
                      cell, nx, ny, hi.x() - lo.x(), hi.y() - lo.y(), kMaxCells);
    grid_nx_ = static_cast<int>(nx);
    grid_ny_ = static_cast<int>(ny);
    const double r_in = 0.5 * std::min(checker_.robot().length, checker_.robot().width);
    const double slack = 0.5 * std::sqrt(2.0) * cell;
    std::vector<char> open(static_cast<std::size_t>(grid_nx_ * grid_ny_));
    grid_clearance_.assign(open.size(), 0.0);
    // Discs covering the footprint: m equal pieces along its longer side, each in a disc through
    // its corners. Three for the 1.8 x 1.2 m base (radius 0.67 m against the 1.08 m circumcircle),
    // so that far more poses are shown clear of everything by the field alone.
    const BaseGeometry& g = checker_.robot();
    const bool along_x = g.length >= g.width;
    const double lng = along_x ? g.length : g.width, shrt = along_x ? g.width : g.length;
    const int m = std::max(1, static_cast<int>(std::lround(2.0 * lng / shrt)));
    cover_radius_ = 0.5 * std::hypot(lng / m, shrt);
    for (int j = 0; j < m; ++j) {
      const double u = -0.5 * lng + (j + 0.5) * lng / m;
      cover_centres_.push_back(g.footprint_offset + (along_x ? Eigen::Vector2d(u, 0.0) : Eigen::Vector2d(0.0, u)));
    }
    for (int iy = 0; iy < grid_ny_; ++iy) {
      for (int ix = 0; ix < grid_nx_; ++ix) {
        const Eigen::Vector2d p = lo + cell * Eigen::Vector2d(ix, iy);
        const double d = checker_.PointClearance(p);
        grid_clearance_[iy * grid_nx_ + ix] = d;
        open[iy * grid_nx_ + ix] = d >= r_in - slack;
      }
    }
    grid_label_.assign(open.size(), -1);
    int label = 0;
    std::deque<int> queue;
    for (std::size_t c = 0; c < open.size(); ++c) {
      if (!open[c] || grid_label_[c] >= 0) continue;
      grid_label_[c] = label;
      queue.push_back(static_cast<int>(c));
      while (!queue.empty()) {
        const int cur = queue.front();
        queue.pop_front();
        const int cx = cur % grid_nx_, cy = cur / grid_nx_;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const int x = cx + dx, y = cy + dy;
            if (x < 0 || y < 0 || x >= grid_nx_ || y >= grid_ny_) continue;
            const int nb = y * grid_nx_ + x;
            if (open[nb] && grid_label_[nb] < 0) {
              grid_label_[nb] = label;
              queue.push_back(nb);
            }
          }
        }
      }
      ++label;
    }
  }
}

StompBasePlanner::~StompBasePlanner() = default;
StompBasePlanner::StompBasePlanner(StompBasePlanner&&) noexcept = default;

double StompBasePlanner::EstimateDuration(const Pose2& start, const Pose2& goal) const {
  const double v = options_.track_speed_fraction * checker_.robot().max_track_speed;
  const double half_gauge = 0.5 * checker_.robot().track_gauge;
  // Driving straight uses both tracks at v; turning in place moves each track by B/2 per radian.
  const double t = (TranslationDistance(start, goal) + half_gauge * AngleDistance(start, goal)) / v;
  return std::max(options_.duration_slack * t, 1.0);
}

bool StompBasePlanner::ProvablyClear(const Pose2& p, double c, double s, double margin) const {
  if (grid_clearance_.empty()) return false;  // built with the reachability grid only
  // PointClearance is 1-Lipschitz, so a point within half a cell diagonal of a node is at least
  // the node's value minus that far from every object; a disc around it, its radius less.
  const double cell = options_.reachability_cell;
  const double need = margin + cover_radius_ + 0.5 * std::sqrt(2.0) * cell + 1e-9;
  const double inv_cell = 1.0 / cell;
  for (const Eigen::Vector2d& o : cover_centres_) {
    const double gx = (p.x + c * o.x() - s * o.y() - grid_origin_.x()) * inv_cell + 0.5;
    const double gy = (p.y + s * o.x() + c * o.y() - grid_origin_.y()) * inv_cell + 0.5;
    if (!(gx >= 0.0 && gy >= 0.0 && gx < grid_nx_ && gy < grid_ny_)) return false;
    const int ix = static_cast<int>(gx), iy = static_cast<int>(gy);  // nearest node (gx, gy >= 0)
    if (grid_clearance_[iy * grid_nx_ + ix] < need) return false;
  }
  return true;
}

double StompBasePlanner::ObstacleCost(const Pose2& p, double margin, double collision_penalty) const {
  const double c = std::cos(p.theta), s = std::sin(p.theta);
  if (ProvablyClear(p, c, s, margin)) return 0.0;
  return checker_.Cost(p, c, s, margin, collision_penalty);
}

void StompBasePlanner::PointCosts(const TrajectoryMatrix& q, Eigen::VectorXd* per_point) const {
  per_point->setZero(q.rows());
  AddSmoothnessCosts(q, options_.smoothness, per_point);
  const double w = options_.obstacle_weight / static_cast<double>(q.rows() - 1);
  const double r = checker_.robot().CircumRadius();
  const Eigen::Index last = q.rows() - 1;
  for (Eigen::Index i = 0; i <= last; ++i) {
    const auto cost_at = [&](const Eigen::Vector3d& p) {
      return ObstacleCost(Pose2(p.x(), p.y(), p.z()), options_.obstacle_margin, options_.collision_penalty);
    };
    const Eigen::Vector3d a = q.row(i).transpose();
    double c = cost_at(a);
    if (options_.obstacle_substeps > 0 && i < last) {
      // Poses between i and i+1 count to point i, so a trajectory cannot jump over an obstacle
      // between two time steps.
      const Eigen::Vector3d b = q.row(i + 1).transpose();
      const double travel = std::hypot(b.x() - a.x(), b.y() - a.y()) + r * std::abs(b.z() - a.z());
      const int m = std::min(options_.obstacle_substeps,
                             static_cast<int>(std::ceil(travel / options_.obstacle_substep_length)));
      for (int s = 1; s < m; ++s) c += cost_at(a + (b - a) * (static_cast<double>(s) / m));
    }
    (*per_point)[i] += w * c;
  }
}

namespace {
// Calls f(pose) along every segment of q, at most `step` of footprint travel apart.
template <typename F>
bool ForEachDensePose(const TrajectoryMatrix& q, double step, double radius, F&& f) {
  for (Eigen::Index j = 0; j + 1 < q.rows(); ++j) {
    const Eigen::Vector3d a = q.row(j).transpose(), b = q.row(j + 1).transpose();
    const double travel = std::hypot(b.x() - a.x(), b.y() - a.y()) + radius * std::abs(b.z() - a.z());
    const int m = std::max(1, static_cast<int>(std::ceil(travel / step)));
    for (int s = (j == 0 ? 0 : 1); s <= m; ++s) {
      const Eigen::Vector3d p = a + (b - a) * (static_cast<double>(s) / m);
      if (!f(Pose2(p.x(), p.y(), p.z()))) return false;
    }
  }
  return true;
}
}  // namespace

double StompBasePlanner::DenseClearance(const TrajectoryMatrix& q) const {
  double d = kInfinity;
  ForEachDensePose(q, options_.collision_check_step, checker_.robot().CircumRadius(), [&](const Pose2& p) {
    d = std::min(d, checker_.Clearance(p));
    return true;
  });
  return d;
}

bool StompBasePlanner::DenseCollisionFree(const TrajectoryMatrix& q, double clearance) const {
  const double margin = clearance + 1e-9;
  return ForEachDensePose(q, options_.collision_check_step, checker_.robot().CircumRadius(),
                          [&](const Pose2& p) { return ObstacleCost(p, margin, 0.0) <= 0.0; });
}

bool StompBasePlanner::IsReachable(const Pose2& start, const Pose2& goal) const {
  if (grid_label_.empty()) return true;
  const auto label = [&](const Pose2& pose) {
    const Eigen::Vector2d c = pose * checker_.robot().footprint_offset;
    const Eigen::Vector2d g = (c - grid_origin_) / options_.reachability_cell;
    const int ix = static_cast<int>(std::lround(g.x())), iy = static_cast<int>(std::lround(g.y()));
    if (ix < 0 || iy < 0 || ix >= grid_nx_ || iy >= grid_ny_) return -1;
    return grid_label_[iy * grid_nx_ + ix];
  };
  const int a = label(start), b = label(goal);
  // A blocked cell cannot be judged (the disc test is conservative): let STOMP try.
  return a < 0 || b < 0 || a == b;
}

bool StompBasePlanner::ProjectOntoConstraints(TrajectoryMatrix* q, Workspace* ws, int steps, double target) const {
  const int n = n_;
  Eigen::VectorXd r = LateralResiduals(*q);
  double err = r.cwiseAbs().maxCoeff();
  TrajectoryMatrix corr(n, 3);
  for (int it = 0; it < steps && err > target; ++it) {
    ws->projector.Linearize(*q);
    corr.setZero();
    ws->projector.Project(&corr, &r);  // corr = -Sigma C^T K^-1 r
    // Backtracking keeps the Gauss-Newton step from overshooting on the nonlinear constraint.
    double alpha = 1.0;
    bool accepted = false;
    for (int ls = 0; ls < 6; ++ls, alpha *= 0.5) {
      TrajectoryMatrix trial = *q;
      trial.middleRows(1, n) += alpha * corr;
      const Eigen::VectorXd rt = LateralResiduals(trial);
      if (rt.squaredNorm() < r.squaredNorm()) {
        *q = std::move(trial);
        r = rt;
        accepted = true;
        break;
      }
    }
    if (!accepted) break;
    err = r.cwiseAbs().maxCoeff();
  }
  return err <= options_.constraint_tolerance;
}

int StompBasePlanner::RunPhase(int phase, TrajectoryMatrix* q, const RandomStream& rng, Workspace* ws,
                               double* final_cost) const {
  const StompPhaseOptions& po = phase == 1 ? options_.phase1 : options_.phase2;
  const bool constrained = phase == 2;
  const int n = n_;
  const int K = options_.num_rollouts;
  const RandomStream phase_rng = rng.Derive(phase == 1 ? "stomp.phase1" : "stomp.phase2");
  for (int k = 0; k < K; ++k) ws->streams[k] = phase_rng.Derive(static_cast<std::uint64_t>(k));
  ws->reused.clear();
  ws->reused_cost.clear();

  Eigen::Vector3d sigma(po.noise_stddev_xy, po.noise_stddev_xy, po.noise_stddev_theta);
  const Eigen::Vector3d sigma_min = po.min_noise_fraction * sigma;
  if (constrained) {
    ws->projector.Reset(S_, sigma, options_.constraint_damping);
    ws->projector.Linearize(*q);
  }

  Eigen::VectorXd point_cost(n + 2);
  PointCosts(*q, &point_cost);
  double cost = point_cost.sum();
  const auto is_valid = [&](const TrajectoryMatrix& t) {
    if (constrained && LateralResiduals(t).cwiseAbs().maxCoeff() > options_.constraint_tolerance) return false;
    return DenseCollisionFree(t, constrained ? options_.required_clearance
                                             : std::max(options_.required_clearance, options_.phase1_clearance));
  };
  TrajectoryMatrix best = *q;
  double best_cost = cost;
  bool best_valid = is_valid(*q);

  const auto rollout = [&](int k) {
    RandomStream& stream = ws->streams[k];
    auto& z = ws->z[k];
    for (int d = 0; d < 3; ++d) {
      for (int i = 0; i < n; ++i) z(i, d) = stream.Normal();
    }
    TrajectoryMatrix& e = ws->eps[k];
    e.noalias() = L_ * z;
    for (int d = 0; d < 3; ++d) e.col(d) *= sigma[d];
    if (constrained) ws->projector.Project(&e);
    ws->traj[k] = *q;
    ws->traj[k].middleRows(1, n) += e;
    PointCosts(ws->traj[k], &ws->cost[k]);
  };

  int it = 0;
  for (; it < po.max_iterations; ++it) {
    if (best_valid && it >= po.min_iterations && phase == 1) break;
    // 1. Noisy rollouts, in parallel; rollout k only ever touches stream k.
    if (!ws->arena) {
      for (int k = 0; k < K; ++k) rollout(k);
    } else {
      ws->arena->execute([&] { oneapi::tbb::parallel_for(0, K, rollout); });
    }
    // Rollouts kept from the previous iteration join with their noise relative to the new mean.
    const int R = static_cast<int>(ws->reused.size());
    const int total = K + R;
    for (int r = 0; r < R; ++r) {
      ws->traj[K + r] = ws->reused[r];
      ws->eps[K + r] = ws->reused[r].middleRows(1, n) - q->middleRows(1, n);
      ws->cost[K + r] = ws->reused_cost[r];
    }
    // 2. Per-time-step probabilities P = exp(-h (S - min S) / (max S - min S)). S of time step i is
    // its own cost (STOMP), or the cost summed over i +- cost_window steps.
    for (int k = 0; k < total; ++k) {
      auto& pre = ws->prefix[k];
      pre[0] = 0.0;
      for (int p = 0; p < n + 2; ++p) pre[p + 1] = pre[p] + ws->cost[k][p];
    }
    for (int i = 0; i < n; ++i) {
      int lo_p = i + 1 - po.cost_window, hi_p = i + 1 + po.cost_window;  // point range
      // The fixed ends' costs count to their neighbours.
      if (lo_p <= 1) lo_p = 0;
      if (hi_p >= n) hi_p = n + 1;
      const auto step_cost = [&](int k) { return ws->prefix[k][hi_p + 1] - ws->prefix[k][lo_p]; };
      double lo = kInfinity, hi = -kInfinity;
      for (int k = 0; k < total; ++k) {
        const double sk = step_cost(k);
        lo = std::min(lo, sk);
        hi = std::max(hi, sk);
      }
      const double range = hi - lo;
      double sum = 0.0;
      for (int k = 0; k < total; ++k) {
        const double w = range > 1e-12 ? std::exp(-options_.exponent_h * (step_cost(k) - lo) / range) : 1.0;
        ws->weights(i, k) = w;
        sum += w;
      }
      ws->weights.row(i).head(total) /= sum;
    }
    // 3. Probability-weighted noise, smoothed through M.
    TrajectoryMatrix dtilde = TrajectoryMatrix::Zero(n, 3);
    for (int k = 0; k < total; ++k) {
      dtilde += ws->eps[k].cwiseProduct(ws->weights.col(k).head(n).replicate(1, 3));
    }
    TrajectoryMatrix delta = M_ * dtilde;
    if (constrained) ws->projector.Project(&delta);
    q->middleRows(1, n) += delta;
    if (constrained) {
      // Second-order drift off the constraints: one Gauss-Newton step back (the next iteration's
      // noise is conditioned on the constraints linearised at the result, below).
      ws->projector.Linearize(*q);
      const Eigen::VectorXd r = LateralResiduals(*q);
      TrajectoryMatrix corr = TrajectoryMatrix::Zero(n, 3);
      ws->projector.Project(&corr, &r);
      q->middleRows(1, n) += corr;
    }
    // 4. Cost of the new trajectory; keep the best (valid first).
    PointCosts(*q, &point_cost);
    const double new_cost = point_cost.sum();
    const bool valid = is_valid(*q);
    if (spdlog::should_log(spdlog::level::trace)) {
      spdlog::trace("stomp phase {} iteration {}: cost {:.4g}, valid {}, noise {:.3f} m, clearance {:.3f} m", phase,
                    it, new_cost, valid, sigma[0], DenseClearance(*q));
    }
    if ((valid && !best_valid) || (valid == best_valid && new_cost < best_cost)) {
      best = *q;
      best_cost = new_cost;
      best_valid = valid;
    }
    const bool converged = valid && it + 1 >= po.min_iterations &&
                           cost - new_cost < po.convergence_tolerance * std::abs(new_cost);
    cost = new_cost;
    if (converged && phase == 2) {
      ++it;
      break;
    }
    // 5. Keep the best rollouts for the next iteration; decay the noise.
    if (options_.num_reused_rollouts > 0) {
      for (int k = 0; k < total; ++k) ws->total[k] = ws->cost[k].sum();
      ws->order.resize(total);
      std::iota(ws->order.begin(), ws->order.end(), 0);
      const int keep = std::min(options_.num_reused_rollouts, total);
      std::partial_sort(ws->order.begin(), ws->order.begin() + keep, ws->order.end(),
                        [&](int a, int b) { return ws->total[a] < ws->total[b]; });
      ws->reused.resize(keep);
      ws->reused_cost.resize(keep);
      for (int r = 0; r < keep; ++r) {
        ws->reused[r] = ws->traj[ws->order[r]];  // same sizes: no allocation after the first time
        ws->reused_cost[r] = ws->cost[ws->order[r]];
      }
    }
    // Exploration narrows only once the trajectory is valid; until then it keeps searching wide.
    if (valid || !po.hold_noise_until_valid) sigma = (sigma * po.noise_decay).cwiseMax(sigma_min);
    if (constrained) {
      ws->projector.Reset(S_, sigma, options_.constraint_damping);
      ws->projector.Linearize(*q);
    }
  }
  *q = best;
  *final_cost = best_cost;
  return it;
}

TrajectoryMatrix StompBasePlanner::TangentInitialization(const TrajectoryMatrix& p1, double theta_start,
                                                         double theta_goal, bool reverse) const {
  const int np = static_cast<int>(p1.rows());  // N + 2
  TrajectoryMatrix q = p1;
  std::vector<double> s(np, 0.0);
  for (int i = 1; i < np; ++i) {
    s[i] = s[i - 1] + std::hypot(p1(i, 0) - p1(i - 1, 0), p1(i, 1) - p1(i - 1, 1));
  }
  const double length = s.back();
  if (length < 1e-6) {
    for (int i = 0; i < np; ++i) {
      q(i, 0) = p1(0, 0);
      q(i, 1) = p1(0, 1);
      q(i, 2) = theta_start + WrapAngle(theta_goal - theta_start) * i / (np - 1.0);
    }
    return q;
  }
  // Unwrapped path tangent at every point (central differences, skipping repeated points).
  std::vector<double> psi(np);
  for (int i = 0; i < np; ++i) {
    int a = std::max(i - 1, 0), b = std::min(i + 1, np - 1);
    while (a > 0 && s[i] - s[a] < 1e-9) --a;
    while (b < np - 1 && s[b] - s[i] < 1e-9) ++b;
    const double t = std::atan2(p1(b, 1) - p1(a, 1), p1(b, 0) - p1(a, 0));
    psi[i] = i == 0 ? t : psi[i - 1] + WrapAngle(t - psi[i - 1]);
  }
  // Drive forwards or in reverse; turn in place the shorter way at both ends.
  const double offset = reverse ? kPi : 0.0;
  const double d1 = WrapAngle(psi.front() + offset - theta_start);
  const double d2 = WrapAngle(theta_goal - (psi.back() + offset));
  const double half_gauge = 0.5 * checker_.robot().track_gauge;
  const double e1 = half_gauge * std::abs(d1), e2 = half_gauge * std::abs(d2);
  const double total = e1 + length + e2;
  const double psi0 = psi.front() + offset;
  int seg = 0;
  for (int i = 0; i < np; ++i) {
    const double u = total * i / (np - 1.0);
    if (u <= e1 && e1 > 0) {
      q(i, 0) = p1(0, 0);
      q(i, 1) = p1(0, 1);
      q(i, 2) = theta_start + d1 * (u / e1);
    } else if (u >= e1 + length) {
      q(i, 0) = p1(np - 1, 0);
      q(i, 1) = p1(np - 1, 1);
      q(i, 2) = psi0 + (psi.back() - psi.front()) + (e2 > 0 ? d2 * (u - e1 - length) / e2 : 0.0);
    } else {
      const double si = u - e1;
      while (seg < np - 2 && s[seg + 1] < si) ++seg;
      const double ds = s[seg + 1] - s[seg];
      const double f = ds > 0 ? (si - s[seg]) / ds : 0.0;
      q(i, 0) = p1(seg, 0) + f * (p1(seg + 1, 0) - p1(seg, 0));
      q(i, 1) = p1(seg, 1) + f * (p1(seg + 1, 1) - p1(seg, 1));
      q(i, 2) = psi0 + (psi[seg] - psi.front()) + f * (psi[seg + 1] - psi[seg]);
    }
  }
  q(0, 2) = theta_start;
  q(np - 1, 0) = p1(np - 1, 0);
  q(np - 1, 1) = p1(np - 1, 1);
  q(np - 1, 2) = psi0 + (psi.back() - psi.front()) + d2;
  return q;
}

TrajectoryMatrix StompBasePlanner::AlignedInitialization(const TrajectoryMatrix& p1, double theta_start,
                                                         double theta_goal, int sign_start, int sign_goal) const {
  const int np = static_cast<int>(p1.rows());  // N + 2
  const double inv_dtau = np - 1;
  double length = 0.0;
  for (int i = 1; i < np; ++i) length += std::hypot(p1(i, 0) - p1(i - 1, 0), p1(i, 1) - p1(i - 1, 1));
  // Hermite tangent basis functions add the difference between the wanted end velocities (along
  // the start and goal headings, at the path's mean speed) and phase 1's end velocities.
  const Eigen::Vector2d v0 = (p1.row(1).head<2>() - p1.row(0).head<2>()).transpose() * inv_dtau;
  const Eigen::Vector2d v1 = (p1.row(np - 1).head<2>() - p1.row(np - 2).head<2>()).transpose() * inv_dtau;
  const Eigen::Vector2d m0 = sign_start * length * Eigen::Vector2d(std::cos(theta_start), std::sin(theta_start));
  const Eigen::Vector2d m1 = sign_goal * length * Eigen::Vector2d(std::cos(theta_goal), std::sin(theta_goal));
  TrajectoryMatrix q = p1;
  for (int i = 0; i < np; ++i) {
    const double t = i / inv_dtau;
    const double h10 = t * (1 - t) * (1 - t), h11 = t * t * (t - 1);
    q.row(i).head<2>() += (h10 * (m0 - v0) + h11 * (m1 - v1)).transpose();
  }
  // Headings along the path, forwards or in reverse, whichever continues the previous heading.
  q(0, 2) = theta_start;
  for (int i = 1; i < np - 1; ++i) {
    const Eigen::Vector2d v = (q.row(i + 1).head<2>() - q.row(i - 1).head<2>()).transpose();
    if (v.norm() < 1e-9) {
      q(i, 2) = q(i - 1, 2);
      continue;
    }
    const double phi = std::atan2(v.y(), v.x());
    double h = q(i - 1, 2) + WrapAngle(phi - q(i - 1, 2));
    if (std::abs(h - q(i - 1, 2)) > 0.5 * kPi) h -= std::copysign(kPi, h - q(i - 1, 2));
    q(i, 2) = h;
  }
  q(np - 1, 2) = q(np - 2, 2) + WrapAngle(theta_goal - q(np - 2, 2));
  return q;
}

BaseTrajectory StompBasePlanner::ToBaseTrajectory(const TrajectoryMatrix& q, double duration, double* max_lateral,
                                                  double* max_track) const {
  const int segments = static_cast<int>(q.rows()) - 1;
  const double half_gauge = 0.5 * checker_.robot().track_gauge;
  std::vector<double> v(segments), w(segments), lat(segments);
  double worst_track = 0.0;
  for (int j = 0; j < segments; ++j) {
    const double tb = 0.5 * (q(j, 2) + q(j + 1, 2));
    const double dx = q(j + 1, 0) - q(j, 0), dy = q(j + 1, 1) - q(j, 1);
    v[j] = std::cos(tb) * dx + std::sin(tb) * dy;  // per unit of normalised segment time
    lat[j] = -std::sin(tb) * dx + std::cos(tb) * dy;
    w[j] = q(j + 1, 2) - q(j, 2);
    worst_track = std::max(worst_track, std::abs(v[j]) + half_gauge * std::abs(w[j]));
  }
  // The estimated duration spread evenly over the segments, stretched where a track would exceed
  // the planning speed: all segments (uniform timing) or just that one (per-segment timing, the
  // controller follows the poses, not the clock).
  const double v_plan = options_.track_speed_fraction * checker_.robot().max_track_speed;
  const double dt_nominal = duration / segments;
  std::vector<double> dt(segments, std::max(dt_nominal, worst_track / v_plan));
  if (options_.per_segment_timing) {
    for (int j = 0; j < segments; ++j) {
      dt[j] = std::max(dt_nominal, (std::abs(v[j]) + half_gauge * std::abs(w[j])) / v_plan);
    }
  }
  BaseTrajectory out;
  out.points.resize(q.rows());
  *max_lateral = 0.0;
  *max_track = 0.0;
  for (int j = 0; j < segments; ++j) {
    out.duration += dt[j];
    v[j] /= dt[j];
    w[j] /= dt[j];
    *max_lateral = std::max(*max_lateral, std::abs(lat[j]) / dt[j]);
    *max_track = std::max(*max_track, std::abs(v[j]) + half_gauge * std::abs(w[j]));
  }
  for (int i = 0; i <= segments; ++i) {
    BaseTrajectory::Point& p = out.points[i];
    p.pose = Pose2(q(i, 0), q(i, 1), WrapAngle(q(i, 2)));
    // Nominal velocities at a pose: those of the segments on either side, averaged.
    const int a = std::max(i - 1, 0), b = std::min(i, segments - 1);
    p.v = 0.5 * (v[a] + v[b]);
    p.omega = 0.5 * (w[a] + w[b]);
  }
  return out;
}

PlanResult StompBasePlanner::Plan(const Pose2& start, const Pose2& goal, const RandomStream& rng) const {
  const auto t0 = std::chrono::steady_clock::now();
  PlanResult result;
  const auto finish = [&](PlanStatus status, std::string message) {
    result.status = status;
    result.message = std::move(message);
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return result;
  };

  std::string closest;
  const double d_start = checker_.Clearance(start, &closest);
  if (d_start < 0.0) {
    return finish(PlanStatus::kStartInCollision,
                  fmt::format("start footprint overlaps {} by {:.3f} m", closest, -d_start));
  }
  const double d_goal = checker_.Clearance(goal, &closest);
  if (d_goal < 0.0) {
    if (closest == "boundary" || !checker_.CentreInsideBoundary(goal)) {
      return finish(PlanStatus::kGoalOutsideBoundary,
                    fmt::format("goal footprint leaves the site boundary by {:.3f} m", -d_goal));
    }
    return finish(PlanStatus::kGoalInCollision, fmt::format("goal footprint overlaps {} by {:.3f} m", closest, -d_goal));
  }
  if (options_.check_reachability && !IsReachable(start, goal)) {
    return finish(PlanStatus::kUnreachable, "no passage wide enough for the robot leads from the start to the goal");
  }

  const int n = n_;
  Workspace ws;
  const int slots = options_.num_rollouts + options_.num_reused_rollouts;
  ws.K = options_.num_rollouts;
  ws.traj.assign(slots, TrajectoryMatrix(n + 2, 3));
  ws.eps.assign(slots, TrajectoryMatrix(n, 3));
  ws.cost.assign(slots, Eigen::VectorXd(n + 2));
  ws.z.assign(options_.num_rollouts, Eigen::Matrix<double, Eigen::Dynamic, 3>(n, 3));
  ws.streams.assign(options_.num_rollouts, RandomStream(0));
  ws.total.assign(slots, 0.0);
  ws.prefix.assign(slots, Eigen::VectorXd(n + 3));
  ws.weights.resize(n, slots);
  if (options_.num_threads != 1) {
    ws.arena = options_.num_threads > 0 ? std::make_unique<oneapi::tbb::task_arena>(options_.num_threads)
                                        : std::make_unique<oneapi::tbb::task_arena>();
  }

  // Phase 1: straight interpolation, holonomic.
  const double theta_goal = start.theta + WrapAngle(goal.theta - start.theta);
  TrajectoryMatrix q(n + 2, 3);
  for (int i = 0; i < n + 2; ++i) {
    const double f = static_cast<double>(i) / (n + 1);
    q.row(i) << start.x + f * (goal.x - start.x), start.y + f * (goal.y - start.y),
        start.theta + f * (theta_goal - start.theta);
  }
  double cost = 0.0;
  Eigen::VectorXd point_cost_buffer(n + 2);
  result.phase1_iterations = RunPhase(1, &q, rng, &ws, &cost);
  result.phase1_clearance = DenseClearance(q);
  {
    double lat = 0, track = 0;
    result.phase1_trajectory = ToBaseTrajectory(q, EstimateDuration(start, goal), &lat, &track);
  }
  spdlog::debug("stomp phase 1: {} iterations, cost {:.4g}, clearance {:.3f} m", result.phase1_iterations, cost,
                result.phase1_clearance);

  // Phase 2: from phase 1's result, with the non-holonomic constraints. Candidate initial
  // trajectories are projected onto the constraints and tried cheapest first.
  std::vector<TrajectoryMatrix> candidates;
  const std::string& init = options_.phase2_initialization;
  if (init == "tangent" || init == "best") {
    TrajectoryMatrix fwd = TangentInitialization(q, start.theta, theta_goal, false);
    TrajectoryMatrix rev = TangentInitialization(q, start.theta, theta_goal, true);
    candidates.push_back(std::move(fwd));
    candidates.push_back(std::move(rev));
  }
  if (init == "phase1" || init == "best") candidates.push_back(q);
  if (init == "best") {
    for (int sign_start : {1, -1}) {
      for (int sign_goal : {1, -1}) {
        candidates.push_back(AlignedInitialization(q, start.theta, theta_goal, sign_start, sign_goal));
      }
    }
  }
  ws.projector.Reset(S_, Eigen::Vector3d(options_.phase2.noise_stddev_xy, options_.phase2.noise_stddev_xy,
                                         options_.phase2.noise_stddev_theta),
                     options_.constraint_damping);
  std::vector<double> candidate_cost;
  for (auto& c : candidates) {
    ProjectOntoConstraints(&c, &ws, options_.constraint_projection_steps, 0.1 * options_.constraint_tolerance);
    PointCosts(c, &point_cost_buffer);
    candidate_cost.push_back(point_cost_buffer.sum());
  }
  std::vector<int> order(candidates.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return candidate_cost[a] < candidate_cost[b]; });
  const int attempts = std::min<int>(options_.phase2_attempts, static_cast<int>(candidates.size()));
  TrajectoryMatrix best_q;
  double best_score = kInfinity;
  for (int a = 0; a < attempts; ++a) {
    TrajectoryMatrix qa = candidates[order[a]];
    // (Arguments of a log call are evaluated even when the level is off: these checks are costly.)
    if (spdlog::should_log(spdlog::level::debug))
      spdlog::debug("stomp phase 2 attempt {} start: cost {:.4g}, clearance {:.3f} m, sideways {:.2e} m", a,
                    candidate_cost[order[a]], DenseClearance(qa), LateralResiduals(qa).cwiseAbs().maxCoeff());
    result.phase2_iterations += RunPhase(2, &qa, a == 0 ? rng : rng.Derive(static_cast<std::uint64_t>(a)), &ws, &cost);
    // The result is polished far below the tolerance (Gauss-Newton converges quadratically here).
    ProjectOntoConstraints(&qa, &ws, 2 * options_.constraint_projection_steps, 1e-3 * options_.constraint_tolerance);
    const bool valid = LateralResiduals(qa).cwiseAbs().maxCoeff() <= options_.constraint_tolerance &&
                       DenseCollisionFree(qa, options_.required_clearance);
    if (spdlog::should_log(spdlog::level::debug))
      spdlog::debug("stomp phase 2 attempt {}: cost {:.4g}, clearance {:.3f} m, valid {}", a, cost, DenseClearance(qa),
                    valid);
    // Score: valid trajectories by cost, invalid ones after all valid ones.
    const double score = valid ? cost : 1e300 - DenseClearance(qa);
    if (score < best_score) {
      best_score = score;
      best_q = qa;
    }
    if (valid) break;
  }
  q = best_q;
  result.iterations = result.phase1_iterations + result.phase2_iterations;

  Eigen::VectorXd point_cost(n + 2);
  PointCosts(q, &point_cost);
  result.cost = point_cost.sum();
  result.max_constraint_violation = LateralResiduals(q).cwiseAbs().maxCoeff();
  result.min_clearance = DenseClearance(q);
  result.trajectory =
      ToBaseTrajectory(q, EstimateDuration(start, goal), &result.max_lateral_velocity, &result.max_track_speed);
  if (result.min_clearance < options_.required_clearance) {
    return finish(PlanStatus::kNotConverged,
                  fmt::format("no collision-free trajectory found (clearance {:.3f} m)", result.min_clearance));
  }
  if (result.max_constraint_violation > options_.constraint_tolerance) {
    return finish(PlanStatus::kNotConverged,
                  fmt::format("trajectory still moves sideways by {:.4f} m per step", result.max_constraint_violation));
  }
  return finish(PlanStatus::kSuccess, "collision-free, no sideways motion");
}

}  // namespace ifab::base
