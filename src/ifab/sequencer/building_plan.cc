#include "ifab/sequencer/building_plan.h"

#include <cmath>

#include "ifab/core/angles.h"
#include "ifab/core/config.h"

namespace ifab::sequencer {

int BuildingPlan::TotalBricks() const {
  int n = 0;
  for (const auto& v : visits) n += v.bricks;
  return n;
}

BuildingPlan BuildingPlan::FromConfig(const ConfigNode& c) {
  c.ExpectKeys({"positions", "bricks", "order"});
  BuildingPlan plan;
  const ConfigNode positions = c["positions"];
  positions.ExpectSequence();
  if (positions.size() == 0) positions.Fail("at least one building position");
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const ConfigNode p = positions[i];
    p.ExpectKeys({"name", "pose"});
    const auto v = p["pose"].AsNumbers(3);
    plan.positions.push_back({p.Get<std::string>("name", "position_" + std::to_string(i)),
                              Pose2(v[0], v[1], WrapAngle(DegToRad(v[2])))});
  }
  int bricks = 0;
  c.ReadPositive("bricks", bricks, kMaxBricks);
  if (bricks == 0) c["bricks"].Fail("a positive number of bricks");
  std::vector<int> order;
  if (auto o = c.Find("order")) {
    for (double x : o->AsNumbers()) {
      // Range first: casting a double outside int's range is undefined.
      if (!(x >= 0 && x < static_cast<double>(plan.positions.size()) && std::floor(x) == x))
        o->Fail(fmt::format("position indices in [0, {}]", plan.positions.size() - 1));
      order.push_back(static_cast<int>(x));
    }
    if (order.empty()) o->Fail("a non-empty list of position indices");
  } else {
    for (std::size_t i = 0; i < plan.positions.size(); ++i) order.push_back(static_cast<int>(i));
  }
  for (int b = 0; b < bricks; ++b) plan.visits.push_back({order[static_cast<std::size_t>(b) % order.size()], 1});
  return plan;
}

}  // namespace ifab::sequencer
