#include "ifab/base/estimator/base_state_estimator.h"

#include <ceres/tiny_solver.h>
#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <nanoflann.hpp>
#include <boost/math/distributions/chi_squared.hpp>

#include "ifab/base/estimator/degeneracy.h"
#include "ifab/base/estimator/kernel_residual.h"
#include "ifab/core/angles.h"
#include "ifab/core/error.h"

namespace ifab::base {

// ---------------------------------------------------------------------------------------------
// Internals

namespace {

// nanoflann adaptor over a vector of 2D points.
struct PointSet {
  std::vector<Eigen::Vector2d> points;
  std::size_t kdtree_get_point_count() const { return points.size(); }
  double kdtree_get_pt(std::size_t i, std::size_t d) const { return points[i][static_cast<int>(d)]; }
  template <class BBox>
  bool kdtree_get_bbox(BBox& /*bb*/) const {
    return false;
  }
};

using KdTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, PointSet>,
                                                   PointSet, 2, std::uint32_t>;

// k nearest neighbours within a radius, into caller-owned arrays (no allocation).
class RadiusKnnResultSet {
 public:
  using DistanceType = double;
  using IndexType = std::uint32_t;
  RadiusKnnResultSet(int capacity, double radius_sq, IndexType* indices, double* dists)
      : capacity_(capacity), radius_sq_(radius_sq), indices_(indices), dists_(dists) {}
  std::size_t size() const { return static_cast<std::size_t>(count_); }
  bool full() const { return count_ == capacity_; }
  bool addPoint(double dist, IndexType index) {
    if (dist >= radius_sq_) return true;
    int i = count_;
    for (; i > 0 && dists_[i - 1] > dist; --i) {
      if (i < capacity_) {
        dists_[i] = dists_[i - 1];
        indices_[i] = indices_[i - 1];
      }
    }
    if (i < capacity_) {
      dists_[i] = dist;
      indices_[i] = index;
    }
    if (count_ < capacity_) ++count_;
    return true;
  }
  double worstDist() const { return full() ? dists_[capacity_ - 1] : radius_sq_; }

 private:
  int capacity_;
  double radius_sq_;
  IndexType* indices_;
  double* dists_;
  int count_{0};
};

// One resolution of a keyframe's points (one per sigma level, coarse levels sparser).
struct ReferenceLevel {
  PointSet cloud;                        // points in the keyframe's base frame
  std::vector<Eigen::Vector2d> normals;  // unit normals (point-to-line only), zero if none
  std::vector<char> near_end;            // within the end margin of its chain's end
  std::vector<double> weight;            // arc-length weight (1 unless weighting is on)
  std::unique_ptr<KdTree> tree;
};

struct Keyframe {
  bool active{false};
  bool selected{false};    // in this scan's reference set
  std::uint64_t order{0};  // insertion counter: larger is newer
  Seconds t{0.0};
  Pose2 T_world_base;
  std::vector<ReferenceLevel> levels;
};

struct Pair {
  int point{0};  // measurement point index
  double weight{1.0};  // the reference point's weight
  Eigen::Vector2d p_ref_world;
  Eigen::Vector2d n_world;  // zero for kernel pairs
};

// Sums over all terms of eq. 3 at one pose, in least-squares form (cost = |r|^2 / 2): the
// (positive semi-definite) Hessian H, the gradient g = J^T r of the cost, and |r|^2.
struct NormalEquations {
  Eigen::Matrix3d H{Eigen::Matrix3d::Zero()};
  Eigen::Vector3d g{Eigen::Vector3d::Zero()};
  double sum_sq{0.0};
  int rows{0};
};

}  // namespace

struct BaseStateEstimator::Impl {
  const EstimatorOptions& o;
  Pose2 T_base_laser;
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
  std::array<double, 4> gate_chi2{};  // chi-square quantile of gate_probability by dof
  std::array<double, 4> chi2_median{};  // chi-square median by dof
  // The window gate (window_gate_probability): the last scans' final poses and covariances
  // with the motion step that led to each, in a fixed ring (no allocation per scan).
  struct WindowEntry {
    Pose2 pose;
    Eigen::Matrix3d cov;
    Pose2 step;  // from the previous entry's pose
    Eigen::Matrix3d step_cov;
  };
  static constexpr std::size_t kWindowCapacity = 256;
  std::vector<WindowEntry> window_ring;
  std::size_t window_count{0}, window_head{0};  // head: the slot the next entry goes to
  bool have_last_step{false};
  Pose2 last_step;
  Eigen::Matrix3d last_step_cov{Eigen::Matrix3d::Zero()};
  double window_chi2{std::numeric_limits<double>::infinity()};
  const WindowEntry& WindowBack(std::size_t i) const {  // i = 0: the newest
    return window_ring[(window_head + kWindowCapacity - 1 - i) % kWindowCapacity];
  }
  // Before each scan: the previous scan's outcome joins the ring (with an informative step only;
  // a scan without one breaks the chain).
  void PushWindow(bool informative, const MotionMeasurement* motion) {
    if (o.window_gate_probability <= 0.0) return;
    if (have_last_step) {
      window_ring[window_head] = WindowEntry{pose, pose_cov, last_step, last_step_cov};
      window_head = (window_head + 1) % kWindowCapacity;
      window_count = std::min(window_count + 1, kWindowCapacity);
    } else if (initialized) {
      window_ring[window_head] = WindowEntry{pose, pose_cov, Pose2(), Eigen::Matrix3d::Zero()};
      window_head = (window_head + 1) % kWindowCapacity;
      window_count = 1;
    }
    if (!informative) window_count = 0;
    have_last_step = informative;
    if (informative) {
      last_step = motion->step;
      last_step_cov = motion->covariance;
    }
  }
  // The squared Mahalanobis distance (translation) of a pose for the current scan from the
  // pose window_gate_distance of odometry travel back (or the chain's start) chained with the
  // steps since; -1 without a chain.
  double WindowMahalanobisSq(const Pose2& solved, const Eigen::Matrix3d& cov_solved) const {
    if (!have_last_step || window_count < 1) return -1.0;
    // Back to window_gate_distance of travel, or to the chain's start when it is shorter.
    double travel = last_step.translation().norm();
    std::size_t back = 0;  // the span starts at WindowBack(back)
    while (travel < o.window_gate_distance && back + 1 < window_count) {
      travel += WindowBack(back).step.translation().norm();
      ++back;
    }
    // Compound from the span's start: its pose and covariance, then each step's.
    const WindowEntry& start = WindowBack(back);
    Pose2 T = start.pose;
    Eigen::Matrix3d C = start.cov;
    auto compound = [&](const Pose2& step, const Eigen::Matrix3d& step_cov) {
      const Eigen::Vector2d arm = T.rotation() * step.translation();
      Eigen::Matrix3d J = Eigen::Matrix3d::Identity();
      J(0, 2) = -arm.y();
      J(1, 2) = arm.x();
      C = J * C * J.transpose() + StepCovarianceInWorld(T, step_cov);
      T = T * step;
    };
    for (std::size_t i = back; i-- > 0;) compound(WindowBack(i).step, WindowBack(i).step_cov);
    compound(last_step, last_step_cov);
    const Eigen::Vector2d d = solved.translation() - T.translation();
    const Eigen::Matrix2d S = (C + cov_solved).topLeftCorner<2, 2>();
    return d.dot(S.ldlt().solve(d));
  }

