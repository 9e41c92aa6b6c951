#pragma once
/// \file
/// A building plan (paper Sec. VI, Fig. 5): building positions expressed relative to the
/// workpiece, visited in a sequence, with the bricks to place at each visit.

#include <string>
#include <vector>

#include "ifab/core/se2.h"

namespace ifab {
class ConfigNode;
}

namespace ifab::sequencer {

struct BuildingPosition {
  std::string name;
  Pose2 T_site_base;  ///< desired base pose in the site (workpiece) frame
};

struct BuildingPlan {
  /// More bricks than any stack a site holds (the paper's: 26); a bound against typos.
  static constexpr int kMaxBricks = 10'000;
  std::vector<BuildingPosition> positions;
  /// One visit per entry: the position index and how many bricks to place there. The first
  /// visit is where the robot starts (no repositioning before it).
  struct Visit {
    int position{0};
    int bricks{1};
  };
  std::vector<Visit> visits;

  int TotalBricks() const;
  int Repositionings() const { return visits.empty() ? 0 : static_cast<int>(visits.size()) - 1; }

  /// Reads {positions: [{name, pose: [x, y, theta_deg]}], bricks: N, order: [i, j, ...]}:
  /// N bricks, one per visit, visiting the positions in `order` repeatedly (the hysteresis loop).
  static BuildingPlan FromConfig(const ConfigNode& config);
};

}  // namespace ifab::sequencer
