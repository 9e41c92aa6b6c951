// Tilt compensation (issue 12): the IMU's accelerometers measure the base's tilt change between
// the scan and the placement, and the compensated pose removes it.
#include "ifab/sequencer/tilt.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "ifab/core/angles.h"
#include "ifab/core/random.h"

namespace ifab::sequencer {
namespace {

constexpr double kG = 9.80665;

// One accelerometer sample of a base at rest with attitude R_site_base: white noise at the
// MTi-G-700's 80 ug/sqrt(Hz) (400 Hz) and a constant bias, as the simulator makes them.
AccelSample Sample(const Eigen::Matrix3d& R_site_base, const Eigen::Vector3d& bias, Seconds t, RandomStream& rng) {
  const double sigma = kG * 80e-6 * std::sqrt(400.0);
  AccelSample s;
  s.stamp.t = t;
  // Draws named, last coordinate first: gcc's order of a call's arguments (C++ leaves it open).
  const double nz = rng.Normal(sigma), ny = rng.Normal(sigma), nx = rng.Normal(sigma);
  s.specific_force = R_site_base.transpose() * Eigen::Vector3d(0, 0, kG) + bias + Eigen::Vector3d(nx, ny, nz);
  return s;
}

// The mission's 2 s window of samples.
std::vector<AccelSample> Samples(const Eigen::Matrix3d& R_site_base, const Eigen::Vector3d& bias, Seconds t0,
                                 RandomStream& rng) {
  std::vector<AccelSample> out;
  for (int i = 0; i < 800; ++i) out.push_back(Sample(R_site_base, bias, t0 + i / 400.0, rng));
  return out;
}

TEST(Tilt, CompensationRemovesACommandedTiltChange) {
  RandomStream rng(12);
  double worst_compensated = 0.0, worst_raw = 0.0, sum_compensated = 0.0;
  for (int trial = 0; trial < 50; ++trial) {
    // The base at the scan: on an uneven floor (a few tenths of a degree), anywhere, any heading.
    // (Draws named, last argument first, as in Samples.)
    const double yaw = rng.Uniform(-kPi, kPi), pitch = DegToRad(rng.Normal(0.2)), roll = DegToRad(rng.Normal(0.2));
    const double z = rng.Normal(0.003), y = rng.Uniform(-2, 2), x = rng.Uniform(-2, 2);
    const Pose3 T_ref = PoseFromXyzRpy(x, y, z, roll, pitch, yaw);
    // The commanded tilt change (the arm reaching out with a brick): up to 0.3 deg about a
    // horizontal axis of the base, turning about the base's origin.
    const double a = rng.Uniform(0, 2 * kPi);
    const Eigen::Matrix3d R_change =
        Eigen::AngleAxisd(DegToRad(rng.Uniform(0.05, 0.3)), Eigen::Vector3d(std::cos(a), std::sin(a), 0)).toRotationMatrix();
    Pose3 T_now = T_ref;
    T_now.linear() = T_ref.linear() * R_change;
    const double bz = rng.Normal(0.5), by = rng.Normal(0.5), bx = rng.Normal(0.5);
    const Eigen::Vector3d bias = 9.80665e-3 * Eigen::Vector3d(bx, by, bz);
    const auto before = Samples(T_ref.linear(), bias, 0.0, rng);
    const auto after = Samples(T_now.linear(), bias, 10.0, rng);
    const auto up_ref = MeanUp(before, 0.0, 2.0);
    const auto up_now = MeanUp(after, 10.0, 12.0);
    ASSERT_TRUE(up_ref && up_now);
    const Pose3 T_comp = CompensateTilt(T_ref, *up_ref, *up_now);
    // Where a brick goal 1.9 m out and 1.3 m up (the top of the stack) lands in the base frame.
    const Eigen::Vector3d p_site = T_now * Eigen::Vector3d(1.9, 0.3, 1.3);
    const double e_comp = (T_comp.inverse() * p_site - T_now.inverse() * p_site).norm();
    const double e_raw = (T_ref.inverse() * p_site - T_now.inverse() * p_site).norm();
    worst_compensated = std::max(worst_compensated, e_comp);
    worst_raw = std::max(worst_raw, e_raw);
    sum_compensated += e_comp;
    EXPECT_LT(RadToDeg(TiltAngle(*up_ref, *up_now)), 0.32);
  }
  // Uncompensated, the change moves the goal by millimetres; compensated, by about a tenth: the
  // accelerometer noise averaged over 2 s (80 ug/sqrt(Hz): 6e-5 rad a window), the bias cancelled.
  EXPECT_GT(worst_raw, 4e-3);
  EXPECT_LT(sum_compensated / 50, 0.25e-3);
  EXPECT_LT(worst_compensated, 0.6e-3);
}

TEST(Tilt, LevelledPoseTakesRollAndPitchFromGravityAndKeepsThePlanarPose) {
  RandomStream rng(21);
  double worst_deg = 0.0;
  for (int trial = 0; trial < 50; ++trial) {
    const Pose3 T_true = PoseFromXyzRpy(rng.Uniform(-2, 2), rng.Uniform(-2, 2), rng.Normal(0.003),
                                        DegToRad(rng.Normal(0.3)), DegToRad(rng.Normal(0.3)), rng.Uniform(-kPi, kPi));
    const Eigen::Vector3d bias = 9.80665e-3 * Eigen::Vector3d(rng.Normal(0.5), rng.Normal(0.5), rng.Normal(0.5));
    const auto up = MeanUp(Samples(T_true.linear(), bias, 0.0, rng), 0.0, 2.0);
    ASSERT_TRUE(up);
    // The planar estimate: x, y, heading right, roll and pitch unknown (zero).
    const auto v = XyzRpyFromPose(T_true);
    const Pose3 planar = PoseFromXyzRpy(v[0], v[1], v[2], 0.0, 0.0, v[5]);
    const Pose3 levelled = LevelledPose(planar, *up);
    EXPECT_LT((levelled.translation() - T_true.translation()).norm(), 1e-12);
    // The base's vertical axis as the truth has it, to within the accelerometer's bias.
    const double tilt_error = TiltAngle(levelled.linear().col(2), T_true.linear().col(2));
    worst_deg = std::max(worst_deg, RadToDeg(tilt_error));
    // The heading is the planar one (up to the tilt's second-order effect).
    EXPECT_NEAR(XyzRpyFromPose(levelled)[5], v[5], DegToRad(0.01));
  }
  EXPECT_LT(worst_deg, 0.12);  // 0.5 mg per axis: 0.03 deg a typical draw
}

TEST(Tilt, HeldTiltCovarianceCarriesTheImuVariance) {
  Eigen::Matrix<double, 6, 6> cov = Eigen::Matrix<double, 6, 6>::Identity() * 1e-8;
  cov(3, 3) = cov(4, 4) = 0.0;  // held: the registration reports nothing there
  const Pose3 T_base_site = PoseFromXyzRpy(1.9, 0.3, -0.05, 0, 0, 0.4);
  const auto out = WithHeldTiltCovariance(T_base_site, cov, DegToRad(0.05));
  // The base's roll and pitch in the site carry the IMU's variance (rotated), its yaw the registration's.
  EXPECT_NEAR(out(3, 3) + out(4, 4), 2 * std::pow(DegToRad(0.05), 2), 1e-12);
  EXPECT_NEAR(out(5, 5), 1e-8, 1e-12);
  // The tilt about the site origin, 1.9 m away, moves the base's origin: its height varies.
  EXPECT_GT(out(2, 2), 1e-8 + 0.5 * std::pow(1.9 * DegToRad(0.05), 2));
}

TEST(Tilt, NoSamplesNoTilt) {
  std::vector<AccelSample> none;
  EXPECT_FALSE(MeanUp(none, 0.0, 1.0).has_value());
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  EXPECT_TRUE(TiltChange(up, up).isIdentity(1e-12));
}

// A sweep during which the arm's weight rocks the base by 0.05 deg: levelled scan by scan from
// the accelerometer, every flange pose lands where the base standing level would put it.
TEST(Tilt, LevelSweepPointsTakesOutTheTiltOfEachScan) {
  RandomStream rng(5);
  const Seconds duration = 6.0;
  auto roll_at = [&](Seconds t) { return DegToRad(0.1 + 0.05 * t / duration); };
  auto pitch_at = [&](Seconds t) { return DegToRad(-0.03 * t / duration); };
  auto R_at = [&](Seconds t) -> Eigen::Matrix3d {
    return PoseFromXyzRpy(0, 0, 0, roll_at(t), pitch_at(t), 0.0).linear();  // a copy, not a view of the temporary
  };
  std::vector<AccelSample> accel;
  for (int k = 0; k < 6 * 400 + 400; ++k) {
    const Seconds t = -0.5 + k / 400.0;
    accel.push_back(Sample(R_at(t), Eigen::Vector3d::Zero(), t, rng));
  }
  std::vector<SweepPoint> points, level;
  for (int scan = 0; scan < 240; ++scan) {
    const Seconds t = scan * duration / 240;
    SweepPoint p;
    p.scan = scan;
    p.t = t;
    // The flange 2 m out and 1.5 m up, in the base as it stands (tilted).
    p.T_base_tool0 = PoseFromXyzRpy(2.0, 0.3 * std::sin(t), 1.5, 0.2, 1.2, 0.1 * t);
    points.push_back(p);
    SweepPoint l = p;
    l.T_base_tool0 = Pose3(R_at(t)) * p.T_base_tool0;  // the level base sees the tilted one turned
    level.push_back(l);
  }
  std::vector<SweepPoint> levelled = points;
  ASSERT_TRUE(LevelSweepPoints(levelled, accel));
  double worst_raw = 0.0, worst = 0.0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    worst_raw = std::max(worst_raw, TranslationDistance(points[i].T_base_tool0, level[i].T_base_tool0));
    worst = std::max(worst, TranslationDistance(levelled[i].T_base_tool0, level[i].T_base_tool0));
  }
  std::printf("flange 2.5 m from the base origin: worst error %.3f mm as tilted, %.3f mm levelled\n", 1e3 * worst_raw,
              1e3 * worst);
  EXPECT_GT(worst_raw, 0.004);
  EXPECT_LT(worst, 0.25 * worst_raw);  // what is left: the accelerometer noise over the window
  // No accelerometer: nothing to level with, the points stay.
  std::vector<SweepPoint> untouched = points;
  EXPECT_FALSE(LevelSweepPoints(untouched, {}));
  EXPECT_TRUE(untouched[7].T_base_tool0.isApprox(points[7].T_base_tool0));
}

}  // namespace
}  // namespace ifab::sequencer