  // The identified scale of the motion covariance (see prior_scale_window): a ring of the
  // normalised innovations and a scratch copy for the median.
  double prior_scale{1.0};
  std::vector<double> nis_ring, nis_scratch;
  std::size_t nis_next{0};
  void AddInnovation(double m2, int dof) {
    if (o.prior_scale_window <= 0 || dof <= 0) return;
    const double r = m2 * prior_scale / chi2_median[static_cast<std::size_t>(dof)];
    if (nis_ring.size() < static_cast<std::size_t>(o.prior_scale_window)) {
      nis_ring.push_back(r);
    } else {
      nis_ring[nis_next] = r;
      nis_next = (nis_next + 1) % nis_ring.size();
    }
    nis_scratch.assign(nis_ring.begin(), nis_ring.end());
    auto mid = nis_scratch.begin() + static_cast<std::ptrdiff_t>(nis_scratch.size() / 2);
    std::nth_element(nis_scratch.begin(), mid, nis_scratch.end());
    // Start from the given model until a tenth of the window is in.
    if (nis_ring.size() * 10 >= static_cast<std::size_t>(o.prior_scale_window)) {
      prior_scale = std::max(1.0, *mid);
    }
  }
  std::uint64_t keyframe_counter{0};
  std::vector<std::unique_ptr<Keyframe>> keyframes;

  // Gyro FIFO (head index into a reserved vector; compacted in place).
  std::vector<Stamped<double>> gyro;
  std::size_t gyro_head{0};
  Seconds gyro_prev_t{-std::numeric_limits<double>::infinity()};  // last dropped sample's time

  // Per-scan buffers (reserved once).
  std::vector<Eigen::Vector2d> valid_base;  // every valid beam endpoint, base frame
  std::vector<double> valid_gap;            // distance to the nearer neighbour along the scan
  std::vector<double> chain_before, chain_after;  // arc length to the chain's ends (scratch)
  std::vector<Eigen::Vector2d> meas_base;   // thinned measurement points of the current level
  std::vector<Pair> pairs;        // grouped by measurement point
  std::vector<int> pair_begin;    // pairs of point i: [pair_begin[i], pair_begin[i + 1])
  std::vector<std::uint32_t> knn_index;
  std::vector<double> knn_dist;

  // Eq. 3 for Ceres' TinySolver. The functor sums the Hessian H (see PointKernelSum), the
  // gradient g and the cost |r|^2 over all pairs and the gyro term, and hands the solver an
  // equivalent 4-row system:
  //   J~ = [L^T; 0],  r~ = [L^-1 g; sqrt(|r|^2 - |L^-1 g|^2)],  H = L L^T,
  // so that J~^T J~ = H, J~^T r~ = g and |r~|^2 = |r|^2: the solver takes exactly the
  // Levenberg-Marquardt steps and cost decisions it would take on the full problem, without
  // storing a residual per pair (fixed size: no allocation, no padding).
  struct Eq3 {
    using Scalar = double;
    enum { NUM_RESIDUALS = 4, NUM_PARAMETERS = 3 };
    const Impl* impl{nullptr};
    double sigma{0.05};
    bool use_gyro{false};
    double gyro_weight{0.0};
    double theta_gyro{0.0};
    Eigen::Vector3d x0{Eigen::Vector3d::Zero()};  // the solver's x is the increment about x0
    Eigen::Vector3d x_pred{Eigen::Vector3d::Zero()};  // the predicted pose (weak prior's anchor)
    double prior_weight{0.0};
    double prior_lever{1.0};
    // The odometry factor (an informative prior): the weight matrix in cost units, replacing
    // the weak prior_weight pull.
    bool prior_full{false};
    Eigen::Matrix3d prior_W{Eigen::Matrix3d::Zero()};
    bool operator()(const double* x, double* residuals, double* jacobian) const;
  } eq3;
  ceres::TinySolver<Eq3> solver;

  explicit Impl(const EstimatorOptions& options) : o(options) {
    num_levels = static_cast<int>(o.coarse_sigmas.size()) + 1;
    const auto beams = static_cast<std::size_t>(o.max_beams);
    const int capacity = std::max(o.num_reference_scans, o.keyframe_capacity);
    keyframes.reserve(static_cast<std::size_t>(capacity));
    for (int k = 0; k < capacity; ++k) {
      auto kf = std::make_unique<Keyframe>();
      kf->levels.resize(static_cast<std::size_t>(num_levels));
      for (auto& level : kf->levels) {
        level.cloud.points.reserve(beams);
        level.normals.reserve(beams);
        level.near_end.reserve(beams);
        level.weight.reserve(beams);
        level.tree = std::make_unique<KdTree>(
            2, level.cloud,
            nanoflann::KDTreeSingleIndexAdaptorParams(
                10, nanoflann::KDTreeSingleIndexAdaptorFlags::SkipInitialBuildIndex));
      }
      keyframes.push_back(std::move(kf));
    }
    gyro.reserve(8192);
    valid_base.reserve(beams);
    valid_gap.reserve(beams);
    chain_before.reserve(beams);
    chain_after.reserve(beams);
    meas_base.reserve(beams);
    const int k = o.neighbors_per_reference;
    pairs.reserve(static_cast<std::size_t>(o.max_points) *
                  static_cast<std::size_t>(o.num_reference_scans * k));
    pair_begin.reserve(beams + 1);
    kf_frames.reserve(static_cast<std::size_t>(capacity));
    candidates.reserve(static_cast<std::size_t>(capacity));
    knn_index.resize(static_cast<std::size_t>(k));
    knn_dist.resize(static_cast<std::size_t>(k));
    eq3.impl = this;
    residual_var.assign(static_cast<std::size_t>(num_levels), -1.0);
    nis_ring.reserve(static_cast<std::size_t>(o.prior_scale_window));
    nis_scratch.reserve(static_cast<std::size_t>(o.prior_scale_window));
    for (int dof = 1; dof <= 3; ++dof) {
      chi2_median[static_cast<std::size_t>(dof)] =
          boost::math::median(boost::math::chi_squared(dof));
      gate_chi2[static_cast<std::size_t>(dof)] =
          o.gate_probability > 0.0
              ? boost::math::quantile(boost::math::chi_squared(dof), o.gate_probability)
              : std::numeric_limits<double>::infinity();
    }
    if (o.window_gate_probability > 0.0) {
      window_ring.resize(kWindowCapacity);
      window_chi2 = boost::math::quantile(boost::math::chi_squared(2), o.window_gate_probability);
    }
    solver.options.max_num_iterations = o.max_iterations + 1;  // TinySolver counts from 1
    // Stop when a step is below 1e-4 of the increment so far (the increment is relative to the
    // round's start pose: ~10 um for a 0.1 m motion).
    solver.options.parameter_tolerance = 1e-3;
    solver.options.gradient_tolerance = 1e-10;
  }

