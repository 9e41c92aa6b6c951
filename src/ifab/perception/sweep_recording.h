#pragma once
/// \file
/// A recorded arm sweep: one joint moving while the arm laser scans. Its file format (JSON) is
/// read and written outside the algorithm modules, by experiments/sweep_io.h.

#include <string>
#include <vector>

#include "ifab/msgs/msgs.h"

namespace ifab {

struct SweepRecording {
  std::string name;
  std::vector<LaserScan> scans;
  std::vector<JointState> joint_states;
  std::vector<SyncPulse> sync_pulses;  ///< empty when times are host times already
  /// The IMU's accelerometer over the sweep (host time; empty if none was recorded): the base's
  /// tilt while the arm moved (its weight tilts the base on its tracks).
  std::vector<AccelSample> accel;
};

}  // namespace ifab
