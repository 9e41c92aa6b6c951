#include "ifab/perception/range_bias.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>

#include "ifab/core/config.h"
#include "ifab/core/error.h"

namespace ifab {
namespace {

// The hat functions over increasing knots that are non-zero at x (clamped): up to 2.
int Hats(const std::vector<double>& knots, double x, int index[2], double weight[2]) {
  const int n = static_cast<int>(knots.size());
  if (n == 1 || x <= knots.front()) {
    index[0] = 0;
    weight[0] = 1.0;
    return 1;
  }
  if (x >= knots.back()) {
    index[0] = n - 1;
    weight[0] = 1.0;
    return 1;
  }
  const int k = static_cast<int>(std::upper_bound(knots.begin(), knots.end(), x) - knots.begin()) - 1;
  const double s = (x - knots[static_cast<std::size_t>(k)]) /
                   (knots[static_cast<std::size_t>(k) + 1] - knots[static_cast<std::size_t>(k)]);
  index[0] = k;
  weight[0] = 1.0 - s;
  index[1] = k + 1;
  weight[1] = s;
  return 2;
}

void CheckKnots(const ConfigNode& node, const std::vector<double>& knots, double lo, double hi) {
  if (knots.empty()) node.Fail("at least one knot");
  for (std::size_t i = 0; i < knots.size(); ++i) {
    if (!(knots[i] >= lo && knots[i] <= hi)) node[i].Fail(fmt::format("a knot within [{}, {}]", lo, hi));
    if (i > 0 && !(knots[i] > knots[i - 1])) node[i].Fail("knots in increasing order");
  }
}

std::vector<double> DegToRadAll(std::vector<double> v) {
  for (double& x : v) x *= M_PI / 180.0;
  return v;
}

// Left perturbation [dt, w] of a pose: (Exp(w) R, t + dt) (rotation about the frame's parent axes
// through the pose's own origin).
Pose3 Perturb(const Pose3& T, const Eigen::Matrix<double, 6, 1>& d) {
  Pose3 out = T;
  out.linear() = ExpSO3(d.tail<3>()) * T.linear();
  out.translation() = T.translation() + d.head<3>();
  return out;
}

struct CellKey {
  std::int64_t x, y, z;
  bool operator==(const CellKey&) const = default;
};
struct CellHash {
  std::size_t operator()(const CellKey& k) const {
    return static_cast<std::size_t>((k.x * 73856093) ^ (k.y * 19349663) ^ (k.z * 83492791));
  }
};

}  // namespace

int RangeBiasModel::Basis(double range, double incidence, int index[4], double weight[4]) const {
  int ri[2], ai[2];
  double rw[2], aw[2];
  const int nr = Hats(range_knots, range, ri, rw);
  const int na = Hats(incidence_knots, incidence, ai, aw);
  const int m = static_cast<int>(incidence_knots.size());
  int n = 0;
  for (int a = 0; a < nr; ++a)
    for (int b = 0; b < na; ++b) {
      index[n] = ri[a] * m + ai[b];
      weight[n] = rw[a] * aw[b];
      ++n;
    }
  return n;
}

double RangeBiasModel::Bias(double range, double incidence) const {
  if (empty()) return 0.0;
  int idx[4];
  double w[4];
  const int n = Basis(range, incidence, idx, w);
  double b = 0.0;
  for (int k = 0; k < n; ++k) b += w[k] * coefficients[idx[k]];
  return b;
}

double RangeBiasModel::Std(double range, double incidence) const {
  if (empty() || covariance.rows() != coefficients.size()) return 0.0;
  int idx[4];
  double w[4];
  const int n = Basis(range, incidence, idx, w);
  double v = 0.0;
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b) v += w[a] * w[b] * covariance(idx[a], idx[b]);
  return std::sqrt(std::max(v, 0.0));
}

