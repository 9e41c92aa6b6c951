#pragma once
/// \file
/// Faults injected into the simulated machine (issue 14's campaign, `ifab run faults`): sensor
/// blackouts and dropped scans, track slip and stalls, gyro spikes and a bias step, a device
/// clock jump, an arm trajectory the arm controller rejects, a brick the gripper drops, the
/// stack bumped between visits, a person stepping onto the path, a sweep with half its points
/// missing. SimRobot calls the hooks below; the stack sees only what a real machine would show
/// (silence, odd stamps, a rejection, a vacuum sensor, points). Ground truth: part of sim.

#include <optional>
#include <string>
#include <vector>

#include "ifab/core/random.h"
#include "ifab/core/se3.h"
#include "ifab/msgs/msgs.h"
#include "ifab/model/site.h"

namespace ifab::sim {

class SimRobot;

enum class FaultKind {
  kBaseLaserBlackout,     ///< the base laser sends nothing for `duration`
  kArmLaserBlackout,      ///< the arm laser sends nothing for `duration`, during sweep `index`
  kDroppedScans,          ///< `count` consecutive scans of `device` are lost
  kTrackSlip,             ///< one track (magnitude > 0: left) loses |magnitude| of its speed for `duration`
  kTrackStall,            ///< one track stands still for `duration`
  kGyroSpikes,            ///< `count` single-sample spikes of `magnitude` rad/s within 1 s
  kGyroBiasStep,          ///< the gyro's bias steps by `magnitude` rad/s (for good)
  kClockJump,             ///< `device`'s clock jumps by `magnitude` s (for good)
  kArmTrajectoryRejected, ///< the arm controller refuses trajectory number `index`
  kBrickDropped,          ///< the gripper loses its brick `duration` s after grip number `index`
  kStackBumped,           ///< the built stack slides by `magnitude` m (direction `angle`)
  kPersonOnPath,          ///< a person stands `magnitude` m ahead of the moving base for `duration`
  kHalfSweep,             ///< sweep number `index` loses half of its points
};
const char* FaultName(FaultKind kind);
constexpr int kNumFaultKinds = 13;

/// One fault to inject and when. Base faults fire after `drive_time` s of driving (summed over
/// maneuvers); arm and sweep faults at the `index`-th trajectory, grip or sweep (1-based).
struct FaultSpec {
  FaultKind kind{FaultKind::kBaseLaserBlackout};
  double drive_time{0.0};   ///< [s] of driving before it starts (base, clock, stack, person)
  int index{1};             ///< trajectory / grip / sweep number
  double duration{0.0};     ///< [s]
  double magnitude{0.0};    ///< see FaultKind
  double angle{0.0};        ///< [rad] direction of a bump
  int count{0};             ///< scans dropped, spikes
  DeviceId device{DeviceId::kBaseLaser};
};

/// What happened to one fault (truth, for the campaign's log).
struct FaultRecord {
  FaultSpec spec;
  bool injected{false};
  Seconds t_start{0.0};   ///< host time it began
  Seconds t_end{0.0};     ///< host time it ended (= t_start for instant faults)
  std::string detail;     ///< what was injected, in words
};

/// The ranges faults are drawn from (the catalogue).
struct FaultDrawOptions {
  int faults_per_run{6};            ///< distinct kinds drawn per mission
  double max_drive_time{12.0};      ///< [s] base faults start within this much driving
  int max_trajectory_index{16};     ///< rejected trajectory drawn from 2..this
  int max_grip_index{3};            ///< dropped brick at grip 1..this
  int max_sweep_index{2};           ///< arm laser faults at sweep 1..this
};

class FaultInjector {
 public:
  explicit FaultInjector(std::vector<FaultSpec> faults, std::uint64_t seed = 1);
  /// n distinct kinds from the catalogue with their parameters.
  static std::vector<FaultSpec> Draw(RandomStream& rng, const FaultDrawOptions& options = {});

  // Hooks, called by SimRobot.
  void OnStep(SimRobot& sim, Seconds t, double dt);
  void FilterTracks(double* v_left, double* v_right);
  void FilterGyro(Seconds t, GyroSample* g);
  void FilterStamp(DeviceId device, Stamp* stamp) const;
  /// False: the scan is lost. May also blank beams (half sweep).
  bool KeepScan(bool arm_laser, Seconds t, LaserScan* scan);
  /// A reason when the arm controller refuses this trajectory (not executed), else nullopt.
  std::optional<std::string> RejectTrajectory(Seconds t);
  void OnGrip(Seconds t);
  void OnLaserActive(DeviceId laser, bool active, Seconds t);

  const std::vector<FaultRecord>& records() const { return records_; }
  /// How far the stack has been bumped so far (truth, for scoring bricks against the stack).
  const Pose3& T_site_stack_moved() const { return T_bump_; }

 private:
  bool Active(const FaultRecord& r, Seconds t) const { return r.injected && t >= r.t_start && t < r.t_end; }
  void Start(FaultRecord& r, Seconds t, double duration, std::string detail);

  std::vector<FaultRecord> records_;
  RandomStream rng_;
  double drive_time_{0.0};
  Seconds now_{0.0};
  double v_left_cmd_{0.0}, v_right_cmd_{0.0};
  int trajectories_{0}, grips_{0}, sweeps_{0};
  bool arm_laser_on_{false};
  Seconds grip_time_{0.0};
  Pose3 T_bump_{Pose3::Identity()};
  std::vector<int> scans_to_drop_;   ///< per record: scans still to drop (kDroppedScans)
  std::vector<Seconds> spike_times_; ///< pending gyro spikes (kGyroSpikes)
  double spike_magnitude_{0.0};
  double gyro_bias_{0.0};
  std::string person_name_;
};

}  // namespace ifab::sim
