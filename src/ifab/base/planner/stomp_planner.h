#pragma once
/// \file
/// Two-phase STOMP base planner (paper Sec. III-A; STOMP: Kalakrishnan et al., ICRA 2011).
///
/// The trajectory is (x, y, theta) at N free time steps between the fixed start and goal. Each
/// iteration draws K noisy rollouts theta + eps_k with eps_k ~ N(0, R^-1), R = A^T A from the
/// finite-difference acceleration matrix A; scores each rollout per time step; weights the
/// rollouts per time step by P = exp(-h (S - min S) / (max S - min S)); and moves the trajectory by
/// the smoothed update M * sum_k P_k eps_k, M = R^-1 with columns scaled to a maximum of 1/N.
/// The cost is acceleration and jerk penalties plus non-smooth obstacle costs from the footprint's
/// clearance to the site boundary and to every obstacle.
///
/// Phase 1 starts from the straight interpolation between start and goal and ignores the tracks'
/// non-holonomic constraint. Phase 2 starts from phase 1's result and enforces no sideways motion
/// as linear constraints (linearised at the current trajectory) for every sample at every time
/// step: the exploration noise is conditioned on them, i.e. projected onto their null space in
/// the metric of R^-1 (the paper's ref. [9]), and so is the update; a Gauss-Newton step per
/// iteration removes the second-order drift off the (nonlinear) constraints.
///
/// Rollouts run in parallel with oneTBB; rollout k draws from its own RandomStream derived from
/// the seed and k, so the result does not depend on the number of threads.
///
/// Where this goes beyond the paper (each behind an option; see data/base/planner.yaml):
/// - phase 2 may start from several projections of phase 1's result (the trajectory itself, its
///   path driven forwards / in reverse with turns on the spot, its path bent to leave and reach
///   the ends along their headings) and tries them cheapest first (phase2_initialization,
///   phase2_attempts): the paper's literal start reaches a success rate of about 0.8-0.9 on the
///   brick-stacking experiment, the candidates about 0.995;
/// - the noise narrows only once the trajectory is valid (hold_noise_until_valid);
/// - poses between time steps are costed too, so a trajectory cannot jump over an obstacle
///   (obstacle_substeps);
/// - goals that the footprint's inscribed disc cannot reach are rejected at once from a grid
///   (check_reachability), so "unreachable" is a status, not STOMP running out of iterations.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "ifab/base/planner/base_trajectory.h"
#include "ifab/base/planner/planning_scene.h"
#include "ifab/base/planner/trajectory_cost.h"
#include "ifab/core/config.h"
#include "ifab/core/random.h"
#include "ifab/core/se2.h"

