#include "ifab/arm/dynamics.h"

#include <gtest/gtest.h>
#include <kdl/chaindynparam.hpp>
#include <kdl/chainfdsolver_recursive_newton_euler.hpp>
#include <kdl/chainidsolver_recursive_newton_euler.hpp>

#include "ifab/core/data_path.h"
#include "ifab/core/random.h"
#include "ifab/core/testing/numeric_jacobian.h"

namespace ifab::arm {
namespace {

constexpr double kTol = 1e-9;

class DynamicsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    robot_ = new RobotModel(LoadRobotModel(DataPath("robots/insitu_fabricator.urdf")));
    model_ = new ArmModel(ArmModel::FromRobotModel(*robot_));
  }
  static void TearDownTestSuite() {
    delete model_;
    delete robot_;
  }

  struct State {
    Vector6d q, qd, qdd;
  };
  // Random state within the joint limits, speeds up to the limits, accelerations up to 10 rad/s^2.
  static State RandomState(RandomStream& rng) {
    State s;
    for (int i = 0; i < kDof; ++i) {
      s.q[i] = rng.Uniform(robot_->q_min[i], robot_->q_max[i]);
      s.qd[i] = rng.Uniform(-robot_->qd_max[i], robot_->qd_max[i]);
      s.qdd[i] = rng.Uniform(-10.0, 10.0);
    }
    return s;
  }
  static KDL::JntArray Kdl(const Vector6d& v) {
    KDL::JntArray a(kDof);
    for (int i = 0; i < kDof; ++i) a(i) = v[i];
    return a;
  }

  static RobotModel* robot_;
  static ArmModel* model_;
};
RobotModel* DynamicsTest::robot_ = nullptr;
ArmModel* DynamicsTest::model_ = nullptr;

TEST_F(DynamicsTest, ModelReadsTheUrdfMasses) {
  // 120 + 85 + 70 + 45 + 12 + 8 kg of moving links (URDF estimates); the foot does not move.
  EXPECT_NEAR(model_->MovingMass(), 340.0, 1e-9);
  EXPECT_NEAR((model_->gravity - Eigen::Vector3d(0, 0, -9.81)).norm(), 0.0, 1e-12);
}

TEST_F(DynamicsTest, ForwardKinematicsMatchesKdl) {
  RandomStream rng(1);
  for (int trial = 0; trial < 100; ++trial) {
    const State s = RandomState(rng);
    const Pose3 ours = ForwardKinematics(*model_, s.q);
    const Pose3 kdl = robot_->ArmForwardKinematics(s.q);
    EXPECT_LT((ours.matrix() - kdl.matrix()).cwiseAbs().maxCoeff(), 1e-12);
  }
}

TEST_F(DynamicsTest, InverseDynamicsMatchesKdlRne) {
  KDL::ChainIdSolver_RNE kdl(robot_->arm_chain, KDL::Vector(0, 0, -9.81));
  KDL::Wrenches no_wrench(robot_->arm_chain.getNrOfSegments(), KDL::Wrench::Zero());
  ArmData data;
  RandomStream rng(2);
  double worst = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    const State s = RandomState(rng);
    KDL::JntArray tau_kdl(kDof);
    ASSERT_EQ(kdl.CartToJnt(Kdl(s.q), Kdl(s.qd), Kdl(s.qdd), no_wrench, tau_kdl), 0);
    const Vector6d tau = InverseDynamics<double>(*model_, data, s.q, s.qd, s.qdd, model_->gravity);
    for (int i = 0; i < kDof; ++i) worst = std::max(worst, std::abs(tau[i] - tau_kdl(i)));
  }
  EXPECT_LT(worst, kTol);
}

TEST_F(DynamicsTest, MassCoriolisGravityMatchKdlDynParam) {
  KDL::ChainDynParam kdl(robot_->arm_chain, KDL::Vector(0, 0, -9.81));
  ArmData data;
  RandomStream rng(3);
  double worst_m = 0.0, worst_c = 0.0, worst_g = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    const State s = RandomState(rng);
    KDL::JntSpaceInertiaMatrix m_kdl(kDof);
    KDL::JntArray c_kdl(kDof), g_kdl(kDof);
    ASSERT_EQ(kdl.JntToMass(Kdl(s.q), m_kdl), 0);
    ASSERT_EQ(kdl.JntToCoriolis(Kdl(s.q), Kdl(s.qd), c_kdl), 0);
    ASSERT_EQ(kdl.JntToGravity(Kdl(s.q), g_kdl), 0);
    const Matrix6d m = MassMatrix<double>(*model_, data, s.q);
    worst_m = std::max(worst_m, (m - m_kdl.data).cwiseAbs().maxCoeff());
    const Vector6d c = InverseDynamics<double>(*model_, data, s.q, s.qd, Vector6d::Zero(),
                                               Eigen::Vector3d::Zero());
    worst_c = std::max(worst_c, (c - c_kdl.data).cwiseAbs().maxCoeff());
    const Vector6d g = GravityTorque<double>(*model_, data, s.q);
    worst_g = std::max(worst_g, (g - g_kdl.data).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst_m, kTol);
  EXPECT_LT(worst_c, kTol);
  EXPECT_LT(worst_g, kTol);
}

