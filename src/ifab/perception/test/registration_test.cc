#include "ifab/perception/registration.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>

#include "ifab/core/random.h"
#include "ifab/core/testing/numeric_jacobian.h"
#include "ifab/core/testing/sanitized.h"
#include "ifab/perception/testing/synthetic.h"

namespace ifab {
namespace {

// The paper's Table I scene: a brick on the ground.
const Box kBrick{Eigen::Vector3d(0.240, 0.115, 0.052)};

std::vector<RegistrationBody> BrickOnGround(const Pose3& T_base_brick, const Pose3& T_base_ground = Pose3::Identity()) {
  RigidObject ground{"ground", Pose3::Identity(), {Plane{Eigen::Vector3d::UnitZ(), 0.0}}};
  RigidObject brick{"brick", Pose3::Identity(), {kBrick}};
  return {{"ground", T_base_ground, {ground}, true}, {"brick", T_base_brick, {brick}, true}};
}

// A laser 0.9 m above the ground whose vertical scan plane yaws across the scene (like a sweep of
// the arm's first joint).
std::function<Pose3(double)> YawSweep(double yaw0, double yaw_rate, Eigen::Vector3d origin = {0.3, 0.0, 0.9}) {
  return [=](double t) {
    Pose3 T = Pose3::Identity();
    T.translation() = origin;
    T.linear() = RotationFromRpy(M_PI / 2, 0.0, yaw0 + yaw_rate * t);
    return T;
  };
}

struct PoseError {
  double translation;
  double rotation;
};
PoseError Error(const Pose3& a, const Pose3& b) { return {TranslationDistance(a, b), RotationAngle(a, b)}; }

const Pose3 kTrueBrick = PoseFromXyzRpy(1.2, 0.1, 0.026, 0.0, 0.0, 0.3);
const Pose3 kGuessBrick = PoseFromXyzRpy(1.215, 0.09, 0.031, 0.02, -0.02, 0.35);

std::vector<RayPoint> BrickCloud(std::uint64_t seed, bool mixed = false, std::vector<char>* mixed_flags = nullptr) {
  const Scene world(BrickOnGround(kTrueBrick));
  testing::SyntheticLaser laser;
  laser.mixed_pixels = mixed;
  RandomStream rng(seed);
  return testing::SynthesizeCloud(world, YawSweep(-0.2, 0.25), 0.0, 2.0, laser, rng, mixed_flags);
}

class RegistrationResiduals : public ::testing::TestWithParam<RegistrationResidual> {};

TEST_P(RegistrationResiduals, RecoversAKnownBrickPoseFromASimulatedCloud) {
  if (GetParam() == RegistrationResidual::kClosest)
    IFAB_SKIP_WHEN_SANITIZED("Registration.RemovesShadowPointsAtTheEdgesOfABlockOnTheGround (eq. 7's closest-point registration) and ClosestPoint.*");
  const auto cloud = BrickCloud(1);
  RegistrationOptions options;
  options.residual = GetParam();
  const RegistrationSummary s = Register(cloud, BrickOnGround(kGuessBrick), options);
  ASSERT_TRUE(s.IsUsable()) << s.BriefReport();
  const RegisteredBody* brick = s.Find("brick");
  ASSERT_NE(brick, nullptr);
  const PoseError e = Error(brick->T_base_body, kTrueBrick);
  if (GetParam() == RegistrationResidual::kRay) {
    // ~800 points on the brick with 18 mm range noise: the std is about 0.5-1 mm and 0.4-1 deg.
    EXPECT_EQ(s.status, RegistrationStatus::kConverged) << s.BriefReport();
    EXPECT_LT(e.translation, 0.0025) << s.BriefReport();
    EXPECT_LT(e.rotation, 1.5 * kDeg) << s.BriefReport();
    EXPECT_NEAR(s.rms_whitened, 1.0, 0.15);  // the noise model fits (Cauchy weights shave the tails)
  } else {
    // Eq. 7 as written: the closest point under 18 mm along-ray noise is biased by several mm
    // (points pushed past a face's border or into the box snap to the wrong face).
    EXPECT_LT(e.translation, 0.015) << s.BriefReport();
    EXPECT_LT(e.rotation, 5.0 * kDeg) << s.BriefReport();
  }
  EXPECT_GT(brick->inliers, 500);
  // The ground fixes only its height, roll and pitch.
  EXPECT_EQ(s.Find("ground")->unconstrained.size(), 3u);
  EXPECT_TRUE(brick->unconstrained.empty());
}

INSTANTIATE_TEST_SUITE_P(Both, RegistrationResiduals,
                         ::testing::Values(RegistrationResidual::kClosest, RegistrationResidual::kRay),
                         [](const auto& p) { return p.param == RegistrationResidual::kClosest ? "closest" : "ray"; });

// Coarse steps on every n-th point first, then all points: the same minimum.
TEST(Registration, CoarseStepsEndAtTheSameMinimum) {
  const auto cloud = BrickCloud(1);
  RegistrationOptions options;
  const RegistrationSummary fine = Register(cloud, BrickOnGround(kGuessBrick), options);
  options.coarse_stride = 8;
  const RegistrationSummary coarse = Register(cloud, BrickOnGround(kGuessBrick), options);
  ASSERT_EQ(fine.status, RegistrationStatus::kConverged) << fine.BriefReport() << "\n" << coarse.BriefReport();
  ASSERT_EQ(coarse.status, RegistrationStatus::kConverged) << coarse.BriefReport();
  const PoseError e = Error(coarse.Find("brick")->T_base_body, fine.Find("brick")->T_base_body);
  EXPECT_LT(e.translation, 2e-5);
  EXPECT_LT(e.rotation, 1e-4);
  EXPECT_NEAR(coarse.num_inliers, fine.num_inliers, 20);  // a few edge points may flip
}

// The normal-equation LM and the Ceres problem solve the same steps: same poses, covariances
// (a-posteriori variance factor included) and cost, also with components held (SubsetManifold in
// Ceres) and the noise scale estimated from the residuals. Each case would fail if the held
// components moved, or if the variance factor or the held rows were left out of one path.
TEST(Registration, NormalEquationsAndCeresGiveTheSameResult) {
  const auto cloud = BrickCloud(2, /*mixed=*/true);
  // (free, the model's noise) and (components held, the noise scale estimated and gated)
  for (const bool hold : {false, true}) {
    {
      const NoiseSource source = hold ? NoiseSource::kEstimated : NoiseSource::kModel;
      auto bodies = BrickOnGround(kGuessBrick);
      if (hold) {  // the ground's height, roll and pitch held; the brick's z held
        bodies[0].fixed = {false, false, true, true, true, false};
        bodies[1].fixed[2] = true;
      }
      RegistrationOptions options;
      options.noise_source = source;
      options.gate_sigmas = source == NoiseSource::kEstimated ? 4.0 : 0.0;
      const RegistrationSummary dense = Register(cloud, bodies, options);
      options.solver = LeastSquaresSolver::kCeres;
      const RegistrationSummary ceres = Register(cloud, bodies, options);
      SCOPED_TRACE(::testing::Message() << "hold " << hold << ", estimated " << (source == NoiseSource::kEstimated));
      ASSERT_EQ(dense.status, ceres.status) << dense.BriefReport() << "\n" << ceres.BriefReport();
      EXPECT_EQ(dense.iterations, ceres.iterations);
      EXPECT_EQ(dense.num_inliers, ceres.num_inliers);
      EXPECT_NEAR(dense.cost, ceres.cost, 1e-8 * ceres.cost);
      for (std::size_t k = 0; k < bodies.size(); ++k) {
        const RegisteredBody& a = dense.bodies[k];
        const RegisteredBody& b = ceres.bodies[k];
        const PoseError e = Error(a.T_base_body, b.T_base_body);
        EXPECT_LT(e.translation, 1e-8) << a.name;
        EXPECT_LT(e.rotation, 1e-8) << a.name;
        EXPECT_TRUE(a.covariance.isApprox(b.covariance, 1e-6)) << a.name << "\n" << a.covariance << "\n" << b.covariance;
        EXPECT_EQ(a.unconstrained, b.unconstrained) << a.name;
        if (hold) {  // held components stay at the guess, and carry no variance
          EXPECT_EQ(a.T_base_body.translation().z(), bodies[k].T_base_body.translation().z()) << a.name;
          EXPECT_EQ(a.covariance(2, 2), 0.0) << a.name;
        }
      }
      EXPECT_GT(dense.bodies[1].covariance(0, 0), 0.0);
    }
  }
}

// Issue 14: NaN or infinite points (a broken file or driver) are left out, not summed into the
// cost; before, one NaN point made the whole registration NaN.
TEST(Registration, LeavesOutNonFinitePoints) {
  auto cloud = BrickCloud(1);
  const RegistrationSummary clean = Register(cloud, BrickOnGround(kGuessBrick), {});
  const double nan = std::numeric_limits<double>::quiet_NaN();
  cloud[3].p.x() = nan;
  cloud[10].origin.z() = std::numeric_limits<double>::infinity();
  const RegistrationSummary s = Register(cloud, BrickOnGround(kGuessBrick), {});
  ASSERT_EQ(s.status, RegistrationStatus::kConverged) << s.BriefReport();
  EXPECT_TRUE(s.Find("brick")->T_base_body.matrix().allFinite());
  const PoseError e = Error(s.Find("brick")->T_base_body, clean.Find("brick")->T_base_body);
  EXPECT_LT(e.translation, 1e-4);
  ASSERT_FALSE(s.warnings.empty());
  EXPECT_NE(s.warnings.back().find("2 non-finite points left out"), std::string::npos);
}

// The paper's Fig. 4: a block on the ground seen across its edges returns mixed pixels between
// the block and the floor behind it. The shadow rule removes them.
TEST(Registration, RemovesShadowPointsAtTheEdgesOfABlockOnTheGround) {
  const Pose3 T_true = PoseFromXyzRpy(1.1, 0.05, 0.125, 0.0, 0.0, 0.4);
  RigidObject ground{"ground", Pose3::Identity(), {Plane{Eigen::Vector3d::UnitZ(), 0.0}}};
  RigidObject block{"block", Pose3::Identity(), {Box{Eigen::Vector3d::Constant(0.25)}}};
  std::vector<RegistrationBody> truth{{"ground", Pose3::Identity(), {ground}, true}, {"block", T_true, {block}, true}};
  const Scene world(truth);
  testing::SyntheticLaser laser;
  laser.mixed_pixels = true;
  RandomStream rng(5);
  std::vector<char> mixed;
  const auto cloud = testing::SynthesizeCloud(world, YawSweep(-0.25, 0.3), 0.0, 1.6, laser, rng, &mixed);
  // Mixed pixels far from every surface are the ones that would bias the fit.
  int far_mixed = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i)
    far_mixed += mixed[i] && world.Closest(cloud[i].p).distance > 0.03;
  ASSERT_GT(far_mixed, 30);

