// Reference relations ("t1 t2 x y z roll pitch yaw" per line; Kuemmerle et al. 2009).
#include <sstream>

#include "fuzz_common.h"
#include "ifab/base/estimator/carmen_log.h"

IFAB_FUZZ_TARGET({
  std::istringstream in(input);
  (void)ifab::base::ParseRelations(in, "fuzz.relations");
})
