// The typed config loaders, through YAML: each top-level key of the input goes to the loader of
// that name (the seed corpus holds every config in data/ in this form).
#include <functional>
#include <map>

#include "fuzz_common.h"
#include "ifab/arm/ik.h"
#include "ifab/arm/ilqg.h"
#include "ifab/arm/primitives.h"
#include "ifab/base/controller/trajectory_controller.h"
#include "ifab/base/estimator/base_state_estimator.h"
#include "ifab/experiments/estimate_log.h"
#include "ifab/base/planner/planning_scene.h"
#include "ifab/base/planner/stomp_planner.h"
#include "ifab/core/config.h"
#include "ifab/perception/calibration.h"
#include "ifab/perception/laser_model.h"
#include "ifab/perception/registration.h"
#include "ifab/perception/scan_assembly.h"
#include "ifab/sequencer/building_plan.h"
#include "ifab/sequencer/laser_sweeps.h"
#include "ifab/sequencer/mission.h"
#include "ifab/sim/components.h"
#include "ifab/sim/lrf_model.h"
#include "ifab/sync/clock_sync.h"

namespace {
using ifab::ConfigNode;
using Loader = std::function<void(const ConfigNode&)>;

const std::map<std::string, Loader>& Loaders() {
  namespace b = ifab::base;
  static const std::map<std::string, Loader> loaders = {
      {"base_planner", [](const ConfigNode& c) { (void)b::StompPlannerOptions::FromConfig(c); }},
      {"estimator", [](const ConfigNode& c) { (void)b::EstimatorOptions::FromConfig(c); }},
      {"estimate_log", [](const ConfigNode& c) { (void)ifab::experiments::EstimateLogOptions::FromConfig(c); }},
      {"base_controller", [](const ConfigNode& c) { (void)b::BaseControllerOptions::FromConfig(c); }},
      {"base", [](const ConfigNode& c) { (void)b::BaseGeometry::FromConfig(c); }},
      {"arm", [](const ConfigNode& c) { (void)ifab::arm::ArmOptions::FromConfig(c); }},
      {"ilqg", [](const ConfigNode& c) { (void)ifab::arm::IlqgOptions::FromConfig(c); }},
      {"ik", [](const ConfigNode& c) { (void)ifab::arm::IkOptions::FromConfig(c); }},
      {"primitives", [](const ConfigNode& c) { (void)ifab::arm::PrimitiveOptions::FromConfig(c); }},
      {"registration", [](const ConfigNode& c) { (void)ifab::RegistrationOptions::FromConfig(c); }},
      {"calibration", [](const ConfigNode& c) { (void)ifab::CalibrationOptions::FromConfig(c); }},
      {"noise", [](const ConfigNode& c) { (void)ifab::LaserNoiseModel::FromConfig(c); }},
      {"scan_assembly", [](const ConfigNode& c) { (void)ifab::ScanAssemblyOptions::FromConfig(c); }},
      {"clock_sync", [](const ConfigNode& c) { (void)ifab::ClockSyncOptions::FromConfig(c); }},
      {"plan", [](const ConfigNode& c) { (void)ifab::sequencer::BuildingPlan::FromConfig(c); }},
      {"mission", [](const ConfigNode& c) { (void)ifab::sequencer::MissionOptions::FromConfig(c); }},
      {"laser_calibration", [](const ConfigNode& c) { (void)ifab::sequencer::LaserCalibrationPlan::FromConfig(c); }},
      {"lrf", [](const ConfigNode& c) { (void)ifab::sim::LrfOptions::FromConfig(c); }},
      {"gyro", [](const ConfigNode& c) { (void)ifab::sim::GyroOptions::FromConfig(c); }},
      {"tracks", [](const ConfigNode& c) { (void)ifab::sim::TrackOptions::FromConfig(c); }},
      {"clocks", [](const ConfigNode& c) { (void)ifab::sim::ClockOptions::FromConfig(c); }},
      {"servo", [](const ConfigNode& c) { (void)ifab::sim::ServoOptions::FromConfig(c); }},
  };
  return loaders;
}
}  // namespace

IFAB_FUZZ_TARGET({
  const ConfigNode root = ConfigNode::FromString(input, "fuzz.yaml");
  if (!root.IsMap()) return 0;
  for (const std::string& key : root.Keys()) {
    const auto it = Loaders().find(key);
    if (it != Loaders().end()) it->second(root[key]);
  }
})
