#include "ifab/base/estimator/base_state_estimator.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "ifab/base/estimator/association.h"
#include "ifab/base/estimator/degeneracy.h"
#include "ifab/base/estimator/eq3_solver.h"
#include "ifab/base/estimator/gyro_buffer.h"
#include "ifab/base/estimator/keyframe_map.h"
#include "ifab/base/estimator/match_quality.h"
#include "ifab/base/estimator/scan_preprocessing.h"
#include "ifab/core/angles.h"
#include "ifab/core/error.h"

namespace ifab::base {

// The estimator's state and its parts (one file each): preprocessing, the reference set, the
// association, the solve and the quality check. AddScan below strings them together.
struct BaseStateEstimator::Impl {
  Impl(const EstimatorOptions& options, const Pose2& T_base_laser)
      : o(options),
        num_levels(NumLevels(options)),
        points(options, T_base_laser),
        map(options),
        scan(options),
        solver(options),
        gate(options.gate_probability),
        window(options),
        prior_scale(options) {
    residual_var.assign(static_cast<std::size_t>(num_levels), -1.0);
  }

  const EstimatorOptions& o;
  int num_levels{1};

  // State.
  bool initialized{false};
  Pose2 pose;  // T_world_base at t_last
  Seconds t_last{0.0};
  Eigen::Vector3d velocity{Eigen::Vector3d::Zero()};  // world vx, vy, omega
  bool have_velocity{false};
  int consecutive_failures{0};
  // Covariance of the pose relative to the reference set (world frame): the last match's, grown
  // by the prior's step covariance over flagged scans. Propagates the odometry factor's prior.
  Eigen::Matrix3d pose_cov{Eigen::Matrix3d::Zero()};
  // Per sigma level: the scan terms' residual variance per row at the last accepted solution,
  // which converts the scan's cost-unit Hessian to physical information (and back for the
  // prior). Negative: not known yet.
  std::vector<double> residual_var;