  double LevelSigma(int level) const {
    return level + 1 < num_levels ? o.coarse_sigmas[static_cast<std::size_t>(level)] : o.sigma;
  }
  // Coarse levels keep points about sigma apart: the kernel sum over points that dense is as
  // smooth as over a continuous wall (ripple ~exp(-2 pi^2 (sqrt(2) sigma / spacing)^2)).
  double ReferenceSpacing(int level) const {
    return level + 1 < num_levels ? std::max(o.reference_point_spacing, LevelSigma(level))
                                  : o.reference_point_spacing;
  }
  double MeasurementSpacing(int level) const {
    return level + 1 < num_levels ? std::max(o.min_point_spacing, LevelSigma(level))
                                  : o.min_point_spacing;
  }

  int NumActiveKeyframes() const {
    int n = 0;
    for (const auto& kf : keyframes) n += kf->active ? 1 : 0;
    return n;
  }
  Keyframe* Newest() {
    Keyframe* best = nullptr;
    for (auto& kf : keyframes) {
      if (kf->active && (!best || kf->order > best->order)) best = kf.get();
    }
    return best;
  }

  // --- gyro -----------------------------------------------------------------------------------

  void PushGyro(Seconds t, double rate) {
    if (gyro.size() == gyro.capacity()) {
      // Full: move the live samples to the front (no reallocation), or drop the oldest half.
      if (gyro_head == 0) gyro_head = gyro.size() / 2;
      gyro_prev_t = gyro[gyro_head - 1].t;
      std::move(gyro.begin() + static_cast<std::ptrdiff_t>(gyro_head), gyro.end(), gyro.begin());
      gyro.resize(gyro.size() - gyro_head);
      gyro_head = 0;
    }
    gyro.push_back({t, rate});
  }

  // Integrated rotation over (ta, tb]; false if the samples do not cover the interval.
  bool IntegrateGyro(Seconds ta, Seconds tb, double* dtheta) const {
    constexpr double kNever = -std::numeric_limits<double>::infinity();
    *dtheta = 0.0;
    if (gyro.size() == gyro_head) return false;
    if (tb <= ta) return gyro.back().t >= tb;
    Seconds prev_t = gyro_prev_t;
    bool started = false;
    Seconds last_t = kNever;
    double last_rate = 0.0;
    for (std::size_t i = gyro_head; i < gyro.size(); ++i) {
      const Seconds ti = gyro[i].t;
      const double rate = gyro[i].value;
      if (ti > ta) {
        // The first sample after ta must reach back to ta (or be the first sample ever).
        if (!started && !(prev_t <= ta + 1e-9 || prev_t == kNever)) return false;
        started = true;
        const Seconds lo = prev_t == kNever ? ta : std::max(prev_t, ta);
        const Seconds hi = std::min(ti, tb);
        if (hi > lo) *dtheta += rate * (hi - lo);
      }
      last_t = ti;
      last_rate = rate;
      prev_t = ti;
      if (ti >= tb) break;
    }
    if (!started) return false;
    // A short gap at the end (the next sample not yet arrived) is bridged with the last rate.
    constexpr double kMaxExtrapolation = 0.05;
    if (last_t < tb) {
      if (tb - last_t > kMaxExtrapolation) return false;
      *dtheta += last_rate * (tb - std::max(last_t, ta));
    }
    return true;
  }

  // Forget samples no later than t, keeping the time of the last one for the next interval.
  void DropGyroUntil(Seconds t) {
    while (gyro_head < gyro.size() && gyro[gyro_head].t <= t) {
      gyro_prev_t = gyro[gyro_head].t;
      ++gyro_head;
    }
    if (gyro_head == gyro.size()) {
      gyro.clear();
      gyro_head = 0;
    }
  }

  // --- points ---------------------------------------------------------------------------------

  // Valid beam endpoints in the base frame. With a base twist (v_base [m/s] in the base frame,
  // omega [rad/s]) each beam is moved from the base pose at its own time to the pose at the
  // scan's middle time (constant twist over the sweep); a zero twist leaves the scan rigid.
  void ExtractPoints(const LaserScan& scan, const Eigen::Vector2d& v_base = Eigen::Vector2d::Zero(),
                     double omega = 0.0) {
    valid_base.clear();
    const double lo = std::max(o.min_range, scan.range_min);
    const double hi = std::min(o.max_range, scan.range_max);
    const bool deskew = scan.time_increment > 0.0 && (omega != 0.0 || v_base.squaredNorm() > 0.0);
    const double mid = 0.5 * static_cast<double>(scan.size() == 0 ? 0 : scan.size() - 1);
    for (std::size_t i = 0; i < scan.size(); ++i) {
      const double r = scan.ranges[i];
      if (!std::isfinite(r) || r < lo || r > hi) continue;
      const double a = scan.Angle(i);
      Eigen::Vector2d p = T_base_laser * Eigen::Vector2d(r * std::cos(a), r * std::sin(a));
      if (deskew) {
        // T_mid_i = exp(dt * twist); over a sweep (< 20 ms) the turn is < 0.01 rad, so the
        // rotation to second order and the translation to first are exact to ~1e-6 m.
        const double dt = (static_cast<double>(i) - mid) * scan.time_increment;
        const double th = omega * dt;
        const double c = 1.0 - 0.5 * th * th;
        p = Eigen::Vector2d(c * p.x() - th * p.y(), th * p.x() + c * p.y()) + dt * v_base;
      }
      valid_base.push_back(p);
    }
    // Distance of each point to its nearer neighbour along the scan (sampling density).
    valid_gap.resize(valid_base.size());
    for (std::size_t i = 0; i < valid_base.size(); ++i) {
      double g = std::numeric_limits<double>::infinity();
      if (i > 0) g = (valid_base[i] - valid_base[i - 1]).norm();
      if (i + 1 < valid_base.size()) g = std::min(g, (valid_base[i] - valid_base[i + 1]).norm());
      valid_gap[i] = g;
    }
  }

