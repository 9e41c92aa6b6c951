#include "ifab/perception/pose_solver.h"

#include <ceres/ceres.h>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>

#include "ifab/core/error.h"
#include "ifab/perception/dense_lm.h"
#include "ifab/perception/residuals.h"

namespace ifab::internal {
namespace {

using Params = std::array<double, 6>;  // [t, w] about R0

constexpr int kChunk = 256;  // points per Ceres residual block, and per unit of (parallel) evaluation

using Vector6 = Eigen::Matrix<double, 6, 1>;
// The norm of 3 whitened components (kClosest) has median 1.538 (chi, 3 dof), 2.28 times that of
// one |N(0, 1)|: divided by this, the robust spread and the gate read as for one component.
constexpr double kChi3MedianRatio = 2.2806;

Pose3 ApplyParams(const Params& x, const Eigen::Matrix3d& R0) {
  Pose3 T = Pose3::Identity();
  T.linear() = ExpSO3(Eigen::Vector3d(x[3], x[4], x[5])) * R0;
  T.translation() = Eigen::Vector3d(x[0], x[1], x[2]);
  return T;
}

Params ParamsAt(const Pose3& T) { return {T.translation().x(), T.translation().y(), T.translation().z(), 0, 0, 0}; }

// Points of one body (registration): residuals of a fixed p_base against the body pose.
class RegistrationChunk final : public ceres::CostFunction {
 public:
  RegistrationChunk(const Scene& scene, const Eigen::Matrix3d& R0, std::vector<RayT<double>> points,
                    std::vector<const PointMatch*> matches)
      : scene_(scene), R0_(R0), points_(std::move(points)), matches_(std::move(matches)) {
    int n = 0;
    for (const auto* m : matches_) n += m->NumResiduals();
    set_num_residuals(n);
    mutable_parameter_block_sizes()->push_back(6);
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const PoseJacobianData X(parameters[0], R0_);
    double* J = jacobians ? jacobians[0] : nullptr;
    int row = 0;
    for (std::size_t i = 0; i < points_.size(); ++i) {
      const PointMatch& m = *matches_[i];
      const ScenePrimitive* prim = m.primitive >= 0 ? &scene_.primitives()[static_cast<std::size_t>(m.primitive)] : nullptr;
      row += PointResidualAnalytic(m, prim, points_[i], X, residuals + row, J ? J + row * 6 : nullptr);
    }
    return true;
  }

 private:
  const Scene& scene_;
  Eigen::Matrix3d R0_;
  std::vector<RayT<double>> points_;
  std::vector<const PointMatch*> matches_;
};

// Points of one body (calibration): eq. 6 inside eq. 7, the mount and the body pose both free.
class CalibrationChunk final : public ceres::CostFunction {
 public:
  CalibrationChunk(const Scene& scene, const Eigen::Matrix3d& R0_laser, const Eigen::Matrix3d& R0_body,
                   std::vector<const SweepPoint*> points, std::vector<const PointMatch*> matches, bool autodiff)
      : scene_(scene), R0_laser_(R0_laser), R0_body_(R0_body), points_(std::move(points)), matches_(std::move(matches)),
        autodiff_(autodiff) {
    int n = 0;
    for (const auto* m : matches_) n += m->NumResiduals();
    set_num_residuals(n);
    mutable_parameter_block_sizes()->push_back(6);
    mutable_parameter_block_sizes()->push_back(6);
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const bool want = jacobians && (jacobians[0] || jacobians[1]);
    if (!autodiff_) return EvaluateAnalytic(parameters, residuals, want ? jacobians : nullptr);
    const double* xl = parameters[0];
    const double* xb = parameters[1];
    using J = ceres::Jet<double, 12>;
    J xlj[6], xbj[6];
    for (int k = 0; k < 6; ++k) {
      xlj[k] = J(xl[k], k);
      xbj[k] = J(xb[k], 6 + k);
    }
    const PoseT<J> XLj(xlj, R0_laser_), XBj(xbj, R0_body_);
    const PoseT<double> XL(xl, R0_laser_), XB(xb, R0_body_);
    int row = 0;
    for (std::size_t i = 0; i < points_.size(); ++i) {
      const PointMatch& m = *matches_[i];
      const SweepPoint& s = *points_[i];
      const ScenePrimitive* prim = m.primitive >= 0 ? &scene_.primitives()[static_cast<std::size_t>(m.primitive)] : nullptr;
      if (want) {
        const RayT<J> ray = LaserRay<J>(XLj, s.T_base_tool0, s.p_laser);
        J r[3];
        const int n = PointResidual<J>(m, prim, ray, XBj, r);
        for (int k = 0; k < n; ++k) {
          residuals[row + k] = r[k].a;
          if (jacobians[0])
            for (int c = 0; c < 6; ++c) jacobians[0][(row + k) * 6 + c] = r[k].v[c];
          if (jacobians[1])
            for (int c = 0; c < 6; ++c) jacobians[1][(row + k) * 6 + c] = r[k].v[6 + c];
        }
        row += n;
      } else {
        const RayT<double> ray = LaserRay<double>(XL, s.T_base_tool0, s.p_laser);
        row += PointResidual<double>(m, prim, ray, XB, residuals + row);
      }
    }
    return true;
  }

 private:
  // The same residuals with hand-derived Jacobians (residuals.h), checked against autodiff.
  bool EvaluateAnalytic(double const* const* parameters, double* residuals, double** jacobians) const {
    const PoseJacobianData XL(parameters[0], R0_laser_), XB(parameters[1], R0_body_);
    using Row6 = Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor>;
    using Row3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
    int row = 0;
    for (std::size_t i = 0; i < points_.size(); ++i) {
      const PointMatch& m = *matches_[i];
      const SweepPoint& s = *points_[i];
      const ScenePrimitive* prim = m.primitive >= 0 ? &scene_.primitives()[static_cast<std::size_t>(m.primitive)] : nullptr;
      const LaserRayJacobian lr = LaserRayWithJacobian(XL, s.T_base_tool0, s.p_laser);
      RayJacobian rj;
      double* jb = jacobians && jacobians[1] ? jacobians[1] + row * 6 : nullptr;
      const int n = PointResidualAnalytic(m, prim, lr.ray, XB, residuals + row, jb, jacobians ? &rj : nullptr);
      if (jacobians && jacobians[0]) {
        Eigen::Map<Row6>(jacobians[0] + row * 6, n, 6) =
            Eigen::Map<const Row3>(rj.d_origin, n, 3) * lr.d_origin + Eigen::Map<const Row3>(rj.d_direction, n, 3) * lr.d_direction;
      }
      row += n;
    }
    return true;
  }

  const Scene& scene_;
  Eigen::Matrix3d R0_laser_, R0_body_;
  std::vector<const SweepPoint*> points_;
  std::vector<const PointMatch*> matches_;
  bool autodiff_{false};
};

// Damping of one step: (x - x_start) / sigma. Re-centred every step, so it holds directions the
// data leave free without pulling the others (the data's information is many orders larger).
class StepPrior final : public ceres::SizedCostFunction<6, 6> {
 public:
  StepPrior(const Params& start, double sigma_t, double sigma_r) : start_(start) {
    for (int k = 0; k < 3; ++k) {
      w_[k] = 1.0 / sigma_t;
      w_[3 + k] = 1.0 / sigma_r;
    }
  }
  bool Evaluate(double const* const* p, double* r, double** j) const override {
    for (int k = 0; k < 6; ++k) r[k] = (p[0][k] - start_[static_cast<std::size_t>(k)]) * w_[k];
    if (j && j[0]) {
      for (int k = 0; k < 36; ++k) j[0][k] = 0.0;
      for (int k = 0; k < 6; ++k) j[0][k * 6 + k] = w_[k];
    }
    return true;
  }

