#include "ifab/core/se3.h"

#include <gtest/gtest.h>

namespace ifab {
namespace {

TEST(Pose3, RpyRoundTrip) {
  for (double roll : {-2.0, 0.0, 0.3}) {
    for (double pitch : {-1.2, 0.0, 0.8}) {
      for (double yaw : {-3.0, 0.1, 2.5}) {
        const auto v = XyzRpyFromPose(PoseFromXyzRpy(1, 2, 3, roll, pitch, yaw));
        EXPECT_NEAR(v[3], roll, 1e-12);
        EXPECT_NEAR(v[4], pitch, 1e-12);
        EXPECT_NEAR(v[5], yaw, 1e-12);
      }
    }
  }
}

TEST(Pose3, RpyIsFixedAxesXyz) {
  // URDF: rpy (0, pi/2, 0) turns x into -z.
  const Eigen::Matrix3d r = RotationFromRpy(0, EIGEN_PI / 2, 0);
  EXPECT_NEAR((r * Eigen::Vector3d::UnitX() - Eigen::Vector3d(0, 0, -1)).norm(), 0.0, 1e-12);
}

TEST(Pose3, InterpolateEndsAndMiddle) {
  const Pose3 a = PoseFromXyzRpy(0, 0, 0, 0, 0, 0);
  const Pose3 b = PoseFromXyzRpy(2, 0, 0, 0, 0, 1.0);
  EXPECT_NEAR(TranslationDistance(Interpolate(a, b, 0.0), a), 0.0, 1e-12);
  EXPECT_NEAR(RotationAngle(Interpolate(a, b, 1.0), b), 0.0, 1e-12);
  const Pose3 m = Interpolate(a, b, 0.5);
  EXPECT_NEAR(m.translation().x(), 1.0, 1e-12);
  EXPECT_NEAR(XyzRpyFromPose(m)[5], 0.5, 1e-12);
}

TEST(Pose3, ExpLogRoundTrip) {
  const Eigen::Vector3d w(0.3, -0.2, 1.1);
  EXPECT_NEAR((LogSO3(ExpSO3(w)) - w).norm(), 0.0, 1e-12);
}

}  // namespace
}  // namespace ifab
