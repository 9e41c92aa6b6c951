#pragma once
/// \file The simulator's default options, which the sim tests start from.

#include "ifab/core/data_path.h"
#include "ifab/sim/sim_robot.h"

namespace ifab::sim {

inline SimOptions DefaultOptions() { return SimOptions::Load(DataPath("sim/insitu_fabricator.yaml")); }

}  // namespace ifab::sim