 private:
  Params start_;
  double w_[6];
};

// Up to 3 residuals of one point and their Jacobian rows (row-major n x 6) with respect to the
// laser mount (calibration) and the point's body.
struct PointTerms {
  int n{0};
  double r[3];
  Eigen::Matrix<double, 3, 6, Eigen::RowMajor> J_laser, J_body;
};

// Registration: a fixed ray p_base against the body pose.
void RegistrationTerms(const PointMatch& m, const ScenePrimitive* prim, const RayT<double>& ray,
                       const PoseJacobianData& XB, bool jacobians, PointTerms& out) {
  out.n = PointResidualAnalytic(m, prim, ray, XB, out.r, jacobians ? out.J_body.data() : nullptr);
}

// Calibration: eq. 6 inside eq. 7, the mount and the body pose both free. Hand-derived Jacobians
// (residuals.h, checked against autodiff) or Ceres autodiff through the templated residuals.
void CalibrationTerms(const PointMatch& m, const ScenePrimitive* prim, const SweepPoint& s, const PoseJacobianData& XL,
                      const PoseJacobianData& XB, bool jacobians, PointTerms& out) {
  using Row3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
  const LaserRayJacobian lr = LaserRayWithJacobian(XL, s.T_base_tool0, s.p_laser);
  RayJacobian rj;
  out.n = PointResidualAnalytic(m, prim, lr.ray, XB, out.r, jacobians ? out.J_body.data() : nullptr,
                                jacobians ? &rj : nullptr);
  if (jacobians && out.n > 0)
    out.J_laser.topRows(out.n) = Eigen::Map<const Row3>(rj.d_origin, out.n, 3) * lr.d_origin +
                                 Eigen::Map<const Row3>(rj.d_direction, out.n, 3) * lr.d_direction;
}

void CalibrationTermsAutodiff(const PointMatch& m, const ScenePrimitive* prim, const SweepPoint& s,
                              const double* xl, const Eigen::Matrix3d& R0_laser, const double* xb,
                              const Eigen::Matrix3d& R0_body, bool jacobians, PointTerms& out) {
  if (!jacobians) {
    const PoseT<double> XL(xl, R0_laser), XB(xb, R0_body);
    out.n = PointResidual<double>(m, prim, LaserRay<double>(XL, s.T_base_tool0, s.p_laser), XB, out.r);
    return;
  }
  using J = ceres::Jet<double, 12>;
  J xlj[6], xbj[6];
  for (int k = 0; k < 6; ++k) {
    xlj[k] = J(xl[k], k);
    xbj[k] = J(xb[k], 6 + k);
  }
  const PoseT<J> XLj(xlj, R0_laser), XBj(xbj, R0_body);
  J r[3];
  out.n = PointResidual<J>(m, prim, LaserRay<J>(XLj, s.T_base_tool0, s.p_laser), XBj, r);
  for (int k = 0; k < out.n; ++k) {
    out.r[k] = r[k].a;
    for (int c = 0; c < 6; ++c) {
      out.J_laser(k, c) = r[k].v[c];
      out.J_body(k, c) = r[k].v[6 + c];
    }
  }
}

// Sums over a run of points of one body: 0.5 |r|^2, J^T J and J^T r by block.
struct BodyAccumulator {
  double cost{0.0};
  Matrix6d H_body{Matrix6d::Zero()}, H_laser{Matrix6d::Zero()}, H_laser_body{Matrix6d::Zero()};
  Vector6 g_body{Vector6::Zero()}, g_laser{Vector6::Zero()};

  void Add(const PointTerms& t, bool jacobians, bool laser) {
    for (int k = 0; k < t.n; ++k) {
      cost += 0.5 * t.r[k] * t.r[k];
      if (!jacobians) continue;
      const Vector6 jb = t.J_body.row(k).transpose();
      H_body.noalias() += jb * jb.transpose();
      g_body += t.r[k] * jb;
      if (laser) {
        const Vector6 jl = t.J_laser.row(k).transpose();
        H_laser.noalias() += jl * jl.transpose();
        H_laser_body.noalias() += jl * jb.transpose();
        g_laser += t.r[k] * jl;
      }
    }
  }
  void Add(const BodyAccumulator& o) {
    cost += o.cost;
    H_body += o.H_body;
    H_laser += o.H_laser;
    H_laser_body += o.H_laser_body;
    g_body += o.g_body;
    g_laser += o.g_laser;
  }
};

double RobustWeight(RobustLoss loss, double scale, double whitened) {
  const double a = std::abs(whitened);
  switch (loss) {
    case RobustLoss::kNone: return 1.0;
    case RobustLoss::kHuber: return a <= scale ? 1.0 : scale / a;
    case RobustLoss::kCauchy: return 1.0 / (1.0 + (a / scale) * (a / scale));
  }
  return 1.0;
}

class Engine {
 public:
  Engine(const PoseProblemInput& input, const std::vector<RegistrationBody>& bodies, const RegistrationOptions& options)
      : input_(input), bodies_(bodies), options_(options), scene_(bodies), noise_(options.noise),
        scale_known_(options.noise_source == NoiseSource::kModel), cos_max_incidence_(std::cos(options.max_incidence)),
        cos_min_incidence_(std::cos(options.min_incidence)) {
    for (const auto& b : bodies_) poses_.push_back(b.T_base_body);
    laser_ = input.T_tool0_laser;
    calibrating_ = input.sweep != nullptr;
    const std::size_t n = calibrating_ ? input.sweep->size() : input.cloud->size();
    matches_.resize(n);
    whitened_.assign(n, 0.0);
    gate_out_.assign(n, 0);
    labels_.resize(n);
    flagged_.resize(n);
    if (!calibrating_) {
      // Registration: the cloud is fixed, so each point's ray is computed once for all steps.
      rays_.resize(n);
      for (std::size_t i = 0; i < n; ++i) {
        const RayPoint& rp = (*input.cloud)[i];
        const double range = rp.Range();
        rays_[i] = {rp.origin, range > 0.0 ? Eigen::Vector3d((rp.p - rp.origin) / range) : Eigen::Vector3d::UnitX(), range};
      }
    }
  }

