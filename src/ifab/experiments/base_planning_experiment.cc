#include "ifab/experiments/base_planning_experiment.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "ifab/core/angles.h"
#include "ifab/core/error.h"

namespace ifab::experiments {
namespace {

using base::FootprintChecker;
using base::PlanResult;
using base::StompBasePlanner;

double Percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const double pos = p * (static_cast<double>(v.size()) - 1.0);
  const std::size_t lo = static_cast<std::size_t>(std::floor(pos));
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

nlohmann::json PoseJson(const Pose2& p) { return {p.x, p.y, p.theta}; }

}  // namespace

BasePlanningExperimentOptions BasePlanningExperimentOptions::FromConfig(const ConfigNode& node) {
  BasePlanningExperimentOptions o;
  node.ExpectKeys({"cases", "seed", "building_position_fraction", "workpiece", "building_radius_min",
                   "building_radius_max", "building_heading_noise", "building_region", "free_pose_boundary_margin",
                   "pose_min_clearance", "max_failures_listed"});
  node.ReadPositive("cases", o.cases);
  node.Read("seed", o.seed);
  node.ReadInRange("building_position_fraction", o.building_position_fraction, 0.0, 1.0);
  if (auto w = node.Find("workpiece")) {
    const auto v = w->AsNumbers(2);
    o.workpiece = {v[0], v[1]};
  }
  node.ReadPositive("building_radius_min", o.building_radius_min);
  node.ReadPositive("building_radius_max", o.building_radius_max);
  if (o.building_radius_max < o.building_radius_min) node["building_radius_max"].Fail("a number >= building_radius_min");
  node.ReadNonNegative("building_heading_noise", o.building_heading_noise);
  if (auto r = node.Find("building_region")) {
    const auto v = r->AsNumbers(4);
    if (!(v[0] < v[1] && v[2] < v[3])) r->Fail("[xmin, xmax, ymin, ymax] with xmin < xmax and ymin < ymax");
    o.building_region = {v[0], v[1], v[2], v[3]};
  }
  node.Read("free_pose_boundary_margin", o.free_pose_boundary_margin);
  node.ReadNonNegative("pose_min_clearance", o.pose_min_clearance);
  node.ReadNonNegative("max_failures_listed", o.max_failures_listed);
  return o;
}

Pose2 SampleExperimentPose(const FootprintChecker& checker, const BasePlanningExperimentOptions& o, RandomStream& rng) {
  const auto& boundary = checker.scene().boundary;
  Eigen::Vector2d lo(-5, -5), hi(5, 5);
  if (!boundary.empty()) {
    lo = hi = boundary[0];
    for (const auto& p : boundary) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
  const double margin = o.free_pose_boundary_margin < 0 ? checker.robot().CircumRadius() : o.free_pose_boundary_margin;
  const bool building = rng.Bernoulli(o.building_position_fraction);
  for (int attempt = 0; attempt < 100000; ++attempt) {
    Pose2 pose;
    if (building) {
      const double a = rng.Uniform(-kPi, kPi);
      const double r = rng.Uniform(o.building_radius_min, o.building_radius_max);
      const Eigen::Vector2d c = o.workpiece + r * Eigen::Vector2d(std::cos(a), std::sin(a));
      const Eigen::Vector4d& box = o.building_region;
      if (c.x() < box[0] || c.x() > box[1] || c.y() < box[2] || c.y() > box[3]) continue;
      pose = Pose2(c.x(), c.y(), WrapAngle(a + kPi + rng.Uniform(-o.building_heading_noise, o.building_heading_noise)));
    } else {
      // Heading first, then y, then x: gcc's order of the arguments (C++ leaves it open).
      const double theta = rng.Uniform(-kPi, kPi), y = rng.Uniform(lo.y(), hi.y()), x = rng.Uniform(lo.x(), hi.x());
      pose = Pose2(x, y, theta);
    }
    if (checker.Clearance(pose) < o.pose_min_clearance) continue;
    if (!building && !boundary.empty()) {
      const Eigen::Vector2d c = pose * checker.robot().footprint_offset;
      double d = std::numeric_limits<double>::infinity();
      for (std::size_t i = 0; i < boundary.size(); ++i) {
        const Eigen::Vector2d a = boundary[i], b = boundary[(i + 1) % boundary.size()];
        const Eigen::Vector2d ab = b - a;
        const double t = std::clamp((c - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
        d = std::min(d, (a + t * ab - c).norm());
      }
      if (d < margin) continue;
    }
    return pose;
  }
  ThrowInputError("base-planning experiment: found no free pose to sample in the site (is the robot larger than it?)");
}

nlohmann::json RunBasePlanningExperiment(const StompBasePlanner& planner, const BasePlanningExperimentOptions& o,
                                         std::vector<BasePlanningCase>* cases_out) {
  const RandomStream root(o.seed);
  std::vector<double> plan_ms, iterations, lengths;
  std::map<std::string, int> status_counts;
  int successes = 0;
  double max_lateral = 0.0, min_clearance = std::numeric_limits<double>::infinity();
  double max_track = 0.0;
  nlohmann::json failures = nlohmann::json::array();
  for (int k = 0; k < o.cases; ++k) {
    const RandomStream case_rng = root.Derive(static_cast<std::uint64_t>(k));
    RandomStream pose_rng = case_rng.Derive("poses");
    BasePlanningCase c;
    c.start = SampleExperimentPose(planner.checker(), o, pose_rng);
    c.goal = SampleExperimentPose(planner.checker(), o, pose_rng);
    c.result = planner.Plan(c.start, c.goal, case_rng.Derive("planner"));
    const PlanResult& r = c.result;
    plan_ms.push_back(r.seconds * 1e3);
    iterations.push_back(r.iterations);
    ++status_counts[PlanStatusName(r.status)];
    if (r.IsUsable()) {
      ++successes;
      max_lateral = std::max(max_lateral, r.max_lateral_velocity);
      min_clearance = std::min(min_clearance, r.min_clearance);
      max_track = std::max(max_track, r.max_track_speed);
      lengths.push_back(r.trajectory.Length());
    } else if (static_cast<int>(failures.size()) < o.max_failures_listed) {
      failures.push_back({{"case", k}, {"start", PoseJson(c.start)}, {"goal", PoseJson(c.goal)},
                          {"status", PlanStatusName(r.status)}, {"message", r.message},
                          {"min_clearance_m", r.min_clearance}, {"phase1_clearance_m", r.phase1_clearance},
                          {"max_constraint_violation_m", r.max_constraint_violation}});
    }
    if (cases_out) cases_out->push_back(std::move(c));
  }
  nlohmann::json j;
  j["cases"] = o.cases;
  j["successes"] = successes;
  j["success_rate"] = o.cases > 0 ? static_cast<double>(successes) / o.cases : 0.0;
  j["plan_ms_median"] = Percentile(plan_ms, 0.5);
  j["plan_ms_p95"] = Percentile(plan_ms, 0.95);
  j["plan_ms_max"] = Percentile(plan_ms, 1.0);
  j["iterations_median"] = Percentile(iterations, 0.5);
  j["max_lateral_velocity_mps"] = max_lateral;
  j["min_clearance_m"] = successes > 0 ? min_clearance : 0.0;
  j["max_track_speed_mps"] = max_track;
  j["path_length_median_m"] = Percentile(lengths, 0.5);
  j["status_counts"] = status_counts;
  j["failures"] = failures;
  j["seed"] = o.seed;
  j["rollout_threads"] = planner.options().num_threads;
  return j;
}

}  // namespace ifab::experiments
