#include "ifab/perception/registration.h"

#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include <chrono>
#include <algorithm>
#include <cmath>
#include <iterator>

#include "ifab/core/config.h"
#include "ifab/perception/pose_solver.h"

namespace ifab {
RegistrationOptions RegistrationOptions::FromConfig(const ConfigNode& c, RegistrationOptions o) {
  c.ExpectKeys({"noise", "noise_source", "gate_sigmas", "fit_tolerance", "convergence", "residual", "max_iterations", "coarse_stride", "max_solver_iterations", "solver", "translation_tolerance",
                "rotation_tolerance", "shadow_points", "shadow_edge_distance", "shadow_distance", "shadow_sigmas", "max_distance", "max_incidence_deg", "min_incidence_deg",
                "loss", "loss_scale", "step_sigma_translation", "step_sigma_rotation", "restarts", "restart_distance", "prior_sigma_translation", "prior_sigma_rotation", "unconstrained_std",
                "num_threads"});
  if (auto n = c.Find("noise")) {
    o.noise = LaserNoiseModel::FromConfig(*n, o.noise);
    o.noise_name = "noise: of " + c.file();
  }
  if (auto n = c.Find("noise_source")) {
    const auto v = n->As<std::string>();
    if (v == "model") o.noise_source = NoiseSource::kModel;
    else if (v == "estimated") o.noise_source = NoiseSource::kEstimated;
    else n->Fail("one of: model (the noise: section, a sensor profile), estimated (scaled to the residuals)");
  }
  c.ReadNonNegative("gate_sigmas", o.gate_sigmas);
  if (auto v = c.Find("convergence")) {
    const auto t = v->As<std::string>();
    if (t == "pose") o.convergence = Convergence::kPose;
    else if (t == "residuals") o.convergence = Convergence::kResiduals;
    else v->Fail("one of: pose (the paper), residuals (the model under the inliers stops moving)");
  }
  c.ReadNonNegative("fit_tolerance", o.fit_tolerance);
  if (o.fit_tolerance > 0.0 && o.fit_tolerance <= 1.0) c["fit_tolerance"].Fail("a factor above 1 (or 0: no test)");
  if (auto r = c.Find("residual")) {
    const auto v = r->As<std::string>();
    if (v == "closest") o.residual = RegistrationResidual::kClosest;
    else if (v == "ray") o.residual = RegistrationResidual::kRay;
    else r->Fail("one of: closest (eq. 7, the paper), ray (range to the face the ray hits)");
  }
  c.ReadPositive("max_iterations", o.max_iterations);
  c.ReadPositive("coarse_stride", o.coarse_stride);
  c.ReadPositive("max_solver_iterations", o.max_solver_iterations);
  if (auto v = c.Find("solver")) {
    const auto t = v->As<std::string>();
    if (t == "normal_equations") o.solver = LeastSquaresSolver::kNormalEquations;
    else if (t == "ceres") o.solver = LeastSquaresSolver::kCeres;
    else v->Fail("one of: normal_equations (LM on accumulated J^T J), ceres (a Ceres problem, the reference)");
  }
  c.ReadPositive("translation_tolerance", o.translation_tolerance);
  c.ReadPositive("rotation_tolerance", o.rotation_tolerance);
  c.Read("shadow_points", o.shadow_points);
  c.ReadNonNegative("shadow_edge_distance", o.shadow_edge_distance);
  c.ReadNonNegative("shadow_distance", o.shadow_distance);
  c.ReadNonNegative("shadow_sigmas", o.shadow_sigmas);
  c.ReadNonNegative("max_distance", o.max_distance);
  if (c.Has("max_incidence_deg")) {
    double deg = o.max_incidence * 180.0 / M_PI;
    c.ReadInRange("max_incidence_deg", deg, 0.0, 90.0);
    o.max_incidence = deg * M_PI / 180.0;
  }
  if (c.Has("min_incidence_deg")) {
    double deg = o.min_incidence * 180.0 / M_PI;
    c.ReadInRange("min_incidence_deg", deg, 0.0, 90.0);
    o.min_incidence = deg * M_PI / 180.0;
  }
  if (o.min_incidence >= o.max_incidence) c["min_incidence_deg"].Fail("an angle below max_incidence_deg");
  if (auto l = c.Find("loss")) {
    const auto v = l->As<std::string>();
    if (v == "none") o.loss = RobustLoss::kNone;
    else if (v == "huber") o.loss = RobustLoss::kHuber;
    else if (v == "cauchy") o.loss = RobustLoss::kCauchy;
    else l->Fail("one of: none, huber, cauchy");
  }
  c.ReadPositive("loss_scale", o.loss_scale);
  c.ReadPositive("step_sigma_translation", o.step_sigma_translation);
  c.ReadPositive("step_sigma_rotation", o.step_sigma_rotation);
  c.ReadNonNegative("restarts", o.restarts);
  c.ReadPositive("restart_distance", o.restart_distance);
  c.ReadPositive("prior_sigma_translation", o.prior_sigma_translation);
  c.ReadPositive("prior_sigma_rotation", o.prior_sigma_rotation);
  c.ReadPositive("unconstrained_std", o.unconstrained_std);
  c.ReadPositive("num_threads", o.num_threads);
  return o;
}

const char* ToString(RegistrationStatus status) {
  switch (status) {
    case RegistrationStatus::kConverged: return "converged";
    case RegistrationStatus::kMaxIterations: return "max_iterations";
    case RegistrationStatus::kNoPoints: return "no_points";
    case RegistrationStatus::kSolverFailed: return "solver_failed";
  }
  return "unknown";
}

const RegisteredBody* RegistrationSummary::Find(const std::string& name) const {
  for (const auto& b : bodies)
    if (b.name == name) return &b;
  return nullptr;
}

std::string RegistrationSummary::BriefReport() const {
  std::string s = fmt::format("registration {} ({}): {} points, {} inliers, {} shadow points removed ({} flagged), "
                              "{} outliers, {} grazing, rms {:.2f} sigma, {} steps, {:.3f} s; noise: {}; fit: {}",
                              ToString(status), message, num_points, num_inliers, num_shadow_removed,
                              num_shadow_flagged, num_outliers, num_grazing, rms_whitened, iterations, seconds,
                              fit.noise_source, fit.message);
  for (const auto& b : bodies) {
    const auto v = XyzRpyFromPose(b.T_base_body);
    s += fmt::format("\n  {} {}: [{:.4f} {:.4f} {:.4f}] m, [{:.3f} {:.3f} {:.3f}] deg, {} inliers, std "
                     "[{:.2f} {:.2f} {:.2f}] mm [{:.3f} {:.3f} {:.3f}] deg",
                     b.name, b.free ? "free" : "fixed", v[0], v[1], v[2], v[3] * 180 / M_PI, v[4] * 180 / M_PI,
                     v[5] * 180 / M_PI, b.inliers, 1e3 * std::sqrt(b.covariance(0, 0)), 1e3 * std::sqrt(b.covariance(1, 1)),
                     1e3 * std::sqrt(b.covariance(2, 2)), std::sqrt(b.covariance(3, 3)) * 180 / M_PI,
                     std::sqrt(b.covariance(4, 4)) * 180 / M_PI, std::sqrt(b.covariance(5, 5)) * 180 / M_PI);
  }
  for (const auto& w : warnings) s += "\n  warning: " + w;
  return s;
}

RegistrationSummary Register(const std::vector<RayPoint>& cloud, const std::vector<RegistrationBody>& bodies,
                             const RegistrationOptions& options) {
  const auto t_start = std::chrono::steady_clock::now();
  internal::PoseProblemInput input;
  input.cloud = &cloud;
  // A non-finite point (from a broken file or driver) would poison every sum: leave it out.
  std::vector<RayPoint> finite;
  const auto is_finite = [](const RayPoint& q) { return q.p.allFinite() && q.origin.allFinite(); };
  if (!std::all_of(cloud.begin(), cloud.end(), is_finite)) {
    std::copy_if(cloud.begin(), cloud.end(), std::back_inserter(finite), is_finite);
    input.cloud = &finite;
  }
  RegistrationSummary best = internal::SolvePoseProblem(input, bodies, options).summary;
  if (input.cloud == &finite)
    best.warnings.push_back(fmt::format("{} non-finite points left out", cloud.size() - finite.size()));
  // Restarts: points near silhouettes switch sides and the alternation can settle in a nearby
  // local minimum along a weakly constrained direction. Start again from the result moved both
  // ways along each body's weakest directions; keep the lowest cost.
  int restarts = 0, returned = 0;
  for (int round = 0; round < options.restarts && best.IsUsable(); ++round) {
    bool improved = false;
    const RegistrationSummary current = best;
    std::vector<Pose3> current_poses;
    for (const auto& b : current.bodies) current_poses.push_back(b.T_base_body);
    for (std::size_t b = 0; b < bodies.size(); ++b) {
      if (!bodies[b].free) continue;
      double extent = 0.0;
      for (const auto& part : bodies[b].parts)
        for (const auto& g : part.primitives)
          if (auto box = Bounds(g, part.T_site_object)) extent = std::max(extent, 0.5 * (box->hi - box->lo).norm());
      if (extent <= 0.0) continue;  // planes only: nothing to hop over
      // Weakest directions of the body's covariance, rotations scaled by its extent.
      Eigen::Matrix<double, 6, 1> d;
      d << 1, 1, 1, extent, extent, extent;
      const Matrix6d scaled = d.asDiagonal() * current.bodies[b].covariance * d.asDiagonal();
      Eigen::SelfAdjointEigenSolver<Matrix6d> eig(0.5 * (scaled + scaled.transpose()));
      // The three weakest directions, and the body's own x and y (a brick's long and short
      // axes, whose silhouettes are what registration leans on).
      std::vector<Eigen::Matrix<double, 6, 1>> directions;
      for (int k = 5; k >= 3; --k) directions.push_back(eig.eigenvectors().col(k));
      for (int axis = 0; axis < 2; ++axis) {
        Eigen::Matrix<double, 6, 1> v = Eigen::Matrix<double, 6, 1>::Zero();
        v.head<3>() = current.bodies[b].T_base_body.linear().col(axis);
        directions.push_back(v);
      }
      for (auto v : directions) {
        for (int c = 0; c < 6; ++c)  // held components stay at the guess
          if (bodies[b].fixed[static_cast<std::size_t>(c)]) v[c] = 0.0;
        if (!(v.norm() > 1e-9)) continue;
        for (double sign : {-1.0, 1.0}) {
          std::vector<RegistrationBody> start = bodies;
          for (std::size_t j = 0; j < bodies.size(); ++j) start[j].T_base_body = current.bodies[j].T_base_body;
          Pose3& T = start[b].T_base_body;
          const double s = sign * options.restart_distance;
          T.linear() = ExpSO3(s * v.tail<3>() / extent) * T.linear();
          T.translation() += s * v.head<3>();
          internal::PoseProblemInput trial_input = input;
          trial_input.return_to = &current_poses;
          internal::PoseProblemOutput trial_out = internal::SolvePoseProblem(trial_input, start, options);
          ++restarts;
          if (trial_out.returned) {
            ++returned;
            continue;
          }
          RegistrationSummary trial = std::move(trial_out.summary);
          if (trial.IsUsable() && trial.cost < best.cost - 1e-9 * std::abs(best.cost)) {
            best = std::move(trial);
            improved = true;
          }
        }
      }
    }
    if (!improved) break;
  }
  if (restarts > 0)
    best.message += fmt::format(" (best of {} restarts, {} of them back at the result they started from)", restarts + 1,
                                returned);
  best.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  return best;
}

std::vector<RegistrationBody> SiteBodies(const Site& site, const Pose3& T_site_base_guess, bool separate_ground) {
  const Pose3 T_base_site = T_site_base_guess.inverse();
  std::vector<RigidObject> objects = site.Objects();
  std::vector<RegistrationBody> bodies;
  RegistrationBody rest{"site", T_base_site, {}, true};
  for (auto& o : objects) {
    const bool is_ground = site.has_ground && o.name == "ground";
    if (is_ground && separate_ground) bodies.push_back({"ground", T_base_site, {o}, true});
    else rest.parts.push_back(o);
  }
  if (!rest.parts.empty()) bodies.push_back(std::move(rest));
  return bodies;
}

std::vector<RegistrationBody> SensorFrameBodies(const Site& site) {
  std::vector<RegistrationBody> bodies;
  for (const SiteObject& o : site.Bodies()) bodies.push_back({o.name, o.T_site_object, o.parts, true});
  return bodies;
}

std::vector<RegisteredPlane> RegisteredPlanes(const RegistrationSummary& summary,
                                              const std::vector<RegistrationBody>& bodies, double max_std) {
  std::vector<RegisteredPlane> out;
  for (std::size_t k = 0; k < bodies.size() && k < summary.bodies.size(); ++k) {
    const RegisteredBody& rb = summary.bodies[k];
    const Pose3& T = rb.T_base_body;
    for (const auto& part : bodies[k].parts) {
      for (const auto& g : part.primitives) {
        Eigen::Vector3d n_part;
        double d_part = 0.0;
        if (const auto* plane = std::get_if<Plane>(&g)) n_part = plane->normal, d_part = plane->offset;
        else if (const auto* poly = std::get_if<ConvexPolygon>(&g)) n_part = poly->normal(), d_part = poly->offset();
        else continue;
        RegisteredPlane p;
        p.body = rb.name;
        const Pose3 T_base_part = T * part.T_site_object;
        p.normal = T_base_part.linear() * n_part;
        p.offset = p.normal.dot(T_base_part * (d_part * n_part));
        // First-order propagation of the pose covariance (perturbation [dt, w] about the body
        // origin t): d offset = n . dt + (n x t) . w, and the normal tilts by w across n.
        const Eigen::Vector3d t = T.translation();
        const Eigen::Vector3d e1 = AnyPerpendicular(p.normal), e2 = p.normal.cross(e1);
        Eigen::Matrix<double, 3, 6> J = Eigen::Matrix<double, 3, 6>::Zero();
        J.block<1, 3>(0, 0) = p.normal.transpose();
        J.block<1, 3>(0, 3) = p.normal.cross(t).transpose();
        J.block<1, 3>(1, 3) = e1.transpose();
        J.block<1, 3>(2, 3) = e2.transpose();
        const Eigen::Matrix3d C = J * rb.covariance * J.transpose();
        p.offset_std = std::sqrt(std::max(0.0, C(0, 0)));
        p.tilt_std = std::sqrt(std::max({0.0, C(1, 1), C(2, 2)}));
        // The tilt is judged at the body's extent, as UnconstrainedDirections does.
        double extent = 0.0;
        if (auto box = Bounds(g, Pose3::Identity())) extent = 0.5 * (box->hi - box->lo).norm();
        p.constrained = rb.free && p.offset_std < max_std && (extent > 0.0 ? p.tilt_std * extent : p.tilt_std) < max_std;
        if (!rb.free) p.constrained = true;
        out.push_back(p);
      }
    }
  }
  return out;
}

SiteLocalization LocalizeInSite(const std::vector<RayPoint>& cloud, const Site& site, const Pose3& T_site_base_guess,
                                const RegistrationOptions& options, bool separate_ground,
                                const std::array<bool, 6>& site_fixed) {
  SiteLocalization out;
  std::vector<RegistrationBody> bodies = SiteBodies(site, T_site_base_guess, separate_ground);
  for (auto& b : bodies)
    if (b.name == "site") b.fixed = site_fixed;
  out.registration = Register(cloud, bodies, options);
  const RegisteredBody* body = out.registration.Find("site");
  if (!body) {  // the site has no object but the ground: nothing to locate the robot by
    out.unconstrained = {"the site has no object besides the ground"};
    return out;
  }
  out.T_site_base = body->T_base_body.inverse();
  out.covariance = InverseCovariance(body->T_base_body, body->covariance);
  out.unconstrained = body->unconstrained;
  return out;
}

Matrix6d InverseCovariance(const Pose3& T, const Matrix6d& covariance) {
  // T = (Exp(w) R, t + d)  =>  T^-1 = (Exp(-R^T w) R^T, -R^T t - R^T d - R^T [t]x w).
  const Eigen::Matrix3d Rt = T.linear().transpose();
  Matrix6d J = Matrix6d::Zero();
  J.block<3, 3>(0, 0) = -Rt;
  J.block<3, 3>(0, 3) = -Rt * Skew(T.translation());
  J.block<3, 3>(3, 3) = -Rt;
  return J * covariance * J.transpose();
}

std::vector<std::string> UnconstrainedDirections(const Matrix6d& information, double extent, double max_std) {
  // Rotations scaled to displacements at the body's extent, so one threshold serves both.
  const double lever = extent > 0.0 ? extent : 1.0;
  Eigen::Matrix<double, 6, 1> d;
  d << 1, 1, 1, 1 / lever, 1 / lever, 1 / lever;
  const Matrix6d scaled = d.asDiagonal() * information * d.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Matrix6d> eig(0.5 * (scaled + scaled.transpose()));
  const double min_information = 1.0 / (max_std * max_std);
  std::vector<int> weak;
  for (int k = 0; k < 6; ++k)
    if (eig.eigenvalues()[k] < min_information) weak.push_back(k);
  if (weak.empty()) return {};
  Eigen::MatrixXd N(6, static_cast<Eigen::Index>(weak.size()));
  for (std::size_t j = 0; j < weak.size(); ++j) N.col(static_cast<Eigen::Index>(j)) = eig.eigenvectors().col(weak[j]);

  static const char* kAxisNames[6] = {"translation along x", "translation along y", "translation along z",
                                      "rotation about x",    "rotation about y",    "rotation about z"};
  std::vector<std::string> named;
  for (int k = 0; k < 6; ++k)
    if (N.row(k).squaredNorm() > 0.9) named.push_back(kAxisNames[k]);
  if (named.size() == weak.size()) return named;
  std::vector<std::string> out;
  for (std::size_t j = 0; j < weak.size(); ++j) {
    const Eigen::VectorXd v = N.col(static_cast<Eigen::Index>(j));
    out.push_back(fmt::format("translation ({:.2f}, {:.2f}, {:.2f}) + rotation ({:.2f}, {:.2f}, {:.2f}) x {:.2f} m",
                              v[0], v[1], v[2], v[3], v[4], v[5], lever));
  }
  return out;
}

}  // namespace ifab
