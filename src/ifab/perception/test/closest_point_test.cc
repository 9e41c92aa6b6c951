// One conformance suite over every primitive type (STYLE.md): the closest point's derivative and
// the residuals' derivatives with respect to the pose parameters, against finite differences.
#include "ifab/perception/closest_point.h"

#include <gtest/gtest.h>

#include <functional>
#include <string>

#include "ifab/core/random.h"
#include "ifab/core/testing/numeric_jacobian.h"
#include "ifab/perception/laser_model.h"
#include "ifab/perception/residuals.h"

namespace ifab {
namespace {

struct PrimitiveCase {
  std::string name;
  Primitive primitive;
};

std::vector<PrimitiveCase> AllPrimitives() {
  return {
      {"plane", Plane{Eigen::Vector3d(0.2, -0.3, 1.0).normalized(), 0.4}},
      {"triangle", ConvexPolygon({{0, 0, 0}, {0.5, 0, 0}, {0.1, 0.4, 0.05}})},
      {"square", ConvexPolygon({{-0.1, -0.1, 0.2}, {0.1, -0.1, 0.2}, {0.1, 0.1, 0.2}, {-0.1, 0.1, 0.2}})},
      {"box", Box{Eigen::Vector3d(0.24, 0.115, 0.052)}},
  };
}

class PrimitiveConformance : public ::testing::TestWithParam<PrimitiveCase> {};

// Query points around the primitive: the derivative is checked where the closest feature does
// not change within the finite-difference step.
std::vector<Eigen::Vector3d> Queries(RandomStream& rng, int n) {
  std::vector<Eigen::Vector3d> q;
  for (int i = 0; i < n; ++i) {  // z, y, x: gcc's order of a call's arguments (C++ leaves it open)
    const double z = rng.Uniform(-0.3, 0.4), y = rng.Uniform(-0.3, 0.5), x = rng.Uniform(-0.4, 0.6);
    q.emplace_back(x, y, z);
  }
  return q;
}

bool FeatureStable(const Primitive& g, const Eigen::Vector3d& p, double h) {
  const ClosestPoint c = Closest(g, p);
  for (int k = 0; k < 3; ++k) {
    for (double s : {-2 * h, 2 * h}) {
      Eigen::Vector3d q = p;
      q[k] += s;
      const ClosestPoint d = Closest(g, q);
      if (d.feature != c.feature || (d.normal - c.normal).norm() > 1e-9) return false;
    }
  }
  return true;
}

TEST_P(PrimitiveConformance, ClosestPointJacobianMatchesFiniteDifferences) {
  const Primitive& g = GetParam().primitive;
  RandomStream rng(1);
  int checked = 0;
  for (const auto& p : Queries(rng, 200)) {
    if (!FeatureStable(g, p, 1e-6)) continue;
    const ClosestPointJacobian cj = ClosestWithJacobian(g, p);
    EXPECT_NEAR((cj.closest.point - Closest(g, p).point).norm(), 0.0, 1e-12);
    testing::ExpectJacobianMatchesNumeric([&](const Eigen::VectorXd& x) -> Eigen::VectorXd {
      return Closest(g, Eigen::Vector3d(x)).point;
    }, p, cj.d_point_d_query, 1e-6);
    ++checked;
  }
  EXPECT_GT(checked, 150);
}

TEST_P(PrimitiveConformance, ClosestPointIsNoFartherThanSampledPoints) {
  // The closest point is on the primitive and no sampled point of it is closer.
  const Primitive& g = GetParam().primitive;
  RandomStream rng(2);
  for (const auto& p : Queries(rng, 50)) {
    const ClosestPoint c = Closest(g, p);
    EXPECT_NEAR(c.distance, (p - c.point).norm(), 1e-12);
    EXPECT_NEAR(Closest(g, c.point).distance, 0.0, 1e-9);
  }
}

// Residuals of every kind through a body pose, with Jets, against finite differences of the
// double version, and the analytic registration path against both.
TEST_P(PrimitiveConformance, ResidualJacobiansMatchFiniteDifferences) {
  const Primitive& g = GetParam().primitive;
  RandomStream rng(3);
  RigidObject part{"part", PoseFromXyzRpy(0.05, -0.02, 0.01, 0.1, -0.2, 0.3), {g}};
  const Pose3 T_base_body = PoseFromXyzRpy(1.2, 0.3, 0.1, 0.05, 0.02, -0.4);
  Scene scene({{"body", T_base_body, {part}, true}});
  const ScenePrimitive& sp = scene.primitives()[0];
  const LaserNoiseModel noise;
  const Eigen::Matrix3d R0 = T_base_body.linear();
  int checked = 0;
  for (const auto& q : Queries(rng, 100)) {
    const Eigen::Vector3d p_base = T_base_body * sp.T_body_primitive * q;
    const Eigen::Vector3d origin(0.0, 0.0, 1.5);
    RayT<double> ray{origin, (p_base - origin).normalized(), (p_base - origin).norm()};
    // Away from x = [t, 0] too, so Exp(w) is exercised off zero.
    Eigen::VectorXd x(6);
    x << T_base_body.translation(), 0.01, -0.02, 0.015;
    const Vector3T<double> p_body = BaseToBody<double>(x.data(), R0, p_base);
    if (!FeatureStable(g, sp.T_primitive_body * p_body, 1e-5)) continue;
    for (auto kind : {PointMatch::Kind::kClosest, PointMatch::Kind::kRange, PointMatch::Kind::kPlane}) {
      PointMatch m;
      m.kind = kind;
      m.body = 0;
      m.primitive = 0;
      m.sqrt_information = noise.SqrtInformation(ray.direction, ray.range);
      m.normal_body = Eigen::Vector3d(0.3, 0.2, 0.9).normalized();
      m.offset_body = 0.1;
      m.inv_sigma = 50.0;
      auto f = [&](const Eigen::VectorXd& xv) -> Eigen::VectorXd {
        double r[3];
        const int n = PointResidual<double>(m, &sp, ray, xv.data(), R0, r);
        return Eigen::Map<Eigen::VectorXd>(r, n);
      };
      using J = ceres::Jet<double, 6>;
      J xj[6];
      for (int k = 0; k < 6; ++k) xj[k] = J(x[k], k);
      RayT<J> ray_j{ray.origin.cast<J>(), ray.direction.cast<J>(), J(ray.range)};
      J r[3];
      const int n = PointResidual<J>(m, &sp, ray_j, xj, R0, r);
      Eigen::MatrixXd jac(n, 6);
      for (int i = 0; i < n; ++i) jac.row(i) = r[i].v.transpose();
      testing::ExpectJacobianMatchesNumeric(f, x, jac, 1e-5);
      double ra[3], ja[18];
      const int na = PointResidualAnalytic(m, &sp, ray, PoseJacobianData(x.data(), R0), ra, ja);
      ASSERT_EQ(na, n);
      for (int i = 0; i < n; ++i) {
        EXPECT_NEAR(ra[i], r[i].a, 1e-9);
        for (int c = 0; c < 6; ++c) EXPECT_NEAR(ja[i * 6 + c], r[i].v[c], 1e-7 * std::max(1.0, std::abs(r[i].v[c])));
      }
      ++checked;
    }
  }
  EXPECT_GT(checked, 90);
}

// The calibration path: eq. 6 (mount parameters) composed with eq. 7.
TEST_P(PrimitiveConformance, MountJacobianMatchesFiniteDifferences) {
  const Primitive& g = GetParam().primitive;
  RigidObject part{"part", Pose3::Identity(), {g}};
  const Pose3 T_base_body = PoseFromXyzRpy(1.0, 0.0, 0.0, 0.0, 0.0, 0.2);
  Scene scene({{"body", T_base_body, {part}, true}});
  const ScenePrimitive& sp = scene.primitives()[0];
  const Pose3 T_base_tool0 = PoseFromXyzRpy(0.9, 0.1, 1.2, M_PI, 0.1, 0.0);
  const Pose3 T_tool0_laser = PoseFromXyzRpy(0.12, 0.0, 0.06, 0.0, -M_PI / 2, 0.0);
  const Eigen::Matrix3d R0l = T_tool0_laser.linear(), R0b = T_base_body.linear();
  RandomStream rng(4);
  int checked = 0;
  for (int i = 0; i < 60; ++i) {
    const double py = rng.Uniform(-0.4, 0.4), px = rng.Uniform(0.8, 1.4);  // y first, as in Queries
    const Eigen::Vector3d p_laser(px, py, 0.0);
    Eigen::VectorXd x(12);
    x << T_tool0_laser.translation(), 0.01, 0.02, -0.01, T_base_body.translation(), -0.01, 0.0, 0.02;
    const RayT<double> ray0 = LaserRay<double>(PoseT<double>(x.data(), R0l), T_base_tool0, p_laser);
    if (!FeatureStable(g, sp.T_primitive_body * BaseToBody<double>(x.data() + 6, R0b, ray0.Point()), 1e-5)) continue;
    for (auto kind : {PointMatch::Kind::kClosest, PointMatch::Kind::kRange, PointMatch::Kind::kPlane}) {
      PointMatch m;
      m.kind = kind;
      m.body = 0;
      m.primitive = 0;
      m.sqrt_information = LaserNoiseModel().SqrtInformation(Eigen::Vector3d(0, 0, -1), 1.0);
      m.normal_body = Eigen::Vector3d(0.1, -0.2, 0.95).normalized();
      m.offset_body = 0.05;
      m.inv_sigma = 40.0;
      auto f = [&](const Eigen::VectorXd& xv) -> Eigen::VectorXd {
        const RayT<double> ray = LaserRay<double>(PoseT<double>(xv.data(), R0l), T_base_tool0, p_laser);
        double r[3];
        const int n = PointResidual<double>(m, &sp, ray, xv.data() + 6, R0b, r);
        return Eigen::Map<Eigen::VectorXd>(r, n);
      };
      using J = ceres::Jet<double, 12>;
      J xj[12];
      for (int k = 0; k < 12; ++k) xj[k] = J(x[k], k);
      const RayT<J> ray = LaserRay<J>(PoseT<J>(xj, R0l), T_base_tool0, p_laser);
      J r[3];
      const int n = PointResidual<J>(m, &sp, ray, xj + 6, R0b, r);
      Eigen::MatrixXd jac(n, 12);
      for (int k = 0; k < n; ++k) jac.row(k) = r[k].v.transpose();
      testing::ExpectJacobianMatchesNumeric(f, x, jac, 1e-5);
      // The analytic calibration path agrees with autodiff.
      const LaserRayJacobian lr = LaserRayWithJacobian(PoseJacobianData(x.data(), R0l), T_base_tool0, p_laser);
      RayJacobian rj;
      double ra[3], jb[18];
      const int na = PointResidualAnalytic(m, &sp, lr.ray, PoseJacobianData(x.data() + 6, R0b), ra, jb, &rj);
      ASSERT_EQ(na, n);
      using Row3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
      const Eigen::MatrixXd jl = Eigen::Map<const Row3>(rj.d_origin, n, 3) * lr.d_origin +
                                 Eigen::Map<const Row3>(rj.d_direction, n, 3) * lr.d_direction;
      for (int k = 0; k < n; ++k) {
        EXPECT_NEAR(ra[k], r[k].a, 1e-9);
        for (int c = 0; c < 6; ++c) {
          EXPECT_NEAR(jl(k, c), r[k].v[c], 1e-7 * std::max(1.0, std::abs(r[k].v[c])));
          EXPECT_NEAR(jb[k * 6 + c], r[k].v[6 + c], 1e-7 * std::max(1.0, std::abs(r[k].v[6 + c])));
        }
      }
      ++checked;
    }
  }
  EXPECT_GT(checked, 90);
}

INSTANTIATE_TEST_SUITE_P(EveryPrimitive, PrimitiveConformance, ::testing::ValuesIn(AllPrimitives()),
                         [](const auto& p) { return p.param.name; });

TEST(LaserNoiseModel, SqrtInformationWhitensTheRotatedCovariance) {
  const LaserNoiseModel noise;
  const Eigen::Vector3d u = Eigen::Vector3d(0.3, -0.5, -0.8).normalized();
  const double range = 2.0;
  const Eigen::Matrix3d S = noise.SqrtInformation(u, range);
  const Eigen::Matrix3d info = S.transpose() * S;
  const Eigen::Matrix3d cov = info.inverse();
  EXPECT_NEAR(u.dot(cov * u), 0.018 * 0.018, 1e-12);
  const Eigen::Vector3d v = AnyPerpendicular(u);
  EXPECT_NEAR(v.dot(cov * v), std::pow(0.0006 * 2 + 0.0015, 2), 1e-12);
  EXPECT_NEAR(noise.NormalVariance(u, range, u), 0.018 * 0.018, 1e-12);
  EXPECT_NEAR(noise.NormalVariance(u, range, v), std::pow(0.0027, 2), 1e-12);
}

}  // namespace
}  // namespace ifab
