#include "ifab/perception/scan_assembly.h"

#include <algorithm>

#include "ifab/core/config.h"
#include "ifab/core/time.h"

namespace ifab {

ScanAssemblyOptions ScanAssemblyOptions::FromConfig(const ConfigNode& c) {
  c.ExpectKeys({"interpolation", "max_sample_gap", "beam_stride", "min_range", "max_range", "range_bias"});
  ScanAssemblyOptions o;
  if (auto i = c.Find("interpolation")) {
    const auto v = i->As<std::string>();
    if (v == "joint") o.interpolation = ArmInterpolation::kJoint;
    else if (v == "pose") o.interpolation = ArmInterpolation::kPose;
    else i->Fail("one of: joint (joint angles, then forward kinematics), pose (flange poses)");
  }
  c.ReadPositive("max_sample_gap", o.max_sample_gap);
  c.ReadPositive("beam_stride", o.beam_stride);
  c.ReadNonNegative("min_range", o.min_range);
  c.ReadNonNegative("max_range", o.max_range);
  if (auto b = c.Find("range_bias")) o.range_bias = RangeBiasCompensation::FromConfig(*b);
  return o;
}

AssembledSweep AssembleSweep(const std::vector<LaserScan>& scans, const std::vector<JointState>& joints,
                             const RobotModel& robot, const ScanAssemblyOptions& options) {
  AssembledSweep out;
  std::vector<Stamped<Vector6d>> q_series;
  q_series.reserve(joints.size());
  for (const auto& j : joints) q_series.push_back({j.stamp.t, j.q});
  std::stable_sort(q_series.begin(), q_series.end(), [](const auto& a, const auto& b) { return a.t < b.t; });
  // kPose: the flange at each sample, its rotation as a quaternion once (slerped per beam)
  std::vector<Pose3> sample_poses;
  std::vector<Eigen::Quaterniond> sample_rotations;
  if (options.interpolation == ArmInterpolation::kPose)
    for (const auto& s : q_series) {
      sample_poses.push_back(robot.T_base_arm_base * robot.ArmForwardKinematics(s.value));
      sample_rotations.emplace_back(sample_poses.back().linear());
    }

  for (std::size_t k = 0; k < scans.size(); ++k) {
    const LaserScan& scan = scans[k];
    for (std::size_t i = 0; i < scan.size(); i += static_cast<std::size_t>(options.beam_stride)) {
      const double r = scan.ranges[i];
      if (!scan.IsValid(i) || r < options.min_range || (options.max_range > 0.0 && r > options.max_range)) {
        ++out.invalid_beams;
        continue;
      }
      const double t = scan.BeamTime(i);
      const auto bracket = Bracket(q_series, t);
      if (!bracket || q_series[bracket->first + 1].t - q_series[bracket->first].t > options.max_sample_gap) {
        ++out.untimed_beams;
        continue;
      }
      const auto [a, s] = *bracket;
      SweepPoint p;
      p.p_laser = scan.Point(i);
      p.t = t;
      p.scan = static_cast<int>(k);
      p.beam = static_cast<int>(i);
      p.q = q_series[a].value + s * (q_series[a + 1].value - q_series[a].value);
      if (options.interpolation == ArmInterpolation::kJoint) {
        p.T_base_tool0 = robot.T_base_arm_base * robot.ArmForwardKinematics(p.q);
      } else {
        p.T_base_tool0.linear() = sample_rotations[a].slerp(s, sample_rotations[a + 1]).toRotationMatrix();
        p.T_base_tool0.translation() =
            (1.0 - s) * sample_poses[a].translation() + s * sample_poses[a + 1].translation();
      }
      out.points.push_back(p);
    }
  }
  return out;
}

std::vector<RayPoint> AssembleCloud(const std::vector<LaserScan>& scans, const std::vector<JointState>& joints,
                                    const RobotModel& robot, const Pose3& T_tool0_laser,
                                    const ScanAssemblyOptions& options, RangeBiasCompensationStats* bias_stats) {
  std::vector<SweepPoint> points = AssembleSweep(scans, joints, robot, options).points;
  if (options.range_bias.active()) {
    const RangeBiasCompensationStats stats = CompensateRangeBias(points, T_tool0_laser, options.range_bias);
    if (bias_stats) *bias_stats = stats;
  }
  return ToBaseFrame(points, T_tool0_laser);
}

}  // namespace ifab
