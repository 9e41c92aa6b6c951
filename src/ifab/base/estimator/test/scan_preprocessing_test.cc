// Scan preprocessing alone: range filter, deskew, thinning, reference sampling.
#include "ifab/base/estimator/scan_preprocessing.h"

#include <gtest/gtest.h>

#include <cmath>

#include "ifab/base/estimator/test/synthetic_scans.h"
#include "ifab/core/angles.h"

namespace ifab::base {
namespace {

// A fan of beams all at range r (a circle around the laser).
LaserScan Fan(int beams, double r) {
  LaserScan scan;
  scan.angle_min = -DegToRad(90.0);
  scan.angle_increment = DegToRad(180.0) / (beams - 1);
  scan.ranges.assign(static_cast<std::size_t>(beams), r);
  return scan;
}

TEST(ScanPreprocessing, RangeFilterDropsShortLongAndMissingBeams) {
  EstimatorOptions o;
  o.min_range = 0.2;
  o.max_range = 10.0;
  ScanPreprocessor pre(o, Pose2());
  LaserScan scan = Fan(5, 1.0);
  scan.ranges[0] = 0.15;                  // below min_range
  scan.ranges[1] = 12.0;                  // beyond max_range
  scan.ranges[2] = LaserScan::kNoReturn;  // no return
  scan.range_max = 5.0;
  scan.ranges[3] = 6.0;                   // beyond the laser's own maximum
  pre.Extract(scan);
  ASSERT_EQ(pre.valid().size(), 1u);
  EXPECT_NEAR(pre.valid()[0].norm(), 1.0, 1e-12);
}

TEST(ScanPreprocessing, PointsAreInTheBaseFrame) {
  EstimatorOptions o;
  const Pose2 T_base_laser(0.4, -0.1, DegToRad(90.0));
  ScanPreprocessor pre(o, T_base_laser);
  LaserScan scan;
  scan.angle_min = 0.0;
  scan.angle_increment = 0.01;
  scan.ranges = {2.0};
  pre.Extract(scan);
  ASSERT_EQ(pre.valid().size(), 1u);
  EXPECT_NEAR(pre.valid()[0].x(), 0.4, 1e-12);  // straight ahead of a laser turned left
  EXPECT_NEAR(pre.valid()[0].y(), 1.9, 1e-12);
}

TEST(ScanPreprocessing, DeskewMovesEachBeamByTheTwistOverItsTimeOffset) {
  EstimatorOptions o;
  ScanPreprocessor pre(o, Pose2());
  LaserScan scan = Fan(181, 3.0);
  scan.time_increment = 1e-4;
  pre.Extract(scan);
  const auto rigid = pre.valid();
  const double omega = 0.5;
  const Eigen::Vector2d v(0.2, 0.0);
  pre.Extract(scan, v, omega);
  ASSERT_EQ(pre.valid().size(), rigid.size());
  // The middle beam stays; the first beam (90 beams before the middle) moves back by the twist.
  const double dt0 = -90 * scan.time_increment;
  EXPECT_NEAR((pre.valid()[90] - rigid[90]).norm(), 0.0, 1e-12);
  const Eigen::Vector2d p0 = rigid[0];
  const Eigen::Vector2d expected(std::cos(omega * dt0) * p0.x() - std::sin(omega * dt0) * p0.y() + v.x() * dt0,
                                 std::sin(omega * dt0) * p0.x() + std::cos(omega * dt0) * p0.y() + v.y() * dt0);
  EXPECT_NEAR((pre.valid()[0] - expected).norm(), 0.0, 1e-6);
  EXPECT_GT((pre.valid()[0] - p0).norm(), 1e-4);  // it did move
  // Without beam times the scan stays rigid whatever the twist.
  scan.time_increment = 0.0;
  pre.Extract(scan, v, omega);
  EXPECT_NEAR((pre.valid()[0] - p0).norm(), 0.0, 1e-12);
}

TEST(ScanPreprocessing, ThinningKeepsPointsAboutTheSpacingApartAndCapsTheCount) {
  for (Thinning thinning : {Thinning::kNoiseIndependent, Thinning::kNearestBeyondSpacing}) {
    EstimatorOptions o;
    o.thinning = thinning;
    ScanPreprocessor pre(o, Pose2());
    pre.Extract(Fan(1081, 2.0));  // beams 5.8 mm apart on the circle
    std::vector<Eigen::Vector2d> out;
    pre.Thin(0.05, 1.0, 10000, &out);
    ASSERT_GT(out.size(), 100u);
    for (std::size_t i = 1; i < out.size(); ++i) {
      const double d = (out[i] - out[i - 1]).norm();
      EXPECT_GT(d, 0.045);
      EXPECT_LT(d, 0.065);
    }
    pre.Thin(0.05, 1.0, 20, &out);
    EXPECT_EQ(out.size(), 20u);
  }
}

TEST(ScanPreprocessing, ThinningFlagsPointsNearTheEndOfTheirChain) {
  EstimatorOptions o;
  ScanPreprocessor pre(o, Pose2());
  LaserScan scan = Fan(361, 2.0);  // 17 mm apart
  for (std::size_t i = 170; i < 190; ++i) scan.ranges[i] = 1.0;  // a depth jump in the middle
  pre.Extract(scan);
  std::vector<Eigen::Vector2d> out;
  std::vector<char> near_end;
  pre.Thin(0.02, 0.1, 10000, &out, 0.12, &near_end);
  ASSERT_EQ(out.size(), near_end.size());
  EXPECT_TRUE(near_end.front());
  EXPECT_TRUE(near_end.back());
  int flagged = 0;
  for (std::size_t i = 0; i < out.size(); ++i) {
    flagged += near_end[i];
    // Points far (along the arc) from either end and from the jump are not flagged.
    const double a = std::atan2(out[i].y(), out[i].x());
    if (out[i].norm() > 1.5 && std::abs(a) > 0.3 && std::abs(a) < 1.2) {
      EXPECT_FALSE(near_end[i]);
    }
  }
  EXPECT_GE(flagged, 8);  // both scan ends and both sides of the jump
}

TEST(ScanPreprocessing, PolylineSamplesAWallEvenlyWithItsNormal) {
  EstimatorOptions o;
  ScanPreprocessor pre(o, Pose2());
  // A wall across x = 2 seen from the origin: beams sparser towards the sides.
  const testing::World wall = {{{2.0, -3.0}, {2.0, 3.0}}};
  testing::ScanSpec spec;
  spec.beams = 181;
  spec.fov = DegToRad(120.0);
  pre.Extract(testing::CastScan(wall, Pose2(), 0.0, spec));
  ReferencePoints ref;
  pre.Densify(0.04, 0.5, 0.1, &ref);
  ASSERT_GT(ref.points.size(), 100u);
  ASSERT_EQ(ref.normals.size(), ref.points.size());
  for (std::size_t i = 0; i < ref.points.size(); ++i) {
    EXPECT_NEAR(ref.points[i].x(), 2.0, 1e-9);
    EXPECT_NEAR(std::abs(ref.normals[i].x()), 1.0, 1e-9);
    if (i > 0 && i + 1 < ref.points.size()) {
      EXPECT_NEAR((ref.points[i] - ref.points[i - 1]).norm(), 0.04, 1e-9);
    }
  }
  EXPECT_TRUE(ref.near_end.front());
  EXPECT_TRUE(ref.near_end.back());
  EXPECT_FALSE(ref.near_end[ref.points.size() / 2]);
}

TEST(ScanPreprocessing, NormalsOfAWallAreAcrossItAndZeroAtACorner) {
  EstimatorOptions o;
  ScanPreprocessor pre(o, Pose2());
  testing::ScanSpec spec;
  spec.beams = 721;
  const testing::World room = testing::RegularRoom(4, 3.0, kPi / 4);  // a square, corners on the axes diagonals
  pre.Extract(testing::CastScan(room, Pose2(), 0.0, spec));
  std::vector<Eigen::Vector2d> normals;
  pre.ComputeNormals(pre.valid(), 0.3, &normals);
  ASSERT_EQ(normals.size(), pre.valid().size());
  const double h = 3.0 / std::sqrt(2.0);  // the walls lie at |x| = h and |y| = h
  int wall_points = 0, not_across = 0, zero_at_corners = 0;
  for (std::size_t i = 0; i < normals.size(); ++i) {
    const Eigen::Vector2d& p = pre.valid()[i];
    const bool near_corner = (p.cwiseAbs() - Eigen::Vector2d(h, h)).norm() < 0.35;
    if (near_corner) {
      zero_at_corners += normals[i].squaredNorm() == 0.0 ? 1 : 0;
      continue;
    }
    ++wall_points;
    const bool on_x_wall = std::abs(std::abs(p.x()) - h) < 0.01;
    not_across += std::abs(on_x_wall ? normals[i].x() : normals[i].y()) > 0.99 ? 0 : 1;
  }
  EXPECT_GT(wall_points, 400);
  EXPECT_EQ(not_across, 0);
  EXPECT_GT(zero_at_corners, 0);  // an L is not line-like
}

TEST(ScanPreprocessing, ArcLengthWeightsCountTheSurfaceEachPointStandsFor) {
  const std::vector<Eigen::Vector2d> pts = {{0, 0}, {0.1, 0}, {0.3, 0}, {5, 0}};
  std::vector<double> w;
  ArcLengthWeights(pts, 0.1, 0.4, ReferenceWeighting::kNone, &w);
  EXPECT_EQ(w, std::vector<double>(4, 1.0));
  ArcLengthWeights(pts, 0.1, 0.4, ReferenceWeighting::kArcLength, &w);
  EXPECT_NEAR(w[0], (0.05 + 0.05) / 0.1, 1e-12);  // the open end counts half a spacing
  EXPECT_NEAR(w[1], (0.05 + 0.1) / 0.1, 1e-12);
  EXPECT_NEAR(w[2], (0.1 + 0.05) / 0.1, 1e-12);   // the far point is beyond the link
  EXPECT_NEAR(w[3], 1.0, 1e-12);                  // isolated: a spacing
}

}  // namespace
}  // namespace ifab::base
