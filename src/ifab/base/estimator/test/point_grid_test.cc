#include "ifab/base/estimator/point_grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <utility>
#include <vector>

namespace ifab::base {
namespace {

// Collects every point handed over within the radius, as the association's result set would
// before keeping the nearest.
struct Collect {
  double radius_sq;
  std::vector<std::pair<double, std::uint32_t>> found;
  bool addPoint(double d2, std::uint32_t i) {
    if (d2 < radius_sq) found.emplace_back(d2, i);
    return true;
  }
};

// Walls (points 4.5 cm apart along segments, as a keyframe's reference) plus scattered clutter.
std::vector<Eigen::Vector2d> SceneLikePoints(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-8.0, 8.0), n(-0.01, 0.01);
  std::vector<Eigen::Vector2d> pts;
  for (int w = 0; w < 6; ++w) {
    const Eigen::Vector2d a(u(rng), u(rng)), b(u(rng), u(rng));
    const int m = static_cast<int>((b - a).norm() / 0.045);
    for (int k = 0; k <= m; ++k) pts.push_back(a + (b - a) * (double(k) / std::max(1, m)) + Eigen::Vector2d(n(rng), n(rng)));
  }
  for (int k = 0; k < 200; ++k) pts.emplace_back(u(rng), u(rng));
  return pts;
}

TEST(PointGrid, RadiusSearchFindsExactlyThePointsWithinTheRadius) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> q(-9.0, 9.0);
  int total = 0;
  for (int scene = 0; scene < 20; ++scene) {
    const auto pts = SceneLikePoints(rng);
    for (double cell : {0.17, 0.05, 1.0}) {
      PointGrid grid;
      grid.Build(pts, cell);
      for (int k = 0; k < 300; ++k) {
        // Queries near the points (on the walls) and anywhere, some outside the grid.
        const Eigen::Vector2d at = k % 2 == 0 ? pts[static_cast<std::size_t>(k) % pts.size()] + Eigen::Vector2d(0.03, -0.02)
                                              : Eigen::Vector2d(q(rng), q(rng));
        for (double radius : {0.17, 0.4}) {
          Collect c{radius * radius, {}};
          grid.RadiusSearch(at, radius, c);
          std::vector<std::uint32_t> brute;
          for (std::size_t i = 0; i < pts.size(); ++i) {
            if ((at - pts[i]).squaredNorm() < radius * radius) brute.push_back(static_cast<std::uint32_t>(i));
          }
          std::vector<std::uint32_t> got;
          for (const auto& [d2, i] : c.found) {
            got.push_back(i);
            EXPECT_NEAR(d2, (at - pts[i]).squaredNorm(), 1e-12);
          }
          std::sort(got.begin(), got.end());
          ASSERT_EQ(got, brute) << "scene " << scene << " cell " << cell << " query " << k;
          total += static_cast<int>(brute.size());
        }
      }
    }
  }
  EXPECT_GT(total, 10000);  // the queries did find points
}

TEST(PointGrid, EmptyAndFarQueriesFindNothing) {
  PointGrid grid;
  Collect c{1.0, {}};
  grid.RadiusSearch(Eigen::Vector2d::Zero(), 1.0, c);
  grid.Build({}, 0.17);
  grid.RadiusSearch(Eigen::Vector2d::Zero(), 1.0, c);
  grid.Build({Eigen::Vector2d(1.0, 1.0)}, 0.17);
  grid.RadiusSearch(Eigen::Vector2d(1e12, -1e12), 1.0, c);
  grid.RadiusSearch(Eigen::Vector2d(std::nan(""), 0.0), 1.0, c);
  EXPECT_TRUE(c.found.empty());
  grid.RadiusSearch(Eigen::Vector2d(1.5, 1.0), 1.0, c);
  EXPECT_EQ(c.found.size(), 1u);
}

}  // namespace
}  // namespace ifab::base
