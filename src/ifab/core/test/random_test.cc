#include "ifab/core/random.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ifab {
namespace {

TEST(RandomStream, SameSeedSameNumbers) {
  RandomStream a(42), b(42), c(43);
  for (int i = 0; i < 100; ++i) {
    const double x = a.Normal();
    EXPECT_EQ(x, b.Normal());
    (void)c;
  }
  EXPECT_NE(RandomStream(42).Normal(), RandomStream(43).Normal());
}

TEST(RandomStream, DerivedStreamsAreIndependentOfParentState) {
  RandomStream a(7);
  const double first = a.Derive("lrf").Normal();
  a.Normal();
  a.Normal();
  EXPECT_EQ(first, a.Derive("lrf").Normal());
  EXPECT_NE(a.Derive("lrf").Normal(), a.Derive("gyro").Normal());
}

TEST(RandomStream, NormalHasRequestedSpread) {
  RandomStream r(1);
  const int n = 20000;
  double sum = 0, sum2 = 0;
  for (int i = 0; i < n; ++i) {
    const double x = r.Normal(2.0);
    sum += x;
    sum2 += x * x;
  }
  const double mean = sum / n;
  EXPECT_NEAR(mean, 0.0, 0.05);
  EXPECT_NEAR(std::sqrt(sum2 / n - mean * mean), 2.0, 0.05);
}

}  // namespace
}  // namespace ifab