  PoseProblemOutput Run() {
    const auto start = std::chrono::steady_clock::now();
    PoseProblemOutput out;
    RegistrationSummary& s = out.summary;
    s.num_points = static_cast<int>(matches_.size());
    if (matches_.empty()) {
      s.status = RegistrationStatus::kNoPoints;
      s.message = "no points";
      Finish(out, start);
      return out;
    }
    bool any_free = calibrating_;
    for (const auto& b : bodies_) any_free = any_free || b.free;

    s.status = RegistrationStatus::kMaxIterations;
    s.message = fmt::format("not converged in {} correspondence steps", options_.max_iterations);
    stride_ = std::max(1, options_.coarse_stride);
    for (int it = 0; it < options_.max_iterations && any_free; ++it) {
      Match();
      if (EstimateNoiseScale()) Match();
      if (CountInliers() == 0) {
        s.status = RegistrationStatus::kNoPoints;
        s.message = "no point lies near the model under the initial guess";
        break;
      }
      s.iterations = it + 1;
      const auto step = Step();
      if (!step.ok) {
        s.status = RegistrationStatus::kSolverFailed;
        s.message = step.message;
        break;
      }
      if (stride_ > 1) {
        // Coarse phase (every stride-th point): once its steps are small, or cycle, go on with
        // all points; only those steps may end the iteration.
        if ((step.max_translation < 10.0 * options_.translation_tolerance &&
             step.max_rotation < 10.0 * options_.rotation_tolerance) ||
            CyclePeriod() > 0) {
          stride_ = 1;
          history_.clear();
          previous_delta_.resize(0);
          relaxation_ = 1.0;
        }
        continue;
      }
      // The noise scale follows the fit down while it moves; once the steps are small it is held,
      // so that the gate's points stop changing and the poses settle.
      // (also after a third of the steps: a scale still drifting then is at the noise level)
      if ((step.max_translation < 10.0 * options_.translation_tolerance &&
           step.max_rotation < 10.0 * options_.rotation_tolerance) ||
          3 * (it + 1) >= options_.max_iterations)
        scale_frozen_ = gate_held_ = true;
      if (ReturnedToStart()) {
        // A restart trial back within 10x the tolerances of the result it is tried against (the
        // threshold at which the coarse phase and the noise scale count steps as small): the
        // steps left would only polish the same minimum again, so it cannot win.
        out.returned = true;
        s.status = RegistrationStatus::kConverged;
        s.message = fmt::format("returned to the restarted result in {} correspondence steps", it + 1);
        s.iterations = it + 1;
        return out;
      }
      if (step.max_translation < options_.translation_tolerance && step.max_rotation < options_.rotation_tolerance) {
        s.status = RegistrationStatus::kConverged;
        s.message = fmt::format("converged in {} correspondence steps", it + 1);
        break;
      }
      // Points whose rays pass an edge can switch faces back and forth, and the steps then cycle
      // through the same few poses (typically within a fraction of a millimetre): stop there.
      if (const int period = CyclePeriod(); period > 0) {
        s.status = RegistrationStatus::kConverged;
        s.message = fmt::format("converged in {} correspondence steps to a {}-cycle of face assignments "
                                "(amplitude {:.3f} mm, {:.4f} deg)",
                                it + 1, period, 1e3 * cycle_translation_, cycle_rotation_ * 180.0 / M_PI);
        break;
      }
    }
    if (!any_free) {
      s.status = RegistrationStatus::kConverged;
      s.message = "no free body: poses held";
    }
    flag_all_ = true;
    Match();  // labels and weights at the final poses
    Finish(out, start);
    return out;
  }

 private:
  struct StepResult {
    bool ok{true};
    std::string message;
    double max_translation{0.0};
    double max_rotation{0.0};
  };

  // The state after each step (all free poses), to detect cycles.
  std::vector<std::vector<Pose3>> history_;
  double cycle_translation_{0.0}, cycle_rotation_{0.0};
  Eigen::VectorXd previous_delta_;
  double relaxation_{1.0};
  int stride_{1};  // points used by the correspondence steps (coarse_stride, then 1)

  bool ReturnedToStart() const {
    if (input_.return_to == nullptr) return false;
    const auto& to = *input_.return_to;
    for (std::size_t k = 0; k < poses_.size() && k < to.size(); ++k) {
      if (!bodies_[k].free) continue;
      if (TranslationDistance(poses_[k], to[k]) > 10.0 * options_.translation_tolerance ||
          RotationAngle(poses_[k], to[k]) > 10.0 * options_.rotation_tolerance)
        return false;
    }
    return true;
  }

  int CyclePeriod() {
    std::vector<Pose3> now = poses_;
    now.push_back(laser_);
    history_.push_back(now);
    const std::size_t n = history_.size();
    for (std::size_t period = 2; period <= 4 && period < n; ++period) {
      const auto& then = history_[n - 1 - period];
      bool same = true;
      for (std::size_t k = 0; k < now.size() && same; ++k)
        same = TranslationDistance(now[k], then[k]) < 1e-9 && RotationAngle(now[k], then[k]) < 1e-9;
      if (!same) continue;
      cycle_translation_ = cycle_rotation_ = 0.0;
      for (std::size_t j = n - period; j < n; ++j)
        for (std::size_t k = 0; k < now.size(); ++k) {
          cycle_translation_ = std::max(cycle_translation_, TranslationDistance(history_[j][k], now[k]));
          cycle_rotation_ = std::max(cycle_rotation_, RotationAngle(history_[j][k], now[k]));
        }
      return static_cast<int>(period);
    }
    return 0;
  }

  // Noise scale from the residuals (NoiseSource::kEstimated): the model's shape times the robust
  // spread of the inliers' whitened errors. Early on that spread is the misalignment, so the gate
  // starts wide and shrinks as the fit settles. Returns true if the scale was updated.
  bool EstimateNoiseScale() {
    if (options_.noise_source != NoiseSource::kEstimated || scale_frozen_) return false;
    std::vector<double> a;
    for (std::size_t i = 0; i < labels_.size(); ++i)
      if (labels_[i] == PointLabel::kInlier) a.push_back(std::abs(whitened_[i]));
    if (a.size() < 10) return false;
    const double k = RobustScale(std::move(a), scale_known_ ? options_.gate_sigmas : 0.0);
    if (!(k > 0.0) || !std::isfinite(k)) return false;
    noise_scale_ *= k;
    noise_ = options_.noise.Scaled(noise_scale_);
    scale_known_ = true;
    return true;
  }

  bool Informs(int body) const { return calibrating_ || bodies_[static_cast<std::size_t>(body)].free; }

  RayPoint PointInBase(std::size_t i) const {
    if (!calibrating_) return (*input_.cloud)[i];
    const SweepPoint& s = (*input_.sweep)[i];
    const Pose3 T_base_laser = s.T_base_tool0 * laser_;
    return {T_base_laser * s.p_laser, T_base_laser.translation()};
  }

  void Match() {
    scene_.SetPoses(poses_);
    inverse_poses_.clear();
    for (const auto& T : poses_) inverse_poses_.push_back(T.inverse());
    auto body = [&](const tbb::blocked_range<std::size_t>& range) {
      for (std::size_t i = range.begin(); i != range.end(); ++i) MatchPoint(i);
    };
    const tbb::blocked_range<std::size_t> all(0, matches_.size(), 512);
    if (options_.num_threads > 1) {
      tbb::task_arena arena(options_.num_threads);
      arena.execute([&] { tbb::parallel_for(all, body); });
    } else {
      body(all);
    }
  }

