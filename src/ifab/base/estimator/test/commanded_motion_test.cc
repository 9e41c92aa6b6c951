// The commanded track speeds as a motion prior: the integration of the commands, and what the
// prior changes in a featureless corridor with the IF's estimator config.
#include "ifab/base/estimator/commanded_motion.h"

#include <gtest/gtest.h>

#include <cmath>

#include "ifab/base/estimator/base_state_estimator.h"
#include "ifab/base/estimator/test/synthetic_scans.h"
#include "ifab/core/angles.h"
#include "ifab/core/error.h"
#include "ifab/core/random.h"

namespace ifab::base {
namespace {

TEST(TrackCommandHistory, IntegratesHeldCommandsWithSkidSteerKinematics) {
  TrackCommandHistory h(1.0);
  EXPECT_NEAR(h.Step(0.0, 1.0).x, 0.0, 1e-12);  // no command yet: the base stands
  h.Add({1.0, 0.2, 0.2});                        // straight at 0.2 m/s from t = 1
  h.Add({3.0, -0.1, 0.1});                       // turning on the spot at 0.2 rad/s from t = 3
  const Pose2 straight = h.Step(0.5, 2.0);
  EXPECT_NEAR(straight.x, 0.2, 1e-12);
  EXPECT_NEAR(straight.y, 0.0, 1e-12);
  const Pose2 turn = h.Step(3.0, 4.0);
  EXPECT_NEAR(turn.theta, 0.2, 1e-12);
  EXPECT_NEAR(std::hypot(turn.x, turn.y), 0.0, 1e-12);
  // Across the change: 0.2 m straight, then the turn.
  const Pose2 both = h.Step(2.0, 3.5);
  EXPECT_NEAR(both.x, 0.2, 1e-12);
  EXPECT_NEAR(both.theta, 0.1, 1e-12);
}

TEST(TrackCommandHistory, AnArcEndsOnTheCircle) {
  TrackCommandHistory h(1.0);
  h.Add({0.0, 0.15, 0.25});  // v = 0.2 m/s, omega = 0.1 rad/s: radius 2 m
  Pose2 chained;
  for (int k = 0; k < 100; ++k) chained = chained * h.Step(0.1 * k, 0.1 * (k + 1));
  const Pose2 once = h.Step(0.0, 10.0);
  EXPECT_NEAR(once.theta, 1.0, 1e-12);
  EXPECT_NEAR(once.x, 2.0 * std::sin(1.0), 1e-12);
  EXPECT_NEAR(once.y, 2.0 * (1.0 - std::cos(1.0)), 1e-12);
  EXPECT_NEAR(TranslationDistance(once, chained), 0.0, 1e-9);
}

TEST(TrackCommandHistory, DropKeepsTheCommandInForceAndRejectsOlderCommands) {
  TrackCommandHistory h(1.0);
  h.Add({0.0, 0.1, 0.1});
  h.Add({1.0, 0.2, 0.2});
  h.Add({2.0, 0.3, 0.3});
  h.DropBefore(1.5);
  EXPECT_EQ(h.size(), 2u);
  EXPECT_NEAR(h.Step(1.5, 2.5).x, 0.5 * 0.2 + 0.5 * 0.3, 1e-12);
  EXPECT_THROW(h.Add({1.0, 0.0, 0.0}), InputError);
}

TEST(CommandedSpeedOptions, ReadsYamlOnTopOfTheSlipDefaults) {
  const auto node = ConfigNode::FromString("use: true\nnoise: {translation_per_m: 0.2}\n");
  const CommandedSpeedOptions o = CommandedSpeedOptions::FromConfig(node);
  EXPECT_TRUE(o.use);
  EXPECT_DOUBLE_EQ(o.noise.translation_per_m, 0.2);
  EXPECT_DOUBLE_EQ(o.noise.rotation_per_rad, CommandedSpeedNoise().rotation_per_rad);
  EXPECT_THROW(CommandedSpeedOptions::FromConfig(ConfigNode::FromString("usee: true\n")), InputError);
  // The IF's config ships with the paper's gyro-only eq. 2.
  const auto shipped = EstimatorOptions::FromConfig(
      ConfigNode::LoadSection(IFAB_DATA_DIR "/estimator/insitu_fabricator.yaml", "estimator"));
  EXPECT_FALSE(shipped.commanded_speeds.use);
}

// The IF drives 2 m along a long featureless corridor (two parallel walls) on the IF's estimator
// config. The commands are what a controller sends; the true base follows them with a hydraulic
// lag and the tracks' slip (speed factor 0.92, inside the published 0.90-0.95), so the commanded
// motion overstates the travel by ~8 %. Gyro only, nothing observes the corridor's axis: the
// kernel sum over the noisy (18 mm) reference polylines has a slope along the walls, the
// constant-velocity prediction feeds it back, and the estimate slides (metres, status ok: the
// scan's Hessian claims information along the axis). With the commanded speeds it follows them.
struct CorridorRun {
  double along_error{0.0};     // estimated minus true travel along the axis [m]
  double across_error{0.0};    // [m]
  double true_travel{0.0};     // [m]
  double prior_fraction{0.0};  // of the scans while moving, with the prior in eq. 3
};

CorridorRun DriveTheCorridor(bool use_commands, std::uint64_t seed) {
  EstimatorOptions o = EstimatorOptions::FromConfig(
      ConfigNode::LoadSection(IFAB_DATA_DIR "/estimator/insitu_fabricator.yaml", "estimator"));
  const Pose2 T_base_laser(0.6, 0.0, 0.0);
  BaseStateEstimator estimator(o, T_base_laser);
  const testing::World world = testing::Corridor(2.0, 400.0);  // a 4 m wide hall, 400 m long
  RandomStream rng(seed);
  TrackCommandHistory commands(1.0);
  const double dt_sim = 0.0025, lag_tau = 0.3, speed_factor = 0.92;  // 400 Hz gyro, scans at 40 Hz
  Pose2 truth(0.0, 0.1, 0.0);
  estimator.Reset(truth, 0.0);
  double v_true = 0.0, t = 0.0, t_prev_scan = 0.0;
  int moving = 0, prior_used = 0;
  testing::ScanSpec spec;
  spec.sigma = 0.018;  // the UTM-30LX along the ray
  for (int k = 1; t < 13.0; ++k) {
    t = k * dt_sim;
    // The controller: stand for 0.5 s, 0.2 m/s for 10 s, stop.
    const double v_cmd = (t > 0.5 && t < 10.5) ? 0.2 : 0.0;
    if (k % 10 == 1) commands.Add({t, v_cmd, v_cmd});  // sent at 40 Hz
    v_true += (speed_factor * v_cmd - v_true) * dt_sim / lag_tau;
    truth = truth * Pose2(v_true * dt_sim, 0.0, 0.0);
    estimator.AddGyro(testing::Gyro(t, rng.Normal(0.0002)));
    if (k % 10 == 0) {
      const LaserScan scan = testing::CastScan(world, truth * T_base_laser, t, spec, &rng);
      const BaseEstimate& e = use_commands
                                  ? estimator.AddScan(scan, commands.Measure(t_prev_scan, t, o.commanded_speeds.noise))
                                  : estimator.AddScan(scan);
      t_prev_scan = t;
      if (v_true > 0.05) {
        ++moving;
        prior_used += e.prior_used ? 1 : 0;
      }
    }
  }
  CorridorRun r;
  r.true_travel = truth.x;
  r.along_error = estimator.Latest().T_world_base.x - truth.x;
  r.across_error = estimator.Latest().T_world_base.y - truth.y;
  r.prior_fraction = moving > 0 ? static_cast<double>(prior_used) / moving : 0.0;
  return r;
}

TEST(CommandedSpeedPrior, KeepsTheCorridorAxisBoundedWhereGyroOnlySlides) {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const CorridorRun gyro = DriveTheCorridor(false, seed);
    const CorridorRun commanded = DriveTheCorridor(true, seed);
    ASSERT_GT(gyro.true_travel, 1.5);
    // Gyro only: the axis is unobserved and the estimate falls behind by most of the travel.
    EXPECT_GT(std::abs(gyro.along_error), 0.5 * gyro.true_travel) << "seed " << seed;
    // Commanded speeds: off by about the slip the commands do not know (8 % here), bounded by
    // the published 10 % plus the lag.
    EXPECT_LT(std::abs(commanded.along_error), 0.12 * commanded.true_travel) << "seed " << seed;
    EXPECT_LT(std::abs(commanded.across_error), 0.02) << "seed " << seed;
    EXPECT_EQ(commanded.prior_fraction, 1.0) << "seed " << seed;
    EXPECT_EQ(gyro.prior_fraction, 0.0) << "seed " << seed;
  }
}

}  // namespace
}  // namespace ifab::base
