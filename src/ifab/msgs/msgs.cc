#include "ifab/msgs/msgs.h"

namespace ifab {

const char* DeviceName(DeviceId id) {
  switch (id) {
    case DeviceId::kBaseLaser: return "base_laser";
    case DeviceId::kArmLaser: return "arm_laser";
    case DeviceId::kGyro: return "gyro";
    case DeviceId::kArm: return "arm";
  }
  return "unknown";
}

}  // namespace ifab