  void MatchPoint(std::size_t i) {
    PointMatch m;
    const RayPoint rp = PointInBase(i);
    flagged_[i] = false;
    labels_[i] = PointLabel::kOutlier;
    const double range = rp.Range();
    if (!(range > 1e-9)) {
      matches_[i] = m;
      return;
    }
    const Eigen::Vector3d u = (rp.p - rp.origin) / range;
    // The closest primitive and the edge test are the costly questions; each is asked only when
    // its answer can change the match (the final Match asks the edge test of every point, for the
    // summary's count). The matches are the same as when both are asked of every point.
    std::optional<Scene::Nearest> nearest;
    auto near_point = [&]() -> const Scene::Nearest& {
      if (!nearest) nearest = scene_.Closest(rp.p);
      return *nearest;
    };
    auto too_far = [&] {
      const Scene::Nearest& n = near_point();
      return n.primitive < 0 || (options_.max_distance > 0.0 && n.distance > options_.max_distance);
    };
    bool flag_known = false;
    auto flagged = [&] {
      if (!flag_known) {
        flagged_[i] = options_.shadow_points &&
                      scene_.RayPassesNearEdge(rp.origin, u, range + options_.shadow_edge_distance,
                                               options_.shadow_edge_distance);
        flag_known = true;
      }
      return static_cast<bool>(flagged_[i]);
    };
    std::optional<Scene::Hit> hit;
    if (options_.residual == RegistrationResidual::kRay) {
      const double reach = options_.max_distance > 0.0 ? options_.max_distance : 1.0;
      hit = scene_.CastRay(rp.origin, u, range + reach);
    }
    // A hit within max_distance of the point along the ray bounds its distance to the model, so
    // the closest primitive need not be asked to know the point is near enough.
    const bool near_by_hit = hit && (options_.max_distance <= 0.0 || std::abs(range - hit->t) <= options_.max_distance);
    if (!near_by_hit && too_far()) {
      matches_[i] = m;
      return;
    }
    if (flag_all_) flagged();
    double whitened = 0.0;
    if (options_.residual == RegistrationResidual::kRay) {
      // The face the ray hits first explains the point by its range (kRange). Near an edge
      // (flagged) a point far off that face either came from the surface on the other side of
      // the edge (then it is matched to the closest surface: these points carry the silhouette,
      // the only horizontal information of a brick seen from above) or is a mixed pixel between
      // the two (a shadow point: zero error). A ray that hits nothing is matched to the tangent
      // plane at its closest point; points too far from their surface get zero error.
      struct Candidate {
        int primitive{-1};
        Eigen::Vector3d x, n;
        bool range{false};
        double signed_distance{0.0}, error{0.0}, sigma{1.0};
      };
      auto closest_candidate = [&] {
        const Scene::Nearest& near = near_point();
        Candidate k;
        k.primitive = near.primitive;
        k.x = near.point;
        k.n = near.feature == Feature::kFace || !(near.distance > 1e-9) ? near.normal
                                                                        : Eigen::Vector3d((rp.p - near.point) / near.distance);
        k.signed_distance = k.n.dot(rp.p - k.x);
        k.error = std::abs(k.signed_distance);
        k.sigma = std::sqrt(noise_.NormalVariance(u, range, k.n));
        return k;
      };
      Candidate chosen;
      if (hit) {
        chosen.primitive = hit->primitive;
        chosen.x = rp.origin + hit->t * u;
        chosen.n = hit->normal;
        chosen.range = true;
        chosen.signed_distance = chosen.n.dot(rp.p - chosen.x);
        // The sensor errs along the ray: compare the range error (at a grazing face a beam that
        // slipped past it is metres long but only millimetres off the face's plane).
        const double c = std::max(std::abs(chosen.n.dot(u)), 1e-3);
        chosen.error = std::abs(chosen.signed_distance) / c;
        chosen.sigma = std::sqrt(noise_.NormalVariance(u, range, chosen.n)) / c;
        const bool off = chosen.error > options_.shadow_distance && chosen.error > options_.shadow_sigmas * chosen.sigma;
        if (off && flagged()) {
          const Candidate other = closest_candidate();
          if (other.primitive == chosen.primitive ||
              (other.error > options_.shadow_distance && other.error > options_.shadow_sigmas * other.sigma)) {
            labels_[i] = PointLabel::kShadow;
            matches_[i] = m;
            return;
          }
          chosen = other;
        }
      } else {
        chosen = closest_candidate();
      }
      if ((options_.max_distance > 0.0 && chosen.error > options_.max_distance) ||
          GateRejects(i, chosen.error / chosen.sigma)) {
        matches_[i] = m;
        return;
      }
      const double c = std::abs(chosen.n.dot(u));
      if (chosen.range && (c < cos_max_incidence_ || c > cos_min_incidence_)) {
        labels_[i] = PointLabel::kGrazing;
        matches_[i] = m;
        return;
      }
      const ScenePrimitive& sp = scene_.primitives()[static_cast<std::size_t>(chosen.primitive)];
      const Pose3& T_body_base = inverse_poses_[static_cast<std::size_t>(sp.body)];
      m.body = sp.body;
      m.primitive = chosen.primitive;
      m.normal_body = T_body_base.linear() * chosen.n;
      m.offset_body = m.normal_body.dot(T_body_base * chosen.x);
      const double normal_sigma = std::sqrt(noise_.NormalVariance(u, range, chosen.n));
      if (chosen.range) {
        m.kind = PointMatch::Kind::kRange;
        m.inv_sigma = c / normal_sigma;
      } else {
        m.kind = PointMatch::Kind::kPlane;
        m.inv_sigma = 1.0 / normal_sigma;
      }
      whitened = chosen.signed_distance / normal_sigma;
    } else {
      // Eq. 7 and the paper's shadow rule: flagged and far from the closest primitive: zero error.
      const Scene::Nearest& near = near_point();
      if (near.distance > options_.shadow_distance && flagged()) {
        labels_[i] = PointLabel::kShadow;
        matches_[i] = m;
        return;
      }
      m.kind = PointMatch::Kind::kClosest;
      m.primitive = near.primitive;
      m.body = scene_.primitives()[static_cast<std::size_t>(near.primitive)].body;
      m.sqrt_information = noise_.SqrtInformation(u, range);
      whitened = (m.sqrt_information * (rp.p - near.point)).norm();
      if (GateRejects(i, whitened / kChi3MedianRatio)) {
        labels_[i] = PointLabel::kOutlier;
        matches_[i] = m;
        return;
      }
    }
    whitened_[i] = m.kind == PointMatch::Kind::kClosest ? whitened / kChi3MedianRatio : whitened;
    const double w = std::sqrt(RobustWeight(options_.loss, options_.loss_scale, whitened));
    m.sqrt_information *= w;
    m.inv_sigma *= w;
    labels_[i] = Informs(m.body) ? PointLabel::kInlier : PointLabel::kFixed;
    matches_[i] = m;
  }

  bool GateActive() const { return options_.gate_sigmas > 0.0 && scale_known_; }
  // The gate's verdict on point i, `sigmas` off its face. Once the steps are small (the scale is
  // held) the verdicts are held too: points at the gate would otherwise flip in and out, and the
  // pose with them, by a fraction of its uncertainty, without end.
  bool GateRejects(std::size_t i, double sigmas) {
    if (!GateActive()) return false;
    if (gate_held_) return gate_out_[i] != 0;
    gate_out_[i] = sigmas > options_.gate_sigmas;
    return gate_out_[i] != 0;
  }

  int CountInliers() const {
    int n = 0;
    for (auto l : labels_) n += l == PointLabel::kInlier;
    return n;
  }

