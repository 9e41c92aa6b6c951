// Recorded arm sweeps (JSON), host stamps or raw device stamps with sync pulses.
#include <cmath>
#include <sstream>

#include "fuzz_common.h"
#include "ifab/experiments/sweep_io.h"

IFAB_FUZZ_TARGET({
  std::istringstream in(input);
  const ifab::SweepRecording s = ifab::ParseSweep(in, "fuzz.json");
  for (std::size_t i = 1; i < s.joint_states.size(); ++i)
    if (!(s.joint_states[i].stamp.t > s.joint_states[i - 1].stamp.t)) __builtin_trap();  // promised order
})
