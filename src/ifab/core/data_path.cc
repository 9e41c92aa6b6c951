#include "ifab/core/data_path.h"

#include <cstdlib>

namespace ifab {

std::string DataDir() {
  if (const char* env = std::getenv("IFAB_DATA_DIR"); env && *env) return env;
  return IFAB_DEFAULT_DATA_DIR;
}

std::string DataPath(const std::string& relative) { return DataDir() + "/" + relative; }

}  // namespace ifab
