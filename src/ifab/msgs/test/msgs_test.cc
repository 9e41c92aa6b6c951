#include "ifab/msgs/msgs.h"

#include <gtest/gtest.h>

namespace ifab {
namespace {

TEST(LaserScan, BeamGeometryAndValidity) {
  LaserScan scan;
  scan.angle_min = -EIGEN_PI / 2;
  scan.angle_increment = EIGEN_PI / 2;
  scan.time_increment = 0.01;
  scan.stamp.t = 5.0;
  scan.ranges = {1.0, LaserScan::kNoReturn, 0.05};
  EXPECT_NEAR((scan.Point(0) - Eigen::Vector3d(0, -1, 0)).norm(), 0.0, 1e-12);
  EXPECT_TRUE(scan.IsValid(0));
  EXPECT_FALSE(scan.IsValid(1));
  EXPECT_FALSE(scan.IsValid(2));  // below range_min
  EXPECT_DOUBLE_EQ(scan.BeamTime(2), 5.02);
  EXPECT_DOUBLE_EQ(scan.MidTime(), 5.01);
}

TEST(DeviceName, NamesEveryDevice) {
  EXPECT_STREQ(DeviceName(DeviceId::kArmLaser), "arm_laser");
  EXPECT_STREQ(DeviceName(DeviceId::kGyro), "gyro");
}

}  // namespace
}  // namespace ifab