  auto guess = truth;
  guess[1].T_base_body = T_true * PoseFromXyzRpy(0.01, -0.01, 0.005, 0.01, 0.0, -0.03);
  for (auto residual : {RegistrationResidual::kClosest, RegistrationResidual::kRay}) {
    RegistrationOptions options;
    options.residual = residual;
    options.loss = RobustLoss::kNone;  // the paper: the shadow rule alone
    const RegistrationSummary with = Register(cloud, guess, options);
    options.shadow_points = false;
    const RegistrationSummary without = Register(cloud, guess, options);
    int removed_far_mixed = 0, removed_good = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      if (with.labels[i] != PointLabel::kShadow && with.labels[i] != PointLabel::kOutlier) continue;
      if (mixed[i] && world.Closest(cloud[i].p).distance > 0.03) ++removed_far_mixed;
      if (!mixed[i] && with.labels[i] == PointLabel::kShadow) ++removed_good;
    }
    const PoseError e_with = Error(with.Find("block")->T_base_body, T_true);
    const PoseError e_without = Error(without.Find("block")->T_base_body, T_true);
    std::printf("%s: %d far mixed pixels, %d removed; %d good points removed of %zu; block error %.2f mm %.3f deg "
                "with the shadow rule, %.2f mm %.3f deg without\n",
                residual == RegistrationResidual::kRay ? "ray" : "closest", far_mixed, removed_far_mixed, removed_good,
                cloud.size(), 1e3 * e_with.translation, e_with.rotation / kDeg, 1e3 * e_without.translation,
                e_without.rotation / kDeg);
    // Most far mixed pixels get zero error (the rest lie near the plane of the face their ray
    // hits, where they do little harm), and few good points are lost. (A beam passing the
    // block's edge to the floor mixes as often as one ending on the block: the ray residual
    // removes 57 % of the far ones here, the closest-point one all.)
    EXPECT_GT(removed_far_mixed, 0.5 * far_mixed);
    EXPECT_LT(removed_good, 0.005 * static_cast<double>(cloud.size()));
    EXPECT_GT(with.num_shadow_removed, 0);
    if (residual == RegistrationResidual::kRay) {
      EXPECT_LT(e_with.translation, 0.002);
    }
    EXPECT_LT(e_with.translation, e_without.translation);
  }
}

