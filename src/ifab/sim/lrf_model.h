#pragma once
/// \file
/// Hokuyo UTM-30LX model (data/sensors/utm30lx.yaml says where each number comes from):
/// 1081 beams over 270 deg at 40 Hz, range 0.1-30 m; noise along the ray; the beam's angular
/// spread across the ray (the measured range belongs to a direction off the nominal beam, so a
/// point lands off the surface it seems to lie on); a short-range bias that depends on range and
/// incidence (paper Fig. 7); mixed pixels at depth edges; beams with no return; dropped scans.

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "ifab/core/random.h"
#include "ifab/core/se3.h"
#include "ifab/msgs/msgs.h"
#include "ifab/sim/world.h"

namespace ifab {
class ConfigNode;
}

namespace ifab::sim {

struct LrfOptions {
  int beams{1081};                    ///< beams per scan
  double fov_deg{270.0};              ///< field of view, centred on the laser's x axis
  double scan_period{0.025};          ///< [s] one scan every 25 ms (40 Hz)
  double sweep_fraction{0.75};        ///< part of the mirror's revolution spent on the 270 deg
  double range_min{0.1};              ///< [m]
  double range_max{30.0};             ///< [m]
  double sigma_along{0.018};          ///< [m] range noise along the ray
  double sigma_across_per_m{0.0006};  ///< across-ray spread: sigma = a r + b
  double sigma_across_const{0.0015};  ///< [m]
  /// Short-range bias: near-field term (range reads long close to the window) ...
  std::vector<double> near_bias_range_m{0.10, 0.115, 0.2};
  std::vector<double> near_bias_m{0.020, 0.020, 0.0};
  /// ... and an intensity ("walk") term at normal incidence: range reads short, shrinking with range.
  std::vector<double> walk_bias_range_m{0.115, 0.25, 0.4, 1.1, 2.4, 5.0};
  std::vector<double> walk_bias_m{0.0, -0.030, -0.030, -0.0085, -0.0015, 0.0};
  double walk_bias_cos_power{8.0};    ///< walk bias scales with cos(incidence)^power
  double mixed_pixel_threshold{0.05}; ///< [m] depth jump inside the beam that makes a mixed pixel
  double mixed_pixel_probability{0.5};///< chance that a straddling beam returns a mixed range
  double beam_divergence{0.0006};     ///< [rad] half-width of the beam for the edge probes
  double no_return_probability{0.002};///< random dropouts per beam
  double max_incidence_deg{85.0};     ///< no return beyond this grazing angle
  double dropped_scan_probability{0.002}; ///< whole scans lost in transport
  bool bias_enabled{true};            ///< switch the short-range bias off (for comparisons)
  bool noise_enabled{true};           ///< switch all noise off (for tests)
  // A drawn unit (as-built world, DrawLrfUnit); the defaults leave the nominal model unchanged.
  std::vector<double> sigma_along_range_m;  ///< range noise table (empty: sigma_along at any range)
  std::vector<double> sigma_along_table_m;
  double sigma_incidence_gain{0.0};   ///< sigma grows by gain (1/cos(incidence) - 1), at most 2x
  double warmup_amplitude{0.0};       ///< [m] range drift amplitude * exp(-t / warmup_tau) after power-on
  double warmup_tau{1200.0};          ///< [s]