  // Keep points at least `spacing` apart in scan order (skipping points whose nearer scan
  // neighbour is farther than max_gap), then at most `max_out` (evenly). With `near_end`, also
  // flag the kept points lying within end_margin (along the scan) of the end of their chain:
  // a chain of points ends where consecutive points are more than max_gap apart (a depth jump,
  // an occlusion, sparse sampling) or at the scan's ends.
  void Thin(double spacing, double max_gap, int max_out, std::vector<Eigen::Vector2d>* out,
            double end_margin = 0.0, std::vector<char>* near_end = nullptr) {
    out->clear();
    if (near_end) {
      near_end->clear();
      // Arc length to the previous and to the next chain break.
      const std::size_t n = valid_base.size();
      chain_before.resize(n);
      chain_after.resize(n);
      for (std::size_t i = 0; i < n; ++i) {
        const double step = i > 0 ? (valid_base[i] - valid_base[i - 1]).norm() : 0.0;
        chain_before[i] = (i == 0 || step > max_gap) ? 0.0 : chain_before[i - 1] + step;
      }
      for (std::size_t i = n; i-- > 0;) {
        const double step = i + 1 < n ? (valid_base[i + 1] - valid_base[i]).norm() : 0.0;
        chain_after[i] = (i + 1 == n || step > max_gap) ? 0.0 : chain_after[i + 1] + step;
      }
    }
    const double s2 = spacing * spacing;
    const bool independent = o.thinning == Thinning::kNoiseIndependent;
    std::size_t prev = valid_base.size(), prev2 = valid_base.size();  // the last two candidates
    for (std::size_t i = 0; i < valid_base.size(); ++i) {
      const Eigen::Vector2d& p = valid_base[i];
      if (valid_gap[i] > max_gap) continue;
      bool keep = out->empty();
      if (!keep && !independent) {
        keep = (p - out->back()).squaredNorm() >= s2;
      } else if (!keep && prev < valid_base.size()) {
        // Decide from the earlier points only: the previous candidate's distance from the last
        // kept point plus one more step like the one before it reaches the spacing.
        const double step = prev2 < valid_base.size() ? (valid_base[prev] - valid_base[prev2]).norm() : 0.0;
        keep = (valid_base[prev] - out->back()).norm() + step >= spacing;
      }
      prev2 = prev;
      prev = i;
      if (keep) {
        out->push_back(p);
        if (near_end) near_end->push_back(std::min(chain_before[i], chain_after[i]) < end_margin);
      }
    }
    const int n = static_cast<int>(out->size());
    if (n > max_out) {
      for (int k = 0; k < max_out; ++k) {
        const auto from = static_cast<std::size_t>(static_cast<long>(k) * n / max_out);
        (*out)[static_cast<std::size_t>(k)] = (*out)[from];
        if (near_end) (*near_end)[static_cast<std::size_t>(k)] = (*near_end)[from];
      }
      out->resize(static_cast<std::size_t>(max_out));
      if (near_end) near_end->resize(static_cast<std::size_t>(max_out));
    }
  }

  // Normals of a reference level's points from the valid points around each (PCA within a
  // radius, walking along the scan); zero where the neighbourhood is not line-like.
  void ComputeNormals(ReferenceLevel* level, double radius) const {
    level->normals.clear();
    const double r2 = radius * radius;
    std::size_t cursor = 0;
    for (const auto& p : level->cloud.points) {
      // p is one of the valid points, in the same order: advance the cursor to it.
      while (cursor < valid_base.size() && (valid_base[cursor] - p).squaredNorm() > 1e-18) ++cursor;
      if (cursor >= valid_base.size()) cursor = 0;
      Eigen::Vector2d sum = Eigen::Vector2d::Zero();
      Eigen::Matrix2d second = Eigen::Matrix2d::Zero();
      int n = 0;
      auto add = [&](const Eigen::Vector2d& q) {
        sum += q;
        second += q * q.transpose();
        ++n;
      };
      for (std::size_t j = cursor; j < valid_base.size() && (valid_base[j] - p).squaredNorm() <= r2; ++j) {
        add(valid_base[j]);
      }
      for (std::size_t j = cursor; j-- > 0 && (valid_base[j] - p).squaredNorm() <= r2;) add(valid_base[j]);
      Eigen::Vector2d normal = Eigen::Vector2d::Zero();
      if (n >= 3) {
        const Eigen::Vector2d mean = sum / n;
        const Eigen::Matrix2d cov = second / n - mean * mean.transpose();
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(cov);
        if (es.eigenvalues()(0) < 0.1 * es.eigenvalues()(1)) normal = es.eigenvectors().col(0);
      }
      level->normals.push_back(normal);
    }
  }

  void AddKeyframe(const Pose2& T_world_base, Seconds t) {
    // Reuse an inactive slot, else the oldest.
    Keyframe* slot = nullptr;
    for (auto& kf : keyframes) {
      if (!kf->active) {
        slot = kf.get();
        break;
      }
    }
    if (!slot) {
      for (auto& kf : keyframes) {
        if (!slot || kf->order < slot->order) slot = kf.get();
      }
    }
    slot->active = true;
    slot->order = ++keyframe_counter;
    slot->t = t;
    slot->T_world_base = T_world_base;
    for (int l = 0; l < num_levels; ++l) {
      ReferenceLevel& level = slot->levels[static_cast<std::size_t>(l)];
      const double max_gap = o.max_reference_gap_sigmas > 0.0
                                 ? o.max_reference_gap_sigmas * LevelSigma(l)
                                 : std::numeric_limits<double>::infinity();
      if (o.interpolate_reference) {
        Densify(ReferenceSpacing(l), max_gap, o.end_margin_sigmas * o.sigma, &level);
      } else {
        Thin(ReferenceSpacing(l), max_gap, o.max_beams, &level.cloud.points,
             o.end_margin_sigmas * o.sigma, &level.near_end);
        ArcLengthWeights(level.cloud.points, ReferenceSpacing(l), max_gap, &level.weight);
        if (o.residual == MatchResidual::kPointToLine) {
          ComputeNormals(&level, std::max(3.0 * ReferenceSpacing(l), 2.0 * LevelSigma(l)));
        } else if (o.structure_degeneracy_ratio > 0.0) {
          ComputeNormals(&level, o.structure_normal_radius);
        } else {
          level.normals.clear();
        }
      }
      level.tree->buildIndex();
    }
  }

