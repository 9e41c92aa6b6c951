// PLY clouds, ASCII and binary (one reader; the seed corpus has both).
#include <sstream>

#include "fuzz_common.h"
#include "ifab/perception/ply.h"

IFAB_FUZZ_TARGET({
  std::istringstream in(input);
  const ifab::PointCloud cloud = ifab::ReadPly(in, "fuzz.ply");
  for (const auto& p : cloud.points)
    if (!p.allFinite()) __builtin_trap();  // the reader promises finite points
})
