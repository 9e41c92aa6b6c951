// Issue 14: hostile configs through the typed loaders. Each case here was accepted, misread
// or undefined behaviour before.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "ifab/base/estimator/base_state_estimator.h"
#include "ifab/base/planner/stomp_planner.h"
#include "ifab/core/config.h"
#include "ifab/core/data_path.h"
#include "ifab/core/testing/error_of.h"
#include "ifab/experiments/experiment.h"
#include "ifab/sequencer/building_plan.h"
#include "ifab/sim/lrf_model.h"

namespace ifab {
namespace {
namespace fs = std::filesystem;
using ::testing::HasSubstr;
using testing::ErrorOf;

ConfigNode Yaml(const std::string& text) { return ConfigNode::FromString(text, "hostile.yaml"); }

TEST(HostileConfig, CountsHaveAnUpperBound) {
  // Before: 2e9 beams or bricks were accepted and sized multi-GB buffers.
  EXPECT_THAT(ErrorOf([] { sim::LrfOptions::FromConfig(Yaml("beams: 2000000000\n")); }),
              HasSubstr("hostile.yaml:1: beams: expected a positive integer (at most 100000), got 2000000000"));
  EXPECT_THAT(ErrorOf([] { base::EstimatorOptions::FromConfig(Yaml("max_beams: 2147483647\n")); }),
              HasSubstr("hostile.yaml:1: max_beams: expected a positive integer (at most 100000)"));
  EXPECT_THAT(ErrorOf([] {
                sequencer::BuildingPlan::FromConfig(Yaml("positions: [{pose: [0, 0, 0]}]\nbricks: 2000000000\n"));
              }),
              HasSubstr("hostile.yaml:2: bricks: expected a positive integer (at most 10000)"));
  // Every other count: at most ConfigNode::kMaxCount.
  EXPECT_THAT(ErrorOf([] { base::StompPlannerOptions::FromConfig(Yaml("num_rollouts: 1000000000\n")); }),
              HasSubstr("num_rollouts: expected a positive integer (at most 10000000)"));
}

TEST(HostileConfig, ATinyReachabilityCellIsRejected) {
  // Before: 1e-6 m over a 10 m site overflowed int in the planner's grid size.
  EXPECT_THAT(ErrorOf([] { base::StompPlannerOptions::FromConfig(Yaml("reachability_cell: 1.0e-6\n")); }),
              HasSubstr("hostile.yaml:1: reachability_cell: expected a number in [0.001, 10]"));
  // Set in code, the planner's own check names it too.
  base::StompPlannerOptions o;
  o.reachability_cell = 1e-6;
  base::PlanningScene scene;
  scene.boundary = {{-50, -50}, {50, -50}, {50, 50}, {-50, 50}};
  EXPECT_THAT(ErrorOf([&] { base::StompBasePlanner planner(scene, base::BaseGeometry{}, o); }),
              HasSubstr("stomp.reachability_cell: 1e-06 m gives"));
}

TEST(HostileConfig, BuildingOrderIsRangeCheckedBeforeTheCast) {
  // Before: static_cast<int>(1e300) (undefined) came before the range check.
  for (const char* bad : {"[1.0e300]", "[-1.0e300]", "[0.5]", "[1]"}) {
    EXPECT_THAT(ErrorOf([&] {
                  sequencer::BuildingPlan::FromConfig(
                      Yaml(std::string("positions: [{pose: [0, 0, 0]}]\nbricks: 2\norder: ") + bad + "\n"));
                }),
                HasSubstr("hostile.yaml:3: order: expected position indices in [0, 0]"))
        << bad;
  }
}

TEST(HostileConfig, KeysThatAreNotNamesAreAnInputError) {
  // Before: yaml-cpp's TypedBadConversion escaped (no file, no line, no exit code 2).
  EXPECT_THAT(ErrorOf([] { Yaml("? [a, b]\n: 1\n").ExpectKeys({"a"}); }),
              HasSubstr("hostile.yaml:1: (top level): expected field names, got a list as a key"));
}

// The brick stack's experiment file, its paths made absolute, in a folder of its own.
fs::path BrickStackConfig(const std::string& name, const std::string& perception_yaml,
                          const std::string& planner_yaml = "") {
  const fs::path dir = fs::path(::testing::TempDir()) / ("ifab_hostile_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ifstream in(DataPath("experiments/brick-stack-short.yaml"));
  std::stringstream ss;
  ss << in.rdbuf();
  std::string text = std::regex_replace(ss.str(), std::regex(R"(\.\./)"), DataPath(""));
  text = std::regex_replace(text, std::regex(R"(perception: \S+)"), "perception: " + (dir / "perception.yaml").string());
  std::ofstream(dir / "perception.yaml") << perception_yaml;
  if (!planner_yaml.empty()) {
    text = std::regex_replace(text, std::regex(R"(planner: \S+)"), "planner: " + (dir / "planner.yaml").string());
    std::ofstream(dir / "planner.yaml") << planner_yaml;
  }
  std::ofstream(dir / "experiment.yaml") << text;
  return dir;
}

std::string RunError(const fs::path& dir) {
  experiments::RunOptions o;
  o.experiment = "brick-stack";
  o.config_path = (dir / "experiment.yaml").string();
  o.out_dir = (dir / "out").string();
  o.force = true;
  o.progress = false;
  return ErrorOf([&] { experiments::RunExperiment(o); });
}

TEST(HostileConfig, TheBrickStackReadsTheScanAssemblySectionItsFileHas) {
  // Before: the mission read `assembly` (which no file has) and ignored `scan_assembly`.
  EXPECT_THAT(RunError(BrickStackConfig("scan_assembly", "scan_assembly: {beam_stride: 0}\n")),
              HasSubstr("perception.yaml:1: scan_assembly.beam_stride: expected a positive integer"));
  // ... and a misnamed section is an error, not silently skipped.
  EXPECT_THAT(RunError(BrickStackConfig("assembly", "assembly: {beam_stride: 2}\n")),
              HasSubstr("perception.yaml:1: assembly: unknown field (expected one of: registration, calibration, "
                        "scan_assembly, clock_sync)"));
}

TEST(HostileConfig, EveryLoaderChecksTheTopLevelOfItsFile) {
  // Before: a misspelt section was ignored and the defaults used.
  EXPECT_THAT(RunError(BrickStackConfig("planner_root", "", "base_planer: {num_rollouts: 3}\n")),
              HasSubstr("planner.yaml:1: base_planer: unknown field (expected one of: base_planner)"));
}

}  // namespace
}  // namespace ifab
