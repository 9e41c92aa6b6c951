#pragma once
/// \file Where ifab finds its data/ folder (robots, sensors, sites, experiments).

#include <string>

namespace ifab {

/// The data folder: $IFAB_DATA_DIR if set, else the source tree's data/ compiled in.
std::string DataDir();
/// A path under the data folder, e.g. DataPath("sensors/utm30lx.yaml").
std::string DataPath(const std::string& relative);

}  // namespace ifab