namespace ifab::base {

/// Options of one STOMP phase.
struct StompPhaseOptions {
  int max_iterations{60};        ///< iterations before giving up
  int min_iterations{3};         ///< iterations before a valid trajectory may stop the phase
  double noise_stddev_xy{0.4};   ///< exploration noise std-dev at the trajectory middle [m]
  double noise_stddev_theta{0.4};  ///< exploration noise std-dev of the heading [rad]
  double noise_decay{0.95};      ///< noise std-dev factor per iteration
  double min_noise_fraction{0.1};  ///< noise never decays below this fraction of the start
  bool hold_noise_until_valid{true};  ///< decay the noise only while the trajectory is valid
  /// Rollouts are weighted per time step i by the cost of steps i +- cost_window (0: step i alone,
  /// as STOMP). In phase 2 a window can help: constrained noise acts non-locally (a heading change
  /// moves every later point).
  int cost_window{0};
  double convergence_tolerance{0.01};  ///< stop when valid and the cost improves less than this (relative)
};

struct StompPlannerOptions {
  int num_time_steps{40};   ///< N free trajectory points between start and goal
  int num_rollouts{12};     ///< K noisy rollouts per iteration
  int num_reused_rollouts{4};  ///< best rollouts of the previous iteration kept (importance sampling)
  double exponent_h{10.0};  ///< sensitivity h of the exponentiated rollout cost
  SmoothnessWeights smoothness;  ///< acceleration and jerk penalties
  double obstacle_weight{1e5};  ///< weight of the obstacle cost (integral over normalised time)
  double obstacle_margin{0.15};    ///< obstacles nearer than this [m] cost (hinge)
  double collision_penalty{1.0};   ///< extra obstacle cost [m-equivalent] of a point in collision
  int obstacle_substeps{8};        ///< max poses costed per time step (in between points, 1 = points only)
  double obstacle_substep_length{0.05};  ///< footprint travel [m] per in-between pose
  double required_clearance{0.0};  ///< clearance [m] a valid trajectory keeps everywhere
  double phase1_clearance{0.1};    ///< phase 1 continues until its path keeps this clearance [m]
  double collision_check_step{0.02};  ///< max footprint travel [m] between dense collision checks
  double duration_slack{1.3};      ///< duration estimate factor over distance / speed
  double track_speed_fraction{0.8};  ///< plan nominal track speeds at this fraction of the limit
  /// Segments that would exceed that speed at the estimated duration are slowed down alone (true)
  /// or the whole trajectory is (false: uniform timing).
  bool per_segment_timing{true};
  double constraint_tolerance{1e-3};  ///< max sideways displacement per time step [m] in phase 2
  int constraint_projection_steps{10};  ///< Gauss-Newton steps onto the constraints at phase-2 start
  double constraint_damping{1e-6};  ///< relative damping of C Sigma C^T
  /// How phase 2 is initialised from phase 1's result, always projected onto the constraints:
  /// "phase1" (the trajectory itself, as the paper says), "tangent" (phase 1's path driven forwards
  /// or in reverse with the heading along it, turning in place at both ends), or "best" (these
  /// three and phase 1's path bent to leave and reach the ends along the start and goal headings,
  /// forwards or in reverse). Candidates are tried in order of cost, up to phase2_attempts.
  std::string phase2_initialization{"best"};
  int phase2_attempts{7};  ///< phase-2 runs from different candidates before giving up
  bool check_reachability{true};   ///< reject goals the footprint's inscribed disc cannot reach
  double reachability_cell{0.1};   ///< grid cell size of the reachability check [m]
  int num_threads{0};              ///< threads for the rollouts; 0 = oneTBB default, 1 = serial
  StompPhaseOptions phase1{60, 3, 0.4, 0.4, 0.95, 0.1, true, 0, 1.0};    ///< ignores the non-holonomic constraint
  StompPhaseOptions phase2{80, 5, 0.15, 0.25, 0.95, 0.1, true, 0, 0.01};  ///< enforces it

  /// Read a `base_planner` YAML section; fields not named keep their defaults.
  static StompPlannerOptions FromConfig(const ConfigNode& node);
  /// False (and why) if an option is out of range.
  bool IsValid(std::string* why) const;
};

enum class PlanStatus {
  kSuccess,             ///< collision-free trajectory without sideways motion
  kStartInCollision,    ///< the start pose overlaps an obstacle or leaves the boundary
  kGoalOutsideBoundary,  ///< the goal's footprint leaves the site boundary
  kGoalInCollision,     ///< the goal's footprint overlaps an obstacle
  kUnreachable,         ///< no path exists for the footprint's inscribed disc
  kNotConverged,        ///< STOMP found no valid trajectory within its iterations
};
const char* PlanStatusName(PlanStatus s);

/// Summary of a planning run (Ceres-style) plus the trajectory.
struct PlanResult {
  PlanStatus status{PlanStatus::kNotConverged};
  std::string message;
  int iterations{0};          ///< phase 1 + phase 2
  int phase1_iterations{0};
  int phase2_iterations{0};
  double cost{0.0};           ///< final STOMP cost
  double seconds{0.0};        ///< wall time of Plan()
  double phase1_clearance{0.0};  ///< clearance of phase 1's (holonomic) trajectory [m]
  double min_clearance{0.0};  ///< footprint clearance along the densely checked trajectory [m]
  double max_lateral_velocity{0.0};  ///< worst sideways speed at the nominal timing [m/s]
  double max_constraint_violation{0.0};  ///< worst sideways displacement per time step [m]
  double max_track_speed{0.0};  ///< worst nominal track speed [m/s]
  /// The planned trajectory; when not usable, the best attempt (for diagnostics; never execute
  /// it), empty if planning did not start.
  BaseTrajectory trajectory;
  BaseTrajectory phase1_trajectory;  ///< phase 1's holonomic result (diagnostics)

