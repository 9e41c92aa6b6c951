#include "ifab/experiments/arm_planning_experiment.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "ifab/arm/arm_model.h"
#include "ifab/arm/primitives.h"
#include "ifab/core/angles.h"
#include "ifab/core/config.h"
#include "ifab/core/random.h"

namespace ifab::experiments {
namespace {

using arm::ArmModel;
using arm::ArmPlan;
using arm::IkOptions;
using arm::IlqgOptions;
using arm::ArmPrimitives;
using arm::IkResult;
using arm::IkSolver;
using arm::IlqgPlanner;
using arm::PlanSummary;

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Gripper pointing down at (r, azimuth, z) in arm_base with yaw about the vertical.
Pose3 GripperDown(double radius, double azimuth, double z, double yaw) {
  Pose3 T = Pose3::Identity();
  T.translation() = Eigen::Vector3d(radius * std::cos(azimuth), radius * std::sin(azimuth), z);
  T.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(kPi, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  return T;
}

class CaseGenerator {
 public:
  CaseGenerator(const RobotModel& robot, const ArmPlanningExperimentConfig& config)
      : robot_(robot), config_(config), ik_(robot, config.ik) {}

  // A configuration with the gripper down at a random task pose (azimuth range in rad), raised by
  // `lift`, solved nearest to q_near. Retries until reachable.
  bool TaskConfiguration(RandomStream& rng, double az_lo, double az_hi, double lift, const Vector6d& q_near,
                         Vector6d& q, Pose3* T_grip = nullptr) {
    for (int attempt = 0; attempt < 50; ++attempt) {
      const double r = rng.Uniform(config_.radius_min, config_.radius_max);
      const double az = rng.Uniform(az_lo, az_hi);
      const double z = rng.Uniform(config_.height_min, config_.height_max);
      const double yaw = az + rng.Uniform(-kPi / 2, kPi / 2);
      const Pose3 grip = GripperDown(r, az, z, yaw);
      if (Solve(grip, lift, q_near, q)) {
        if (T_grip) *T_grip = grip;
        return true;
      }
    }
    return false;
  }

  bool Solve(const Pose3& T_grip, double lift, const Vector6d& q_near, Vector6d& q) {
    Pose3 raised = T_grip;
    raised.translation().z() += lift;
    const Pose3 T_arm_base_tool0 = raised * robot_.T_tool0_gripper.inverse();
    const IkResult r = ik_.Solve(T_arm_base_tool0, q_near);
    if (!r.ok()) return false;
    q = r.q;
    return true;
  }

  // The arm configuration above (lift) or at the feeder's brick, nearest to q_near.
  bool FeederConfiguration(RandomStream& rng, double lift, const Vector6d& q_near, Vector6d& q, Pose3* T_grip) {
    const Pose3 T_arm_base_brick = robot_.T_base_arm_base.inverse() * *config_.T_base_feeder_brick;
    Box brick;
    brick.size.z() = config_.brick_height;
    const Pose3 grip = ArmPrimitives::GripperPoseOnBrick(T_arm_base_brick, brick, rng.Bernoulli(0.5));
    if (T_grip) *T_grip = grip;
    return Solve(grip, lift, q_near, q);
  }

  bool Make(int index, RandomStream rng, ArmPlanningCase& c) {
    c.index = index;
    const double u = rng.Uniform();
    const Vector6d& home = config_.q_home;
    const double a = config_.approach_height;
    const double side = rng.Bernoulli(0.5) ? 1.0 : -1.0;
    const double feeder_lo = DegToRad(50.0), feeder_hi = DegToRad(120.0), stack = DegToRad(45.0);
    const bool on_board_feeder = config_.T_base_feeder_brick.has_value();
    if (u < config_.transfer_fraction) {
      c.kind = "transfer";
      Vector6d q_feeder, q_stack;
      const bool ok = on_board_feeder
                          ? FeederConfiguration(rng, a, home, q_feeder, nullptr)
                          : TaskConfiguration(rng, side > 0 ? feeder_lo : -feeder_hi, side > 0 ? feeder_hi : -feeder_lo,
                                              a, home, q_feeder);
      if (!ok) return false;
      if (!TaskConfiguration(rng, -stack, stack, a, q_feeder, q_stack)) return false;
      const bool to_stack = rng.Bernoulli(0.5);
      c.q_from = to_stack ? q_feeder : q_stack;
      c.q_to = to_stack ? q_stack : q_feeder;
    } else if (u < config_.transfer_fraction + config_.approach_fraction) {
      c.kind = "approach";
      Vector6d q_above, q_contact;
      Pose3 grip;
      // Half of the descents onto the feeder's brick when it rides on the robot.
      const bool ok = on_board_feeder && rng.Bernoulli(0.5)
                          ? FeederConfiguration(rng, a, home, q_above, &grip)
                          : TaskConfiguration(rng, -feeder_hi, feeder_hi, a, home, q_above, &grip);
      if (!ok) return false;
      if (!Solve(grip, 0.0, q_above, q_contact)) return false;
      const bool down = rng.Bernoulli(0.5);
      c.q_from = down ? q_above : q_contact;
      c.q_to = down ? q_contact : q_above;
    } else if (u < config_.transfer_fraction + config_.approach_fraction + config_.scan_fraction) {
      Vector6d q_task;
      if (!TaskConfiguration(rng, -stack, stack, a, home, q_task)) return false;
      if (rng.Bernoulli(0.5)) {
        // A sweep of one joint (the paper's scans sweep joints one at a time).
        c.kind = "sweep";
        static constexpr int kSweepJoints[] = {0, 3, 4, 5};
        const int j = kSweepJoints[rng.UniformInt(0, 3)];
        const double amplitude = DegToRad(rng.Uniform(config_.sweep_min_deg, config_.sweep_max_deg));
        c.q_from = q_task;
        c.q_to = q_task;
        double target = q_task[j] + (rng.Bernoulli(0.5) ? amplitude : -amplitude);
        if (target > robot_.q_max[j] || target < robot_.q_min[j]) target = q_task[j] - (target - q_task[j]);
        c.q_to[j] = std::clamp(target, robot_.q_min[j], robot_.q_max[j]);
      } else {
        // To a scan pose 0.4-0.8 m above the work.
        c.kind = "scan_pose";
        Vector6d q_scan;
        if (!TaskConfiguration(rng, -stack, stack, rng.Uniform(0.4, 0.8), q_task, q_scan)) return false;
        c.q_from = q_task;
        c.q_to = q_scan;
      }
    } else {
      c.kind = "home";
      Vector6d q_task;
      if (!TaskConfiguration(rng, -feeder_hi, feeder_hi, a, home, q_task)) return false;
      const bool leave = rng.Bernoulli(0.5);
      c.q_from = leave ? home : q_task;
      c.q_to = leave ? q_task : home;
    }
    return true;
  }

 private:
  const RobotModel& robot_;
  const ArmPlanningExperimentConfig& config_;
  IkSolver ik_;
};

}  // namespace

ArmPlanningExperimentConfig ArmPlanningExperimentConfig::FromConfig(const ConfigNode& node,
                                                                    const ArmPlanningExperimentConfig& base) {
  node.ExpectMap();
  // seed, robot and arm are read by the experiment wrapper (src/ifab/experiments/arm_planning.cc).
  node.ExpectKeys({"seed", "robot", "robot_yaml", "arm", "cases", "mix", "workspace", "sweep_deg", "home_deg",
                   "brick_height", "ilqg", "ik"});
  ArmPlanningExperimentConfig c = base;
  node.ReadPositive("cases", c.cases);
  if (auto mix = node.Find("mix")) {
    mix->ExpectKeys({"transfer", "approach", "scan"});
    mix->ReadInRange("transfer", c.transfer_fraction, 0.0, 1.0);
    mix->ReadInRange("approach", c.approach_fraction, 0.0, 1.0);
    mix->ReadInRange("scan", c.scan_fraction, 0.0, 1.0);
    if (c.transfer_fraction + c.approach_fraction + c.scan_fraction > 1.0 + 1e-9)
      mix->Fail("fractions transfer + approach + scan <= 1 (the rest are home moves)");
  }
  if (auto ws = node.Find("workspace")) {
    ws->ExpectKeys({"radius", "height", "approach_height"});
    if (auto r = ws->Find("radius")) {
      const auto v = r->AsNumbers(2);
      if (!(v[0] > 0.0 && v[1] >= v[0])) r->Fail("[min, max] with 0 < min <= max [m]");
      c.radius_min = v[0];
      c.radius_max = v[1];
    }
    if (auto h = ws->Find("height")) {
      const auto v = h->AsNumbers(2);
      if (!(v[1] >= v[0])) h->Fail("[min, max] with min <= max [m]");
      c.height_min = v[0];
      c.height_max = v[1];
    }
    ws->ReadNonNegative("approach_height", c.approach_height);
  }
  if (auto s = node.Find("sweep_deg")) {
    const auto v = s->AsNumbers(2);
    if (!(v[0] > 0.0 && v[1] >= v[0])) s->Fail("[min, max] with 0 < min <= max [deg]");
    c.sweep_min_deg = v[0];
    c.sweep_max_deg = v[1];
  }
  if (auto h = node.Find("home_deg")) {
    const auto v = h->AsNumbers(6);
    for (int i = 0; i < 6; ++i) c.q_home[i] = DegToRad(v[i]);
  }
  node.ReadPositive("brick_height", c.brick_height);
  if (auto s = node.Find("ilqg")) c.ilqg = IlqgOptions::FromConfig(*s, c.ilqg);
  if (auto s = node.Find("ik")) c.ik = IkOptions::FromConfig(*s);
  return c;
}

std::string ArmPlanningResult::CasesCsv() const {
  std::string out =
      "index,kind,status,iterations,cost,plan_ms,duration_s,steps,final_error_deg,final_speed_deg_s,within_limits,"
      "q_from_deg,q_to_deg\n";
  auto deg = [](const Vector6d& q) {
    return fmt::format("{:.3f} {:.3f} {:.3f} {:.3f} {:.3f} {:.3f}", RadToDeg(q[0]), RadToDeg(q[1]), RadToDeg(q[2]),
                       RadToDeg(q[3]), RadToDeg(q[4]), RadToDeg(q[5]));
  };
  for (const ArmPlanningCase& c : cases) {
    const PlanSummary& s = c.summary;
    out += fmt::format("{},{},{},{},{:.9g},{:.3f},{:.3f},{},{:.3e},{:.3e},{},{},{}\n", c.index, c.kind,
                       ToString(s.status), s.iterations, s.cost, 1e3 * s.seconds, s.duration, s.steps,
                       RadToDeg(s.final_position_error), RadToDeg(s.final_speed), s.within_limits ? 1 : 0,
                       deg(c.q_from), deg(c.q_to));
  }
  return out;
}

ArmPlanningResult RunArmPlanningExperiment(const RobotModel& robot, const ArmPlanningExperimentConfig& config,
                                           std::uint64_t seed) {
  ArmPlanningResult result;
  CaseGenerator generator(robot, config);
  const RandomStream root = RandomStream(seed).Derive("arm-planning");
  int index = 0;
  for (std::uint64_t draw = 0; static_cast<int>(result.cases.size()) < config.cases; ++draw) {
    ArmPlanningCase c;
    if (generator.Make(index, root.Derive(draw), c)) {
      result.cases.push_back(c);
      ++index;
    }
    if (draw > static_cast<std::uint64_t>(config.cases) * 10) break;  // a workspace nothing reaches
  }

  IlqgPlanner planner(ArmModel::FromRobotModel(robot), config.ilqg);
  std::vector<double> iterations, plan_ms, durations;
  int converged = 0, usable = 0;
  double error_max = 0.0;
  std::map<std::string, std::vector<double>> ms_by_kind;
  std::map<std::string, int> count_by_kind;
  for (ArmPlanningCase& c : result.cases) {
    const ArmPlan plan = planner.Plan(c.q_from, c.q_to);
    c.summary = plan.summary;
    const PlanSummary& s = c.summary;
    converged += s.status == arm::PlanStatus::kConverged;
    usable += s.IsUsable();
    iterations.push_back(s.iterations);
    plan_ms.push_back(1e3 * s.seconds);
    durations.push_back(s.duration);
    error_max = std::max(error_max, RadToDeg(s.final_position_error));
    ms_by_kind[c.kind].push_back(1e3 * s.seconds);
    ++count_by_kind[c.kind];
  }
  const double n = std::max<std::size_t>(1, result.cases.size());
  nlohmann::json& j = result.results;
  j["cases"] = result.cases.size();
  j["converged_rate"] = converged / n;
  j["usable_rate"] = usable / n;
  j["iterations_median"] = Median(iterations);
  j["iterations_max"] = iterations.empty() ? 0.0 : *std::max_element(iterations.begin(), iterations.end());
  j["plan_ms_median"] = Median(plan_ms);
  j["plan_ms_max"] = plan_ms.empty() ? 0.0 : *std::max_element(plan_ms.begin(), plan_ms.end());
  j["final_joint_error_deg_max"] = error_max;
  j["motion_duration_s_median"] = Median(durations);
  j["seed"] = seed;
  for (const auto& [kind, ms] : ms_by_kind) {
    j["by_kind"][kind] = {{"cases", count_by_kind[kind]}, {"plan_ms_median", Median(ms)}};
  }
  return result;
}

}  // namespace ifab::experiments
