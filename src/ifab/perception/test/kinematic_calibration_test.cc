#include "ifab/perception/kinematic_calibration.h"

#include <gtest/gtest.h>

#include "ifab/core/random.h"
#include "ifab/perception/testing/synthetic.h"

namespace ifab {
namespace {

constexpr double kDeg = M_PI / 180.0;

Vector6d RandomPosture(RandomStream& rng) {
  Vector6d q;
  q << rng.Uniform(-0.6, 0.6), rng.Uniform(0.0, 0.6), rng.Uniform(-0.2, 0.5), rng.Uniform(-0.6, 0.6),
      rng.Uniform(0.5, 1.5), rng.Uniform(-1.5, 1.5);
  return q;
}

// A point 1.5 m in front of the laser, as the chain and mount put it.
Eigen::Vector3d Target(const Pose3& T_laser) { return T_laser * Eigen::Vector3d(1.5, 0.0, 0.0); }

struct Outcome {
  double design_rms_mm, fitted_rms_mm;
};

// One arm drawn with errors of an uncalibrated arm; views at random postures see the true laser
// through the design chain (each view's mount, with noise of its covariance); the fit is then
// checked at postures it never saw.
Outcome RunOnce(std::uint64_t seed) {
  const RobotModel robot = testing::DesignRobot();
  RandomStream rng(seed);
  std::vector<Pose3> truth;
  for (unsigned i = 0; i < robot.arm_chain.getNrOfSegments(); ++i)
    truth.push_back(PoseFromXyzRpy(rng.Normal(0.0005), rng.Normal(0.0005), rng.Normal(0.0005), rng.Normal(0.01 * kDeg),
                                   rng.Normal(0.01 * kDeg), rng.Normal(0.01 * kDeg)));
  const Pose3 M_true = robot.T_tool0_arm_laser * PoseFromXyzRpy(0.003, -0.002, 0.004, 0.5 * kDeg, 0.2 * kDeg, -0.3 * kDeg);
  const double sigma_t = 0.00005, sigma_r = 0.002 * kDeg;  // a view's mount: 0.05 mm, 0.002 deg
  Matrix6d cov = Matrix6d::Zero();
  cov.diagonal() << Eigen::Vector3d::Constant(sigma_t * sigma_t), Eigen::Vector3d::Constant(sigma_r * sigma_r);
  std::vector<FlangeObservation> views;
  for (int v = 0; v < 10; ++v) {
    FlangeObservation o;
    o.q = RandomPosture(rng);
    const Pose3 eff = ChainForwardKinematics(robot.arm_chain, o.q).inverse() *
                      ChainForwardKinematics(robot.arm_chain, o.q, truth) * M_true;
    Pose3 noisy = eff;
    noisy.translation() += Eigen::Vector3d(rng.Normal(sigma_t), rng.Normal(sigma_t), rng.Normal(sigma_t));
    noisy.linear() = ExpSO3(Eigen::Vector3d(rng.Normal(sigma_r), rng.Normal(sigma_r), rng.Normal(sigma_r))) * eff.linear();
    o.T_tool0_laser = noisy;
    o.covariance = cov;
    views.push_back(o);
  }
  KinematicCalibrationOptions links;
  links.model = KinematicModel::kLinks;
  const KinematicCalibration k = CalibrateArmKinematics(robot.arm_chain, views, robot.T_tool0_arm_laser, links);
  EXPECT_TRUE(k.usable) << k.BriefReport();
  // The design chain's best: the fit's own first stage (one mount, the targets' frame).
  KinematicCalibrationOptions no_links = links;
  no_links.link_translation_sigma = 1e-12;
  no_links.link_rotation_sigma = 1e-12;
  const KinematicCalibration d = CalibrateArmKinematics(robot.arm_chain, views, robot.T_tool0_arm_laser, no_links);
  double e_fit = 0.0, e_design = 0.0;
  const int n = 30;
  for (int i = 0; i < n; ++i) {
    const Vector6d q = RandomPosture(rng);
    const Eigen::Vector3d truth_point = Target(ChainForwardKinematics(robot.arm_chain, q, truth) * M_true);
    e_fit += (Target(k.T_targets_correction * ChainForwardKinematics(robot.arm_chain, q, k.link_errors) * k.T_tool0_laser) -
              truth_point).squaredNorm();
    e_design += (Target(d.T_targets_correction * ChainForwardKinematics(robot.arm_chain, q) * d.T_tool0_laser) -
                 truth_point).squaredNorm();
  }
  std::printf("%s\n", k.BriefReport().c_str());
  return {1e3 * std::sqrt(e_design / n), 1e3 * std::sqrt(e_fit / n)};
}

TEST(KinematicCalibrationTest, ChainErrorsFromViewsCorrectPosturesNotSeen) {
  double design = 0.0, fitted = 0.0;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const Outcome o = RunOnce(seed);
    std::printf("seed %d: rms error 1.5 m in front of the laser at unseen postures: design %.2f mm, fitted %.2f mm\n",
                static_cast<int>(seed), o.design_rms_mm, o.fitted_rms_mm);
    design += o.design_rms_mm;
    fitted += o.fitted_rms_mm;
  }
  EXPECT_LT(fitted, 0.5 * design);
}

// Joint zero offsets (0.02 deg each) seen from five views: the fitted joints 2-5 put the laser
// where the arm does at postures the views never saw.
TEST(KinematicCalibrationTest, JointOffsetsFromFiveViewsCorrectPosturesNotSeen) {
  const RobotModel robot = testing::DesignRobot();
  double design = 0.0, fitted = 0.0;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    RandomStream rng(100 + seed);
    Vector6d offsets;
    for (int i = 0; i < 6; ++i) offsets[i] = rng.Normal(0.02 * kDeg);
    const Pose3 M_true = robot.T_tool0_arm_laser * PoseFromXyzRpy(0.002, 0.001, -0.003, 0.3 * kDeg, 0.0, 0.2 * kDeg);
    const double sigma_t = 0.00005, sigma_r = 0.002 * kDeg;
    std::vector<FlangeObservation> views;
    for (int v = 0; v < 5; ++v) {
      FlangeObservation o;
      o.q = RandomPosture(rng);
      const Pose3 eff = ChainForwardKinematics(robot.arm_chain, o.q).inverse() *
                        ChainForwardKinematics(robot.arm_chain, o.q + offsets) * M_true;
      o.T_tool0_laser = eff;
      o.T_tool0_laser.translation() += Eigen::Vector3d(rng.Normal(sigma_t), rng.Normal(sigma_t), rng.Normal(sigma_t));
      o.covariance = Matrix6d::Zero();
      o.covariance.diagonal() << Eigen::Vector3d::Constant(sigma_t * sigma_t), Eigen::Vector3d::Constant(sigma_r * sigma_r);
      views.push_back(o);
    }
    const KinematicCalibration k = CalibrateArmKinematics(robot.arm_chain, views, robot.T_tool0_arm_laser);
    ASSERT_TRUE(k.usable) << k.BriefReport();
    ASSERT_EQ(k.joint_offsets.size(), 4u);
    KinematicCalibrationOptions none;
    none.joint_offset_sigma = 1e-12;
    const KinematicCalibration d = CalibrateArmKinematics(robot.arm_chain, views, robot.T_tool0_arm_laser, none);
    double e_fit = 0.0, e_design = 0.0;
    for (int i = 0; i < 30; ++i) {
      const Vector6d q = RandomPosture(rng);
      const Eigen::Vector3d truth = Target(ChainForwardKinematics(robot.arm_chain, q + offsets) * M_true);
      e_fit += (Target(k.T_targets_correction * ChainForwardKinematics(robot.arm_chain, q, k.link_errors) *
                       k.T_tool0_laser) - truth).squaredNorm();
      e_design += (Target(d.T_targets_correction * ChainForwardKinematics(robot.arm_chain, q) * d.T_tool0_laser) -
                   truth).squaredNorm();
    }
    std::printf("seed %d: unseen postures, rms 1.5 m in front of the laser: design %.2f mm, fitted %.2f mm; %s\n",
                static_cast<int>(seed), 1e3 * std::sqrt(e_design / 30), 1e3 * std::sqrt(e_fit / 30),
                k.BriefReport().c_str());
    design += std::sqrt(e_design / 30);
    fitted += std::sqrt(e_fit / 30);
  }
  EXPECT_LT(fitted, 0.5 * design);
}

TEST(KinematicCalibrationTest, ExactChainFitsWithoutErrors) {
  const RobotModel robot = testing::DesignRobot();
  RandomStream rng(9);
  std::vector<FlangeObservation> views;
  for (int v = 0; v < 8; ++v) {
    FlangeObservation o;
    o.q = RandomPosture(rng);
    o.T_tool0_laser = robot.T_tool0_arm_laser;
    o.covariance = 1e-8 * Matrix6d::Identity();
    views.push_back(o);
  }
  const KinematicCalibration k = CalibrateArmKinematics(robot.arm_chain, views, robot.T_tool0_arm_laser);
  ASSERT_TRUE(k.usable);
  EXPECT_LT(k.rms_design, 1e-3);
  for (const auto& e : k.link_errors) EXPECT_LT(e.translation().norm(), 1e-6);
  EXPECT_LT(TranslationDistance(k.T_tool0_laser, robot.T_tool0_arm_laser), 1e-6);
}

}  // namespace
}  // namespace ifab
