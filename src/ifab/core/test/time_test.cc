#include "ifab/core/time.h"

#include <gtest/gtest.h>

#include "ifab/core/se3.h"

namespace ifab {
namespace {

TEST(StampedSeries, InterpolatesInsideAndRefusesOutside) {
  std::vector<Stamped<double>> s{{0.0, 0.0}, {1.0, 10.0}, {3.0, 30.0}};
  auto lerp = [](double a, double b, double t) { return a + t * (b - a); };
  EXPECT_NEAR(*InterpolateAt(s, 0.5, lerp), 5.0, 1e-12);
  EXPECT_NEAR(*InterpolateAt(s, 2.0, lerp), 20.0, 1e-12);
  EXPECT_NEAR(*InterpolateAt(s, 3.0, lerp), 30.0, 1e-12);
  EXPECT_FALSE(InterpolateAt(s, -0.1, lerp).has_value());
  EXPECT_FALSE(InterpolateAt(s, 3.1, lerp).has_value());
}

TEST(StampedSeries, InterpolatesPoses) {
  std::vector<Stamped<Pose3>> s{{0.0, PoseFromXyzRpy(0, 0, 0, 0, 0, 0)},
                                {2.0, PoseFromXyzRpy(2, 0, 0, 0, 0, 1)}};
  const auto p = InterpolateAt(s, 1.0, [](const Pose3& a, const Pose3& b, double t) {
    return Interpolate(a, b, t);
  });
  ASSERT_TRUE(p.has_value());
  EXPECT_NEAR(p->translation().x(), 1.0, 1e-12);
}

}  // namespace
}  // namespace ifab
