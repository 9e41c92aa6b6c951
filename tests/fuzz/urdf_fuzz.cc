// Robot descriptions (URDF through urdfdom, then our checks and the KDL tree).
#include "fuzz_common.h"
#include "ifab/model/robot_model.h"

IFAB_FUZZ_TARGET({
  const ifab::RobotModel m = ifab::ParseRobotModel(input, "fuzz.urdf");
  ifab::Vector6d q = 0.5 * (m.q_min + m.q_max);
  (void)m.ArmForwardKinematics(q);
})
