// Eq. 2's gyro integration alone.
#include "ifab/base/estimator/gyro_buffer.h"

#include <gtest/gtest.h>

namespace ifab::base {
namespace {

TEST(GyroBuffer, IntegratesTheRateBetweenScans) {
  GyroBuffer g;
  for (int i = 1; i <= 400; ++i) g.Push(0.0025 * i, i <= 200 ? 0.2 : -0.1);  // 400 Hz, 1 s
  double dtheta = 0.0;
  ASSERT_TRUE(g.Integrate(0.0, 0.5, &dtheta));
  EXPECT_NEAR(dtheta, 0.1, 1e-12);
  ASSERT_TRUE(g.Integrate(0.25, 0.75, &dtheta));
  EXPECT_NEAR(dtheta, 0.25 * 0.2 - 0.25 * 0.1, 1e-12);
  // A short gap at the end is bridged with the last rate; a long one is not covered.
  ASSERT_TRUE(g.Integrate(0.9, 1.02, &dtheta));
  EXPECT_NEAR(dtheta, -0.1 * 0.12, 1e-12);
  EXPECT_FALSE(g.Integrate(0.9, 1.2, &dtheta));
}

TEST(GyroBuffer, DroppedSamplesStillBoundTheNextInterval) {
  GyroBuffer g;
  for (int i = 1; i <= 100; ++i) g.Push(0.01 * i, 1.0);
  g.DropUntil(0.5);
  double dtheta = 0.0;
  ASSERT_TRUE(g.Integrate(0.5, 0.8, &dtheta));
  EXPECT_NEAR(dtheta, 0.3, 1e-12);
  // Before the oldest kept sample's interval: not covered.
  EXPECT_FALSE(g.Integrate(0.3, 0.8, &dtheta));
  g.DropUntil(2.0);
  EXPECT_TRUE(g.Empty());
}

TEST(GyroBuffer, KeepsWorkingWhenFull) {
  GyroBuffer g(64);
  for (int i = 1; i <= 1000; ++i) g.Push(0.01 * i, 0.5);
  double dtheta = 0.0;
  ASSERT_TRUE(g.Integrate(9.8, 10.0, &dtheta));
  EXPECT_NEAR(dtheta, 0.1, 1e-12);
  EXPECT_DOUBLE_EQ(g.BackTime(), 10.0);
}

}  // namespace
}  // namespace ifab::base