RangeBiasModel RangeBiasModel::FromConfig(const ConfigNode& c) {
  c.ExpectMap();
  c.ExpectKeys({"range_knots", "incidence_knots_deg", "coefficients", "covariance"});
  RangeBiasModel m;
  m.range_knots = c["range_knots"].AsNumbers();
  CheckKnots(c["range_knots"], m.range_knots, 0.0, 1e3);
  const std::vector<double> a = c["incidence_knots_deg"].AsNumbers();
  CheckKnots(c["incidence_knots_deg"], a, 0.0, 90.0);
  m.incidence_knots = DegToRadAll(a);
  const int n = m.size();
  m.coefficients = Eigen::VectorXd::Zero(n);
  m.covariance = Eigen::MatrixXd::Zero(n, n);
  if (auto k = c.Find("coefficients")) {
    const auto v = k->AsNumbers(n);
    for (int i = 0; i < n; ++i) m.coefficients[i] = v[static_cast<std::size_t>(i)];
  }
  if (auto k = c.Find("covariance")) {
    k->ExpectSequence(n);
    for (int i = 0; i < n; ++i) {
      const auto row = (*k)[static_cast<std::size_t>(i)].AsNumbers(n);
      for (int j = 0; j < n; ++j) m.covariance(i, j) = row[static_cast<std::size_t>(j)];
    }
    if (!m.covariance.isApprox(m.covariance.transpose(), 1e-9) || (m.covariance.diagonal().array() < 0).any())
      k->Fail("a symmetric covariance with a non-negative diagonal");
  }
  return m;
}

std::string RangeBiasModel::ToYaml(int indent) const {
  const std::string pad(static_cast<std::size_t>(indent), ' ');
  auto list = [](const auto& v, double scale, const char* f) {
    std::string s = "[";
    for (Eigen::Index i = 0; i < static_cast<Eigen::Index>(v.size()); ++i)
      s += (i ? ", " : "") + fmt::format(fmt::runtime(f), scale * v[static_cast<std::size_t>(i)]);
    return s + "]";
  };
  std::vector<double> coef(coefficients.data(), coefficients.data() + coefficients.size());
  std::string s = pad + "range_knots: " + list(range_knots, 1.0, "{}") + "  # m\n";
  s += pad + "incidence_knots_deg: " + list(incidence_knots, 180.0 / M_PI, "{:.6g}") + "\n";
  s += pad + "coefficients: " + list(coef, 1.0, "{:.6e}") + "  # m, range-major\n";
  s += pad + "covariance:  # m^2\n";
  for (Eigen::Index i = 0; i < covariance.rows(); ++i) {
    std::vector<double> row(static_cast<std::size_t>(covariance.cols()));
    for (Eigen::Index j = 0; j < covariance.cols(); ++j) row[static_cast<std::size_t>(j)] = covariance(i, j);
    s += pad + "  - " + list(row, 1.0, "{:.6e}") + "\n";
  }
  return s;
}

RangeBiasOptions RangeBiasOptions::FromConfig(const ConfigNode& c) {
  c.ExpectMap();
  c.ExpectKeys({"range_knots", "incidence_knots_deg", "sigma_along", "prior_sigma", "smoothness_sigma",
                "max_residual", "edge_distance", "max_incidence_deg", "loss_scale", "max_iterations",
                "step_tolerance", "pose_prior_sigma_translation", "pose_prior_sigma_rotation", "point_stride",
                "sweep_correlated_errors"});
  RangeBiasOptions o;
  if (auto k = c.Find("range_knots")) {
    o.range_knots = k->AsNumbers();
    CheckKnots(*k, o.range_knots, 0.0, 1e3);
  }
  if (auto k = c.Find("incidence_knots_deg")) {
    const auto a = k->AsNumbers();
    CheckKnots(*k, a, 0.0, 90.0);
    o.incidence_knots = DegToRadAll(a);
  }
  c.ReadPositive("sigma_along", o.sigma_along);
  c.ReadPositive("prior_sigma", o.prior_sigma);
  c.ReadPositive("smoothness_sigma", o.smoothness_sigma);
  c.ReadPositive("max_residual", o.max_residual);
  c.ReadNonNegative("edge_distance", o.edge_distance);
  double inc = o.max_incidence * 180.0 / M_PI;
  c.ReadInRange("max_incidence_deg", inc, 1.0, 90.0);
  o.max_incidence = inc * M_PI / 180.0;
  c.ReadPositive("loss_scale", o.loss_scale);
  c.ReadPositive("max_iterations", o.max_iterations);
  c.ReadPositive("step_tolerance", o.step_tolerance);
  c.ReadPositive("pose_prior_sigma_translation", o.pose_prior_sigma_translation);
  c.ReadPositive("pose_prior_sigma_rotation", o.pose_prior_sigma_rotation);
  c.ReadPositive("point_stride", o.point_stride);
  o.sweep_correlated_errors = c.Get<bool>("sweep_correlated_errors", o.sweep_correlated_errors);
  return o;
}

