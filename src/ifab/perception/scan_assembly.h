#pragma once
/// \file
/// Scan assembly (paper Sec. V-A, eq. 6): laser points of scans taken during an arm sweep are put
/// into the robot base frame with p_base = T_base_tool0(t_i) T_tool0_laser p_laser, where the arm
/// pose at each beam's own time t_i = scan.stamp.t + i * time_increment is interpolated linearly
/// between the arm's joint-state samples. All times are host times (after clock sync).
///
/// Interpolation: by default the joint angles are interpolated and the flange pose follows by
/// forward kinematics (what the arm does between samples); `kPose` interpolates the flange poses
/// of the two samples instead (translation linear, rotation slerp), as the paper's wording has it
/// for poses received from the arm controller.
///
/// Range bias (range_bias.h): with an identified model, AssembleCloud first corrects every range
/// by the bias at its range and incidence and drops returns where the model is too uncertain;
/// without one (or `range_bias.compensate: false`) it is eq. 6 as the paper writes it.

#include <vector>

#include "ifab/model/robot_model.h"
#include "ifab/msgs/msgs.h"
#include "ifab/perception/cloud.h"
#include "ifab/perception/range_bias.h"

namespace ifab {

class ConfigNode;

enum class ArmInterpolation { kJoint, kPose };

struct ScanAssemblyOptions {
  ArmInterpolation interpolation{ArmInterpolation::kJoint};  ///< what is interpolated
  double max_sample_gap{0.1};  ///< [s] beams between joint samples farther apart are dropped
  int beam_stride{1};          ///< keep every n-th beam (decimation)
  double min_range{0.0};       ///< [m] drop shorter ranges (besides the scan's own range_min)
  double max_range{0.0};       ///< [m] drop longer ranges (0: the scan's range_max only)
  RangeBiasCompensation range_bias;  ///< the arm laser's range bias (empty model: eq. 6 as written)

  /// Reads {interpolation: joint|pose, max_sample_gap, beam_stride, min_range, max_range,
  /// range_bias: {...}} (range_bias.h).
  static ScanAssemblyOptions FromConfig(const ConfigNode& config);
};

struct AssembledSweep {
  std::vector<SweepPoint> points;
  int invalid_beams{0};    ///< no return or out of range
  int untimed_beams{0};    ///< outside the joint samples or in a gap between them
};

/// Raw points of a sweep with the flange pose at each beam's time (eq. 6 without the mount, so
/// calibration can solve the mount).
AssembledSweep AssembleSweep(const std::vector<LaserScan>& scans, const std::vector<JointState>& joints,
                             const RobotModel& robot, const ScanAssemblyOptions& options = {});

/// Eq. 6: the sweep's cloud in the base frame, each point with its ray origin; the range bias
/// compensated first when options.range_bias is active (its counts into *bias_stats if given).
std::vector<RayPoint> AssembleCloud(const std::vector<LaserScan>& scans, const std::vector<JointState>& joints,
                                    const RobotModel& robot, const Pose3& T_tool0_laser,
                                    const ScanAssemblyOptions& options = {},
                                    RangeBiasCompensationStats* bias_stats = nullptr);

}  // namespace ifab
