#pragma once
/// \file
/// A hal::Robot that forwards every call to the simulator. The experiments derive from it to
/// watch the truth as time passes (Wait) without copying the whole interface each time.

#include "ifab/hal/robot.h"
#include "ifab/sim/sim_robot.h"

namespace ifab::experiments {

class SimForwardingRobot : public hal::Robot {
 public:
  explicit SimForwardingRobot(sim::SimRobot& sim) : sim_(sim) {}
  Seconds Now() const override { return sim_.Now(); }
  void Wait(Seconds dt) override { sim_.Wait(dt); }
  void CommandTracks(const TrackCommand& c) override { sim_.CommandTracks(c); }
  void SendJointTrajectory(const JointTrajectory& t) override { sim_.SendJointTrajectory(t); }
  bool ArmBusy() const override { return sim_.ArmBusy(); }
  std::string ArmRejection() const override { return sim_.ArmRejection(); }
  std::optional<bool> VacuumHolding() const override { return sim_.VacuumHolding(); }
  void SetGripper(bool grip) override { sim_.SetGripper(grip); }
  void SetLaserActive(DeviceId id, bool active) override { sim_.SetLaserActive(id, active); }
  std::vector<LaserScan> TakeLaserScans(DeviceId id) override { return sim_.TakeLaserScans(id); }
  std::vector<GyroSample> TakeGyroSamples() override { return sim_.TakeGyroSamples(); }
  // hal's default returns none: forgetting it would leave the mission without tilt data.
  std::vector<AccelSample> TakeAccelSamples() override { return sim_.TakeAccelSamples(); }
  std::vector<JointState> TakeJointStates() override { return sim_.TakeJointStates(); }
  std::vector<SyncPulse> TakeSyncPulses() override { return sim_.TakeSyncPulses(); }

 protected:
  sim::SimRobot& sim_;
};

}  // namespace ifab::experiments