  static LrfOptions FromConfig(const ConfigNode& config);
  double SigmaAcross(double range) const { return sigma_across_per_m * range + sigma_across_const; }
  double AngleIncrement() const;
  double TimeIncrement() const { return scan_period * sweep_fraction / (beams - 1); }
  /// Range bias at range r and incidence angle (0 = normal) [m], positive = reads long.
  double Bias(double range, double incidence) const { return BiasAtCos(range, std::cos(incidence)); }
  /// Range noise's sigma at range r and incidence [m].
  double SigmaAlong(double range, double incidence) const { return SigmaAlongAtCos(range, std::cos(incidence)); }
  /// The same two given cos(incidence) (what a beam has: no acos and cos per beam).
  double BiasAtCos(double range, double cos_incidence) const;
  double SigmaAlongAtCos(double range, double cos_incidence) const;
};

/// How UTM-30LX units differ from the nominal model (data/sim/as_built.yaml `lasers:`).
struct LrfUnitTolerances {
  double walk_bias_scale_sigma{0.15};       ///< each unit's walk term = nominal * N(1, sigma)
  double walk_bias_cos_power_sigma{1.0};    ///< its incidence power = nominal + N(0, sigma)
  double near_bias_shift_sigma_m{0.002};    ///< its near-field term shifted by N(0, sigma) [m]
  std::vector<double> sigma_along_range_m{0.1, 2.0};  ///< range noise table (Pomerleau et al. 2012)
  std::vector<double> sigma_along_m{0.005, 0.018};
  double sigma_incidence_gain{0.3};
  double sigma_unit_scale_sigma{0.1};       ///< each unit's noise = table * N(1, sigma)
  double warmup_amplitude_sigma_m{0.002};   ///< warm-up drift amplitude N(0, sigma) [m]
  double warmup_tau_s{1200.0};              ///< [s]
  static LrfUnitTolerances FromConfig(const ConfigNode& config);
};

/// One unit drawn around the nominal model: its own range-bias curve, noise and warm-up drift.
LrfOptions DrawLrfUnit(const LrfOptions& nominal, const LrfUnitTolerances& tolerances, RandomStream& rng);

/// One simulated beam, with the quantities a test needs to check the model.
struct BeamSample {
  double range{LaserScan::kNoReturn};  ///< what the sensor reports
  double true_range{LaserScan::kNoReturn};  ///< distance to the surface along the actual beam
  double across_offset{0.0};  ///< [m] where the actual beam hit, across the nominal ray
  bool mixed{false};
};

class LrfModel {
 public:
  explicit LrfModel(LrfOptions options)
      : options_(std::move(options)), cos_max_incidence_(std::cos(options_.max_incidence_deg * EIGEN_PI / 180.0)) {}
  const LrfOptions& options() const { return options_; }
  /// The unit has been on for t seconds: its warm-up drift now.
  void SetTimeSincePowerOn(double t) {
    drift_ = options_.warmup_amplitude == 0.0 ? 0.0 : options_.warmup_amplitude * std::exp(-t / options_.warmup_tau);
  }
  double drift() const { return drift_; }

  /// One beam from `origin` along nominal unit direction `d` with in-plane perpendicular `u`
  /// (the direction of increasing beam angle) and out-of-plane normal `w`.
  BeamSample Beam(const World& world, const Eigen::Vector3d& origin, const Eigen::Vector3d& d,
                  const Eigen::Vector3d& u, const Eigen::Vector3d& w, RandomStream& rng) const {
    const auto nominal = world.CastRay(origin, d, 1e-6, options_.range_max + 1.0);
    return Measure(world, origin, d, u, w, nominal, /*near_edge=*/true, rng);
  }