std::string RangeBiasSummary::BriefReport() const {
  std::string s = fmt::format(
      "range bias {} ({}): {} of {} points used, rms {:.2f} sigma (covariance x{:.2f}), {} steps, {:.2f} s",
      usable ? "identified" : "not usable", message, num_used, num_points, rms_whitened, variance_factor,
      iterations, seconds);
  for (const auto& w : warnings) s += "\n  warning: " + w;
  return s;
}

namespace {

// Errors that repeat along a sweep (the floor patch's own shape, the arm posture's kinematic
// error, a target not quite its drawn size) do not average down over the sweep's points the way
// the noise does, only over sweeps. Their covariance shows in how much each sweep's gradient
// scatters beyond what the noise alone gives (a cluster-robust "sandwich", the clusters being the
// sweeps): M = sum_g s_g s_g^T - f H_data, with s_g sweep g's score (centred over the sweeps) and
// f H_data its expectation under independent noise; the part of M that is positive, mapped
// through H^-1, is added to the noise-only covariance f H^-1. With independent noise M is about
// zero and the covariance stays f H^-1.
Eigen::MatrixXd SweepCorrelatedCovariance(const Eigen::MatrixXd& H_inv, const Eigen::MatrixXd& H_data,
                                          const Eigen::MatrixXd& sweep_scores, double variance_factor) {
  const int G = static_cast<int>(sweep_scores.cols());
  const Eigen::VectorXd mean = sweep_scores.rowwise().mean();
  const Eigen::MatrixXd centred = sweep_scores.colwise() - mean;
  // G / (G - 1): the centring took one sweep's worth of scatter out.
  Eigen::MatrixXd M = centred * centred.transpose() * (double(G) / (G - 1)) - variance_factor * H_data;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (M + M.transpose()));
  const Eigen::VectorXd lambda = eig.eigenvalues().cwiseMax(0.0);
  M = eig.eigenvectors() * lambda.asDiagonal() * eig.eigenvectors().transpose();
  return H_inv * M * H_inv;
}

}  // namespace