  // The parameter blocks and cost functions of the current matches.
  struct Built {
    std::unique_ptr<ceres::Problem> problem;
    std::vector<Params> x;
    Params x_laser{};
    std::vector<Eigen::Matrix3d> R0;
    Eigen::Matrix3d R0_laser{Eigen::Matrix3d::Identity()};
    std::vector<double*> free_blocks;  // laser first (calibration), then free bodies in order
    std::vector<int> block_body;       // -1: the laser
    int num_residuals{0};
  };

  // stride: every stride-th informative point (coarse steps); the information uses all.
  Built Build(bool with_priors, int stride = 1) {
    Built b;
    ceres::Problem::Options po;
    po.cost_function_ownership = ceres::TAKE_OWNERSHIP;
    b.problem = std::make_unique<ceres::Problem>(po);
    b.x.resize(poses_.size());
    b.R0.resize(poses_.size());
    for (std::size_t k = 0; k < poses_.size(); ++k) {
      b.x[k] = ParamsAt(poses_[k]);
      b.R0[k] = poses_[k].linear();
    }
    b.x_laser = ParamsAt(laser_);
    b.R0_laser = laser_.linear();

    // Group the informative points by body, in chunks.
    std::vector<std::vector<std::size_t>> by_body(poses_.size());
    for (std::size_t i = 0; i < matches_.size(); i += static_cast<std::size_t>(stride))
      if (labels_[i] == PointLabel::kInlier) by_body[static_cast<std::size_t>(matches_[i].body)].push_back(i);

    for (std::size_t k = 0; k < poses_.size(); ++k) {
      const auto& idx = by_body[k];
      for (std::size_t c = 0; c < idx.size(); c += kChunk) {
        const std::size_t end = std::min(idx.size(), c + kChunk);
        std::vector<const PointMatch*> ms;
        for (std::size_t j = c; j < end; ++j) {
          ms.push_back(&matches_[idx[j]]);
          b.num_residuals += matches_[idx[j]].NumResiduals();
        }
        if (calibrating_) {
          std::vector<const SweepPoint*> ps;
          for (std::size_t j = c; j < end; ++j) ps.push_back(&(*input_.sweep)[idx[j]]);
          b.problem->AddResidualBlock(new CalibrationChunk(scene_, b.R0_laser, b.R0[k], std::move(ps), std::move(ms),
                                                           input_.autodiff),
                                      nullptr, b.x_laser.data(), b.x[k].data());
        } else {
          std::vector<RayT<double>> ps;
          for (std::size_t j = c; j < end; ++j) {
            const RayPoint& rp = (*input_.cloud)[idx[j]];
            const double range = rp.Range();
            ps.push_back({rp.origin, (rp.p - rp.origin) / range, range});
          }
          b.problem->AddResidualBlock(new RegistrationChunk(scene_, b.R0[k], std::move(ps), std::move(ms)), nullptr,
                                      b.x[k].data());
        }
      }
    }
    auto add_block = [&](double* block, int body) {
      if (!b.problem->HasParameterBlock(block)) b.problem->AddParameterBlock(block, 6);
      if (body >= 0 && with_priors) {  // (the information is wanted over all 6 components)
        std::vector<int> held;
        for (int c = 0; c < 6; ++c)
          if (bodies_[static_cast<std::size_t>(body)].fixed[static_cast<std::size_t>(c)]) held.push_back(c);
        if (held.size() == 6) b.problem->SetParameterBlockConstant(block);
        else if (!held.empty()) b.problem->SetManifold(block, new ceres::SubsetManifold(6, held));
      }
      b.free_blocks.push_back(block);
      b.block_body.push_back(body);
      if (with_priors) {
        Params start;
        std::copy(block, block + 6, start.begin());
        b.problem->AddResidualBlock(
            new StepPrior(start, options_.step_sigma_translation, options_.step_sigma_rotation), nullptr, block);
      }
    };
    if (calibrating_) add_block(b.x_laser.data(), -1);
    for (std::size_t k = 0; k < poses_.size(); ++k) {
      if (bodies_[k].free) {
        add_block(b.x[k].data(), static_cast<int>(k));
      } else if (b.problem->HasParameterBlock(b.x[k].data())) {
        b.problem->SetParameterBlockConstant(b.x[k].data());
      }
    }
    return b;
  }

  // The least-squares problem of one correspondence step: the informative points grouped by body,
  // and the free parameter blocks (6 each: the laser first when calibrating, then the free bodies).
  struct StepProblem {
    std::vector<Params> x0;  // every body at the step's start ([t, 0] about R0)
    Params x0_laser{};
    std::vector<Eigen::Matrix3d> R0;
    Eigen::Matrix3d R0_laser{Eigen::Matrix3d::Identity()};
    std::vector<std::vector<std::size_t>> points;  // per body: its informative points
    struct Chunk {
      std::size_t body, begin, end;
    };
    std::vector<Chunk> chunks;
    int laser_block{-1};          // offset of the laser's block in x, -1 held
    std::vector<int> body_block;  // per body: offset of its block in x, -1 held
    std::vector<int> block_body;  // per block: its body, -1 the laser
    int num_parameters{0};
    int num_residuals{0};
    bool priors{false};  // damp the step: (x - x0) / step sigma per free block
    std::vector<char> held;  // per parameter: held at its start (a body's fixed components; step problems only)

    Eigen::VectorXd Start() const {
      Eigen::VectorXd x(num_parameters);
      if (laser_block >= 0) x.segment<6>(laser_block) = Eigen::Map<const Vector6>(x0_laser.data());
      for (std::size_t k = 0; k < x0.size(); ++k)
        if (body_block[k] >= 0) x.segment<6>(body_block[k]) = Eigen::Map<const Vector6>(x0[k].data());
      return x;
    }
    Params Laser(const Eigen::VectorXd& x) const { return laser_block < 0 ? x0_laser : Block(x, laser_block); }
    Params Body(const Eigen::VectorXd& x, std::size_t k) const {
      return body_block[k] < 0 ? x0[k] : Block(x, body_block[k]);
    }
    static Params Block(const Eigen::VectorXd& x, int offset) {
      Params p;
      for (int c = 0; c < 6; ++c) p[static_cast<std::size_t>(c)] = x[offset + c];
      return p;
    }
  };

  // stride: every stride-th informative point (coarse steps); the information uses all.
  StepProblem MakeStepProblem(bool with_priors, int stride = 1) const {
    StepProblem p;
    p.priors = with_priors;
    p.x0.resize(poses_.size());
    p.R0.resize(poses_.size());
    for (std::size_t k = 0; k < poses_.size(); ++k) {
      p.x0[k] = ParamsAt(poses_[k]);
      p.R0[k] = poses_[k].linear();
    }
    p.x0_laser = ParamsAt(laser_);
    p.R0_laser = laser_.linear();
    p.points.resize(poses_.size());
    for (std::size_t i = 0; i < matches_.size(); i += static_cast<std::size_t>(stride)) {
      if (labels_[i] != PointLabel::kInlier) continue;
      const auto k = static_cast<std::size_t>(matches_[i].body);
      p.points[k].push_back(i);
      p.num_residuals += matches_[i].NumResiduals();
    }
    for (std::size_t k = 0; k < poses_.size(); ++k)
      for (std::size_t c = 0; c < p.points[k].size(); c += kChunk)
        p.chunks.push_back({k, c, std::min(p.points[k].size(), c + kChunk)});
    if (calibrating_) {
      p.laser_block = p.num_parameters;
      p.block_body.push_back(-1);
      p.num_parameters += 6;
    }
    p.body_block.assign(poses_.size(), -1);
    for (std::size_t k = 0; k < poses_.size(); ++k) {
      if (!bodies_[k].free) continue;
      p.body_block[k] = p.num_parameters;
      p.block_body.push_back(static_cast<int>(k));
      p.num_parameters += 6;
    }
    p.held.assign(static_cast<std::size_t>(p.num_parameters), 0);
    if (with_priors)  // (the information is wanted over all 6 components)
      for (std::size_t b = 0; b < p.block_body.size(); ++b)
        for (int c = 0; c < 6; ++c)
          p.held[6 * b + static_cast<std::size_t>(c)] =
              p.block_body[b] >= 0 && bodies_[static_cast<std::size_t>(p.block_body[b])].fixed[static_cast<std::size_t>(c)];
    return p;
  }

