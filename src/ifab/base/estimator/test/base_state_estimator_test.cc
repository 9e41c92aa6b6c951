#include "ifab/base/estimator/base_state_estimator.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "ifab/base/estimator/test/synthetic_scans.h"
#include <Eigen/LU>

#include "ifab/core/angles.h"

// Count heap allocations (for the no-allocation-per-scan test). Counting is off unless a test
// switches it on, so the rest of the program is unaffected.
namespace {
std::atomic<bool> g_count_allocations{false};
std::atomic<long> g_allocations{0};
}  // namespace
// The replacement pair below is malloc/free based; GCC cannot see that they match.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void* operator new(std::size_t size) {
  if (g_count_allocations.load(std::memory_order_relaxed)) ++g_allocations;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
#pragma GCC diagnostic pop

namespace ifab::base {
namespace {

using testing::CastScan;
using testing::Gyro;
using testing::ScanSpec;

// The laser sits 0.4 m ahead of the base centre, turned by 2 degrees.
const Pose2 kBaseLaser(0.4, 0.05, DegToRad(2.0));

EstimatorOptions RobotOptions() {
  EstimatorOptions o;
  o.sigma = 0.03;
  o.coarse_sigmas = {0.15};
  return o;
}

LaserScan ScanAt(const testing::World& world, const Pose2& T_world_base, Seconds t,
                 RandomStream* rng = nullptr, double noise = 0.01) {
  ScanSpec spec;
  spec.sigma = noise;
  return CastScan(world, T_world_base * kBaseLaser, t, spec, rng);
}

TEST(EstimatorOptions, ReadsYamlAndRejectsTypos) {
  const auto node = ConfigNode::FromString(
      "sigma: 0.04\ncoarse_sigmas: [0.2, 0.1]\nresidual: point_to_line\nmotion_prior: none\n",
      "est.yaml");
  const auto o = EstimatorOptions::FromConfig(node);
  EXPECT_EQ(o.sigma, 0.04);
  EXPECT_EQ(o.coarse_sigmas, (std::vector<double>{0.2, 0.1}));
  EXPECT_EQ(o.residual, MatchResidual::kPointToLine);
  EXPECT_EQ(o.motion_prior, MotionPrior::kNone);
  EXPECT_EQ(o.num_reference_scans, EstimatorOptions{}.num_reference_scans);
  try {
    EstimatorOptions::FromConfig(ConfigNode::FromString("sigam: 0.04\n", "est.yaml"));
    FAIL() << "a typo must be rejected";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("est.yaml:1: sigam: unknown field"));
  }
  EXPECT_THROW(EstimatorOptions::FromConfig(ConfigNode::FromString("residual: icp\n")), InputError);
  EXPECT_THROW(EstimatorOptions::FromConfig(ConfigNode::FromString("min_range: 5\nmax_range: 2\n")),
               InputError);
}

// Recovery of a known transform between two simulated scans, from a start at the old pose.
TEST(BaseStateEstimator, RecoversKnownTransformBetweenTwoScans) {
  const auto world = testing::LRoom();
  RandomStream rng(7);
  for (const Pose2& motion : {Pose2(0.12, -0.05, DegToRad(4.0)), Pose2(-0.08, 0.1, DegToRad(-3.0)),
                              Pose2(0.2, 0.0, 0.0)}) {
    BaseStateEstimator estimator(RobotOptions(), kBaseLaser);
    const Pose2 T0(0.5, 0.3, 0.2);
    const Pose2 T1 = T0 * motion;
    estimator.Reset(T0, 0.0);
    EXPECT_EQ(estimator.AddScan(ScanAt(world, T0, 0.0, &rng)).status, EstimateStatus::kReference);
    const BaseEstimate& e = estimator.AddScan(ScanAt(world, T1, 0.025, &rng));
    SCOPED_TRACE(::testing::Message() << "motion " << motion);
    EXPECT_EQ(e.status, EstimateStatus::kOk);
    EXPECT_LT(TranslationDistance(e.T_world_base, T1), 0.01);
    EXPECT_LT(AngleDistance(e.T_world_base, T1), DegToRad(0.3));
    // The covariance is a proper one and not absurdly confident or vague.
    EXPECT_GT(e.covariance.determinant(), 0.0);
    EXPECT_LT(std::sqrt(e.covariance(0, 0)), 0.01);
    EXPECT_GT(e.matched_fraction, 0.9);
  }
}

// Same with the paper's settings (one sigma, no coarse levels) on a small motion.
TEST(BaseStateEstimator, PaperSettingsRecoverSmallMotion) {
  const auto world = testing::LRoom();
  RandomStream rng(3);
  EstimatorOptions o;
  o.sigma = 0.05;
  BaseStateEstimator estimator(o, kBaseLaser);
  const Pose2 T0(0.0, 0.0, 0.0);
  const Pose2 T1 = T0 * Pose2(0.03, 0.01, DegToRad(1.0));
  estimator.Reset(T0, 0.0);
  estimator.AddScan(ScanAt(world, T0, 0.0, &rng));
  const BaseEstimate& e = estimator.AddScan(ScanAt(world, T1, 0.025, &rng));
  EXPECT_EQ(e.status, EstimateStatus::kOk);
  EXPECT_LT(TranslationDistance(e.T_world_base, T1), 0.005);
  EXPECT_LT(AngleDistance(e.T_world_base, T1), DegToRad(0.2));
}

// In a round room the scans fix the position but not the heading: matching alone keeps the
// old heading (wrong by the turn); with eq. 2 the gyro supplies it.
TEST(BaseStateEstimator, GyroFusionCorrectsRotationScanMatchingGetsWrong) {
  const auto world = testing::RegularRoom(720, 4.0);
  RandomStream rng(11);
  const Pose2 T0(0.3, -0.2, 0.0);
  const double turn = DegToRad(10.0);
  const Pose2 T1(0.35, -0.2, turn);  // turning on the spot while drifting 5 cm
  auto run = [&](bool with_gyro) {
    BaseStateEstimator estimator(RobotOptions(), kBaseLaser);
    estimator.Reset(T0, 0.0);
    estimator.AddScan(ScanAt(world, T0, 0.0, &rng));
    if (with_gyro) {
      for (int k = 1; k <= 10; ++k) estimator.AddGyro(Gyro(0.05 * k / 10.0, turn / 0.05));
    }
    return estimator.AddScan(ScanAt(world, T1, 0.05, &rng));
  };
  const BaseEstimate alone = run(false);
  const BaseEstimate fused = run(true);
  EXPECT_GT(AngleDistance(alone.T_world_base, T1), DegToRad(5.0)) << "matching alone should fail here";
  EXPECT_TRUE(fused.gyro_used);
  EXPECT_LT(AngleDistance(fused.T_world_base, T1), DegToRad(0.2));
  EXPECT_LT(TranslationDistance(fused.T_world_base, T1), 0.02);
  EXPECT_EQ(fused.status, EstimateStatus::kOk);
}

// A regular octagon looks the same every 45 degrees: a 30 degree turn started from the old
// heading falls into the wrong copy (15 degrees back) without the gyro.
TEST(BaseStateEstimator, GyroFusionAvoidsSymmetricWrongMinimum) {
  const auto world = testing::RegularRoom(8, 3.0);
  const Pose2 T0(0.0, 0.0, 0.0);
  const double turn = DegToRad(30.0);
  const Pose2 T1(0.0, 0.0, turn);
  auto run = [&](bool with_gyro) {
    BaseStateEstimator estimator(RobotOptions(), Pose2());
    estimator.Reset(T0, 0.0);
    estimator.AddScan(CastScan(world, T0, 0.0));
    if (with_gyro) estimator.AddGyro(Gyro(0.5, turn / 0.5));
    return estimator.AddScan(CastScan(world, T1, 0.5));
  };
  EXPECT_GT(AngleDistance(run(false).T_world_base, T1), DegToRad(5.0));
  EXPECT_LT(AngleDistance(run(true).T_world_base, T1), DegToRad(0.2));
}

TEST(BaseStateEstimator, FlagsTooFewPoints) {
  BaseStateEstimator estimator(RobotOptions(), kBaseLaser);
  const auto world = testing::LRoom();
  estimator.Reset(Pose2(), 0.0);
  estimator.AddScan(ScanAt(world, Pose2(), 0.0));
  LaserScan empty = ScanAt(world, Pose2(), 0.025);
  for (std::size_t i = 20; i < empty.size(); ++i) empty.ranges[i] = LaserScan::kNoReturn;
  const BaseEstimate& e = estimator.AddScan(empty);
  EXPECT_EQ(e.status, EstimateStatus::kTooFewPoints);
  EXPECT_FALSE(e.IsUsable());
}

// Between two long parallel walls the position along the corridor is not observable.
TEST(BaseStateEstimator, FlagsDegenerateCorridor) {
  EstimatorOptions o = RobotOptions();
  o.reference_weighting = ReferenceWeighting::kArcLength;
  BaseStateEstimator estimator(o, kBaseLaser);
  const auto world = testing::Corridor(1.2);
  estimator.Reset(Pose2(), 0.0);
  estimator.AddScan(ScanAt(world, Pose2(), 0.0));
  const BaseEstimate& e = estimator.AddScan(ScanAt(world, Pose2(0.05, 0.02, 0.01), 0.025));
  EXPECT_EQ(e.status, EstimateStatus::kDegenerate);
  EXPECT_TRUE(e.IsUsable());
  // Across the corridor and in heading it is still well determined.
  EXPECT_NEAR(e.T_world_base.y, 0.02, 0.01);
  EXPECT_NEAR(e.T_world_base.theta, 0.01, DegToRad(0.3));
  EXPECT_GT(e.covariance(0, 0), 10.0 * e.covariance(1, 1));
}

// The scan turned by 20 degrees but the gyro says the robot did not turn.
TEST(BaseStateEstimator, FlagsRotationTheGyroDoesNotExplain) {
  EstimatorOptions o = RobotOptions();
  o.gyro_weight = 10.0;  // weak, so that the match wins and the disagreement shows
  BaseStateEstimator estimator(o, kBaseLaser);
  const auto world = testing::LRoom();
  estimator.Reset(Pose2(), 0.0);
  estimator.AddScan(ScanAt(world, Pose2(), 0.0));
  for (int k = 1; k <= 10; ++k) estimator.AddGyro(Gyro(0.0025 * k, 0.0));
  const BaseEstimate& e = estimator.AddScan(ScanAt(world, Pose2(0.0, 0.0, DegToRad(8.0)), 0.025));
  EXPECT_EQ(e.status, EstimateStatus::kUnexplainedJump);
  EXPECT_FALSE(e.IsUsable());
  EXPECT_NEAR(e.T_world_base.theta, 0.0, 1e-9) << "a failed match returns the prediction";
}

TEST(BaseStateEstimator, FlagsTranslationJump) {
  BaseStateEstimator estimator(RobotOptions(), kBaseLaser);
  const auto world = testing::LRoom();
  estimator.Reset(Pose2(), 0.0);
  estimator.AddScan(ScanAt(world, Pose2(), 0.0));
  const BaseEstimate& e = estimator.AddScan(ScanAt(world, Pose2(0.45, 0.0, 0.0), 0.025));
  EXPECT_EQ(e.status, EstimateStatus::kUnexplainedJump);
}

// Driving through the room: the estimate follows the truth with little drift.
TEST(BaseStateEstimator, TracksADriveThroughTheRoom) {
  const auto world = testing::LRoom();
  RandomStream rng(5);
  BaseStateEstimator estimator(RobotOptions(), kBaseLaser);
  Pose2 truth(-1.5, -0.5, 0.0);
  estimator.Reset(truth, 0.0);
  estimator.AddScan(ScanAt(world, truth, 0.0, &rng));
  const double dt = 0.025, v = 0.3;
  int usable = 0, n = 0;
  for (int k = 1; k <= 400; ++k) {
    const double omega = 0.25 * std::sin(0.02 * k);
    // Gyro at 400 Hz with noise 0.01 deg/s/sqrt(Hz).
    for (int j = 1; j <= 10; ++j) {
      const double noise = DegToRad(0.01) * std::sqrt(400.0) * rng.Normal();
      estimator.AddGyro(Gyro((k - 1) * dt + j * dt / 10.0, omega + noise));
    }
    truth = truth * Pose2(v * dt, 0.0, omega * dt);
    const BaseEstimate& e = estimator.AddScan(ScanAt(world, truth, k * dt, &rng));
    usable += e.IsUsable() ? 1 : 0;
    ++n;
  }
  EXPECT_EQ(usable, n);
  EXPECT_LT(TranslationDistance(estimator.Latest().T_world_base, truth), 0.03);
  EXPECT_LT(AngleDistance(estimator.Latest().T_world_base, truth), DegToRad(0.5));
}

TEST(BaseStateEstimator, ResetKeepingReferencesMovesThemWithThePose) {
  const auto world = testing::LRoom();
  BaseStateEstimator estimator(RobotOptions(), kBaseLaser);
  estimator.Reset(Pose2(), 0.0);
  estimator.AddScan(ScanAt(world, Pose2(), 0.0));
  // Localization says the robot is really at (1, 2, 90 deg) in the site frame.
  const Pose2 T_site_base(1.0, 2.0, DegToRad(90.0));
  estimator.Reset(T_site_base, 0.01, /*keep_references=*/true);
  EXPECT_EQ(estimator.NumReferenceScans(), 1);
  const BaseEstimate& e = estimator.AddScan(ScanAt(world, Pose2(0.05, 0.0, 0.0), 0.025));
  const Pose2 expected = T_site_base * Pose2(0.05, 0.0, 0.0);
  EXPECT_EQ(e.status, EstimateStatus::kOk);
  EXPECT_LT(TranslationDistance(e.T_world_base, expected), 0.005);
  estimator.Reset(T_site_base, 0.03);
  EXPECT_EQ(estimator.NumReferenceScans(), 0);
}

TEST(BaseStateEstimator, RejectsOversizedAndBackwardScans) {
  EstimatorOptions o = RobotOptions();
  o.max_beams = 100;
  BaseStateEstimator estimator(o, kBaseLaser);
  EXPECT_THROW(estimator.AddScan(ScanAt(testing::LRoom(), Pose2(), 0.0)), InputError);
  BaseStateEstimator ok(RobotOptions(), kBaseLaser);
  ok.AddScan(ScanAt(testing::LRoom(), Pose2(), 1.0));
  EXPECT_THROW(ok.AddScan(ScanAt(testing::LRoom(), Pose2(), 0.5)), InputError);
}

// Standing still (no new keyframes), an update allocates nothing.
TEST(BaseStateEstimator, NoAllocationPerScanInSteadyState) {
  const auto world = testing::LRoom();
  RandomStream rng(9);
  BaseStateEstimator estimator(RobotOptions(), kBaseLaser);
  estimator.Reset(Pose2(), 0.0);
  std::vector<LaserScan> scans;
  for (int k = 0; k < 6; ++k) scans.push_back(ScanAt(world, Pose2(), 0.025 * k, &rng));
  std::vector<GyroSample> gyro;
  for (int k = 0; k < 60; ++k) gyro.push_back(Gyro(0.0025 * (k + 1), 0.0));
  estimator.AddScan(scans[0]);
  for (int k = 0; k < 10; ++k) estimator.AddGyro(gyro[static_cast<std::size_t>(k)]);
  estimator.AddScan(scans[1]);  // warm-up
  g_allocations = 0;
  g_count_allocations = true;
  for (int s = 2; s < 6; ++s) {
    for (int k = 10 * (s - 1); k < 10 * s; ++k) estimator.AddGyro(gyro[static_cast<std::size_t>(k)]);
    const BaseEstimate& e = estimator.AddScan(scans[static_cast<std::size_t>(s)]);
    EXPECT_FALSE(e.keyframe_added);
  }
  g_count_allocations = false;
  EXPECT_EQ(g_allocations.load(), 0);
}

}  // namespace
}  // namespace ifab::base