RangeBiasSummary IdentifyRangeBias(const std::vector<CalibrationSweep>& sweeps,
                                   const std::vector<RegistrationBody>& bodies, const Pose3& T_tool0_laser_guess,
                                   const RangeBiasOptions& o) {
  const auto wall_start = std::chrono::steady_clock::now();
  RangeBiasSummary s;
  s.model.range_knots = o.range_knots;
  s.model.incidence_knots = o.incidence_knots;
  const int K = s.model.size();
  const int nr = static_cast<int>(o.range_knots.size()), na = static_cast<int>(o.incidence_knots.size());
  s.model.coefficients = Eigen::VectorXd::Zero(K);
  s.T_tool0_laser = T_tool0_laser_guess;
  for (const auto& b : bodies) s.T_base_body.push_back(b.T_base_body);
  std::vector<int> free_index(bodies.size(), -1);  // parameter block of each free body
  int P = K + 6;
  for (std::size_t b = 0; b < bodies.size(); ++b)
    if (bodies[b].free) {
      free_index[b] = P;
      P += 6;
    }
  std::vector<const SweepPoint*> points;
  std::vector<int> point_sweep;  // the sweep each point came from (the covariance's clusters)
  for (std::size_t k = 0; k < sweeps.size(); ++k)
    for (std::size_t i = 0; i < sweeps[k].points.size(); i += static_cast<std::size_t>(o.point_stride)) {
      points.push_back(&sweeps[k].points[i]);
      point_sweep.push_back(static_cast<int>(k));
    }
  const int G = static_cast<int>(sweeps.size());
  s.num_points = static_cast<int>(points.size());

  // The prior: each knot near zero, and close to its neighbours along range and along incidence
  // (first differences: where no data are, the model stays flat and its std grows with the
  // distance to the data; second differences would extrapolate trends with false confidence).
  Eigen::MatrixXd prior = Eigen::MatrixXd::Zero(P, P);
  prior.topLeftCorner(K, K).diagonal().setConstant(1.0 / (o.prior_sigma * o.prior_sigma));
  const double ws = 1.0 / (o.smoothness_sigma * o.smoothness_sigma);
  auto add_difference = [&](int a, int b) {
    prior(a, a) += ws;
    prior(b, b) += ws;
    prior(a, b) -= ws;
    prior(b, a) -= ws;
  };
  for (int r = 0; r < nr; ++r)
    for (int a = 1; a < na; ++a) add_difference(r * na + a - 1, r * na + a);
  for (int a = 0; a < na; ++a)
    for (int r = 1; r < nr; ++r) add_difference((r - 1) * na + a, r * na + a);
  for (int p = K; p < P; p += 6) {
    prior.block<3, 3>(p, p).diagonal().setConstant(1.0 / std::pow(o.pose_prior_sigma_translation, 2));
    prior.block<3, 3>(p + 3, p + 3).diagonal().setConstant(1.0 / std::pow(o.pose_prior_sigma_rotation, 2));
  }

  Eigen::VectorXd moved = Eigen::VectorXd::Zero(P);  // the poses' change from the guesses (for their prior)
  Eigen::MatrixXd H(P, P);
  Eigen::VectorXd g(P);
  const double sigma2 = o.sigma_along * o.sigma_along;
  double chi2 = 0.0, weight_sum = 0.0;
  Eigen::MatrixXd sweep_scores(P, G);  // each sweep's share of the gradient
  for (int iter = 0; iter <= o.max_iterations; ++iter) {
    Scene scene(bodies);
    scene.SetPoses(s.T_base_body);
    H = prior;
    g = prior * moved;
    g.head(K) = prior.topLeftCorner(K, K) * s.model.coefficients;
    chi2 = 0.0;
    weight_sum = 0.0;
    sweep_scores.setZero();
    int used = 0;
    for (std::size_t pi = 0; pi < points.size(); ++pi) {
      const SweepPoint* sp = points[pi];
      const double r_meas = sp->p_laser.norm();
      if (!(r_meas > 0.0)) continue;
      const Pose3 T_base_laser = sp->T_base_tool0 * s.T_tool0_laser;
      const Eigen::Vector3d o_base = T_base_laser.translation();
      const Eigen::Vector3d u_laser = sp->p_laser / r_meas;
      const Eigen::Vector3d d = T_base_laser.linear() * u_laser;
      const auto hit = scene.CastRay(o_base, d, r_meas + o.max_residual + 1.0);
      if (!hit) continue;
      const double nd = hit->normal.dot(d);
      if (std::abs(nd) < std::cos(o.max_incidence)) continue;
      const double incidence = std::acos(std::min(1.0, std::abs(nd)));
      int idx[4];
      double w[4];
      // The basis at the modelled range, not the measured one: the measured range carries the
      // noise, and a regressor that correlates with the noise biases least squares (by about
      // sigma^2 / knot spacing, 3 mm here).
      const int nb = s.model.Basis(hit->t, incidence, idx, w);
      double bias = 0.0;
      for (int k = 0; k < nb; ++k) bias += w[k] * s.model.coefficients[idx[k]];
      const double e = r_meas - bias - hit->t;
      if (std::abs(e) > o.max_residual) continue;
      if (o.edge_distance > 0.0 && scene.RayPassesNearEdge(o_base, d, hit->t + o.max_residual, o.edge_distance))
        continue;
      ++used;
      // Cauchy weight of the whitened error.
      const double z = e / (o.loss_scale * o.sigma_along);
      const double wr = 1.0 / (1.0 + z * z);
      const double wt = wr / sigma2;
      chi2 += wr * e * e / sigma2;
      weight_sum += wr;
      // e = r_meas - b - t: de = -db - dt. dt/do = -n/(n.d), dt/dd = -t n/(n.d).
      const Eigen::Vector3d& n = hit->normal;
      const Eigen::Vector3d dt_do = -n / nd, dt_dd = -hit->t * n / nd;
      const Eigen::Matrix3d& R_bt = sp->T_base_tool0.linear();
      const Eigen::Vector3d u_tool0 = s.T_tool0_laser.linear() * u_laser;
      // Mount perturbation (tool0 axes, rotation about the laser's origin): do = R_bt dt,
      // dd = R_bt (w x u_tool0).
      Eigen::Matrix<double, 1, 6> J_mount;
      J_mount.head<3>() = -(dt_do.transpose() * R_bt);
      J_mount.tail<3>() = -(dt_dd.transpose() * R_bt * (-Skew(u_tool0)));
      // Body perturbation (base frame, about its origin c): the face moves by dt + w x (p - c).
      const int body = scene.primitives()[static_cast<std::size_t>(hit->primitive)].body;
      const int pb = free_index[static_cast<std::size_t>(body)];
      Eigen::Matrix<double, 1, 6> J_body = Eigen::Matrix<double, 1, 6>::Zero();
      if (pb >= 0) {
        const Eigen::Vector3d p = o_base + hit->t * d;
        const Eigen::Vector3d c = s.T_base_body[static_cast<std::size_t>(body)].translation();
        J_body.head<3>() = -(n / nd).transpose();
        J_body.tail<3>() = -((p - c).cross(n) / nd).transpose();
      }
      // Accumulate the sparse row: 4 bias entries, the mount, one body.
      int cols[16];
      double vals[16];
      int m = 0;
      for (int k = 0; k < nb; ++k) {
        cols[m] = idx[k];
        vals[m++] = -w[k];
      }
      for (int k = 0; k < 6; ++k) {
        cols[m] = K + k;
        vals[m++] = J_mount[k];
      }
      if (pb >= 0)
        for (int k = 0; k < 6; ++k) {
          cols[m] = pb + k;
          vals[m++] = J_body[k];
        }
      const int sweep = point_sweep[pi];
      for (int a = 0; a < m; ++a) {
        g[cols[a]] += wt * vals[a] * e;
        sweep_scores(cols[a], sweep) += wt * vals[a] * e;
        for (int b = 0; b < m; ++b) H(cols[a], cols[b]) += wt * vals[a] * vals[b];
      }
    }
    s.num_used = used;
    if (used == 0) {
      s.message = "no point hits the model";
      s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
      return s;
    }
    if (iter == o.max_iterations) break;  // the last pass only evaluates (H and chi^2 at the result)
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(H);
    if (ldlt.info() != Eigen::Success) {
      s.message = "the normal equations are singular";
      return s;
    }
    const Eigen::VectorXd step = -ldlt.solve(g);
    s.model.coefficients += step.head(K);
    s.T_tool0_laser = Perturb(s.T_tool0_laser, step.segment<6>(K));
    for (std::size_t b = 0; b < bodies.size(); ++b)
      if (free_index[b] >= 0) s.T_base_body[b] = Perturb(s.T_base_body[b], step.segment<6>(free_index[b]));
    moved.tail(P - K) += step.tail(P - K);
    s.iterations = iter + 1;
    const double biggest = std::max(step.head(K).cwiseAbs().maxCoeff(), step.tail(P - K).cwiseAbs().maxCoeff());
    if (biggest < o.step_tolerance) {
      s.message = "converged";
      // One more pass evaluates H and chi^2 at the result.
      iter = o.max_iterations - 1;
    }
  }
  if (s.message.empty()) s.message = "max iterations";
  s.rms_whitened = std::sqrt(chi2 / std::max(weight_sum, 1.0));
  // A noise model that is too optimistic (unmodelled floor unevenness, a cube not quite its
  // nominal size) shows as chi^2 per point above 1: widen the covariance by it, never narrow it.
  s.variance_factor = std::max(1.0, chi2 / std::max(weight_sum, 1.0));
  const Eigen::MatrixXd H_inv = H.ldlt().solve(Eigen::MatrixXd::Identity(P, P));
  Eigen::MatrixXd cov = H_inv * s.variance_factor;
  if (o.sweep_correlated_errors && G > 1) cov += SweepCorrelatedCovariance(H_inv, H - prior, sweep_scores,
                                                                          s.variance_factor);
  s.model.covariance = cov.topLeftCorner(K, K);
  s.mount_covariance = cov.block<6, 6>(K, K);
  s.usable = s.model.coefficients.allFinite() && s.model.covariance.allFinite();
  if (!s.usable) s.message = "the solution is not finite";
  if (s.rms_whitened > 2.0)
    s.warnings.push_back(fmt::format("rms {:.2f} sigma: the range noise or the model does not fit", s.rms_whitened));
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  return s;
}

