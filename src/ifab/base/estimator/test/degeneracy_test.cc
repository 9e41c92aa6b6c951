#include "ifab/base/estimator/degeneracy.h"

#include <gtest/gtest.h>

namespace ifab::base {
namespace {

// A corridor along x: the scan knows y and theta well, x not at all.
Eigen::Matrix3d CorridorInformation() { return Eigen::Vector3d(0.0, 1e6, 1e6).asDiagonal(); }
Eigen::Matrix3d OdometryInformation() { return Eigen::Vector3d(1e3, 1e3, 1e4).asDiagonal(); }

TEST(Degeneracy, CorridorAxisIsDegenerateAgainstThePrior) {
  const Eigen::Matrix3d prior = OdometryInformation();
  const DegeneracyAnalysis a = AnalyseDegeneracy(CorridorInformation(), &prior, 2.0, 0.02);
  ASSERT_EQ(a.num_degenerate, 1);
  EXPECT_NEAR(std::abs(a.directions(0, 0)), 1.0, 1e-9);  // along x
  EXPECT_TRUE(a.with_prior);
}

TEST(Degeneracy, WellConstrainedSceneHasNoDegenerateDirection) {
  const Eigen::Matrix3d prior = OdometryInformation();
  const Eigen::Matrix3d scan = Eigen::Vector3d(1e6, 1e6, 1e6).asDiagonal();
  EXPECT_EQ(AnalyseDegeneracy(scan, &prior, 2.0, 0.02).num_degenerate, 0);
  EXPECT_EQ(AnalyseDegeneracy(scan, nullptr, 2.0, 0.02).num_degenerate, 0);
}

TEST(Degeneracy, WithoutPriorTheScaledRatioDecides) {
  const DegeneracyAnalysis a = AnalyseDegeneracy(CorridorInformation(), nullptr, 2.0, 0.02);
  EXPECT_EQ(a.num_degenerate, 1);
  EXPECT_NEAR(a.ratio, 0.0, 1e-12);
}

TEST(Degeneracy, RemapTakesThePriorAlongTheDegenerateDirectionOnly) {
  const Eigen::Matrix3d prior = OdometryInformation();
  const DegeneracyAnalysis a = AnalyseDegeneracy(CorridorInformation(), &prior, 2.0, 0.02);
  const Eigen::Vector3d dx(0.3, 0.02, 0.01);  // solution minus prior
  const Eigen::Vector3d remapped = RemapDegenerate(a, prior, dx);
  EXPECT_NEAR(remapped.x(), 0.0, 1e-12);   // along the corridor: the prior's
  EXPECT_NEAR(remapped.y(), 0.02, 1e-12);  // across and the heading: the solution's
  EXPECT_NEAR(remapped.z(), 0.01, 1e-12);
}

TEST(Degeneracy, MahalanobisOfTheInnovationOverWellConstrainedDirections) {
  // One direction, scan information 99 x the prior's: the fused offset is 0.99 of the
  // innovation, whose variance is prior variance * (1 + 1/99).
  const Eigen::Matrix3d prior = Eigen::Vector3d(100.0, 100.0, 100.0).asDiagonal();  // sigma 0.1
  const Eigen::Matrix3d scan = Eigen::Vector3d(9900.0, 0.0, 0.0).asDiagonal();
  const DegeneracyAnalysis a = AnalyseDegeneracy(scan, &prior, 1.0, 0.02);
  EXPECT_EQ(a.num_degenerate, 2);
  const double innovation = 0.3;  // 3 sigma of the prior
  int dof = 0;
  const double m2 = InnovationMahalanobisSq(a, prior, Eigen::Vector3d(0.99 * innovation, 0.5, -0.5), &dof);
  EXPECT_EQ(dof, 1);
  EXPECT_NEAR(m2, innovation * innovation / (0.01 * (1.0 + 1.0 / 99.0)), 1e-6);
}

TEST(Degeneracy, TranslationGateIgnoresTheHeadingInnovation) {
  // Scan information 99 x the prior's in every direction: the fused offset is 0.99 of the
  // scan-only one, and the combined variance per direction 0.01 * (1 + 1/99).
  const Eigen::Matrix3d prior = Eigen::Vector3d(100.0, 100.0, 100.0).asDiagonal();
  const Eigen::Matrix3d scan = Eigen::Vector3d(9900.0, 9900.0, 9900.0).asDiagonal();
  const DegeneracyAnalysis a = AnalyseDegeneracy(scan, &prior, 1.0, 0.02);
  ASSERT_EQ(a.num_degenerate, 0);
  const double var = 0.01 * (1.0 + 1.0 / 99.0);
  int dof = 0;
  // A heading-only innovation of 5 sigma: the full gate sees it, the translation gate does not.
  const Eigen::Vector3d turn(0.0, 0.0, 0.99 * 0.5);
  EXPECT_NEAR(InnovationMahalanobisSq(a, prior, turn, &dof), 0.25 / var, 1e-6);
  EXPECT_NEAR(InnovationTranslationMahalanobisSq(a, prior, turn, &dof), 0.0, 1e-9);
  EXPECT_EQ(dof, 2);
  // A translation innovation counts in full.
  const Eigen::Vector3d slide(0.99 * 0.3, 0.99 * 0.4, 0.0);
  EXPECT_NEAR(InnovationTranslationMahalanobisSq(a, prior, slide, &dof), 0.25 / var, 1e-6);
}

TEST(Degeneracy, TranslationGateLeavesADegenerateCorridorAxisUntested) {
  const Eigen::Matrix3d prior = OdometryInformation();
  const DegeneracyAnalysis a = AnalyseDegeneracy(CorridorInformation(), &prior, 2.0, 0.02);
  ASSERT_EQ(a.num_degenerate, 1);
  int dof = 0;
  // Far along the corridor (which the prior alone decides): nothing to test there.
  const double m2 = InnovationTranslationMahalanobisSq(a, prior, Eigen::Vector3d(1.0, 0.0, 0.0), &dof);
  EXPECT_EQ(dof, 1);
  EXPECT_NEAR(m2, 0.0, 1e-6);
}

}  // namespace
}  // namespace ifab::base
