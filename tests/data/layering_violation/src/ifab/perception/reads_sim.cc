// A fixture for tests/CMakeLists.txt's layering.detects_a_loader_opening_sim: an algorithm-side
// loader that opens the simulator's section of a robot YAML. Never compiled.
#include "ifab/core/config.h"

namespace ifab {
double TrueMountX(const ConfigNode& robot_yaml) { return robot_yaml["sim"]["arm_laser_mount_error"][0].As<double>(); }
}  // namespace ifab