  // Weight of each reference point: the arc length it stands for (half the way to each
  // neighbour in its chain) over the nominal spacing; 1 everywhere unless weighting is on.
  void ArcLengthWeights(const std::vector<Eigen::Vector2d>& points, double spacing, double max_gap,
                        std::vector<double>* weight) const {
    weight->assign(points.size(), 1.0);
    if (o.reference_weighting != ReferenceWeighting::kArcLength) return;
    const double link = std::max(max_gap, 2.0 * spacing);
    for (std::size_t k = 0; k < points.size(); ++k) {
      double w = 0.0;
      for (int side : {-1, 1}) {
        const long j = static_cast<long>(k) + side;
        double half = 0.5 * spacing;
        if (j >= 0 && j < static_cast<long>(points.size())) {
          const double d = (points[static_cast<std::size_t>(j)] - points[k]).norm();
          if (d <= link) half = 0.5 * d;
        }
        w += half;
      }
      (*weight)[k] = w / spacing;
    }
  }

  // The reference as a polyline: consecutive valid points are linked when they are at most
  // max_link apart and the link is not nearly parallel to the beam (which is what a depth jump
  // looks like); each chain of links is sampled every `spacing`. Points on no link (isolated
  // returns) are dropped. Every sample then stands for the same length of surface, however
  // sparse the beams were (far walls, grazing incidence), so eq. 1's sum does not pull towards
  // where the reference happens to be dense nor stick to its sparse samples.
  void Densify(double spacing, double max_link, double end_margin, ReferenceLevel* level) {
    auto& pts = level->cloud.points;
    pts.clear();
    level->near_end.clear();
    level->normals.clear();
    level->weight.clear();
    const std::size_t n = valid_base.size();
    const Eigen::Vector2d origin = T_base_laser.translation();
    constexpr double kMinSinIncidence = 0.17;  // links within 10 deg of the beam are depth jumps
    auto linked = [&](std::size_t i) {  // i to i + 1
      const Eigen::Vector2d d = valid_base[i + 1] - valid_base[i];
      const double len = d.norm();
      if (len > max_link) return false;
      if (len < 1e-9) return true;
      const Eigen::Vector2d ray = (valid_base[i] - origin).normalized();
      return std::abs(ray.x() * d.y() - ray.y() * d.x()) / len >= kMinSinIncidence;
    };
    std::size_t i = 0;
    while (i + 1 < n) {
      if (!linked(i)) {
        ++i;
        continue;
      }
      // A chain from i to j (all links i..j-1 present).
      std::size_t j = i + 1;
      while (j + 1 < n && linked(j)) ++j;
      const std::size_t first = pts.size();
      chain_before.clear();  // arc position of each sample of this chain
      double arc = 0.0, next = 0.0;
      for (std::size_t k = i; k < j; ++k) {
        const Eigen::Vector2d a = valid_base[k], b = valid_base[k + 1];
        const double len = (b - a).norm();
        const Eigen::Vector2d dir = len > 0.0 ? Eigen::Vector2d((b - a) / len) : Eigen::Vector2d(1.0, 0.0);
        for (; next < arc + len; next += spacing) {
          pts.push_back(a + (next - arc) * dir);
          level->normals.emplace_back(-dir.y(), dir.x());
          level->weight.push_back(1.0);
          level->near_end.push_back(0);
          chain_before.push_back(next);
        }
        arc += len;
      }
      // The chain's last point, unless a sample is already close to it.
      if (arc - chain_before.back() > 0.5 * spacing) {
        pts.push_back(valid_base[j]);
        level->normals.push_back(level->normals.back());
        level->weight.push_back(1.0);
        level->near_end.push_back(0);
        chain_before.push_back(arc);
      }
      // Flag samples within end_margin of either end of the chain.
      for (std::size_t k = first; k < pts.size(); ++k) {
        const double from_start = chain_before[k - first];
        level->near_end[k] = (from_start < end_margin || arc - from_start < end_margin) ? 1 : 0;
      }
      i = j;
    }
  }

  // Distance used to pick keyframes: translation plus 1 m per radian of turn.
  static double KeyframeDistance(const Pose2& a, const Pose2& b) {
    const double dx = a.x - b.x, dy = a.y - b.y;
    return std::sqrt(dx * dx + dy * dy) + std::abs(std::remainder(a.theta - b.theta, 2.0 * kPi));
  }

  // The reference set for a scan at the predicted pose: every kept keyframe, or, when more are
  // kept than are matched, the num_reference_scans nearest to the pose.
  std::vector<std::pair<double, Keyframe*>> candidates;  // scratch, reserved
  void SelectReferences(const Pose2& T_world_base) {
    candidates.clear();
    for (auto& kf : keyframes) {
      kf->selected = false;
      if (kf->active) candidates.emplace_back(KeyframeDistance(kf->T_world_base, T_world_base), kf.get());
    }
    const auto n = std::min(candidates.size(), static_cast<std::size_t>(o.num_reference_scans));
    std::nth_element(candidates.begin(), candidates.begin() + static_cast<std::ptrdiff_t>(n) -
                                             (n > 0 ? 1 : 0),
                     candidates.end());
    for (std::size_t k = 0; k < n; ++k) candidates[k].second->selected = true;
  }

  // True if no kept keyframe is within the keyframe spacing of the pose.
  bool NeedsKeyframe(const Pose2& T_world_base, Seconds t) {
    const Keyframe* newest = Newest();
    if (newest == nullptr) return true;
    if (t - newest->t >= o.keyframe_interval && TranslationDistance(T_world_base, newest->T_world_base) > 0.0) {
      return true;
    }
    const double d2 = o.keyframe_distance * o.keyframe_distance;
    const double angle = DegToRad(o.keyframe_angle_deg);
    for (const auto& kf : keyframes) {
      if (!kf->active) continue;
      const double dx = T_world_base.x - kf->T_world_base.x, dy = T_world_base.y - kf->T_world_base.y;
      if (dx * dx + dy * dy < d2 &&
          std::abs(std::remainder(T_world_base.theta - kf->T_world_base.theta, 2.0 * kPi)) < angle) {
        return false;
      }
    }
    return true;
  }

  void DropOldKeyframes(Seconds t) {
    Keyframe* newest = Newest();
    for (auto& kf : keyframes) {
      if (kf->active && kf.get() != newest && t - kf->t > o.horizon) kf->active = false;
    }
  }

  // --- matching -------------------------------------------------------------------------------

  // Pairs at the pose for a level; returns the fraction of measurement points with a pair.
  struct KeyframeFrame {
    const ReferenceLevel* level;
    Eigen::Matrix2d R_kf_base;
    Eigen::Vector2d t_kf_base;
    Eigen::Matrix2d R_world_kf;
    Eigen::Vector2d t_world_kf;
  };
  std::vector<KeyframeFrame> kf_frames;

