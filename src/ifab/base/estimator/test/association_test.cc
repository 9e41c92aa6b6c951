// Association and eq. 1's sums alone, on synthetic scans.
#include "ifab/base/estimator/association.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include "ifab/base/estimator/test/synthetic_scans.h"

namespace ifab::base {
namespace {

// A keyframe of the world seen from the origin, and the same scan as measurement points.
struct MatchSetup {
  MatchSetup(const testing::World& world, EstimatorOptions options)
      : o(std::move(options)), pre(o, Pose2()), map(o), scan(o) {
    pre.Extract(testing::CastScan(world, Pose2(), 0.0));
    map.Add(Pose2(), 0.0, &pre);
    map.Select(Pose2());
    pre.Thin(o.min_point_spacing, 1e9, o.max_points, &scan.meas_base);
  }
  double Radius() const { return o.search_radius_sigmas * std::sqrt(2.0) * o.sigma; }
  EstimatorOptions o;
  ScanPreprocessor pre;
  KeyframeMap map;
  Association scan;
};

TEST(Association, TheSameScanMatchesItselfEverywhere) {
  MatchSetup s(testing::LRoom(), EstimatorOptions{});
  const double matched = s.scan.Associate(s.map, Pose2(), 0, s.Radius());
  EXPECT_GT(matched, 0.75);  // all but the points whose nearest reference lies near a chain's end
  EXPECT_NEAR(s.scan.MatchedFraction(), matched, 1e-12);
  EXPECT_NEAR(s.scan.InlierFraction(Pose2(), s.o.sigma), 1.0, 1e-12);
  EXPECT_GT(s.scan.Score(Pose2(), s.o.sigma), 1.0);  // each point near a few reference points
  // At the true pose the gradient of eq. 1's sum vanishes (up to the points' sampling).
  const NormalEquations ne = s.scan.Accumulate(Pose2(), s.o.sigma);
  EXPECT_GT(ne.rows, 0);
  EXPECT_LT(ne.g.head<2>().norm(), 1e-2 * ne.H.diagonal().head<2>().norm());
}

TEST(Association, TheGradientPointsBackToTheReference) {
  MatchSetup s(testing::LRoom(), EstimatorOptions{});
  const Pose2 off(0.03, -0.02, 0.0);
  s.scan.Associate(s.map, off, 0, s.Radius());
  const NormalEquations ne = s.scan.Accumulate(off, s.o.sigma);
  // A Gauss-Newton step from the offset pose goes most of the way back.
  const Eigen::Vector3d step = -ne.H.ldlt().solve(ne.g);
  EXPECT_LT((Eigen::Vector2d(off.x, off.y) + step.head<2>()).norm(), 0.5 * std::hypot(off.x, off.y));
}

TEST(Association, NothingMatchesFarAway) {
  MatchSetup s(testing::LRoom(), EstimatorOptions{});
  EXPECT_LT(s.scan.Associate(s.map, Pose2(20.0, 20.0, 0.0), 0, s.Radius()), 0.05);
  EXPECT_LT(s.scan.InlierFraction(Pose2(20.0, 20.0, 0.0), s.o.sigma), 0.5);
}

TEST(Association, StructureOfACorridorHasNoInformationAlongIt) {
  EstimatorOptions o;
  o.structure_degeneracy_ratio = 0.01;  // reference normals are computed for the structure check
  MatchSetup s(testing::Corridor(), o);
  s.scan.Associate(s.map, Pose2(), 0, s.Radius());
  const Eigen::Matrix3d S = s.scan.StructureInformation(Pose2());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(S);
  EXPECT_LT(es.eigenvalues()(0), 1e-6 * es.eigenvalues()(2));
  EXPECT_NEAR(std::abs(es.eigenvectors().col(0).x()), 1.0, 1e-3);  // the corridor's axis
  // The room has none.
  MatchSetup r(testing::LRoom(), o);
  r.scan.Associate(r.map, Pose2(), 0, r.Radius());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> er(r.scan.StructureInformation(Pose2()));
  EXPECT_GT(er.eigenvalues()(0), 1e-2 * er.eigenvalues()(2));
}

TEST(Association, LeverIsTheRmsDistanceOfThePoints) {
  MatchSetup s(testing::RegularRoom(64, 2.0), EstimatorOptions{});
  EXPECT_NEAR(s.scan.Lever(), 2.0, 0.02);
}

}  // namespace
}  // namespace ifab::base