TEST_F(DynamicsTest, ForwardDynamicsMatchesKdlAndInvertsInverseDynamics) {
  KDL::ChainFdSolver_RNE kdl(robot_->arm_chain, KDL::Vector(0, 0, -9.81));
  KDL::Wrenches no_wrench(robot_->arm_chain.getNrOfSegments(), KDL::Wrench::Zero());
  ArmData data;
  RandomStream rng(4);
  double worst = 0.0, worst_roundtrip = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    const State s = RandomState(rng);
    const Vector6d tau = InverseDynamics<double>(*model_, data, s.q, s.qd, s.qdd, model_->gravity);
    ASSERT_TRUE(ForwardDynamics<double>(*model_, data, s.q, s.qd, tau, model_->gravity));
    worst_roundtrip = std::max(worst_roundtrip, (data.qdd - s.qdd).cwiseAbs().maxCoeff());
    KDL::JntArray qdd_kdl(kDof);
    ASSERT_EQ(kdl.CartToJnt(Kdl(s.q), Kdl(s.qd), Kdl(tau), no_wrench, qdd_kdl), 0);
    worst = std::max(worst, (data.qdd - qdd_kdl.data).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(worst, kTol);
  EXPECT_LT(worst_roundtrip, kTol);
}

TEST_F(DynamicsTest, JetsPassThroughWithTheSameValues) {
  using J = ceres::Jet<double, 18>;
  ArmData data;
  ArmDataT<J> jet_data;
  RandomStream rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const State s = RandomState(rng);
    const Vector6d tau = InverseDynamics<double>(*model_, data, s.q, s.qd, s.qdd, model_->gravity);
    Vec6<J> q, qd, t;
    for (int i = 0; i < kDof; ++i) {
      q[i] = J(s.q[i], i);
      qd[i] = J(s.qd[i], kDof + i);
      t[i] = J(tau[i], 2 * kDof + i);
    }
    ASSERT_TRUE(ForwardDynamics<J>(*model_, jet_data, q, qd, t, model_->gravity));
    for (int i = 0; i < kDof; ++i) EXPECT_NEAR(jet_data.qdd[i].a, s.qdd[i], 1e-9);
    const FrameT<J> x = ForwardKinematics<J>(*model_, jet_data, q);
    const Pose3 pose = ForwardKinematics(*model_, s.q);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(x.p[i].a, pose.translation()[i], 1e-12);
  }
}

// The planner's derivatives (one Jet pass through RNEA, then M^-1) against central differences
// and against Jets pushed through the whole forward dynamics.
TEST_F(DynamicsTest, ForwardDynamicsDerivativesMatchFiniteDifferencesAndFullJets) {
  DerivativeData work;
  DynamicsDerivatives d;
  RandomStream rng(6);
  for (int trial = 0; trial < 10; ++trial) {
    const State s = RandomState(rng);
    ArmData data;
    const Vector6d tau = InverseDynamics<double>(*model_, data, s.q, s.qd, s.qdd, model_->gravity);
    ASSERT_TRUE(ForwardDynamicsDerivatives(*model_, work, s.q, s.qd, tau, model_->gravity, d));
    EXPECT_LT((d.qdd - s.qdd).cwiseAbs().maxCoeff(), 1e-9);

    Eigen::VectorXd x(18);
    x << s.q, s.qd, tau;
    auto fd = [&](const Eigen::VectorXd& v) -> Eigen::VectorXd {
      ArmData w;
      ForwardDynamics<double>(*model_, w, Vector6d(v.segment<6>(0)), Vector6d(v.segment<6>(6)),
                              Vector6d(v.segment<6>(12)), model_->gravity);
      return w.qdd;
    };
    Eigen::MatrixXd jac(6, 18);
    jac << d.dqdd_dq, d.dqdd_dqd, d.M_inv;
    testing::ExpectJacobianMatchesNumeric(fd, x, jac, 1e-5, 1e-6);

    using J = ceres::Jet<double, 18>;
    ArmDataT<J> jd;
    Vec6<J> q, qd, t;
    for (int i = 0; i < kDof; ++i) {
      q[i] = J(s.q[i], i);
      qd[i] = J(s.qd[i], kDof + i);
      t[i] = J(tau[i], 2 * kDof + i);
    }
    ForwardDynamics<J>(*model_, jd, q, qd, t, model_->gravity);
    for (int i = 0; i < kDof; ++i) {
      EXPECT_LT((jd.qdd[i].v.transpose() - jac.row(i)).cwiseAbs().maxCoeff(),
                1e-9 * std::max(1.0, jac.row(i).cwiseAbs().maxCoeff()));
    }
  }
}

}  // namespace
}  // namespace ifab::arm