// A single plane fixes three of six directions; the summary says which are free.
TEST(Registration, WarnsAboutDirectionsTheScanDoesNotConstrain) {
  RigidObject ground{"ground", Pose3::Identity(), {Plane{Eigen::Vector3d::UnitZ(), 0.0}}};
  const std::vector<RegistrationBody> world_bodies{{"ground", Pose3::Identity(), {ground}, true}};
  const Scene world(world_bodies);
  testing::SyntheticLaser laser;
  RandomStream rng(6);
  const auto cloud = testing::SynthesizeCloud(world, YawSweep(-0.2, 0.4), 0.0, 0.5, laser, rng);
  auto guess = world_bodies;
  guess[0].T_base_body = PoseFromXyzRpy(0.1, -0.2, 0.01, 0.01, -0.01, 0.3);
  const RegistrationSummary s = Register(cloud, guess, {});
  ASSERT_TRUE(s.IsUsable());
  const auto& free_dirs = s.bodies[0].unconstrained;
  EXPECT_EQ(free_dirs, (std::vector<std::string>{"translation along x", "translation along y", "rotation about z"}));
  ASSERT_EQ(s.warnings.size(), 1u);
  EXPECT_NE(s.warnings[0].find("3 direction(s)"), std::string::npos) << s.warnings[0];
  // The constrained directions are recovered: the plane is back at z = 0, level.
  const Eigen::Vector3d n = s.bodies[0].T_base_body.linear() * Eigen::Vector3d::UnitZ();
  EXPECT_NEAR(n.z(), 1.0, 1e-6);
  EXPECT_NEAR(n.dot(s.bodies[0].T_base_body.translation()), 0.0, 2e-4);
  // Free directions keep their guess (the step damping holds them).
  EXPECT_NEAR(s.bodies[0].T_base_body.translation().x(), 0.1, 1e-4);
}

