// Site files (YAML): boundary polygon, walls, obstacles, bricks.
#include "fuzz_common.h"
#include "ifab/core/config.h"
#include "ifab/model/site.h"

IFAB_FUZZ_TARGET({
  const ifab::Site site = ifab::SiteFromConfig(ifab::ConfigNode::FromString(input, "fuzz.yaml"));
  for (const auto& w : site.walls)
    if (!w.T_site_box.matrix().allFinite()) __builtin_trap();  // walls from a validated polygon
  (void)site.Objects();
  (void)site.ObstacleFootprints();
})