  // 0.5 |r(x)|^2 of the step problem and, when H and g are given (sized and zeroed), J^T J and
  // J^T r over its free blocks, accumulated point by point (the Jacobian is never stored). Chunks
  // are summed in a fixed order, so the result does not depend on the number of threads.
  bool Evaluate(const StepProblem& p, const Eigen::VectorXd& x, double* cost, Eigen::MatrixXd* H, Eigen::VectorXd* g) const {
    const bool jacobians = H != nullptr;
    const Params xl = p.Laser(x);
    const PoseJacobianData XL(xl.data(), p.R0_laser);
    std::vector<Params> xb(poses_.size());
    std::vector<PoseJacobianData> XB;
    XB.reserve(poses_.size());
    for (std::size_t k = 0; k < poses_.size(); ++k) {
      xb[k] = p.Body(x, k);
      XB.emplace_back(xb[k].data(), p.R0[k]);
    }
    const bool laser_free = p.laser_block >= 0;
    std::vector<BodyAccumulator> sums(p.chunks.size());
    auto run = [&](std::size_t c) {
      const auto& chunk = p.chunks[c];
      const std::size_t k = chunk.body;
      BodyAccumulator& acc = sums[c];
      PointTerms t;
      for (std::size_t j = chunk.begin; j < chunk.end; ++j) {
        const std::size_t i = p.points[k][j];
        const PointMatch& m = matches_[i];
        const ScenePrimitive* prim = m.primitive >= 0 ? &scene_.primitives()[static_cast<std::size_t>(m.primitive)] : nullptr;
        if (!calibrating_) {
          RegistrationTerms(m, prim, rays_[i], XB[k], jacobians, t);
        } else if (input_.autodiff) {
          CalibrationTermsAutodiff(m, prim, (*input_.sweep)[i], xl.data(), p.R0_laser, xb[k].data(), p.R0[k], jacobians, t);
        } else {
          CalibrationTerms(m, prim, (*input_.sweep)[i], XL, XB[k], jacobians, t);
        }
        acc.Add(t, jacobians, laser_free);
      }
    };
    if (options_.num_threads > 1 && p.chunks.size() > 1) {
      tbb::task_arena arena(options_.num_threads);
      arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, p.chunks.size()), [&](const tbb::blocked_range<std::size_t>& r) {
          for (std::size_t c = r.begin(); c != r.end(); ++c) run(c);
        });
      });
    } else {
      for (std::size_t c = 0; c < p.chunks.size(); ++c) run(c);
    }
    std::vector<BodyAccumulator> body_sums(poses_.size());
    for (std::size_t c = 0; c < p.chunks.size(); ++c) body_sums[p.chunks[c].body].Add(sums[c]);
    *cost = 0.0;
    for (std::size_t k = 0; k < poses_.size(); ++k) {
      const BodyAccumulator& a = body_sums[k];
      *cost += a.cost;
      if (!jacobians) continue;
      const int ob = p.body_block[k], ol = p.laser_block;
      if (ob >= 0) {
        H->block<6, 6>(ob, ob) += a.H_body;
        g->segment<6>(ob) += a.g_body;
      }
      if (ol >= 0) {
        H->block<6, 6>(ol, ol) += a.H_laser;
        g->segment<6>(ol) += a.g_laser;
        if (ob >= 0) {
          H->block<6, 6>(ol, ob) += a.H_laser_body;
          H->block<6, 6>(ob, ol) += a.H_laser_body.transpose();
        }
      }
    }
    if (p.priors) {
      // Damping of one step: (x - x_start) / sigma. Re-centred every step, so it holds directions
      // the data leave free without pulling the others (the data's information is many orders larger).
      const Eigen::VectorXd d = x - p.Start();
      for (int c = 0; c < p.num_parameters; ++c) {
        const double sigma = c % 6 < 3 ? options_.step_sigma_translation : options_.step_sigma_rotation;
        const double w2 = 1.0 / (sigma * sigma);
        *cost += 0.5 * w2 * d[c] * d[c];
        if (jacobians) {
          (*H)(c, c) += w2;
          (*g)[c] += w2 * d[c];
        }
      }
    }
    if (jacobians) {
      // Held components (a SubsetManifold in Ceres's terms): no gradient, no coupling, unit
      // curvature, so every LM step leaves them at their start and moves the rest as the
      // reduced problem would.
      for (int c = 0; c < p.num_parameters; ++c) {
        if (!p.held[static_cast<std::size_t>(c)]) continue;
        H->row(c).setZero();
        H->col(c).setZero();
        (*H)(c, c) = 1.0;
        (*g)[c] = 0.0;
      }
    }
    return std::isfinite(*cost);
  }

  // One step's solve with the Ceres problem (options.solver = ceres): the reference the
  // normal-equation solve is tested against.
  bool SolveWithCeres(std::vector<Params>& x_body, Params& x_laser, std::vector<Eigen::Matrix3d>& R0,
                      Eigen::Matrix3d& R0_laser, std::string& message) {
    Built b = Build(/*with_priors=*/true, stride_);
    ceres::Solver::Options so;
    so.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
    so.max_num_iterations = options_.max_solver_iterations;
    so.function_tolerance = 1e-10;
    so.gradient_tolerance = 1e-14;
    so.parameter_tolerance = 1e-10;
    so.num_threads = options_.num_threads;
    so.logging_type = ceres::SILENT;
    ceres::Solver::Summary summary;
    ceres::Solve(so, b.problem.get(), &summary);
    spdlog::debug("registration step: {}", summary.BriefReport());
    if (!summary.IsSolutionUsable()) {
      message = "Ceres: " + summary.message;
      return false;
    }
    x_body = b.x;
    x_laser = b.x_laser;
    R0 = b.R0;
    R0_laser = b.R0_laser;
    return true;
  }

  // The same step by LM on normal equations accumulated point by point (dense_lm.h).
  bool SolveNormalEquations(std::vector<Params>& x_body, Params& x_laser, std::vector<Eigen::Matrix3d>& R0,
                            Eigen::Matrix3d& R0_laser, std::string& message) {
    const StepProblem p = MakeStepProblem(/*with_priors=*/true, stride_);
    DenseLmOptions lm;
    lm.max_iterations = options_.max_solver_iterations;
    Eigen::VectorXd x = p.Start();
    const DenseLmSummary summary = SolveDenseLm(
        [&](const Eigen::VectorXd& at, double* cost, Eigen::MatrixXd* H, Eigen::VectorXd* g) {
          return Evaluate(p, at, cost, H, g);
        },
        x, lm);
    spdlog::debug("registration step: {} ({} iterations, cost {:.6g} -> {:.6g})", summary.message, summary.iterations,
                  summary.initial_cost, summary.final_cost);
    if (!summary.usable) {
      message = "solver: " + summary.message;
      return false;
    }
    x_laser = p.Laser(x);
    x_body.resize(poses_.size());
    for (std::size_t k = 0; k < poses_.size(); ++k) x_body[k] = p.Body(x, k);
    R0 = p.R0;
    R0_laser = p.R0_laser;
    return true;
  }

  StepResult Step() {
    StepResult r;
    std::vector<Params> x_body;
    Params x_laser{};
    std::vector<Eigen::Matrix3d> R0;
    Eigen::Matrix3d R0_laser;
    const bool solved_ok = options_.solver == LeastSquaresSolver::kCeres
                               ? SolveWithCeres(x_body, x_laser, R0, R0_laser, r.message)
                               : SolveNormalEquations(x_body, x_laser, R0, R0_laser, r.message);
    if (!solved_ok) {
      r.ok = false;
      return r;
    }
    // The solved step as one vector (translations, rotations at a 0.1 m lever). When it turns
    // back on the previous one, the face assignments are flipping between two states: take only
    // a fraction of it (halved at every reversal), so the iteration settles between them.
    std::vector<Pose3> solved;
    Eigen::VectorXd delta = Eigen::VectorXd::Zero(6 * static_cast<Eigen::Index>(poses_.size() + 1));
    for (std::size_t k = 0; k <= poses_.size(); ++k) {
      const bool laser = k == poses_.size();
      if (laser ? !calibrating_ : !bodies_[k].free) {
        solved.push_back(laser ? laser_ : poses_[k]);
        continue;
      }
      const Params& x = laser ? x_laser : x_body[k];
      const Pose3& before = laser ? laser_ : poses_[k];
      solved.push_back(ApplyParams(x, laser ? R0_laser : R0[k]));
      delta.segment<3>(6 * static_cast<Eigen::Index>(k)) = solved.back().translation() - before.translation();
      delta.segment<3>(6 * static_cast<Eigen::Index>(k) + 3) = 0.1 * Eigen::Vector3d(x[3], x[4], x[5]);
    }
    if (previous_delta_.size() == delta.size() && delta.dot(previous_delta_) < -0.3 * delta.norm() * previous_delta_.norm())
      relaxation_ = std::max(relaxation_ / 2.0, 1.0 / 64.0);
    else
      relaxation_ = std::min(relaxation_ * 1.5, 1.0);
    previous_delta_ = delta;
    std::vector<Pose3> moves;  // T_next * T_before^-1 per body
    for (std::size_t k = 0; k <= poses_.size(); ++k) {
      Pose3& pose = k == poses_.size() ? laser_ : poses_[k];
      const Pose3 next = Interpolate(pose, solved[k], relaxation_);
      r.max_translation = std::max(r.max_translation, (next.translation() - pose.translation()).norm());
      r.max_rotation = std::max(r.max_rotation, RotationAngle(next, pose));
      moves.push_back(next * pose.inverse());
      pose = next;
    }
    if (options_.convergence == Convergence::kResiduals && !calibrating_) {
      // How far the step moved the model under each inlier, along its normal: motion the data
      // do not see (a plane sliding in itself, turning about its normal) does not count.
      r.max_translation = r.max_rotation = 0.0;
      for (std::size_t i = 0; i < matches_.size(); ++i) {
        if (labels_[i] != PointLabel::kInlier) continue;
        const PointMatch& m = matches_[i];
        const Eigen::Vector3d& p = (*input_.cloud)[i].p;
        const Pose3& T_move = moves[static_cast<std::size_t>(m.body)];
        const Eigen::Vector3d d = T_move * p - p;
        const double along = m.kind == PointMatch::Kind::kClosest
                                 ? d.norm()
                                 : std::abs((T_move.linear() * inverse_poses_[static_cast<std::size_t>(m.body)].linear().transpose() *
                                             m.normal_body).dot(d));
        r.max_translation = std::max(r.max_translation, along);
      }
    }
    spdlog::debug("registration step: moved {:.3g} m, {:.3g} rad, relaxation {}", r.max_translation, r.max_rotation, relaxation_);
    return r;
  }

  void Finish(PoseProblemOutput& out, std::chrono::steady_clock::time_point start) {
    RegistrationSummary& s = out.summary;
    out.T_tool0_laser = laser_;
    s.labels = labels_;
    s.point_body.assign(matches_.size(), -1);
    for (std::size_t i = 0; i < matches_.size(); ++i) {
      if (labels_[i] == PointLabel::kInlier || labels_[i] == PointLabel::kFixed) s.point_body[i] = matches_[i].body;
      s.num_inliers += labels_[i] == PointLabel::kInlier;
      s.num_shadow_flagged += flagged_[i];
      s.num_shadow_removed += labels_[i] == PointLabel::kShadow;
      s.num_outliers += labels_[i] == PointLabel::kOutlier;
      s.num_grazing += labels_[i] == PointLabel::kGrazing;
    }
    for (std::size_t k = 0; k < bodies_.size(); ++k) {
      RegisteredBody rb;
      rb.name = bodies_[k].name;
      rb.free = bodies_[k].free;
      static const char* kNames[6] = {"x", "y", "z", "rx", "ry", "rz"};
      for (int c = 0; c < 6; ++c)
        if (bodies_[k].fixed[static_cast<std::size_t>(c)]) rb.fixed.push_back(kNames[c]);
      rb.T_base_body = poses_[k];
      for (std::size_t i = 0; i < matches_.size(); ++i)
        rb.inliers += labels_[i] == PointLabel::kInlier && matches_[i].body == static_cast<int>(k);
      s.bodies.push_back(rb);
    }
    if (s.num_inliers > 0) Information(out);
    std::vector<double> inlier_whitened;
    for (std::size_t i = 0; i < matches_.size(); ++i)
      if (labels_[i] == PointLabel::kInlier) inlier_whitened.push_back(whitened_[i]);
    s.fit = AssessFit(inlier_whitened, s.cost, num_residuals_, num_parameters_, options_.fit_tolerance,
                      options_.noise_source == NoiseSource::kEstimated, options_.gate_sigmas);
    s.fit.noise = noise_;
    s.fit.noise_scale = noise_scale_;
    s.fit.noise_source = options_.noise_source == NoiseSource::kEstimated
                             ? fmt::format("estimated from the residuals (shape of {}, scaled {:.3f}x)", options_.noise_name,
                                           noise_scale_)
                             : options_.noise_name;
    for (const auto& rb : s.bodies)
      if (!rb.unconstrained.empty())
        s.warnings.push_back(fmt::format("body '{}' is not constrained by the scan in {} direction(s): {}", rb.name,
                                         rb.unconstrained.size(), fmt::join(rb.unconstrained, ", ")));
    if (!out.laser_unconstrained.empty())
      s.warnings.push_back(fmt::format("the laser mount is not constrained by the sweeps in {} direction(s): {}",
                                       out.laser_unconstrained.size(), fmt::join(out.laser_unconstrained, ", ")));
    s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }

  // Cost and J^T J at the final poses from the Ceres problem (options.solver = ceres).
  void InformationWithCeres(double& cost, int& num_residuals, std::vector<int>& block_body, Eigen::MatrixXd& H) {
    Built b = Build(/*with_priors=*/false);
    ceres::Problem::EvaluateOptions eo;
    eo.parameter_blocks = b.free_blocks;
    eo.apply_loss_function = false;
    ceres::CRSMatrix crs;
    if (b.free_blocks.empty()) {
      b.problem->Evaluate(ceres::Problem::EvaluateOptions(), &cost, nullptr, nullptr, nullptr);
    } else {
      b.problem->Evaluate(eo, &cost, nullptr, nullptr, &crs);
    }
    num_residuals = b.num_residuals;
    block_body = b.block_body;
    const int n = static_cast<int>(b.free_blocks.size()) * 6;
    H = Eigen::MatrixXd::Zero(n, n);
    for (int row = 0; row < crs.num_rows; ++row) {
      for (int a = crs.rows[static_cast<std::size_t>(row)]; a < crs.rows[static_cast<std::size_t>(row) + 1]; ++a) {
        for (int c = a; c < crs.rows[static_cast<std::size_t>(row) + 1]; ++c) {
          const double v = crs.values[static_cast<std::size_t>(a)] * crs.values[static_cast<std::size_t>(c)];
          const int i = crs.cols[static_cast<std::size_t>(a)], j = crs.cols[static_cast<std::size_t>(c)];
          H(i, j) += v;
          if (i != j) H(j, i) += v;
        }
      }
    }
  }

  // Cost, covariance and unconstrained directions at the final poses from J^T J.
  void Information(PoseProblemOutput& out) {
    RegistrationSummary& s = out.summary;
    double cost = 0.0;
    int num_residuals = 0;
    std::vector<int> block_body;
    Eigen::MatrixXd H;
    if (options_.solver == LeastSquaresSolver::kCeres) {
      InformationWithCeres(cost, num_residuals, block_body, H);
    } else {
      const StepProblem p = MakeStepProblem(/*with_priors=*/false);
      H = Eigen::MatrixXd::Zero(p.num_parameters, p.num_parameters);
      Eigen::VectorXd g = Eigen::VectorXd::Zero(p.num_parameters);
      Evaluate(p, p.Start(), &cost, &H, &g);
      num_residuals = p.num_residuals;
      block_body = p.block_body;
    }
    s.cost = cost;
    s.rms_whitened = num_residuals > 0 ? std::sqrt(2.0 * cost / num_residuals) : 0.0;
    if (block_body.empty()) return;
    const int n = static_cast<int>(block_body.size()) * 6;
    // Held components are no parameters; the rest are scaled to the residuals' actual spread (the
    // a-posteriori variance factor), so error bars widen when the noise model is too optimistic.
    std::vector<char> held(static_cast<std::size_t>(n), 0);
    for (std::size_t k = 0; k < block_body.size(); ++k)
      for (int c = 0; c < 6; ++c)
        held[k * 6 + static_cast<std::size_t>(c)] =
            block_body[k] >= 0 && bodies_[static_cast<std::size_t>(block_body[k])].fixed[static_cast<std::size_t>(c)];
    num_residuals_ = num_residuals;
    num_parameters_ = n - static_cast<int>(std::count(held.begin(), held.end(), 1));
    const double s0_squared = num_residuals > num_parameters_ ? 2.0 * cost / (num_residuals - num_parameters_) : 1.0;
    if (s0_squared > 0.0) H /= s0_squared;
    Eigen::VectorXd prior(n);
    for (int k = 0; k < n; ++k) {
      const double sigma = (k % 6) < 3 ? options_.prior_sigma_translation : options_.prior_sigma_rotation;
      prior[k] = 1.0 / (sigma * sigma);
      if (held[static_cast<std::size_t>(k)]) H(k, k) += 1e12;  // known exactly
    }
    const Eigen::MatrixXd H_reg = H + Eigen::MatrixXd(prior.asDiagonal());
    const Eigen::MatrixXd covariance = H_reg.ldlt().solve(Eigen::MatrixXd::Identity(n, n));
    for (std::size_t k = 0; k < block_body.size(); ++k) {
      const int o = static_cast<int>(k) * 6;
      // Marginal information of this block: Schur complement over the others (regularised).
      Matrix6d marginal = H.block(o, o, 6, 6);
      if (n > 6) {
        std::vector<int> rest;
        for (int j = 0; j < n; ++j)
          if (j < o || j >= o + 6) rest.push_back(j);
        const int m = static_cast<int>(rest.size());
        Eigen::MatrixXd H_rr(m, m), H_kr(6, m);
        for (int a = 0; a < m; ++a) {
          for (int c = 0; c < m; ++c) H_rr(a, c) = H_reg(rest[static_cast<std::size_t>(a)], rest[static_cast<std::size_t>(c)]);
          for (int r = 0; r < 6; ++r) H_kr(r, a) = H(o + r, rest[static_cast<std::size_t>(a)]);
        }
        marginal -= H_kr * H_rr.ldlt().solve(H_kr.transpose());
      }
      const int body = block_body[k];
      const double extent = body < 0 ? input_.laser_extent : scene_.Extent(body);
      const auto free_dirs = UnconstrainedDirections(marginal, extent, options_.unconstrained_std);
      Matrix6d cov = covariance.block(o, o, 6, 6);
      for (int c = 0; c < 6; ++c)
        if (held[static_cast<std::size_t>(o + c)]) cov.row(c).setZero(), cov.col(c).setZero();
      if (body < 0) {
        out.laser_covariance = cov;
        out.laser_unconstrained = free_dirs;
      } else {
        s.bodies[static_cast<std::size_t>(body)].covariance = cov;
        s.bodies[static_cast<std::size_t>(body)].unconstrained = free_dirs;
      }
    }
  }

  const PoseProblemInput& input_;
  const std::vector<RegistrationBody>& bodies_;
  RegistrationOptions options_;
  Scene scene_;
  std::vector<Pose3> poses_, inverse_poses_;
  Pose3 laser_{Pose3::Identity()};
  bool calibrating_{false};
  std::vector<PointMatch> matches_;
  std::vector<double> whitened_;  // per point: its error over the noise model's sigma (before the loss)
  LaserNoiseModel noise_;         // options_.noise, or scaled to the residuals (kEstimated)
  bool scale_known_{true};
  // The incidence limits as cosines, once: two std::cos per point and match step were 1.5 % of a run.
  double cos_max_incidence_{0.0}, cos_min_incidence_{1.0};
  bool scale_frozen_{false};
  bool gate_held_{false};
  std::vector<char> gate_out_;  // per point: rejected by the gate (when gate_held_)
  double noise_scale_{1.0};
  int num_residuals_{0}, num_parameters_{0};
  std::vector<PointLabel> labels_;
  std::vector<char> flagged_;
  std::vector<RayT<double>> rays_;  // registration: each point's ray (origin, unit direction, range)
  bool flag_all_{false};  // ask every point's edge test (the final Match: the summary counts them)
};

}  // namespace

PoseProblemOutput SolvePoseProblem(const PoseProblemInput& input, const std::vector<RegistrationBody>& bodies,
                                   const RegistrationOptions& options) {
  IFAB_CHECK((input.cloud != nullptr) != (input.sweep != nullptr));
  Engine engine(input, bodies, options);
  return engine.Run();
}

}  // namespace ifab::internal
