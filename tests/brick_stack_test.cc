// Issue 7's integration test: the short brick stacking variant (3 bricks, 2 building positions,
// 2 repositionings) runs the whole Fig. 2 loop in the default simulator (slip, laser noise and
// bias, gyro, clocks, arm and gripper errors all on).
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "ifab/core/data_path.h"
#include "ifab/experiments/experiment.h"

namespace ifab::experiments {
namespace {

TEST(BrickStack, ShortVariantPlacesEveryBrickNearItsDesignedPose) {
  RunOptions o;
  o.experiment = "brick-stack";
  o.config_path = DataPath("experiments/brick-stack-short.yaml");
  o.out_dir = (std::filesystem::path(::testing::TempDir()) / "ifab_brick_stack_short").string();
  o.force = true;  // ctest may run again over the same folder
  o.progress = false;
  const auto r = RunExperiment(o);
  EXPECT_FALSE(r["failed"].get<bool>()) << r.dump(2);
  EXPECT_EQ(r["bricks_placed"].get<int>(), 3);
  EXPECT_EQ(r["repositionings"].get<int>(), 2);
  // The arm laser's mount was calibrated first; the paper's figures bound the mean errors, and
  // no brick may be off by more than 5 mm.
  EXPECT_EQ(r["arm_laser_mount"]["source"].get<std::string>(), "calibrated");
  EXPECT_LE(r["brick_error_long_mm_mean"].get<double>(), 4.6);
  EXPECT_LE(r["brick_error_short_mm_mean"].get<double>(), 3.5);
  EXPECT_LE(r["brick_error_mm_max"].get<double>(), 5.0);
  EXPECT_LE(r["after_localization_vs_desired_m_max"].get<double>(), 0.08);
  EXPECT_LE(r["after_localization_vs_desired_deg_max"].get<double>(), 4.0);
  for (const char* f : {"brick_errors.csv", "trajectory_planned.csv", "trajectory_estimated.csv",
                        "trajectory_true.csv", "visits.csv", "results.json"})
    EXPECT_TRUE(std::filesystem::exists(std::filesystem::path(o.out_dir) / f)) << f;
}

}  // namespace
}  // namespace ifab::experiments