  double Associate(const Pose2& T_world_base, int level_index, double radius) {
    pairs.clear();
    pair_begin.clear();
    kf_frames.clear();
    for (const auto& kf : keyframes) {
      if (!kf->active || !kf->selected) continue;
      const ReferenceLevel& level = kf->levels[static_cast<std::size_t>(level_index)];
      if (level.cloud.points.empty()) continue;
      const Pose2 T_kf_base = kf->T_world_base.inverse() * T_world_base;
      kf_frames.push_back({&level, T_kf_base.rotation(), T_kf_base.translation(),
                           kf->T_world_base.rotation(), kf->T_world_base.translation()});
    }
    const double r2 = radius * radius;
    const bool line = o.residual == MatchResidual::kPointToLine;
    int matched = 0;
    for (std::size_t i = 0; i < meas_base.size(); ++i) {
      pair_begin.push_back(static_cast<int>(pairs.size()));
      for (const KeyframeFrame& f : kf_frames) {
        const Eigen::Vector2d q_kf = f.R_kf_base * meas_base[i] + f.t_kf_base;
        RadiusKnnResultSet result(o.neighbors_per_reference, r2, knn_index.data(), knn_dist.data());
        f.level->tree->findNeighbors(result, q_kf.data(), nanoflann::SearchParams());
        // Nearest to the end of a reference chain: the kernel sum there is one-sided and would
        // pull the point along the surface towards the reference's pose. Skip this reference.
        if (result.size() > 0 && f.level->near_end[knn_index[0]]) continue;
        for (std::size_t k = 0; k < result.size() && pairs.size() < pairs.capacity(); ++k) {
          const std::uint32_t j = knn_index[k];
          Pair pr;
          pr.point = static_cast<int>(i);
          pr.p_ref_world = f.R_world_kf * f.level->cloud.points[j] + f.t_world_kf;
          pr.weight = f.level->weight[j];
          if (line) {
            pr.n_world = f.R_world_kf * f.level->normals[j];
            if (pr.n_world.squaredNorm() == 0.0) continue;  // no line here
          } else if (j < f.level->normals.size()) {
            pr.n_world = f.R_world_kf * f.level->normals[j];  // for StructureInformation only
          } else {
            pr.n_world.setZero();
          }
          pairs.push_back(pr);
        }
      }
      matched += static_cast<int>(pairs.size()) > pair_begin.back() ? 1 : 0;
    }
    pair_begin.push_back(static_cast<int>(pairs.size()));
    return meas_base.empty() ? 0.0
                             : static_cast<double>(matched) / static_cast<double>(meas_base.size());
  }

  // H, g and |r|^2 of the scan terms at the pose (the gyro term is added by the caller).
  NormalEquations Accumulate(const Pose2& T_world_base, double sigma) const {
    NormalEquations ne;
    const Eigen::Matrix2d R = T_world_base.rotation();
    const Eigen::Vector2d t = T_world_base.translation();
    const bool line = o.residual == MatchResidual::kPointToLine;
    for (std::size_t i = 0; i < meas_base.size(); ++i) {
      const int begin = pair_begin[i], end = pair_begin[i + 1];
      if (begin == end) continue;
      const Eigen::Vector2d p = R * meas_base[i] + t;
      PointKernelSum sum;
      for (int k = begin; k < end; ++k) {
        const Pair& pr = pairs[static_cast<std::size_t>(k)];
        if (line) {
          sum.AddLine(p - pr.p_ref_world, pr.n_world, sigma, pr.weight);
        } else {
          sum.AddPoint(p - pr.p_ref_world, sigma, pr.weight);
        }
      }
      const Eigen::Matrix<double, 2, 3> J = PointJacobian(t, p);
      ne.H.noalias() += J.transpose() * sum.PsdHessian() * J;
      ne.g.noalias() += J.transpose() * sum.gradient;
      ne.sum_sq += 2.0 * sum.cost;
      ne.rows += end - begin;
    }
    return ne;
  }

  // The scene's structure as point-to-line information (Zhang, Kaess, Singh 2016): each matched
  // point constrains the pose along the local normal of its nearest reference point only. Unlike
  // the kernel sum's Hessian it has no curvature along a wall, however its points are spaced.
  // Unit weights: only its directions and their ratios are used (structure_degeneracy_ratio).
  Eigen::Matrix3d StructureInformation(const Pose2& T_world_base) const {
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    const Eigen::Vector2d t = T_world_base.translation();
    for (std::size_t i = 0; i + 1 < pair_begin.size(); ++i) {
      const int begin = pair_begin[i], end = pair_begin[i + 1];
      if (begin == end) continue;
      const Eigen::Vector2d p = T_world_base * meas_base[i];
      int best_k = begin;
      double best = std::numeric_limits<double>::infinity();
      for (int k = begin; k < end; ++k) {
        const double d2 = (p - pairs[static_cast<std::size_t>(k)].p_ref_world).squaredNorm();
        if (d2 < best) {
          best = d2;
          best_k = k;
        }
      }
      const Eigen::Vector2d& n = pairs[static_cast<std::size_t>(best_k)].n_world;
      if (n.squaredNorm() == 0.0) continue;  // not line-like there (a corner, clutter)
      const Eigen::RowVector3d j = n.transpose() * PointJacobian(t, p);
      H.noalias() += j.transpose() * j;
    }
    return H;
  }

  // Of the measurement points with pairs, the fraction whose nearest reference point lies
  // within 2 sigma (kernel >= exp(-1)).
  double InlierFraction(const Pose2& T_world_base, double sigma) const {
    const double r2 = 4.0 * sigma * sigma;
    int matched = 0, inliers = 0;
    for (std::size_t i = 0; i + 1 < pair_begin.size(); ++i) {
      const int begin = pair_begin[i], end = pair_begin[i + 1];
      if (begin == end) continue;
      ++matched;
      const Eigen::Vector2d p = T_world_base * meas_base[i];
      double best = std::numeric_limits<double>::infinity();
      for (int k = begin; k < end; ++k) {
        best = std::min(best, (p - pairs[static_cast<std::size_t>(k)].p_ref_world).squaredNorm());
      }
      inliers += best <= r2 ? 1 : 0;
    }
    return matched > 0 ? static_cast<double>(inliers) / static_cast<double>(matched) : 0.0;
  }