RangeBiasCompensation RangeBiasCompensation::FromConfig(const ConfigNode& c) {
  c.ExpectMap();
  c.ExpectKeys({"compensate", "normal_radius", "min_neighbours", "max_std_fraction", "sigma_along", "incidence",
                "model_gap", "model"});
  RangeBiasCompensation o;
  c.Read("compensate", o.compensate);
  c.ReadPositive("normal_radius", o.normal_radius);
  c.ReadPositive("min_neighbours", o.min_neighbours);
  if (o.min_neighbours < 3) c["min_neighbours"].Fail("at least 3 (a plane)");
  c.ReadPositive("max_std_fraction", o.max_std_fraction);
  c.ReadPositive("sigma_along", o.sigma_along);
  if (auto k = c.Find("incidence")) {
    const std::string v = k->As<std::string>();
    if (v == "model") o.incidence_from_model = true;
    else if (v == "normals") o.incidence_from_model = false;
    else k->Fail("model or normals");
  }
  c.ReadPositive("model_gap", o.model_gap);
  if (auto m = c.Find("model")) o.model = RangeBiasModel::FromConfig(*m);
  return o;
}

std::vector<Eigen::Vector3d> EstimateNormals(const std::vector<RayPoint>& cloud, double radius, int min_neighbours,
                                             double along_sigma) {
  // Sufficient statistics per cell of a hash grid (cells of 2/3 the radius, so a cell and its 26
  // neighbours span about +-radius): a point's normal is the PCA of its cell's block. O(N), and the
  // same for every point of a cell, which is what a sweep's dense clouds need.
  const double cell = 2.0 * radius / 3.0;
  auto key = [&](const Eigen::Vector3d& p, int dx, int dy, int dz) {
    const auto c = [&](double v, int d) { return static_cast<std::int64_t>(std::floor(v / cell)) + d; };
    return CellKey{c(p.x(), dx), c(p.y(), dy), c(p.z(), dz)};
  };
  struct Moments {
    int n{0};
    Eigen::Vector3d sum{Eigen::Vector3d::Zero()};
    Eigen::Matrix3d second{Eigen::Matrix3d::Zero()}, rays{Eigen::Matrix3d::Zero()};
    Eigen::Vector3d normal{Eigen::Vector3d::Zero()};
    bool done{false};
  };
  std::unordered_map<CellKey, Moments, CellHash> grid;
  grid.reserve(cloud.size() / 8 + 1);
  for (const RayPoint& q : cloud) {
    Moments& m = grid[key(q.p, 0, 0, 0)];
    ++m.n;
    m.sum += q.p;
    m.second += q.p * q.p.transpose();
    const Eigen::Vector3d ray = q.Ray();
    m.rays += ray * ray.transpose();
  }
  std::vector<Eigen::Vector3d> normals(cloud.size(), Eigen::Vector3d::Zero());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d& p = cloud[i].p;
    Moments& home = grid[key(p, 0, 0, 0)];
    if (!home.done) {
      home.done = true;
      Moments block;
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            const auto it = grid.find(key(p, dx, dy, dz));
            if (it == grid.end()) continue;
            block.n += it->second.n;
            block.sum += it->second.sum;
            block.second += it->second.second;
            block.rays += it->second.rays;
          }
      if (block.n >= min_neighbours) {
        const Eigen::Vector3d mean = block.sum / block.n;
        // The along-ray noise spreads the block along the rays and tilts a plain PCA normal
        // towards them: take its expected covariance out.
        const Eigen::Matrix3d cov = block.second / block.n - mean * mean.transpose() -
                                    along_sigma * along_sigma * block.rays / block.n;
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
        eig.computeDirect(cov);
        home.normal = eig.eigenvectors().col(0).normalized();
      }
    }
    Eigen::Vector3d normal = home.normal;
    if (normal.isZero()) continue;
    if (normal.dot(cloud[i].origin - p) < 0) normal = -normal;
    normals[i] = normal;
  }
  return normals;
}

