// The recorded-log config (data/estimator/carmen.yaml) on synthetic CARMEN-like drives: a long
// featureless corridor and two identical doorways. The odometry is a factor of eq. 3.
#include <gtest/gtest.h>

#include "ifab/base/estimator/base_state_estimator.h"
#include "ifab/base/estimator/test/synthetic_scans.h"
#include "ifab/core/angles.h"
#include "ifab/core/random.h"

namespace ifab::base {
namespace {

using testing::CastScan;
using testing::ScanSpec;
using testing::World;

EstimatorOptions RecordedLogOptions() {
  return EstimatorOptions::FromConfig(
      ConfigNode::LoadFile(std::string(IFAB_DATA_DIR) + "/estimator/carmen.yaml")["estimator"]);
}
OdometryNoise RecordedLogNoise() {
  return OdometryNoise::FromConfig(ConfigNode::LoadFile(
      std::string(IFAB_DATA_DIR) + "/estimator/carmen.yaml")["log"]["odometry_noise"]);
}

// A SICK LMS as in ROBOTLASER1 logs: 181 beams over 180 deg, 8 m of useful range.
ScanSpec Sick181() {
  ScanSpec s;
  s.beams = 181;
  s.fov = DegToRad(180.0);
  s.range_max = 8.0;
  s.sigma = 0.01;
  return s;
}

// A long featureless corridor: the scan cannot see the motion along it. The odometry
// over-reports the distance by 3 % (a worn wheel); the estimate must follow it along the axis
// (not slide) and report the axis as the degenerate direction.
//
// carmen.yaml as shipped: the match's kernel sum over raw reference points ripples along the
// walls, but degeneracy is read from the point-to-line structure (structure_degeneracy_ratio),
// which has no such ripple, so the axis goes to the odometry.
TEST(RecordedLog, CorridorFollowsOdometryAlongTheAxisAndReportsTheDegenerateDirection) {
  const EstimatorOptions o = RecordedLogOptions();
  const OdometryNoise noise = RecordedLogNoise();
  BaseStateEstimator estimator(o, Pose2());
  const World world = testing::Corridor(1.0, 400.0);
  RandomStream rng(7);
  estimator.Reset(Pose2(), 0.0);
  estimator.AddScan(CastScan(world, Pose2(), 0.0, Sick181(), &rng));
  const double step = 0.2;  // 1 m/s at 5 Hz
  double x_odometry = 0.0;
  int degenerate_along_x = 0;
  const int scans = 100;
  for (int k = 1; k <= scans; ++k) {
    const Pose2 truth(step * k, 0.02 * std::sin(0.1 * k), 0.01 * std::sin(0.07 * k));
    const Pose2 odometry_step(1.03 * step, 0.0, 0.0);
    x_odometry += odometry_step.x;
    const BaseEstimate& e = estimator.AddScan(
        CastScan(world, truth, 0.2 * k, Sick181(), &rng),
        MotionMeasurement{odometry_step, StepCovariance(odometry_step, noise)});
    ASSERT_TRUE(e.IsUsable()) << "scan " << k << ": " << StatusName(e.status) << " m2 "
                              << e.mahalanobis_sq << " dof " << e.gate_dof << " x "
                              << e.T_world_base.x << " truth " << truth.x << " matched "
                              << e.matched_fraction << " inliers " << e.inlier_fraction;
    if (e.status == EstimateStatus::kDegenerate && e.num_degenerate >= 1 &&
        std::abs(e.degenerate_directions(0, 0)) > 0.95) {
      ++degenerate_along_x;
    }
    // Across the corridor and in heading the scan decides.
    // (Chained over ~70 keyframes the lateral error grows to ~3 mm per metre.)
    EXPECT_NEAR(e.T_world_base.y, truth.y, 0.1) << "scan " << k;
    EXPECT_NEAR(e.T_world_base.theta, truth.theta, DegToRad(1.0)) << "scan " << k;
  }
  // Along it the odometry decides: within 1 % of the distance of the odometry's position.
  EXPECT_NEAR(estimator.Latest().T_world_base.x, x_odometry, 0.01 * x_odometry);
  EXPECT_EQ(degenerate_along_x, scans);
}

// A corridor with two identical doorways 2 m apart (0.8 m wide, 0.5 m deep recesses in the
// left wall), scanned facing the doorways with 1.6 m of useful range: each scan sees one doorway
// only. The robot drives 2 m, in front of the second doorway, but the odometry, slipping,
// reports 0.4 m: the scan looks exactly like the reference seen from the first doorway, and the
// match near the prediction is the wrong one (0 m). It must be flagged, fall back to the prior,
// and not become a keyframe.
TEST(RecordedLog, MatchToTheWrongOfTwoIdenticalDoorwaysIsFlagged) {
  const EstimatorOptions o = RecordedLogOptions();  // as shipped: the window gate catches it
  const OdometryNoise noise = RecordedLogNoise();
  World world;
  auto wall = [&](double ax, double ay, double bx, double by) {
    world.push_back({Eigen::Vector2d(ax, ay), Eigen::Vector2d(bx, by)});
  };
  wall(-50.0, -1.0, 50.0, -1.0);  // the other wall
  double x = -50.0;
  for (double door : {0.0, 2.0}) {
    wall(x, 1.0, door - 0.4, 1.0);
    wall(door - 0.4, 1.0, door - 0.4, 1.5);
    wall(door - 0.4, 1.5, door + 0.4, 1.5);
    wall(door + 0.4, 1.5, door + 0.4, 1.0);
    x = door + 0.4;
  }
  wall(x, 1.0, 50.0, 1.0);
  ScanSpec spec = Sick181();
  spec.range_max = 1.6;
  RandomStream rng(3);
  BaseStateEstimator estimator(o, Pose2());
  const Pose2 start(0.0, 0.0, kPi / 2);  // facing the doorways
  estimator.Reset(start, 0.0);
  ASSERT_TRUE(estimator.AddScan(CastScan(world, start, 0.0, spec, &rng)).keyframe_added);
  const int references = estimator.NumReferenceScans();
  const Pose2 truth(2.0, 0.0, kPi / 2);
  const Pose2 odometry_step = start.inverse() * Pose2(0.4, 0.0, kPi / 2);
  const BaseEstimate& e = estimator.AddScan(
      CastScan(world, truth, 0.2, spec, &rng),
      MotionMeasurement{odometry_step, StepCovariance(odometry_step, noise)});
  EXPECT_TRUE(e.IsFlagged()) << StatusName(e.status) << " at x = " << e.T_world_base.x;
  EXPECT_EQ(e.status, EstimateStatus::kUnexplainedJump);
  EXPECT_NEAR(e.T_world_base.x, 0.4, 1e-9) << "a flagged match falls back to the prior";
  EXPECT_FALSE(e.keyframe_added);
  EXPECT_EQ(estimator.NumReferenceScans(), references);
  // The match's own view: it would have put the robot at the first doorway, 0.4 m behind the
  // odometry (chi-square, 2 dof, 0.999: 13.8).
  EXPECT_GT(e.window_mahalanobis_sq, 13.8);
}

// ACES's corridor stall in miniature: the robot drives 6 cm a scan (the odometry says so), but
// what the laser sees moves with it at 80 % of its speed, so the match moves 1.2 cm a scan. A
// step's shortfall (4.8 cm against the odometry's 1.4 cm sigma) is within a per-scan 0.999 gate
// (the squared distance ~11 < 13.8); over a metre of travel it is not: the window gate flags it.
TEST(RecordedLog, MatchThatFallsBehindTheOdometryOverAMetreIsFlagged) {
  const OdometryNoise noise = RecordedLogNoise();
  const World world = testing::LRoom();
  auto run = [&](const EstimatorOptions& o, int* flagged, int* flagged_keyframes) {
    RandomStream rng(11);
    BaseStateEstimator estimator(o, Pose2());
    estimator.Reset(Pose2(), 0.0);
    estimator.AddScan(CastScan(world, Pose2(), 0.0, Sick181(), &rng));
    *flagged = *flagged_keyframes = 0;
    const Pose2 odometry_step(0.06, 0.0, 0.0);
    for (int k = 1; k <= 40; ++k) {
      const Pose2 seen(0.2 * 0.06 * k, 0.0, 0.0);  // where the scene says the robot is
      const BaseEstimate& e = estimator.AddScan(
          CastScan(world, seen, 0.2 * k, Sick181(), &rng),
          MotionMeasurement{odometry_step, StepCovariance(odometry_step, noise)});
      *flagged += e.IsFlagged() ? 1 : 0;
      *flagged_keyframes += e.IsFlagged() && e.keyframe_added ? 1 : 0;
    }
  };
  const EstimatorOptions shipped = RecordedLogOptions();
  ASSERT_GT(shipped.window_gate_probability, 0.0);
  int flagged = 0, flagged_keyframes = 0;
  run(shipped, &flagged, &flagged_keyframes);
  EXPECT_GE(flagged, 10) << "of 40 scans, 2.4 m of odometry against 0.5 m of match";
  EXPECT_EQ(flagged_keyframes, 0);
  EstimatorOptions no_window = shipped;
  no_window.window_gate_probability = 0.0;
  run(no_window, &flagged, &flagged_keyframes);
  EXPECT_EQ(flagged, 0) << "without the window gate every clinging match passes";
}

}  // namespace
}  // namespace ifab::base
