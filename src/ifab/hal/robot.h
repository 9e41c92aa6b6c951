#pragma once
/// \file
/// The hardware interface the stack drives. The simulator (sim::SimRobot) implements it, and
/// so would a driver for the real machine; no algorithm can tell which one it talks to.
/// Sensor data is drained: each Take* call returns what arrived since the previous call.

#include <optional>
#include <string>
#include <vector>

#include "ifab/msgs/msgs.h"

namespace ifab::hal {

class Robot {
 public:
  virtual ~Robot() = default;

  /// Host clock [s].
  virtual Seconds Now() const = 0;
  /// Let dt of host time pass (the simulator steps its world; a real robot sleeps).
  virtual void Wait(Seconds dt) = 0;

  // Base.
  /// Speed references for the tracks; held until the next command.
  virtual void CommandTracks(const TrackCommand& command) = 0;

  // Arm.
  /// Hand a joint position trajectory to the arm's own controller (starts now).
  virtual void SendJointTrajectory(const JointTrajectory& trajectory) = 0;
  /// True while the arm controller is still executing a trajectory.
  virtual bool ArmBusy() const = 0;
  /// Why the arm controller refused the last trajectory sent (it is then not executed); empty
  /// if it accepted it. A driver that cannot tell returns empty.
  virtual std::string ArmRejection() const { return {}; }
  /// The vacuum gripper's sensor: whether it holds something; nullopt if it has no sensor.
  virtual std::optional<bool> VacuumHolding() const { return std::nullopt; }
  /// Vacuum gripper on (grip) or off (release).
  virtual void SetGripper(bool grip) = 0;

  // Sensors.
  /// Switch a laser scanner's emission on or off (the UTM-30LX's BM/QT commands); an idle laser
  /// sends no scans. Lasers start on. A driver that cannot switch them may ignore this.
  virtual void SetLaserActive(DeviceId /*laser*/, bool /*active*/) {}
  virtual std::vector<LaserScan> TakeLaserScans(DeviceId laser) = 0;
  virtual std::vector<GyroSample> TakeGyroSamples() = 0;
  /// The IMU's accelerometer samples (stamped like the gyro's). A robot without accelerometers
  /// returns none, and the stack then says it cannot measure tilt.
  virtual std::vector<AccelSample> TakeAccelSamples() { return {}; }
  virtual std::vector<JointState> TakeJointStates() = 0;
  virtual std::vector<SyncPulse> TakeSyncPulses() = 0;
};

}  // namespace ifab::hal
