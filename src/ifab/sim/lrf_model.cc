#include "ifab/sim/lrf_model.h"

#include <cmath>

#include "ifab/core/angles.h"
#include "ifab/core/config.h"

namespace ifab::sim {
namespace {

// Piecewise-linear table lookup, flat beyond the ends.
double Lookup(const std::vector<double>& x, const std::vector<double>& y, double v) {
  if (x.empty()) return 0.0;
  if (v <= x.front()) return y.front();
  if (v >= x.back()) return y.back();
  for (std::size_t i = 0; i + 1 < x.size(); ++i) {
    if (v <= x[i + 1]) {
      const double s = (v - x[i]) / (x[i + 1] - x[i]);
      return y[i] + s * (y[i + 1] - y[i]);
    }
  }
  return y.back();
}

void ReadTable(const ConfigNode& c, const char* key_x, const char* key_y, std::vector<double>& x,
               std::vector<double>& y) {
  if (!c.Has(key_x) && !c.Has(key_y)) return;
  x = c[key_x].AsNumbers();
  y = c[key_y].AsNumbers();
  if (x.size() != y.size() || x.empty()) c[key_y].Fail(fmt::format("as many numbers as {} ({})", key_x, x.size()));
  for (std::size_t i = 1; i < x.size(); ++i)
    if (!(x[i] > x[i - 1])) c[key_x].Fail("strictly increasing ranges");
}

}  // namespace

LrfOptions LrfOptions::FromConfig(const ConfigNode& c) {
  c.ExpectKeys({"beams", "fov_deg", "scan_period", "sweep_fraction", "range_min", "range_max",
                "sigma_along", "sigma_across_per_m", "sigma_across_const", "near_bias_range_m",
                "near_bias_m", "walk_bias_range_m", "walk_bias_m", "walk_bias_cos_power",
                "mixed_pixel_threshold", "mixed_pixel_probability", "beam_divergence",
                "no_return_probability", "max_incidence_deg", "dropped_scan_probability",
                "bias_enabled", "noise_enabled"});
  LrfOptions o;
  c.ReadPositive("beams", o.beams, 100000);  // no 2D laser has more beams a scan
  if (o.beams < 2) c["beams"].Fail("at least 2 beams");
  c.ReadInRange("fov_deg", o.fov_deg, 1.0, 360.0);
  c.ReadPositive("scan_period", o.scan_period);
  c.ReadInRange("sweep_fraction", o.sweep_fraction, 0.01, 1.0);
  c.ReadPositive("range_min", o.range_min);
  c.ReadPositive("range_max", o.range_max);
  if (o.range_max <= o.range_min) c["range_max"].Fail("a number above range_min");
  c.ReadNonNegative("sigma_along", o.sigma_along);
  c.ReadNonNegative("sigma_across_per_m", o.sigma_across_per_m);
  c.ReadNonNegative("sigma_across_const", o.sigma_across_const);
  ReadTable(c, "near_bias_range_m", "near_bias_m", o.near_bias_range_m, o.near_bias_m);
  ReadTable(c, "walk_bias_range_m", "walk_bias_m", o.walk_bias_range_m, o.walk_bias_m);
  c.ReadNonNegative("walk_bias_cos_power", o.walk_bias_cos_power);
  c.ReadPositive("mixed_pixel_threshold", o.mixed_pixel_threshold);
  c.ReadInRange("mixed_pixel_probability", o.mixed_pixel_probability, 0.0, 1.0);
  c.ReadNonNegative("beam_divergence", o.beam_divergence);
  c.ReadInRange("no_return_probability", o.no_return_probability, 0.0, 1.0);
  c.ReadInRange("max_incidence_deg", o.max_incidence_deg, 0.0, 90.0);
  c.ReadInRange("dropped_scan_probability", o.dropped_scan_probability, 0.0, 1.0);
  c.Read("bias_enabled", o.bias_enabled);
  c.Read("noise_enabled", o.noise_enabled);
  return o;
}

double LrfOptions::AngleIncrement() const { return DegToRad(fov_deg) / (beams - 1); }

double LrfOptions::BiasAtCos(double range, double cos_incidence) const {
  if (!bias_enabled) return 0.0;
  const double c = std::max(0.0, cos_incidence);
  // Integer powers by multiplication: std::pow dominated the scan's cost.
  const double p = walk_bias_cos_power;
  double cp = 1.0;
  if (p == std::floor(p) && p <= 16) {
    for (int k = 0; k < static_cast<int>(p); ++k) cp *= c;
  } else {
    cp = std::pow(c, p);
  }
  return Lookup(near_bias_range_m, near_bias_m, range) + Lookup(walk_bias_range_m, walk_bias_m, range) * cp;
}

double LrfOptions::SigmaAlongAtCos(double range, double cos_incidence) const {
  const double base = sigma_along_table_m.empty() ? sigma_along : Lookup(sigma_along_range_m, sigma_along_table_m, range);
  if (sigma_incidence_gain == 0.0) return base;
  const double c = std::max(0.5, cos_incidence);
  return base * std::min(2.0, 1.0 + sigma_incidence_gain * (1.0 / c - 1.0));
}

LrfUnitTolerances LrfUnitTolerances::FromConfig(const ConfigNode& c) {
  LrfUnitTolerances o;
  c.ReadNonNegative("walk_bias_scale_sigma", o.walk_bias_scale_sigma);
  c.ReadNonNegative("walk_bias_cos_power_sigma", o.walk_bias_cos_power_sigma);
  c.ReadNonNegative("near_bias_shift_sigma_m", o.near_bias_shift_sigma_m);
  ReadTable(c, "sigma_along_range_m", "sigma_along_m", o.sigma_along_range_m, o.sigma_along_m);
  c.ReadNonNegative("sigma_incidence_gain", o.sigma_incidence_gain);
  c.ReadNonNegative("sigma_unit_scale_sigma", o.sigma_unit_scale_sigma);
  c.ReadNonNegative("warmup_amplitude_sigma_m", o.warmup_amplitude_sigma_m);
  c.ReadPositive("warmup_tau_s", o.warmup_tau_s);
  return o;
}

LrfOptions DrawLrfUnit(const LrfOptions& nominal, const LrfUnitTolerances& t, RandomStream& rng) {
  LrfOptions o = nominal;
  const double walk_scale = std::max(0.0, 1.0 + rng.Normal(t.walk_bias_scale_sigma));
  for (double& b : o.walk_bias_m) b *= walk_scale;
  o.walk_bias_cos_power = std::max(1.0, std::round(nominal.walk_bias_cos_power + rng.Normal(t.walk_bias_cos_power_sigma)));
  // The near-field term shifts where it is non-zero (it still fades to 0 at the table's end).
  const double shift = rng.Normal(t.near_bias_shift_sigma_m);
  for (std::size_t i = 0; i + 1 < o.near_bias_m.size(); ++i) o.near_bias_m[i] += shift;
  const double noise_scale = std::max(0.3, 1.0 + rng.Normal(t.sigma_unit_scale_sigma));
  o.sigma_along_range_m = t.sigma_along_range_m;
  o.sigma_along_table_m = t.sigma_along_m;
  for (double& s : o.sigma_along_table_m) s *= noise_scale;
  o.sigma_along = noise_scale * nominal.sigma_along;
  o.sigma_incidence_gain = t.sigma_incidence_gain;
  o.warmup_amplitude = rng.Normal(t.warmup_amplitude_sigma_m);
  o.warmup_tau = t.warmup_tau_s;
  return o;
}

BeamSample LrfModel::Measure(const World& world, const Eigen::Vector3d& origin, const Eigen::Vector3d& d,
                             const Eigen::Vector3d& u, const Eigen::Vector3d& w,
                             const std::optional<WorldHit>& nominal, bool near_edge, RandomStream& rng,
                             double edge_range) const {
  const LrfOptions& o = options_;
  BeamSample out;
  const bool noisy = o.noise_enabled;
  if (noisy && rng.Bernoulli(o.no_return_probability)) return out;
  if (!nominal) return out;

  // Where the beam really points: the nominal ray plus an offset across it whose size at range r
  // is sigma_across(r) (encoder jitter in the scan plane, spot centroid out of it).
  Eigen::Vector3d dir = d;
  std::optional<WorldHit> hit = nominal;
  if (noisy) {
    // As an angle, where the beam meets an edge beside it (the nearer surface): a beam passing an
    // edge to the floor jitters as far there as its neighbour ending on the edge's face, so the
    // two cross it as often.
    const double r0 = nominal->range;
    const double r_jitter = near_edge ? std::max(std::min(r0, edge_range), 0.1) : r0;
    const double sigma = o.SigmaAcross(r_jitter) / r_jitter;
    // The ziggurat (core/random.h): the same normal distribution, a few times cheaper per draw.
    const double a_in = rng.NormalZiggurat(sigma);
    const double a_out = rng.NormalZiggurat(sigma);
    dir = (d + a_in * u + a_out * w).normalized();
    out.across_offset = a_in * r0;  // where it lands, across the nominal ray
    if (near_edge) {
      hit = world.CastRay(origin, dir, 1e-6, o.range_max + 1.0);
    } else {  // same surface: intersect the deviated ray with the nominal hit's plane
      const double denom = nominal->normal.dot(dir);
      if (denom < -1e-9) hit->range = nominal->range * nominal->normal.dot(d) / denom;
    }
  }
  if (!hit) return out;
  // cos(incidence), compared with cos of the limit (acos is decreasing): no acos per beam.
  const double cos_incidence = std::clamp(-hit->normal.dot(dir), -1.0, 1.0);
  if (cos_incidence < cos_max_incidence_) return out;
  out.true_range = hit->range;
  double range = hit->range;

  // Mixed pixels: the beam's footprint straddles a depth edge (probe both sides of the beam).
  // The footprint's width is the one where it meets the edge, at the nearer surface's range: a
  // beam passing an edge to the floor behind is as wide there as one ending on the edge's face
  // (taken at its own far range, it would mix less often than its neighbour across the edge,
  // and the edge would read moved towards the far side).
  if (noisy && near_edge && o.beam_divergence > 0.0) {
    const double spread = o.beam_divergence + o.sigma_across_const / std::max(std::min(range, edge_range), 0.1);
    for (double side : {-1.0, 1.0}) {
      const auto probe = world.CastRay(origin, (dir + side * spread * u).normalized(), 1e-6, o.range_max + 1.0);
      const double r_probe = probe ? probe->range : o.range_max + 1.0;
      if (std::abs(r_probe - range) > o.mixed_pixel_threshold && r_probe <= o.range_max &&
          rng.Bernoulli(o.mixed_pixel_probability)) {
        range = range + rng.Uniform(0.0, 1.0) * (r_probe - range);
        out.mixed = true;
        break;
      }
    }
  }
  range += o.BiasAtCos(range, cos_incidence) + drift_;
  if (noisy) range += rng.NormalZiggurat(o.SigmaAlongAtCos(range, cos_incidence));
  if (range < o.range_min || range > o.range_max) return out;
  out.range = range;
  return out;
}

}  // namespace ifab::sim
