// The reference set alone: when a keyframe is added, which are matched, which are dropped.
#include "ifab/base/estimator/keyframe_map.h"

#include <gtest/gtest.h>

#include "ifab/base/estimator/test/synthetic_scans.h"
#include "ifab/core/angles.h"

namespace ifab::base {
namespace {

struct MapFixture {
  explicit MapFixture(EstimatorOptions options) : o(std::move(options)), pre(o, Pose2()), map(o) {
    pre.Extract(testing::CastScan(testing::LRoom(), Pose2(), 0.0));
  }
  EstimatorOptions o;
  ScanPreprocessor pre;
  KeyframeMap map;
};

TEST(KeyframeMap, SigmaLevelsRunCoarseToFine) {
  EstimatorOptions o;
  o.sigma = 0.03;
  o.coarse_sigmas = {0.2, 0.1};
  o.reference_point_spacing = 0.04;
  o.min_point_spacing = 0.05;
  EXPECT_EQ(NumLevels(o), 3);
  EXPECT_DOUBLE_EQ(LevelSigma(o, 0), 0.2);
  EXPECT_DOUBLE_EQ(LevelSigma(o, 2), 0.03);
  EXPECT_DOUBLE_EQ(ReferenceSpacing(o, 0), 0.2);   // coarse: about sigma apart
  EXPECT_DOUBLE_EQ(ReferenceSpacing(o, 2), 0.04);  // fine: as configured
  EXPECT_DOUBLE_EQ(MeasurementSpacing(o, 1), 0.1);
  EXPECT_DOUBLE_EQ(MeasurementSpacing(o, 2), 0.05);
}

TEST(KeyframeMap, AddsAKeyframeOnlyBeyondTheSpacingOrTurn) {
  EstimatorOptions o;
  o.keyframe_distance = 0.15;
  o.keyframe_angle_deg = 5.0;
  MapFixture f(o);
  EXPECT_TRUE(f.map.NeedsKeyframe(Pose2(), 0.0));  // empty
  f.map.Add(Pose2(), 0.0, &f.pre);
  EXPECT_EQ(f.map.NumActive(), 1);
  const auto& level = f.map.keyframes()[0]->levels.back();
  EXPECT_GT(level.ref.points.size(), 100u);
  EXPECT_EQ(level.ref.near_end.size(), level.ref.points.size());
  EXPECT_FALSE(f.map.NeedsKeyframe(Pose2(0.1, 0.0, 0.0), 1.0));
  EXPECT_TRUE(f.map.NeedsKeyframe(Pose2(0.2, 0.0, 0.0), 1.0));
  EXPECT_FALSE(f.map.NeedsKeyframe(Pose2(0.0, 0.0, DegToRad(4.0)), 1.0));
  EXPECT_TRUE(f.map.NeedsKeyframe(Pose2(0.0, 0.0, DegToRad(6.0)), 1.0));
}

TEST(KeyframeMap, SelectsTheNearestKeyframesWhenMoreAreKept) {
  EstimatorOptions o;
  o.num_reference_scans = 2;
  o.keyframe_capacity = 5;
  MapFixture f(o);
  for (int k = 0; k < 5; ++k) f.map.Add(Pose2(1.0 * k, 0.0, 0.0), k, &f.pre);
  EXPECT_EQ(f.map.NumActive(), 5);
  f.map.Select(Pose2(3.1, 0.0, 0.0));
  std::vector<double> selected;
  for (const auto& kf : f.map.keyframes()) {
    if (kf->selected) selected.push_back(kf->T_world_base.x);
  }
  std::sort(selected.begin(), selected.end());
  EXPECT_EQ(selected, (std::vector<double>{3.0, 4.0}));
  // A sixth replaces the oldest.
  f.map.Add(Pose2(9.0, 0.0, 0.0), 5.0, &f.pre);
  EXPECT_EQ(f.map.NumActive(), 5);
  for (const auto& kf : f.map.keyframes()) EXPECT_NE(kf->T_world_base.x, 0.0);
  EXPECT_DOUBLE_EQ(f.map.Newest()->T_world_base.x, 9.0);
}

TEST(KeyframeMap, DropsKeyframesBeyondTheHorizonButNeverTheNewest) {
  EstimatorOptions o;
  o.horizon = 10.0;
  MapFixture f(o);
  f.map.Add(Pose2(0.0, 0.0, 0.0), 0.0, &f.pre);
  f.map.Add(Pose2(1.0, 0.0, 0.0), 5.0, &f.pre);
  f.map.DropOld(12.0);
  EXPECT_EQ(f.map.NumActive(), 1);
  f.map.DropOld(100.0);
  EXPECT_EQ(f.map.NumActive(), 1);
  EXPECT_DOUBLE_EQ(f.map.Newest()->T_world_base.x, 1.0);
}

TEST(KeyframeMap, MovesRigidlyAndClears) {
  EstimatorOptions o;
  MapFixture f(o);
  f.map.Add(Pose2(1.0, 0.0, 0.0), 0.0, &f.pre);
  f.map.MoveRigidly(Pose2(0.0, 0.0, kPi / 2));
  EXPECT_NEAR(f.map.Newest()->T_world_base.x, 0.0, 1e-12);
  EXPECT_NEAR(f.map.Newest()->T_world_base.y, 1.0, 1e-12);
  EXPECT_NEAR(f.map.Newest()->T_world_base.theta, kPi / 2, 1e-12);
  f.map.Clear();
  EXPECT_EQ(f.map.NumActive(), 0);
  EXPECT_EQ(f.map.Newest(), nullptr);
}

}  // namespace
}  // namespace ifab::base