  bool IsUsable() const { return status == PlanStatus::kSuccess; }
  std::string BriefReport() const;
};

/// The planner: an immutable model (scene, robot, STOMP matrices, reachability grid). Plan() is
/// const and may be called from several threads.
class StompBasePlanner {
 public:
  StompBasePlanner(PlanningScene scene, BaseGeometry robot, StompPlannerOptions options = {});
  ~StompBasePlanner();
  StompBasePlanner(StompBasePlanner&&) noexcept;

  /// Plan from T_site_start to T_site_goal; rng seeds the rollouts (not advanced).
  PlanResult Plan(const Pose2& T_site_start, const Pose2& T_site_goal, const RandomStream& rng) const;

  /// Movement duration estimated before planning from the Euclidean distance, the heading
  /// difference and the admissible track speed (paper Sec. III-A).
  double EstimateDuration(const Pose2& T_site_start, const Pose2& T_site_goal) const;

  const FootprintChecker& checker() const { return checker_; }
  const StompPlannerOptions& options() const { return options_; }

  /// Per-point cost of a full trajectory (N+2 rows): smoothness + obstacle terms. Public for tests.
  void PointCosts(const TrajectoryMatrix& q, Eigen::VectorXd* per_point) const;
  /// Minimum footprint clearance along q, checked at most collision_check_step apart.
  double DenseClearance(const TrajectoryMatrix& q) const;
  /// True if the footprint keeps `clearance` along q (same sampling, culled, faster).
  bool DenseCollisionFree(const TrajectoryMatrix& q, double clearance) const;

 private:
  struct Workspace;
  int RunPhase(int phase, TrajectoryMatrix* q, const RandomStream& rng, Workspace* ws,
               double* final_cost) const;
  bool IsReachable(const Pose2& start, const Pose2& goal) const;
  TrajectoryMatrix TangentInitialization(const TrajectoryMatrix& phase1, double theta_start,
                                         double theta_goal, bool reverse) const;
  TrajectoryMatrix AlignedInitialization(const TrajectoryMatrix& phase1, double theta_start, double theta_goal,
                                         int sign_start, int sign_goal) const;
  // Gauss-Newton steps (with backtracking) until the worst residual is below target [m].
  bool ProjectOntoConstraints(TrajectoryMatrix* q, Workspace* ws, int steps, double target) const;
  BaseTrajectory ToBaseTrajectory(const TrajectoryMatrix& q, double duration, double* max_lateral,
                                  double* max_track) const;
  // True if the footprint at p is provably at least `margin` from the boundary's edges (inside it)
  // and from every obstacle, from the point clearance field alone; false if that cannot be shown.
  bool ProvablyClear(const Pose2& p, double c, double s, double margin) const;
  // checker_.Cost, skipped (it is exactly zero) where ProvablyClear holds.
  double ObstacleCost(const Pose2& p, double margin, double collision_penalty) const;

  StompPlannerOptions options_;
  FootprintChecker checker_;
  int n_{0};                // free time steps
  Eigen::MatrixXd S_;       // R^-1 normalised to a maximum of 1 (noise shape)
  Eigen::MatrixXd L_;       // Cholesky factor of S_
  Eigen::MatrixXd M_;       // R^-1 with columns scaled to a maximum of 1/N
  // Reachability grid for the inscribed disc.
  Eigen::Vector2d grid_origin_{0, 0};
  int grid_nx_{0}, grid_ny_{0};
  std::vector<int> grid_label_;  // connected component per cell, -1 = blocked
  // Signed point clearance (FootprintChecker::PointClearance) at each grid node, and the discs
  // that cover the footprint (centres in the base frame, common radius): a cheap lower bound on
  // the footprint's clearance that lets most obstacle costs be skipped.
  std::vector<double> grid_clearance_;
  std::vector<Eigen::Vector2d> cover_centres_;
  double cover_radius_{0.0};
};

}  // namespace ifab::base