  // The parts.
  GyroBuffer gyro;           // eq. 2's samples
  ScanPreprocessor points;   // range filter, deskew, thinning, reference sampling
  KeyframeMap map;           // the reference set
  Association scan;          // eq. 1's pairs and sums
  Eq3Solver solver;          // eq. 3
  GateTable gate;            // quality check: the Mahalanobis gate's thresholds
  WindowGate window;         // quality check: the window gate
  PriorScale prior_scale;    // the motion covariance's identified scale
};

// ---------------------------------------------------------------------------------------------
// Public API

BaseStateEstimator::BaseStateEstimator(const EstimatorOptions& options, const Pose2& T_base_laser)
    : options_(options), T_base_laser_(T_base_laser) {
  const std::string problem = options_.Validate();
  IFAB_THROW_UNLESS(problem.empty(), "EstimatorOptions: {}", problem);
  impl_ = std::make_unique<Impl>(options_, T_base_laser_);
}

BaseStateEstimator::~BaseStateEstimator() = default;

int BaseStateEstimator::NumReferenceScans() const { return impl_->map.NumActive(); }

void BaseStateEstimator::Reset(const Pose2& T_world_base, Seconds t, bool keep_references) {
  Impl& m = *impl_;
  if (keep_references && m.initialized) {
    // Move the reference set rigidly with the correction T_new * T_old^-1.
    const Pose2 correction = T_world_base * m.pose.inverse();
    m.map.MoveRigidly(correction);
    m.velocity.head<2>() = (correction.rotation() * m.velocity.head<2>()).eval();
  } else {
    m.map.Clear();
    m.velocity.setZero();
    m.have_velocity = false;
  }
  m.consecutive_failures = 0;
  m.pose = T_world_base;
  m.pose_cov.setZero();
  m.window.Clear();
  m.t_last = t;
  m.initialized = true;
  m.gyro.DropUntil(t - 1e-9);
  latest_ = BaseEstimate{};
  latest_.t = t;
  latest_.T_world_base = T_world_base;
  latest_.status = EstimateStatus::kReference;
}

void BaseStateEstimator::AddGyro(const GyroSample& sample) {
  Impl& m = *impl_;
  if (!m.gyro.Empty()) {
    IFAB_THROW_UNLESS(sample.stamp.t >= m.gyro.BackTime(),
                      "gyro sample at t = {} s is older than the previous one ({} s)",
                      sample.stamp.t, m.gyro.BackTime());
  }
  m.gyro.Push(sample.stamp.t, sample.rate.z());
}


const BaseEstimate& BaseStateEstimator::AddScan(const LaserScan& scan,
                                                const std::optional<MotionMeasurement>& motion) {
  Impl& m = *impl_;
  const EstimatorOptions& o = options_;
  IFAB_THROW_UNLESS(static_cast<int>(scan.size()) <= o.max_beams,
                    "laser scan has {} beams, more than max_beams = {} the estimator was sized for",
                    scan.size(), o.max_beams);
  const Seconds t = scan.MidTime();
  if (!m.initialized) Reset(Pose2(), t);
  IFAB_THROW_UNLESS(t >= m.t_last - 1e-9,
                    "laser scan at t = {} s is older than the previous one ({} s)", t, m.t_last);

  BaseEstimate& e = latest_;
  e = BaseEstimate{};
  e.t = t;
  const double dt = t - m.t_last;

  // Gyro rotation since the previous scan (eq. 2's sum of omega_i dt).
  double dtheta_gyro = 0.0;
  e.gyro_used = o.gyro_weight > 0.0 && m.gyro.Integrate(m.t_last, t, &dtheta_gyro);
  m.gyro.DropUntil(t);

  // The base's twist during the sweep (improvement, off for the paper's rigid scan): the turn
  // rate from the gyro since the previous scan (else the motion's or the last estimate's), the
  // velocity from the motion or the last estimate, in the base frame.
  Eigen::Vector2d v_base = Eigen::Vector2d::Zero();
  double omega = 0.0;
  if (o.deskew && dt > 1e-6) {
    if (motion) {
      v_base = motion->step.translation() / dt;
      omega = motion->step.theta / dt;
    } else if (m.have_velocity) {
      v_base = m.pose.rotation().transpose() * m.velocity.head<2>();
      omega = m.velocity.z();
    }
    if (e.gyro_used) omega = dtheta_gyro / dt;
  }
  m.points.Extract(scan, v_base, omega);

  // Prediction: gyro rotation (else the motion's or the last turn rate), translation from the
  // motion or the motion prior. With a motion covariance the prediction is an informative
  // prior: the pose's covariance propagated through the step plus the step's own.
  Pose2 predicted = m.pose;
  const bool cv = o.motion_prior == MotionPrior::kConstantVelocity && m.have_velocity;
  if (motion) {
    predicted = m.pose * motion->step;
  } else if (cv) {
    predicted.x += m.velocity.x() * dt;
    predicted.y += m.velocity.y() * dt;
    predicted.theta = WrapAngle(m.pose.theta + m.velocity.z() * dt);
  }
  if (e.gyro_used) predicted.theta = WrapAngle(m.pose.theta + dtheta_gyro);
  const bool informative = motion && motion->HasCovariance();
  Eigen::Matrix3d prior_cov = Eigen::Matrix3d::Zero();
  if (informative) {
    // d(T_prev * step) / d(prev) = [I, perp(R_prev t_step); 0, 1].
    const Eigen::Vector2d arm = m.pose.rotation() * motion->step.translation();
    Eigen::Matrix3d J = Eigen::Matrix3d::Identity();
    J(0, 2) = -arm.y();
    J(1, 2) = arm.x();
    prior_cov = J * m.pose_cov * J.transpose() +
                m.prior_scale.scale() * StepCovarianceInWorld(m.pose, motion->covariance);
  }
  e.prior_used = informative;
  m.window.Push(m.pose, m.pose_cov, m.initialized, informative, informative ? &*motion : nullptr);

  auto finish_failed = [&](EstimateStatus status) -> const BaseEstimate& {
    e.status = status;
    e.T_world_base = predicted;
    if (informative) {
      e.covariance = prior_cov;
    } else {
      // The prediction's uncertainty: a generous guess (the match gave nothing).
      const double s_t = o.max_translation_jump, s_r = DegToRad(o.max_rotation_jump_deg);
      e.covariance = Eigen::Vector3d(s_t * s_t, s_t * s_t, s_r * s_r).asDiagonal();
    }
    m.pose = predicted;
    m.pose_cov = informative ? prior_cov : Eigen::Matrix3d::Zero();
    m.t_last = t;
    // After several scans in a row without overlap the references are too far behind to
    // recover from: restart the reference set from this scan at the prior's pose (the status
    // stays flagged; the keyframe's pose is the prior's, not a match's).
    if (status == EstimateStatus::kTooFewPoints) {
      if (o.reseed_after_failures > 0 && ++m.consecutive_failures >= o.reseed_after_failures &&
          static_cast<int>(m.points.valid().size()) >= o.min_points) {
        m.map.Clear();
        m.map.Add(predicted, t, &m.points);
        e.keyframe_added = true;
        m.consecutive_failures = 0;
      }
    }
    return e;
  };

  // The first scan after a reset only becomes the reference.
  if (m.map.NumActive() == 0) {
    e.status = EstimateStatus::kReference;
    e.T_world_base = m.pose;
    e.covariance.setZero();
    e.num_points = static_cast<int>(m.points.valid().size());
    if (e.num_points >= o.min_points) {
      m.map.Add(m.pose, t, &m.points);
      e.keyframe_added = true;
    } else {
      e.status = EstimateStatus::kTooFewPoints;
    }
    m.t_last = t;
    return e;
  }
  if (static_cast<int>(m.points.valid().size()) < o.min_points) {
    e.num_points = static_cast<int>(m.points.valid().size());
    return finish_failed(EstimateStatus::kTooFewPoints);
  }

  // Eq. 3 by levels of sigma (coarse to fine when configured), re-associating in each.
  m.map.Select(predicted);
  Eq3Problem problem;
  problem.x_pred = Eigen::Vector3d(predicted.x, predicted.y, predicted.theta);
  problem.use_gyro = e.gyro_used;
  problem.informative = informative;
  if (informative) problem.info_prior = prior_cov.inverse();
  const Eigen::Vector3d& x_pred = problem.x_pred;
  const Eigen::Matrix3d& info_prior = problem.info_prior;
  const int fine = m.num_levels - 1;
  const Eq3Result solution = m.solver.Solve(problem, &m.points, m.map, &m.scan, &m.residual_var);
  e.iterations = solution.iterations;
  if (solution.failed) return finish_failed(EstimateStatus::kSolverFailed);
  const Eigen::Vector3d& x = solution.x;
  const bool pairs_current = solution.pairs_current;  // the pairs were made at (about) the final pose
  Pose2 solved(x[0], x[1], x[2]);
  e.num_points = static_cast<int>(m.scan.meas_base.size());

  // Quality at the solution, with a fresh association at the finest level unless the last
  // round's pairs were made at (about) this pose already.
  const double sigma = o.sigma;
  e.matched_fraction = pairs_current
                           ? m.scan.MatchedFraction()
                           : m.scan.Associate(m.map, solved, fine, o.search_radius_sigmas * std::sqrt(2.0) * sigma);
  if (m.scan.Empty() || e.matched_fraction < o.min_matched_fraction) {
    return finish_failed(EstimateStatus::kTooFewPoints);
  }
  e.inlier_fraction = m.scan.InlierFraction(solved, sigma);
  if (e.inlier_fraction < o.min_inlier_fraction) return finish_failed(EstimateStatus::kPoorScore);
  e.score = m.scan.Score(solved, sigma);
  NormalEquations ne = m.scan.Accumulate(solved, sigma);
  // The scan's residual variance per row: covariance = H^-1 * variance (the usual estimate of
  // a least-squares fit's covariance); the scan's physical information is H / variance.
  const double residual_var = std::max(ne.sum_sq / std::max(1, ne.rows - 3), 1e-12);
  e.gyro_error_rad = e.gyro_used ? WrapAngle(solved.theta - predicted.theta) : 0.0;
  if (e.gyro_used) ne.H(2, 2) += o.gyro_weight;
  e.cost = 0.5 * (ne.sum_sq + (e.gyro_used ? o.gyro_weight * e.gyro_error_rad * e.gyro_error_rad : 0.0));
  const double lever = m.scan.Lever();
  Eigen::Matrix3d info_scan = ne.H / residual_var;
  if (informative && o.structure_degeneracy_ratio > 0.0) {
    // Directions the structure leaves (nearly) unconstrained carry no information whatever the
    // kernel sum's curvature says: remove them, so the analysis below hands them to the prior.
    info_scan = StructureTrustedInformation(info_scan, m.scan.StructureInformation(solved), lever,
                                            o.structure_degeneracy_ratio);
  }

  if (informative) {
    // Degenerate directions against the prior; the gate over the others (degeneracy.h).
    const DegeneracyAnalysis deg = AnalyseDegeneracy(info_scan, &info_prior, lever, o.degeneracy_ratio);
    e.degeneracy = deg.ratio;
    e.num_degenerate = deg.num_degenerate;
    e.degenerate_directions = deg.directions;
    Eigen::Vector3d dx = x - x_pred;
    dx[2] = WrapAngle(dx[2]);
    e.mahalanobis_sq = InnovationMahalanobisSq(deg, info_prior, dx, &e.gate_dof);
    m.prior_scale.Add(e.mahalanobis_sq, e.gate_dof, m.gate.median);
    if (o.gate_translation_only) {
      e.mahalanobis_sq = InnovationTranslationMahalanobisSq(deg, info_prior, dx, &e.gate_dof);
    }
    if (e.gate_dof > 0 && e.mahalanobis_sq > m.gate.quantile[static_cast<std::size_t>(e.gate_dof)]) {
      return finish_failed(EstimateStatus::kUnexplainedJump);
    }
    if (o.remap_degenerate && deg.num_degenerate > 0) {
      const Eigen::Vector3d dx_remapped = RemapDegenerate(deg, info_prior, dx);
      solved = Pose2(x_pred[0] + dx_remapped[0], x_pred[1] + dx_remapped[1],
                     WrapAngle(x_pred[2] + dx_remapped[2]));
    }
    e.covariance = (deg.info_scan_trusted + info_prior).inverse();
    if (o.window_gate_probability > 0.0) {
      // Translation only: the chained heading carries the odometry's turn lag.
      e.window_mahalanobis_sq = m.window.MahalanobisSq(solved, e.covariance);
      if (e.window_mahalanobis_sq > m.window.threshold()) {
        return finish_failed(EstimateStatus::kUnexplainedJump);
      }
    }
    m.residual_var[static_cast<std::size_t>(fine)] = residual_var;
  } else {
    const DegeneracyAnalysis deg = AnalyseDegeneracy(info_scan, nullptr, lever, o.degeneracy_ratio);
    e.degeneracy = deg.ratio;
    e.num_degenerate = deg.num_degenerate;
    e.degenerate_directions = deg.directions;
    e.covariance = (ne.H + 1e-9 * Eigen::Matrix3d::Identity()).inverse() * residual_var;
    // A jump the gyro or the motion does not explain.
    const bool rotation_jump =
        e.gyro_used && std::abs(e.gyro_error_rad) > DegToRad(o.max_rotation_jump_deg);
    const bool translation_jump =
        (solved.translation() - predicted.translation()).norm() > o.max_translation_jump;
    if (rotation_jump || translation_jump) return finish_failed(EstimateStatus::kUnexplainedJump);
  }

  e.status = e.num_degenerate > 0 ? EstimateStatus::kDegenerate : EstimateStatus::kOk;
  e.T_world_base = solved;
  m.consecutive_failures = 0;
  m.pose_cov = informative ? e.covariance : Eigen::Matrix3d::Zero();

  // Velocity for the next prediction.
  if (dt > 1e-6) {
    m.velocity = Eigen::Vector3d((solved.x - m.pose.x) / dt, (solved.y - m.pose.y) / dt,
                                 WrapAngle(solved.theta - m.pose.theta) / dt);
    m.have_velocity = true;
  }
  m.pose = solved;
  m.t_last = t;

  // Reference set: a new keyframe when no kept one is within the keyframe spacing.
  if (m.map.NeedsKeyframe(solved, t)) {
    m.map.Add(solved, t, &m.points);
    e.keyframe_added = true;
  }
  m.map.DropOld(t);
  return e;
}

}  // namespace ifab::base