// The UTM-30LX reads strong near-normal returns short (paper Fig. 7). Points within
// min_incidence of their face's normal get no error: the floor is then found where it is.
TEST(Registration, MinIncidenceLeavesOutNearNormalReturns) {
  RigidObject ground{"ground", Pose3::Identity(), {Plane{Eigen::Vector3d::UnitZ(), 0.0}}};
  const std::vector<RegistrationBody> world_bodies{{"ground", Pose3::Identity(), {ground}, true}};
  const Scene world(world_bodies);
  testing::SyntheticLaser laser;
  laser.noisy = false;
  RandomStream rng(7);
  auto cloud = testing::SynthesizeCloud(world, YawSweep(-0.2, 0.4), 0.0, 0.5, laser, rng);
  // A bump like Fig. 7's: beams within 30 deg of the floor's normal read 20 mm short.
  int bumped = 0;
  for (auto& p : cloud) {
    const Eigen::Vector3d u = (p.p - p.origin).normalized();
    if (-u.z() > std::cos(30.0 * kDeg)) {
      p.p -= 0.02 * u;
      ++bumped;
    }
  }
  ASSERT_GT(bumped, 100);
  RegistrationOptions options;
  options.fit_tolerance = 0.0;  // a noise-free cloud agrees with no noise model
  const RegistrationSummary plain = Register(cloud, world_bodies, options);
  options.min_incidence = 40.0 * kDeg;
  const RegistrationSummary guarded = Register(cloud, world_bodies, options);
  ASSERT_TRUE(plain.IsUsable() && guarded.IsUsable());
  EXPECT_GT(plain.bodies[0].T_base_body.translation().z(), 0.002);  // the bump lifts the floor
  EXPECT_NEAR(guarded.bodies[0].T_base_body.translation().z(), 0.0, 1e-6);
  EXPECT_GE(guarded.num_grazing, bumped);
  EXPECT_EQ(plain.num_grazing, 0);
}

