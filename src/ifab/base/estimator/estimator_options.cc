// EstimatorOptions: reading from YAML and validation; status names.
#include "ifab/base/estimator/estimator_options.h"

#include <fmt/format.h>

#include "ifab/base/estimator/estimate.h"
#include "ifab/core/error.h"

namespace ifab::base {

// ---------------------------------------------------------------------------------------------
// Options

namespace {

MatchResidual ParseResidual(const ConfigNode& node) {
  const auto s = node.As<std::string>();
  if (s == "kernel") return MatchResidual::kKernel;
  if (s == "point_to_line") return MatchResidual::kPointToLine;
  node.Fail("'kernel' or 'point_to_line'");
}

ReferenceWeighting ParseWeighting(const ConfigNode& node) {
  const auto s = node.As<std::string>();
  if (s == "none") return ReferenceWeighting::kNone;
  if (s == "arc_length") return ReferenceWeighting::kArcLength;
  node.Fail("'none' or 'arc_length'");
}

Thinning ParseThinning(const ConfigNode& node) {
  const auto s = node.As<std::string>();
  if (s == "nearest_beyond_spacing") return Thinning::kNearestBeyondSpacing;
  if (s == "noise_independent") return Thinning::kNoiseIndependent;
  node.Fail("'nearest_beyond_spacing' or 'noise_independent'");
}

MotionPrior ParseMotionPrior(const ConfigNode& node) {
  const auto s = node.As<std::string>();
  if (s == "none") return MotionPrior::kNone;
  if (s == "constant_velocity") return MotionPrior::kConstantVelocity;
  node.Fail("'none' or 'constant_velocity'");
}

}  // namespace

EstimatorOptions EstimatorOptions::FromConfig(const ConfigNode& node) {
  EstimatorOptions o;
  node.ExpectKeys({"min_range", "max_range", "min_point_spacing", "max_points", "max_beams",
                   "min_points", "residual", "sigma", "coarse_sigmas", "search_radius_sigmas",
                   "neighbors_per_reference", "num_reference_scans", "keyframe_distance",
                   "keyframe_angle_deg", "keyframe_interval", "horizon",
                   "reference_point_spacing", "gyro_weight", "motion_prior", "max_associations",
                   "max_iterations", "converged_step", "min_matched_fraction",
                   "degeneracy_ratio", "max_rotation_jump_deg", "max_translation_jump",
                   "reseed_after_failures", "max_reference_gap_sigmas", "end_margin_sigmas",
                   "prior_weight", "reference_weighting", "interpolate_reference",
                   "keyframe_capacity", "thinning", "deskew", "min_inlier_fraction",
                   "gate_probability", "gate_translation_only", "window_gate_probability", "window_gate_distance", "remap_degenerate", "prior_scale_window",
                   "structure_degeneracy_ratio", "structure_normal_radius", "commanded_speeds"});
  node.ReadNonNegative("min_range", o.min_range);
  node.ReadPositive("max_range", o.max_range);
  node.ReadNonNegative("min_point_spacing", o.min_point_spacing);
  if (auto c = node.Find("thinning")) o.thinning = ParseThinning(*c);
  node.Read("deskew", o.deskew);
  node.ReadPositive("max_points", o.max_points);
  node.ReadPositive("max_beams", o.max_beams, 100000);  // no 2D laser has more beams a scan
  node.ReadPositive("min_points", o.min_points);
  if (auto c = node.Find("residual")) o.residual = ParseResidual(*c);
  node.ReadPositive("sigma", o.sigma);
  if (auto c = node.Find("coarse_sigmas")) {
    o.coarse_sigmas = c->AsNumbers();
    for (double s : o.coarse_sigmas) {
      if (!(s > 0.0)) c->Fail("a list of positive numbers");
    }
  }
  node.ReadPositive("search_radius_sigmas", o.search_radius_sigmas);
  node.ReadPositive("neighbors_per_reference", o.neighbors_per_reference);
  node.ReadPositive("num_reference_scans", o.num_reference_scans);
  node.ReadNonNegative("keyframe_distance", o.keyframe_distance);
  node.ReadNonNegative("keyframe_angle_deg", o.keyframe_angle_deg);
  node.ReadPositive("keyframe_interval", o.keyframe_interval);
  node.ReadPositive("horizon", o.horizon);
  node.ReadNonNegative("reference_point_spacing", o.reference_point_spacing);
  node.ReadNonNegative("max_reference_gap_sigmas", o.max_reference_gap_sigmas);
  node.ReadNonNegative("end_margin_sigmas", o.end_margin_sigmas);
  node.ReadNonNegative("prior_weight", o.prior_weight);
  if (auto c = node.Find("reference_weighting")) o.reference_weighting = ParseWeighting(*c);
  node.Read("interpolate_reference", o.interpolate_reference);
  node.ReadNonNegative("keyframe_capacity", o.keyframe_capacity);
  node.ReadNonNegative("gyro_weight", o.gyro_weight);
  if (auto c = node.Find("motion_prior")) o.motion_prior = ParseMotionPrior(*c);
  node.ReadPositive("max_associations", o.max_associations);
  node.ReadPositive("max_iterations", o.max_iterations);
  node.ReadPositive("converged_step", o.converged_step);
  node.ReadInRange("min_matched_fraction", o.min_matched_fraction, 0.0, 1.0);
  node.ReadInRange("degeneracy_ratio", o.degeneracy_ratio, 0.0, 1.0);
  node.ReadInRange("structure_degeneracy_ratio", o.structure_degeneracy_ratio, 0.0, 1.0);
  node.ReadPositive("structure_normal_radius", o.structure_normal_radius);
  node.ReadPositive("max_rotation_jump_deg", o.max_rotation_jump_deg);
  node.ReadPositive("max_translation_jump", o.max_translation_jump);
  node.ReadNonNegative("reseed_after_failures", o.reseed_after_failures);
  node.ReadInRange("min_inlier_fraction", o.min_inlier_fraction, 0.0, 1.0);
  node.ReadInRange("gate_probability", o.gate_probability, 0.0, 1.0 - 1e-12);
  node.Read("gate_translation_only", o.gate_translation_only);
  node.ReadInRange("window_gate_probability", o.window_gate_probability, 0.0, 1.0 - 1e-12);
  node.ReadPositive("window_gate_distance", o.window_gate_distance);
  node.Read("remap_degenerate", o.remap_degenerate);
  node.ReadNonNegative("prior_scale_window", o.prior_scale_window);
  if (auto c = node.Find("commanded_speeds")) o.commanded_speeds = CommandedSpeedOptions::FromConfig(*c);
  const std::string problem = o.Validate();
  if (!problem.empty()) ThrowInputError("{}: {}", node.Where(), problem);
  return o;
}

std::string EstimatorOptions::Validate() const {
  if (!(max_range > min_range)) return fmt::format("max_range {} must exceed min_range {}", max_range, min_range);
  if (max_points <= 0 || max_beams <= 0 || min_points <= 0) return "max_points, max_beams and min_points must be positive";
  if (min_points > max_points) return fmt::format("min_points {} exceeds max_points {}", min_points, max_points);
  if (!(sigma > 0.0)) return "sigma must be positive";
  for (double s : coarse_sigmas) {
    if (!(s > 0.0)) return "coarse_sigmas must be positive";
  }
  if (num_reference_scans <= 0 || neighbors_per_reference <= 0) return "num_reference_scans and neighbors_per_reference must be positive";
  if (max_associations <= 0 || max_iterations <= 0) return "max_associations and max_iterations must be positive";
  if (gyro_weight < 0.0) return "gyro_weight must be >= 0";
  return {};
}

const char* StatusName(EstimateStatus status) {
  switch (status) {
    case EstimateStatus::kOk: return "ok";
    case EstimateStatus::kDegenerate: return "degenerate";
    case EstimateStatus::kReference: return "reference";
    case EstimateStatus::kTooFewPoints: return "too_few_points";
    case EstimateStatus::kPoorScore: return "poor_score";
    case EstimateStatus::kUnexplainedJump: return "unexplained_jump";
    case EstimateStatus::kSolverFailed: return "solver_failed";
  }
  return "unknown";
}

}  // namespace ifab::base
