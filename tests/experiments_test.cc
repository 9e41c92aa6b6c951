// End-to-end checks of the experiments through the same entry point as `ifab run`.
#include <gtest/gtest.h>

#include <filesystem>

#include "ifab/core/data_path.h"
#include "ifab/core/error.h"
#include "ifab/experiments/experiment.h"
#include "ifab/sim/sim_robot.h"

namespace ifab::experiments {
namespace {

std::string TempDir(const std::string& name) {
  const auto dir = std::filesystem::path(::testing::TempDir()) / ("ifab_" + name);
  std::filesystem::remove_all(dir);
  return dir.string();
}

TEST(LrfBias, BumpShrinksWithHeightAndIsAbout3cmAt0_4m) {
  RunOptions o;
  o.experiment = "lrf-bias";
  o.out_dir = TempDir("lrf_bias");
  o.force = true;  // ctest may run again over the same folder
  o.progress = false;
  const auto r = RunExperiment(o);
  const auto bumps = r["bump_height_mm"];
  ASSERT_EQ(bumps.size(), 3u);
  EXPECT_GE(bumps[0].get<double>(), 20.0);
  EXPECT_LE(bumps[0].get<double>(), 40.0);
  EXPECT_GT(bumps[0].get<double>(), bumps[1].get<double>());
  EXPECT_GT(bumps[1].get<double>(), bumps[2].get<double>());
  EXPECT_TRUE(std::filesystem::exists(std::filesystem::path(o.out_dir) / "lrf_bias_points.csv"));
  EXPECT_TRUE(std::filesystem::exists(std::filesystem::path(o.out_dir) / "results.json"));
}

TEST(SimRobot, MalformedUrdfNamesTheFile) {
  try {
    sim::SimOptions::Load(std::string(IFAB_TEST_DATA_DIR) + "/bad_robot.yaml");
    sim::SimOptions o = sim::SimOptions::Load(std::string(IFAB_TEST_DATA_DIR) + "/bad_robot.yaml");
    sim::SimRobot robot(o, Pose2(), Vector6d::Zero(), 1);
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.urdf: not a valid URDF"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ifab::experiments
