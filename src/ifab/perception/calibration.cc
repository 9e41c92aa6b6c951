#include "ifab/perception/calibration.h"

#include <Eigen/Cholesky>
#include <Eigen/SVD>
#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "ifab/core/config.h"
#include "ifab/perception/fit_quality.h"
#include "ifab/perception/pose_solver.h"

namespace ifab {

CalibrationOptions CalibrationOptions::FromConfig(const ConfigNode& c, CalibrationOptions o) {
  c.ExpectKeys({"registration", "laser_extent", "autodiff"});
  if (auto r = c.Find("registration")) o.registration = RegistrationOptions::FromConfig(*r, o.registration);
  c.ReadPositive("laser_extent", o.laser_extent);
  c.Read("autodiff", o.autodiff);
  return o;
}

std::string CalibrationSummary::BriefReport() const {
  const auto v = XyzRpyFromPose(T_tool0_laser);
  std::string s = fmt::format(
      "calibration {} ({}): T_tool0_laser [{:.4f} {:.4f} {:.4f}] m [{:.3f} {:.3f} {:.3f}] deg, std [{:.2f} {:.2f} "
      "{:.2f}] mm [{:.3f} {:.3f} {:.3f}] deg; {} points, {} inliers, {} shadow removed, rms {:.2f} sigma, {} steps, "
      "{:.2f} s; noise: {}; fit: {}",
      ToString(status), message, v[0], v[1], v[2], v[3] * 180 / M_PI, v[4] * 180 / M_PI, v[5] * 180 / M_PI,
      1e3 * std::sqrt(covariance(0, 0)), 1e3 * std::sqrt(covariance(1, 1)), 1e3 * std::sqrt(covariance(2, 2)),
      std::sqrt(covariance(3, 3)) * 180 / M_PI, std::sqrt(covariance(4, 4)) * 180 / M_PI,
      std::sqrt(covariance(5, 5)) * 180 / M_PI, num_points, num_inliers, num_shadow_removed, rms_whitened, iterations,
      seconds, fit.noise_source, fit.message);
  for (const auto& w : warnings) s += "\n  warning: " + w;
  return s;
}

CalibrationSummary CalibrateLaserMount(const std::vector<CalibrationSweep>& sweeps,
                                       const std::vector<RegistrationBody>& bodies, const Pose3& T_tool0_laser_guess,
                                       const CalibrationOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  std::vector<SweepPoint> all;
  std::vector<std::size_t> sweep_of;
  for (std::size_t k = 0; k < sweeps.size(); ++k) {
    all.insert(all.end(), sweeps[k].points.begin(), sweeps[k].points.end());
    sweep_of.insert(sweep_of.end(), sweeps[k].points.size(), k);
  }
  internal::PoseProblemInput input;
  input.sweep = &all;
  input.T_tool0_laser = T_tool0_laser_guess;
  input.laser_extent = options.laser_extent;
  input.autodiff = options.autodiff;
  const internal::PoseProblemOutput r = internal::SolvePoseProblem(input, bodies, options.registration);

  CalibrationSummary s;
  s.status = r.summary.status;
  s.message = r.summary.message;
  s.iterations = r.summary.iterations;
  s.cost = r.summary.cost;
  s.seconds = r.summary.seconds;
  s.T_tool0_laser = r.T_tool0_laser;
  s.covariance = r.laser_covariance;
  s.unconstrained = r.laser_unconstrained;
  s.bodies = r.summary.bodies;
  s.num_points = r.summary.num_points;
  s.num_inliers = r.summary.num_inliers;
  s.num_shadow_removed = r.summary.num_shadow_removed;
  s.rms_whitened = r.summary.rms_whitened;
  s.fit = r.summary.fit;
  s.warnings = r.summary.warnings;
  s.sweep_inliers.assign(sweeps.size(), 0);
  for (std::size_t i = 0; i < r.summary.labels.size(); ++i)
    s.sweep_inliers[sweep_of[i]] += r.summary.labels[i] == PointLabel::kInlier;
  for (std::size_t k = 0; k < sweeps.size(); ++k)
    if (s.sweep_inliers[k] == 0)
      s.warnings.push_back(fmt::format("sweep '{}' has no point on the target", sweeps[k].name));
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return s;
}

std::vector<RegistrationBody> CubeOnGroundBodies(double size, const Pose3& T_base_cube, double ground_z) {
  Pose3 T_base_ground = Pose3::Identity();
  T_base_ground.translation().z() = ground_z;
  RigidObject ground{"ground", Pose3::Identity(), {Plane{Eigen::Vector3d::UnitZ(), 0.0}}};
  RigidObject cube{"cube", Pose3::Identity(), {Box{Eigen::Vector3d::Constant(size)}}};
  return {{"ground", T_base_ground, {ground}, true}, {"cube", T_base_cube, {cube}, true}};
}

GroundExtentOptions GroundExtentOptions::FromConfig(const ConfigNode& c) {
  c.ExpectMap();
  c.ExpectKeys({"enabled", "ring_width_m", "significance", "sectors", "max_height_m", "min_ring_points"});
  GroundExtentOptions o;
  c.Read("enabled", o.enabled);
  c.ReadPositive("ring_width_m", o.ring_width);
  c.ReadPositive("significance", o.significance);
  c.ReadPositive("sectors", o.sectors);
  c.ReadPositive("max_height_m", o.max_height);
  c.Read("min_ring_points", o.min_ring_points);
  if (o.min_ring_points < 3) c["min_ring_points"].Fail("at least 3 (a plane)");
  return o;
}

namespace {

// The chi-square quantile with k degrees of freedom at the upper tail probability of a two-sided
// normal test at `sigmas` (Wilson-Hilferty). With k = 1 it is exactly sigmas^2: the one-sector
// test is the plain z-test of the ring's mean.
double ChiSquareBound(int k, double sigmas) {
  if (k == 1) return sigmas * sigmas;
  const double tail = std::erfc(sigmas / std::sqrt(2.0));
  return ChiSquareQuantile(k, NormalQuantile(1.0 - tail));
}

}  // namespace

GroundExtent MeasureGroundExtent(const std::vector<CalibrationSweep>& sweeps, const Pose3& T_tool0_laser,
                                 const Pose3& T_base_ground, const Pose3& T_base_cube, double cube_size,
                                 double max_radius, const GroundExtentOptions& options) {
  IFAB_CHECK(options.ring_width > 0.0);
  IFAB_CHECK(options.sectors >= 1);
  struct GroundReturn {
    double rho, x, y, h;  // distance from the cube's centre; position and height in the ground frame
    int sector;           // of options.sectors equal angles about the cube's centre
  };
  std::vector<GroundReturn> ground;
  const Pose3 T_ground_base = T_base_ground.inverse(Eigen::Isometry);
  const Pose3 T_cube_base = T_base_cube.inverse(Eigen::Isometry);
  const Eigen::Vector2d centre = T_base_cube.translation().head<2>();
  const double footprint = 0.5 * cube_size + 0.5 * options.ring_width;  // the cube and its foot's shadowed edge
  const int K = options.sectors;
  for (const CalibrationSweep& sweep : sweeps)
    for (const SweepPoint& p : sweep.points) {
      const Eigen::Vector3d p_base = p.T_base_tool0 * (T_tool0_laser * p.p_laser);
      const Eigen::Vector3d g = T_ground_base * p_base;
      if (std::abs(g.z()) > options.max_height) continue;
      const Eigen::Vector3d c = T_cube_base * p_base;
      if (std::abs(c.x()) < footprint && std::abs(c.y()) < footprint) continue;
      const Eigen::Vector2d d = p_base.head<2>() - centre;
      const double turn = std::atan2(d.y(), d.x()) / (2.0 * M_PI) + 0.5;  // [0, 1]
      ground.push_back({d.norm(), g.x(), g.y(), g.z(), std::min(K - 1, static_cast<int>(turn * K))});
    }
  GroundExtent out;
  double farthest = 0.0;
  for (const auto& g : ground) farthest = std::max(farthest, g.rho);
  max_radius = std::min(max_radius, farthest);
  out.radius = max_radius;
  if (ground.empty()) {
    out.message = "no ground returns about the cube";
    return out;
  }
  // The innermost ring that clears the cube's corners is taken as flat: the cube stands on it.
  const double w = options.ring_width;
  double r = w * std::ceil((std::sqrt(0.5) * cube_size + 0.5 * w) / w);
  while (r < max_radius) {
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    double hh = 0.0;
    int inside = 0;
    for (const auto& g : ground)
      if (g.rho < r) {
        const Eigen::Vector3d a(1.0, g.x, g.y);
        A += a * a.transpose();
        b += a * g.h;
        hh += g.h * g.h;
        ++inside;
      }
    const double outer = std::min(r + w, max_radius);
    std::vector<double> sum(static_cast<std::size_t>(K), 0.0), sum2(static_cast<std::size_t>(K), 0.0);
    std::vector<int> n(static_cast<std::size_t>(K), 0);
    Eigen::Vector3d plane = Eigen::Vector3d::Zero();
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(A);
    const bool fitted = inside >= options.min_ring_points && ldlt.info() == Eigen::Success && ldlt.isPositive();
    // The plane's own uncertainty (the inside returns' scatter through (A^T A)^-1): extrapolated to
    // the ring it leans opposite sectors opposite ways, which the sectors' test must not take for
    // the floor's.
    Eigen::Matrix3d plane_cov = Eigen::Matrix3d::Zero();
    if (fitted) {
      plane = ldlt.solve(b);
      const double ss = std::max(0.0, hh - b.dot(plane));  // the inside residuals' sum of squares at the solution
      plane_cov = ss / std::max(1, inside - 3) * ldlt.solve(Eigen::Matrix3d::Identity());
    }
    std::vector<Eigen::Vector3d> regressor(static_cast<std::size_t>(K), Eigen::Vector3d::Zero());
    for (const auto& g : ground)
      if (g.rho >= r && g.rho < outer) {
        const double e = g.h - plane.dot(Eigen::Vector3d(1.0, g.x, g.y));
        const auto k = static_cast<std::size_t>(g.sector);
        sum[k] += e;
        sum2[k] += e * e;
        regressor[k] += Eigen::Vector3d(1.0, g.x, g.y);
        ++n[k];
      }
    GroundExtent::Ring ring;
    ring.outer = outer;
    // The whole ring's mean and standard error (reported), and the sectors' test.
    double all = 0.0, all2 = 0.0;
    for (int k = 0; k < K; ++k) {
      all += sum[static_cast<std::size_t>(k)];
      all2 += sum2[static_cast<std::size_t>(k)];
      ring.points += n[static_cast<std::size_t>(k)];
    }
    if (fitted && ring.points >= options.min_ring_points) {
      const int m = ring.points;
      const double mean = all / m;
      ring.mean_mm = 1e3 * mean;
      ring.se_mm = 1e3 * std::sqrt(std::max(0.0, (all2 - m * mean * mean) / (m - 1)) / m);
      // The tested sectors' means, with their covariance: each one's scatter over its returns, plus
      // the plane's uncertainty at the sector's mean position (shared by all, so not diagonal).
      std::vector<double> means;
      std::vector<Eigen::Vector3d> at;
      std::vector<double> own;
      for (int k = 0; k < K; ++k) {
        const auto i = static_cast<std::size_t>(k);
        // One sector: the whole ring (K = 1 is the ring's mean test). Otherwise a sector with too
        // few returns carries no evidence and is left out.
        if (n[i] < (K == 1 ? options.min_ring_points : std::max(3, options.min_ring_points / K))) continue;
        const double mk = sum[i] / n[i];
        const double vk = std::max(0.0, (sum2[i] - n[i] * mk * mk) / (n[i] - 1));
        if (vk <= 0.0) continue;
        means.push_back(mk);
        own.push_back(vk / n[i]);
        at.push_back(regressor[i] / n[i]);
        if (std::abs(mk) > std::abs(1e-3 * ring.worst_sector_mm)) ring.worst_sector_mm = 1e3 * mk;
      }
      ring.sectors = static_cast<int>(means.size());
      if (ring.sectors > 0) {
        const int S = ring.sectors;
        Eigen::MatrixXd C(S, S);
        Eigen::VectorXd mv(S);
        for (int i = 0; i < S; ++i) {
          mv[i] = means[static_cast<std::size_t>(i)];
          for (int j = 0; j < S; ++j)
            C(i, j) = at[static_cast<std::size_t>(i)].dot(plane_cov * at[static_cast<std::size_t>(j)]) +
                      (i == j ? own[static_cast<std::size_t>(i)] : 0.0);
        }
        ring.chi2 = mv.dot(C.ldlt().solve(mv));
      }
      out.rings.push_back(ring);
      if (ring.sectors > 0) {
        out.rings.back().bound = ChiSquareBound(ring.sectors, options.significance);
        if (ring.chi2 > out.rings.back().bound) {
          out.radius = r;
          out.limited = true;
          out.message = fmt::format(
              "the ground is one plane out to {:.2f} m from the cube: the ring to {:.2f} m lies off it (mean {:+.2f} mm, "
              "{:.2f} mm standard error; sector farthest off {:+.2f} mm; chi-square {:.1f} over {} sectors > {:.1f}; "
              "{} returns)",
              r, outer, ring.mean_mm, ring.se_mm, ring.worst_sector_mm, ring.chi2, ring.sectors,
              out.rings.back().bound, m);
          return out;
        }
      }
    } else {
      out.rings.push_back(ring);
    }
    r = outer;
  }
  out.message = fmt::format("the ground is one plane out to {:.2f} m from the cube (every ring within {:.0f} standard "
                            "errors of it)", max_radius, options.significance);
  return out;
}

void CropSweeps(std::vector<CalibrationSweep>& sweeps, const Pose3& T_tool0_laser, const Eigen::Vector2d& center,
                double radius) {
  for (CalibrationSweep& sweep : sweeps)
    std::erase_if(sweep.points, [&](const SweepPoint& p) {
      const Eigen::Vector3d p_base = p.T_base_tool0 * (T_tool0_laser * p.p_laser);
      return (p_base.head<2>() - center).norm() > radius;
    });
}

Pose3 AveragePoses(const std::vector<Pose3>& poses) {
  IFAB_CHECK(!poses.empty());
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  for (const auto& p : poses) {
    t += p.translation();
    m += p.linear();
  }
  // Nearest rotation to the mean matrix (chordal L2 mean).
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d r = svd.matrixU() * svd.matrixV().transpose();
  if (r.determinant() < 0) {
    Eigen::Matrix3d u = svd.matrixU();
    u.col(2) *= -1;
    r = u * svd.matrixV().transpose();
  }
  Pose3 out = Pose3::Identity();
  out.linear() = r;
  out.translation() = t / static_cast<double>(poses.size());
  return out;
}

}  // namespace ifab