TEST(UnconstrainedDirections, NamesAxesOrWritesTheDirection) {
  Matrix6d info = Matrix6d::Identity() * 1e8;
  EXPECT_TRUE(UnconstrainedDirections(info, 0.1, 0.01).empty());
  info(1, 1) = 0.0;
  EXPECT_EQ(UnconstrainedDirections(info, 0.1, 0.01), std::vector<std::string>{"translation along y"});
  // A combination of translation along x and rotation about z is free.
  Eigen::Matrix<double, 6, 1> v;
  v << 1, 0, 0, 0, 0, 10;  // 1 m along x per 0.1 rad about z: a lever of 10 m
  v.normalize();
  info = 1e8 * (Matrix6d::Identity() - v * v.transpose());
  const auto dirs = UnconstrainedDirections(info, 0.1, 0.01);
  ASSERT_EQ(dirs.size(), 1u);
  EXPECT_NE(dirs[0].find("translation ("), std::string::npos) << dirs[0];
}

TEST(InverseCovariance, MatchesFiniteDifferences) {
  const Pose3 T = PoseFromXyzRpy(1.0, -2.0, 0.5, 0.1, -0.2, 0.7);
  // The map from a perturbation [d, w] of T (T' = (Exp(w) R, t + d)) to the perturbation of T^-1.
  auto f = [&](const Eigen::VectorXd& x) -> Eigen::VectorXd {
    Pose3 Tp = Pose3::Identity();
    Tp.linear() = ExpSO3(x.tail<3>()) * T.linear();
    Tp.translation() = T.translation() + x.head<3>();
    const Pose3 inv = T.inverse(), inv_p = Tp.inverse();
    Eigen::VectorXd out(6);
    out.head<3>() = inv_p.translation() - inv.translation();
    out.tail<3>() = LogSO3(inv_p.linear() * inv.linear().transpose());
    return out;
  };
  const Eigen::MatrixXd J = ::ifab::testing::NumericJacobian(f, Eigen::VectorXd::Zero(6));
  Matrix6d C;
  C.setIdentity();
  C(0, 3) = C(3, 0) = 0.3;
  const Matrix6d expected = J * C * J.transpose();
  EXPECT_TRUE(InverseCovariance(T, C).isApprox(expected, 1e-6));
}

}  // namespace
}  // namespace ifab