  // Mean e_mi over the points (kernels of peak 1) for the current pairs.
  double Score(const Pose2& T_world_base, double sigma) const {
    double sum = 0.0;
    for (const Pair& pr : pairs) {
      sum += KernelScore(T_world_base * meas_base[static_cast<std::size_t>(pr.point)] - pr.p_ref_world,
                         sigma);
    }
    return meas_base.empty() ? 0.0 : sum / static_cast<double>(meas_base.size());
  }
};

bool BaseStateEstimator::Impl::Eq3::operator()(const double* x, double* residuals,
                                              double* jacobian) const {
  const Pose2 T_world_base(x0[0] + x[0], x0[1] + x[1], x0[2] + x[2]);
  NormalEquations ne = impl->Accumulate(T_world_base, sigma);
  // Eq. 2: E_G = theta_k - (theta_{k-1} + sum omega_i dt), weighted by c_G.
  if (use_gyro) {
    const double e_g = WrapAngle(T_world_base.theta - theta_gyro);
    ne.H(2, 2) += gyro_weight;
    ne.g(2) += gyro_weight * e_g;
    ne.sum_sq += gyro_weight * e_g * e_g;
  }
  // A weak pull to the prediction keeps directions the scan does not observe (a corridor's
  // axis) at the prediction instead of letting the solver wander along them.
  if (prior_full) {
    Eigen::Vector3d dx(x0[0] + x[0] - x_pred[0], x0[1] + x[1] - x_pred[1], 0.0);
    dx[2] = WrapAngle(x0[2] + x[2] - x_pred[2]);
    const Eigen::Vector3d Wdx = prior_W * dx;
    ne.H += prior_W;
    ne.g += Wdx;
    ne.sum_sq += dx.dot(Wdx);
  } else if (prior_weight > 0.0) {
    const Eigen::Vector3d w(prior_weight, prior_weight, prior_weight * prior_lever * prior_lever);
    Eigen::Vector3d dx(x0[0] + x[0] - x_pred[0], x0[1] + x[1] - x_pred[1], 0.0);
    dx[2] = WrapAngle(x0[2] + x[2] - x_pred[2]);
    ne.H.diagonal() += w;
    ne.g += w.cwiseProduct(dx);
    ne.sum_sq += dx.dot(w.cwiseProduct(dx));
  }
  if (!std::isfinite(ne.sum_sq)) return false;
  if (!jacobian) {
    residuals[0] = std::sqrt(ne.sum_sq);
    residuals[1] = residuals[2] = residuals[3] = 0.0;
    return true;
  }
  // H = L L^T (a tiny ridge keeps it factorable when a direction is unobserved).
  const double ridge = 1e-12 * (ne.H.trace() + 1.0);
  const Eigen::LLT<Eigen::Matrix3d> llt(ne.H + ridge * Eigen::Matrix3d::Identity());
  if (llt.info() != Eigen::Success) return false;
  const Eigen::Matrix3d L = llt.matrixL();
  const Eigen::Vector3d r3 = L.triangularView<Eigen::Lower>().solve(ne.g);
  residuals[0] = r3[0];
  residuals[1] = r3[1];
  residuals[2] = r3[2];
  residuals[3] = std::sqrt(std::max(0.0, ne.sum_sq - r3.squaredNorm()));
  // Column-major 4 x 3: J~ = [L^T; 0].
  for (int c = 0; c < 3; ++c) {
    for (int r = 0; r < 3; ++r) jacobian[c * 4 + r] = L(c, r);
    jacobian[c * 4 + 3] = 0.0;
  }
  return true;
}

// ---------------------------------------------------------------------------------------------
// Public API

BaseStateEstimator::BaseStateEstimator(const EstimatorOptions& options, const Pose2& T_base_laser)
    : options_(options), T_base_laser_(T_base_laser) {
  const std::string problem = options_.Validate();
  IFAB_THROW_UNLESS(problem.empty(), "EstimatorOptions: {}", problem);
  impl_ = std::make_unique<Impl>(options_);
  impl_->T_base_laser = T_base_laser_;
}

BaseStateEstimator::~BaseStateEstimator() = default;

int BaseStateEstimator::NumReferenceScans() const { return impl_->NumActiveKeyframes(); }

void BaseStateEstimator::Reset(const Pose2& T_world_base, Seconds t, bool keep_references) {
  Impl& m = *impl_;
  if (keep_references && m.initialized) {
    // Move the reference set rigidly with the correction T_new * T_old^-1.
    const Pose2 correction = T_world_base * m.pose.inverse();
    for (auto& kf : m.keyframes) {
      if (kf->active) kf->T_world_base = correction * kf->T_world_base;
    }
    m.velocity.head<2>() = (correction.rotation() * m.velocity.head<2>()).eval();
  } else {
    for (auto& kf : m.keyframes) kf->active = false;
    m.velocity.setZero();
    m.have_velocity = false;
  }
  m.consecutive_failures = 0;
  m.pose = T_world_base;
  m.pose_cov.setZero();
  m.window_count = 0;
  m.have_last_step = false;
  m.t_last = t;
  m.initialized = true;
  m.DropGyroUntil(t - 1e-9);
  latest_ = BaseEstimate{};
  latest_.t = t;
  latest_.T_world_base = T_world_base;
  latest_.status = EstimateStatus::kReference;
}

void BaseStateEstimator::AddGyro(const GyroSample& sample) {
  Impl& m = *impl_;
  if (m.gyro.size() > m.gyro_head) {
    IFAB_THROW_UNLESS(sample.stamp.t >= m.gyro.back().t,
                      "gyro sample at t = {} s is older than the previous one ({} s)",
                      sample.stamp.t, m.gyro.back().t);
  }
  m.PushGyro(sample.stamp.t, sample.rate.z());
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
  e.gyro_used = o.gyro_weight > 0.0 && m.IntegrateGyro(m.t_last, t, &dtheta_gyro);
  m.DropGyroUntil(t);

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
  m.ExtractPoints(scan, v_base, omega);

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
                m.prior_scale * StepCovarianceInWorld(m.pose, motion->covariance);
  }
  e.prior_used = informative;
  m.PushWindow(informative, informative ? &*motion : nullptr);

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
          static_cast<int>(m.valid_base.size()) >= o.min_points) {
        for (auto& kf : m.keyframes) kf->active = false;
        m.AddKeyframe(predicted, t);
        e.keyframe_added = true;
        m.consecutive_failures = 0;
      }
    }
    return e;
  };

  // The first scan after a reset only becomes the reference.
  if (m.NumActiveKeyframes() == 0) {
    e.status = EstimateStatus::kReference;
    e.T_world_base = m.pose;
    e.covariance.setZero();
    e.num_points = static_cast<int>(m.valid_base.size());
    if (e.num_points >= o.min_points) {
      m.AddKeyframe(m.pose, t);
      e.keyframe_added = true;
    } else {
      e.status = EstimateStatus::kTooFewPoints;
    }
    m.t_last = t;
    return e;
  }
  if (static_cast<int>(m.valid_base.size()) < o.min_points) {
    e.num_points = static_cast<int>(m.valid_base.size());
    return finish_failed(EstimateStatus::kTooFewPoints);
  }

  // Eq. 3 by levels of sigma (coarse to fine when configured), re-associating in each.
  m.SelectReferences(predicted);
  Eigen::Vector3d x(predicted.x, predicted.y, predicted.theta);
  const Eigen::Vector3d x_pred = x;
  m.eq3.use_gyro = e.gyro_used;
  m.eq3.gyro_weight = o.gyro_weight;
  m.eq3.theta_gyro = predicted.theta;
  m.eq3.x_pred = x;
  m.eq3.prior_weight = o.prior_weight;
  m.eq3.prior_lever = 1.0;
  m.eq3.prior_full = informative;
  Eigen::Matrix3d info_prior = Eigen::Matrix3d::Zero();
  if (informative) info_prior = prior_cov.inverse();
  const int fine = m.num_levels - 1;
  bool pairs_current = false;  // the pairs were made at (about) the final pose
  for (int level = 0; level < m.num_levels; ++level) {
    const double sigma = m.LevelSigma(level);
    const double radius = o.search_radius_sigmas * std::sqrt(2.0) * sigma;
    m.Thin(m.MeasurementSpacing(level), std::numeric_limits<double>::infinity(), o.max_points,
           &m.meas_base);
    m.eq3.sigma = sigma;
    for (int round = 0; round < o.max_associations; ++round) {
      m.Associate(Pose2(x[0], x[1], x[2]), level, radius);
      if (m.pairs.empty()) break;
      if (informative) {
        // The odometry factor in the scan's cost units: physical information times the scan
        // terms' residual variance per row (the same factor that turns the scan's Hessian into
        // its covariance), so each side weighs by what it knows.
        double& var = m.residual_var[static_cast<std::size_t>(level)];
        if (var <= 0.0) {
          const NormalEquations ne0 = m.Accumulate(Pose2(x[0], x[1], x[2]), sigma);
          var = std::max(ne0.sum_sq / std::max(1, ne0.rows - 3), 1e-12);
        }
        m.eq3.prior_W = var * info_prior;
      }
      // TinySolver's function tolerance is absolute (on 2 * cost): scale it with the pairs.
      m.solver.options.function_tolerance = 1e-8 * static_cast<double>(m.pairs.size());
      m.eq3.x0 = x;
      Eigen::Vector3d increment = Eigen::Vector3d::Zero();
      const auto& summary = m.solver.Solve(m.eq3, &increment);
      e.iterations += std::max(0, summary.iterations);
      if (!increment.allFinite()) return finish_failed(EstimateStatus::kSolverFailed);
      x += increment;
      x[2] = WrapAngle(x[2]);
      pairs_current = std::max(increment.head<2>().norm(), std::abs(increment[2])) < o.converged_step;
      if (pairs_current) break;
    }
  }
  Pose2 solved(x[0], x[1], x[2]);
  e.num_points = static_cast<int>(m.meas_base.size());

  // Quality at the solution, with a fresh association at the finest level unless the last
  // round's pairs were made at (about) this pose already.
  const double sigma = o.sigma;
  if (pairs_current) {
    int matched = 0;
    for (std::size_t i = 0; i + 1 < m.pair_begin.size(); ++i) {
      matched += m.pair_begin[i + 1] > m.pair_begin[i] ? 1 : 0;
    }
    e.matched_fraction = m.meas_base.empty() ? 0.0 : static_cast<double>(matched) / static_cast<double>(m.meas_base.size());
  } else {
    e.matched_fraction = m.Associate(solved, fine, o.search_radius_sigmas * std::sqrt(2.0) * sigma);
  }
  if (m.pairs.empty() || e.matched_fraction < o.min_matched_fraction) {
    return finish_failed(EstimateStatus::kTooFewPoints);
  }
  e.inlier_fraction = m.InlierFraction(solved, sigma);
  if (e.inlier_fraction < o.min_inlier_fraction) return finish_failed(EstimateStatus::kPoorScore);
  e.score = m.Score(solved, sigma);
  NormalEquations ne = m.Accumulate(solved, sigma);
  // The scan's residual variance per row: covariance = H^-1 * variance (the usual estimate of
  // a least-squares fit's covariance); the scan's physical information is H / variance.
  const double residual_var = std::max(ne.sum_sq / std::max(1, ne.rows - 3), 1e-12);
  e.gyro_error_rad = e.gyro_used ? WrapAngle(solved.theta - predicted.theta) : 0.0;
  if (e.gyro_used) ne.H(2, 2) += o.gyro_weight;
  e.cost = 0.5 * (ne.sum_sq + (e.gyro_used ? o.gyro_weight * e.gyro_error_rad * e.gyro_error_rad : 0.0));
  double lever_sq = 0.0;
  for (const auto& q : m.meas_base) lever_sq += q.squaredNorm();
  const double lever = std::sqrt(std::max(lever_sq / static_cast<double>(m.meas_base.size()), 1e-6));
  Eigen::Matrix3d info_scan = ne.H / residual_var;
  if (informative && o.structure_degeneracy_ratio > 0.0) {
    // Directions the structure leaves (nearly) unconstrained carry no information whatever the
    // kernel sum's curvature says: remove them, so the analysis below hands them to the prior.
    const double l = std::max(lever, 1e-3);
    const Eigen::Vector3d scale(1.0, 1.0, 1.0 / l);  // (x, y, lever * theta) -> (x, y, theta)
    const Eigen::Matrix3d S = m.StructureInformation(solved);
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(scale.asDiagonal() * S * scale.asDiagonal());
    const double smax = es.eigenvalues()(2);
    Eigen::Matrix3d P = Eigen::Matrix3d::Identity();
    for (int i = 0; i < 3; ++i) {
      if (!(es.eigenvalues()(i) >= o.structure_degeneracy_ratio * smax)) {
        P -= es.eigenvectors().col(i) * es.eigenvectors().col(i).transpose();
      }
    }
    const Eigen::Vector3d unscale = scale.cwiseInverse();
    const Eigen::Matrix3d H_scaled = scale.asDiagonal() * info_scan * scale.asDiagonal();
    info_scan = unscale.asDiagonal() * (P * H_scaled * P) * unscale.asDiagonal();
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
    m.AddInnovation(e.mahalanobis_sq, e.gate_dof);
    if (o.gate_translation_only) {
      e.mahalanobis_sq = InnovationTranslationMahalanobisSq(deg, info_prior, dx, &e.gate_dof);
    }
    if (e.gate_dof > 0 && e.mahalanobis_sq > m.gate_chi2[static_cast<std::size_t>(e.gate_dof)]) {
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
      e.window_mahalanobis_sq = m.WindowMahalanobisSq(solved, e.covariance);
      if (e.window_mahalanobis_sq > m.window_chi2) {
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
  if (m.NeedsKeyframe(solved, t)) {
    m.AddKeyframe(solved, t);
    e.keyframe_added = true;
  }
  m.DropOldKeyframes(t);
  return e;
}

}  // namespace ifab::base
