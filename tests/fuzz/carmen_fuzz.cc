// CARMEN laser logs (FLASER, ROBOTLASER1, ODOM lines).
#include <sstream>

#include "fuzz_common.h"
#include "ifab/base/estimator/carmen_log.h"

IFAB_FUZZ_TARGET({
  std::istringstream in(input);
  (void)ifab::base::ParseCarmenLog(in, "fuzz.log");
})