namespace {

// Each point's incidence [rad] (NaN: unknown) and the factor (r - b) / r its range is scaled by
// (0: dropped), counted into stats.
std::vector<double> CompensationFactors(const std::vector<RayPoint>& cloud, const RangeBiasCompensation& c,
                                        const Scene* scene, RangeBiasCompensationStats& stats) {
  const std::vector<Eigen::Vector3d> normals = EstimateNormals(cloud, c.normal_radius, c.min_neighbours, c.sigma_along);
  const bool use_model = scene && c.incidence_from_model;
  const double max_std = c.max_std_fraction * c.sigma_along;
  std::vector<double> factor(cloud.size(), 0.0);
  double correction = 0.0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const double r = cloud[i].Range();
    if (!(r > 0.0)) continue;
    const Eigen::Vector3d d = cloud[i].Ray();
    double incidence = std::numeric_limits<double>::quiet_NaN();
    bool from_model = false;
    if (use_model) {
      const auto hit = scene->CastRay(cloud[i].origin, d, r + c.model_gap);
      if (hit && std::abs(hit->t - r) < c.model_gap) {
        incidence = std::acos(std::min(1.0, std::abs(hit->normal.dot(d))));
        from_model = true;
      }
    }
    if (std::isnan(incidence)) {
      if (normals[i].isZero()) {
        ++stats.dropped_no_normal;
        continue;
      }
      incidence = std::acos(std::min(1.0, std::abs(normals[i].dot(d))));
    }
    if (c.model.Std(r, incidence) > max_std) {
      ++stats.dropped_uncertain;
      continue;
    }
    const double b = c.model.Bias(r, incidence);
    factor[i] = (r - b) / r;
    correction -= b;
    ++stats.compensated;
    if (from_model) ++stats.incidence_from_model;
  }
  if (stats.compensated > 0) stats.mean_correction = correction / stats.compensated;
  return factor;
}

}  // namespace

RangeBiasCompensationStats CompensateRangeBias(std::vector<SweepPoint>& points, const Pose3& T_tool0_laser,
                                               const RangeBiasCompensation& c, const Scene* scene) {
  RangeBiasCompensationStats stats;
  if (!c.active()) return stats;
  const std::vector<double> factor = CompensationFactors(ToBaseFrame(points, T_tool0_laser), c, scene, stats);
  std::vector<SweepPoint> kept;
  kept.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    if (factor[i] > 0.0) {
      kept.push_back(points[i]);
      kept.back().p_laser *= factor[i];
    }
  points = std::move(kept);
  return stats;
}

RangeBiasCompensationStats CompensateRangeBias(std::vector<RayPoint>& cloud, const RangeBiasCompensation& c,
                                               const Scene* scene) {
  RangeBiasCompensationStats stats;
  if (!c.active()) return stats;
  const std::vector<double> factor = CompensationFactors(cloud, c, scene, stats);
  std::vector<RayPoint> kept;
  kept.reserve(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i)
    if (factor[i] > 0.0) kept.push_back({cloud[i].origin + factor[i] * (cloud[i].p - cloud[i].origin), cloud[i].origin});
  cloud = std::move(kept);
  return stats;
}

}  // namespace ifab
