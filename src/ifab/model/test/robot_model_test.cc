#include "ifab/model/robot_model.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

#include "ifab/core/angles.h"
#include "ifab/core/data_path.h"
#include "ifab/core/error.h"

namespace ifab {
namespace {

TEST(RobotModel, FlangeAtZeroPoseMatchesTheDataSheet) {
  const RobotModel robot = LoadRobotModel(DataPath("robots/insitu_fabricator.urdf"));
  EXPECT_EQ(robot.arm_chain.getNrOfJoints(), 6u);
  const Pose3 T = robot.ArmForwardKinematics(Vector6d::Zero());
  EXPECT_NEAR((T.translation() - Eigen::Vector3d(1.580, 0, 1.765)).norm(), 0.0, 1e-9);
  // tool0's z axis points out of the flange (along arm_base x at the zero pose).
  EXPECT_NEAR((T.linear().col(2) - Eigen::Vector3d::UnitX()).norm(), 0.0, 1e-6);
}

TEST(RobotModel, KnownJointMotions) {
  const RobotModel robot = LoadRobotModel(DataPath("robots/insitu_fabricator.urdf"));
  Vector6d q = Vector6d::Zero();
  q[0] = EIGEN_PI / 2;  // joint 1 swings the flange to +y
  EXPECT_NEAR((robot.ArmForwardKinematics(q).translation() - Eigen::Vector3d(0, 1.580, 1.765)).norm(), 0, 1e-6);
  q.setZero();
  q[2] = -EIGEN_PI / 2;  // joint 3 about +y by -90 deg lifts the forearm up
  const Eigen::Vector3d p = robot.ArmForwardKinematics(q).translation();
  EXPECT_NEAR(p.x(), 0.175 - 0.175, 1e-6);  // the J4 offset now points back
  EXPECT_NEAR(p.z(), 0.495 + 1.095 + 1.270 + 0.135, 1e-6);
  EXPECT_TRUE(robot.WithinLimits(Vector6d::Zero()));
  q.setZero();
  q[1] = 2.0;
  EXPECT_TRUE(robot.WithinLimits(q));
  q[1] = -2.0;
  EXPECT_FALSE(robot.WithinLimits(q));
  EXPECT_NEAR(robot.qd_max[5], DegToRad(360), 1e-6);
}

TEST(RobotModel, BadUrdfGivesAClearError) {
  const std::string path = ::testing::TempDir() + "/bad.urdf";
  {
    std::ofstream out(path);
    out << "<robot name='x'><link name='a'/><joint name='j' type='revolute'><parent link='a'/></joint></robot>";
  }
  try {
    LoadRobotModel(path);
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr(path));
    EXPECT_THAT(e.what(), ::testing::HasSubstr("not a valid URDF"));
  }
  EXPECT_THROW(LoadRobotModel("/nonexistent.urdf"), InputError);
}

}  // namespace
}  // namespace ifab