  /// A full scan. `T_site_laser_at(s)` gives the laser pose at fraction s in [0, 1] of the sweep
  /// (the robot may move during a scan); the stamps are filled by the caller.
  template <typename PoseAt>
  void Scan(const World& world, PoseAt&& T_site_laser_at, RandomStream& rng, LaserScan& scan) const {
    const int n = options_.beams;
    scan.angle_min = -0.5 * options_.fov_deg * EIGEN_PI / 180.0;
    scan.angle_increment = options_.AngleIncrement();
    scan.time_increment = options_.TimeIncrement();
    scan.range_min = options_.range_min;
    scan.range_max = options_.range_max;
    scan.ranges.resize(static_cast<std::size_t>(n));
    rays_.resize(static_cast<std::size_t>(n));
    constexpr int kPoseSegments = 16;  // the pose is interpolated between 17 samples per scan
    Pose3 poses[kPoseSegments + 1];
    for (int k = 0; k <= kPoseSegments; ++k) poses[k] = T_site_laser_at(double(k) / kPoseSegments);
    // The beam angles' cos and sin, once per laser (the same values as computing them per scan).
    if (beam_cos_sin_.size() != static_cast<std::size_t>(n) || beam_angle_min_ != scan.angle_min ||
        beam_angle_increment_ != scan.angle_increment) {
      beam_cos_sin_.resize(static_cast<std::size_t>(n));
      for (int i = 0; i < n; ++i) {
        const double a = scan.Angle(static_cast<std::size_t>(i));
        beam_cos_sin_[static_cast<std::size_t>(i)] = Eigen::Vector2d(std::cos(a), std::sin(a));
      }
      beam_angle_min_ = scan.angle_min;
      beam_angle_increment_ = scan.angle_increment;
    }
    // Pass 1: the nominal beams (one ray cast each).
    for (int i = 0; i < n; ++i) {
      const double s = double(i) / (n - 1);
      const int k = std::min(kPoseSegments - 1, int(s * kPoseSegments));
      const double f = s * kPoseSegments - k;
      Ray& ray = rays_[static_cast<std::size_t>(i)];
      ray.o = (1 - f) * poses[k].translation() + f * poses[k + 1].translation();
      const Eigen::Matrix3d& R = f < 0.5 ? poses[k].linear() : poses[k + 1].linear();
      const Eigen::Vector2d& cs = beam_cos_sin_[static_cast<std::size_t>(i)];
      ray.d = R * Eigen::Vector3d(cs.x(), cs.y(), 0.0);
      ray.u = R * Eigen::Vector3d(-cs.y(), cs.x(), 0.0);
      ray.w = R.col(2);
      ray.hit = world.CastRay(ray.o, ray.d, 1e-6, options_.range_max + 1.0);
    }
    // Pass 2: measure; only beams beside a depth edge need the full (multi-ray) treatment.
    auto range_of = [&](int i) {
      const auto& h = rays_[static_cast<std::size_t>(i)].hit;
      return h ? h->range : 1e9;
    };
    auto object_of = [&](int i) {
      const auto& h = rays_[static_cast<std::size_t>(i)].hit;
      return h ? h->object : -2;
    };
    for (int i = 0; i < n; ++i) {
      // A beam within two of another object or depth is near an edge: its jitter and footprint
      // (2.5 mrad at 0.8 m for the UTM-30LX) reach past its neighbour (4.4 mrad away).
      bool near_edge = false;
      double edge_range = range_of(i);  // the nearer surface beside the edge: where the beam meets it
      for (int j = std::max(0, i - 2); j <= std::min(n - 1, i + 2); ++j) {
        if (j == i) continue;
        near_edge = near_edge || object_of(j) != object_of(i) ||
                    std::abs(range_of(j) - range_of(i)) > options_.mixed_pixel_threshold;
        edge_range = std::min(edge_range, range_of(j));
      }
      const Ray& ray = rays_[static_cast<std::size_t>(i)];
      scan.ranges[static_cast<std::size_t>(i)] =
          Measure(world, ray.o, ray.d, ray.u, ray.w, ray.hit, near_edge, rng, edge_range).range;
    }
  }

 private:
  struct Ray {
    Eigen::Vector3d o, d, u, w;
    std::optional<WorldHit> hit;
  };
  /// The measurement of one beam given its nominal hit. Away from edges the beam's small
  /// deviation is intersected with the plane of the nominal hit instead of the whole world.
  /// `edge_range`: the range of the nearer surface beside a depth edge (the neighbour beams'),
  /// where the beam's footprint meets the edge; infinity: the beam's own range.
  BeamSample Measure(const World& world, const Eigen::Vector3d& origin, const Eigen::Vector3d& d,
                     const Eigen::Vector3d& u, const Eigen::Vector3d& w, const std::optional<WorldHit>& nominal,
                     bool near_edge, RandomStream& rng,
                     double edge_range = std::numeric_limits<double>::infinity()) const;

  LrfOptions options_;
  double cos_max_incidence_;  // cos(max_incidence_deg): no return below it
  double drift_{0.0};  // [m] warm-up drift added to every range
  mutable std::vector<Ray> rays_;  // scratch of Scan(); an LrfModel is not shared across threads
  mutable std::vector<Eigen::Vector2d> beam_cos_sin_;  // per beam, for the angles below
  mutable double beam_angle_min_{0.0}, beam_angle_increment_{0.0};
};

}  // namespace ifab::sim
