#include "ifab/core/random.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

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

namespace ifab {
namespace {

double StandardNormalCdf(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

// The ziggurat's samples against the normal distribution: moments, the tails beyond the base
// strip's edge (r = 3.654, where the exact tail sampler takes over) and a chi-square over 200
// equiprobable bins; the same test on Normal's polar method for comparison.
void ExpectStandardNormal(const std::vector<double>& xs) {
  const double n = static_cast<double>(xs.size());
  double s1 = 0, s2 = 0, s4 = 0;
  int beyond3 = 0, beyond_r = 0, beyond4 = 0;
  constexpr int kBins = 200;
  std::vector<int> counts(kBins, 0);
  for (double x : xs) {
    s1 += x;
    s2 += x * x;
    s4 += x * x * x * x;
    beyond3 += std::abs(x) > 3.0;
    beyond_r += std::abs(x) > 3.6541528853610088;
    beyond4 += std::abs(x) > 4.0;
    const int bin = std::min(kBins - 1, static_cast<int>(StandardNormalCdf(x) * kBins));
    ++counts[static_cast<std::size_t>(bin)];
  }
  // Standard errors at n = 4e6: mean 5e-4, variance 7e-4, 4th moment 5e-3.
  EXPECT_NEAR(s1 / n, 0.0, 0.002);
  EXPECT_NEAR(s2 / n, 1.0, 0.003);
  EXPECT_NEAR(s4 / n, 3.0, 0.02);
  const auto expect_tail = [&](int count, double threshold) {
    const double p = 2.0 * (1.0 - StandardNormalCdf(threshold));
    const double expected = p * n;
    EXPECT_NEAR(count, expected, 4.0 * std::sqrt(expected)) << "beyond " << threshold;
  };
  expect_tail(beyond3, 3.0);
  expect_tail(beyond_r, 3.6541528853610088);
  expect_tail(beyond4, 4.0);
  double chi2 = 0.0;
  const double e = n / kBins;
  for (int c : counts) chi2 += (c - e) * (c - e) / e;
  // 199 degrees of freedom: mean 199, sd 20; the 0.9999 quantile is ~280.
  EXPECT_LT(chi2, 280.0);
}

TEST(RandomStream, ZigguratIsStandardNormal) {
  for (std::uint64_t seed : {1u, 2u}) {
    RandomStream r(seed);
    std::vector<double> xs(4000000);
    for (double& x : xs) x = r.NormalZiggurat();
    ExpectStandardNormal(xs);
    RandomStream q(seed);
    for (double& x : xs) x = q.Normal();
    ExpectStandardNormal(xs);
  }
}

TEST(RandomStream, ZigguratScalesAndRepeats) {
  RandomStream a(5), b(5);
  double sum2 = 0;
  const int n = 100000;
  for (int i = 0; i < n; ++i) {
    const double x = a.NormalZiggurat(0.018);
    EXPECT_EQ(x, b.NormalZiggurat(0.018));
    sum2 += x * x;
  }
  EXPECT_NEAR(std::sqrt(sum2 / n), 0.018, 0.018 * 0.01);
}

}  // namespace
}  // namespace ifab
