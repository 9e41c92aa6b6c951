// The arm laser's calibration as the mission runs it (sequencer::CalibrateArmLaser, through
// hal::Robot only) on the default simulated robot, short-range bias on: the plan of
// data/experiments/registration-consistency.yaml (8 sweeps of a 0.25 m cube from all around; every
// 4th beam here to keep the test short) finds the true mount from the design one.
#include <gtest/gtest.h>

#include "ifab/core/config.h"
#include "ifab/core/data_path.h"
#include "ifab/sequencer/laser_sweeps.h"
#include "ifab/sim/sim_robot.h"

namespace ifab {
namespace {

TEST(CalibrateArmLaser, FindsTheSimulatedMountFromCubeSweeps) {
  const sim::SimOptions options = sim::SimOptions::Load(DataPath("sim/insitu_fabricator.yaml"));
  ASSERT_TRUE(options.arm_laser.bias_enabled);
  const RobotModel model = LoadRobotModel(DataPath("robots/insitu_fabricator.urdf"));
  const arm::ArmOptions arm_options = arm::ArmOptions::Load(DataPath("arm/arm.yaml"));
  const ConfigNode experiment = ConfigNode::LoadFile(DataPath("experiments/registration-consistency.yaml"));
  sequencer::LaserCalibrationPlan plan = sequencer::LaserCalibrationPlan::FromConfig(experiment["calibration"]);
  plan.beam_stride = 4;
  Vector6d q_start;
  q_start << 0.0, 0.3, 0.3, 0.0, 1.2, 0.0;
  // The cube stands where the plan expects it, 4 mm and 1 deg off (it is known roughly).
  const Pose3 T_site_cube = PoseFromXyzRpy(0.0, 0.0, 0.5 * plan.cube_size, 0.0, 0.0, 0.0);
  const Pose3 T_base_cube = plan.T_base_cube() * PoseFromXyzRpy(0.004, -0.003, 0.0, 0.0, 0.0, 0.017);
  const auto b = XyzRpyFromPose(T_site_cube * T_base_cube.inverse());
  sim::SimRobot robot(options, Pose2(b[0], b[1], b[5]), q_start, 11);
  robot.mutable_world().AddBrick({"cube", T_site_cube, Box{Eigen::Vector3d::Constant(plan.cube_size)}});

  std::vector<std::string> progress;
  const CalibrationSummary s = sequencer::CalibrateArmLaser(
      robot, model, arm_options, plan, q_start, [&](const std::string& what) { progress.push_back(what); });
  ASSERT_TRUE(s.IsUsable()) << s.BriefReport();
  EXPECT_EQ(progress.size(), plan.sweeps.size() + 1);
  for (int n : s.sweep_inliers) EXPECT_GT(n, 100) << s.BriefReport();
  EXPECT_TRUE(s.unconstrained.empty()) << s.BriefReport();
  const Pose3 truth = robot.true_T_tool0_arm_laser();
  const Pose3 design = model.T_tool0_arm_laser;
  ASSERT_GT(TranslationDistance(design, truth), 0.004);  // the design mount is mm off
  EXPECT_LT(TranslationDistance(s.T_tool0_laser, truth), 0.0015) << s.BriefReport();
  EXPECT_LT(RotationAngle(s.T_tool0_laser, truth), 0.001) << s.BriefReport();  // 0.06 deg
  // The arm is back where it started.
  EXPECT_LT((robot.true_joint_angles() - q_start).cwiseAbs().maxCoeff(), 1e-3);
}

}  // namespace
}  // namespace ifab
