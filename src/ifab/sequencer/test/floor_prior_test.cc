// The floor's prior on a registered pose (issue 12): a small workpiece 2 m away pins the base's
// height and pitch only together; the prior decides that combination and keeps the workpiece
// where the scan saw it.
#include "ifab/sequencer/floor_prior.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "ifab/core/angles.h"

namespace ifab::sequencer {
namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

// Covariance of T_site_base from scan points on a workpiece (base frame): each pins where it
// lies, to 0.5 mm, through f = Exp(w) R p + t + d - p_site (Jacobian [I, -[R p]x]); plus a loose
// prior of 1 m / 1 rad on everything.
Matrix6d ScanCovariance(const Pose3& T_site_base, const std::vector<Eigen::Vector3d>& points_base) {
  Matrix6d info = Matrix6d::Identity();
  for (const auto& p : points_base) {
    const Eigen::Vector3d q = T_site_base.linear() * p;
    Eigen::Matrix<double, 3, 6> J;
    J.leftCols<3>().setIdentity();
    J.rightCols<3>() << 0, q.z(), -q.y(), -q.z(), 0, q.x(), q.y(), -q.x(), 0;
    info += J.transpose() * J / (0.0005 * 0.0005);
  }
  return info.inverse();
}

struct Case {
  std::vector<Eigen::Vector3d> workpiece_base;  // what the scan saw, in the base frame
  Pose3 registered;                             // tilted 1 deg, height compensating
};

Case TiltedRegistration() {
  // A brick-sized workpiece 2 m ahead and 0.3 m up: its three corners close together.
  Case c;
  c.workpiece_base = {{2.0, 0.0, 0.3}, {2.0, 0.1, 0.3}, {2.1, 0.0, 0.3}};
  // The truth is level at the floor (z = 0); the registration slid along its weak direction:
  // pitched by 1 deg about the base origin, and raised so that the workpiece stays put.
  const Eigen::Matrix3d R = Eigen::AngleAxisd(DegToRad(1.0), Eigen::Vector3d::UnitY()).toRotationMatrix();
  c.registered = Pose3::Identity();
  c.registered.linear() = R;
  c.registered.translation() = c.workpiece_base[0] - R * c.workpiece_base[0];
  return c;
}

double WorkpieceMoved(const Case& c, const Pose3& fused) {
  double worst = 0.0;
  for (const auto& p : c.workpiece_base) worst = std::max(worst, (fused * p - c.registered * p).norm());
  return worst;
}

TEST(FloorPriorTest, LevelsTheBaseAndKeepsTheWorkpieceWhereTheScanSawIt) {
  const Case c = TiltedRegistration();
  const Matrix6d cov = ScanCovariance(c.registered, c.workpiece_base);
  const FloorPrior prior{0.0, 0.004, DegToRad(0.1)};
  const Pose3 fused = FuseFloorPrior(c.registered, cov, prior);
  const double tilt_before = std::acos(c.registered.linear()(2, 2));
  const double tilt_after = std::acos(std::min(1.0, fused.linear()(2, 2)));
  EXPECT_LT(tilt_after, 0.2 * tilt_before);                     // the prior decides the tilt ...
  EXPECT_LT(std::abs(fused.translation().z()), 0.25 * std::abs(c.registered.translation().z()));
  // ... and the scan the workpiece: it moves by a fraction of what the per-component fusion
  // moves it (the prior, 10 sigma off the scan's tilt, still pulls the pins a little).
  EXPECT_LT(WorkpieceMoved(c, fused), 0.0015);
  EXPECT_LT(WorkpieceMoved(c, fused), 0.3 * WorkpieceMoved(c, FuseFloorPriorPerComponent(c.registered, cov, prior)));
}

TEST(FloorPriorTest, PerComponentFusionMovesTheWorkpiece) {
  // Why the full update: pulling height and pitch each alone breaks what the scan pinned.
  const Case c = TiltedRegistration();
  const Matrix6d cov = ScanCovariance(c.registered, c.workpiece_base);
  const FloorPrior prior{0.0, 0.004, DegToRad(0.1)};
  EXPECT_GT(WorkpieceMoved(c, FuseFloorPriorPerComponent(c.registered, cov, prior)), 0.005);
}

TEST(FloorPriorTest, AWellPinnedPoseBarelyMoves) {
  // A scan that fixes the tilt on its own (a workpiece spread over 2 m in height and width) keeps it.
  Case c = TiltedRegistration();
  c.workpiece_base = {{2.0, -1.0, 0.0}, {2.0, 1.0, 0.0}, {2.0, 0.0, 2.0}, {1.0, 0.0, 0.0}};
  const Matrix6d cov = ScanCovariance(c.registered, c.workpiece_base);
  const Pose3 fused = FuseFloorPrior(c.registered, cov, FloorPrior{0.0, 0.004, DegToRad(0.1)});
  EXPECT_LT(WorkpieceMoved(c, fused), 0.0015);
  EXPECT_NEAR(std::acos(fused.linear()(2, 2)), DegToRad(1.0), DegToRad(0.05));
}

TEST(FloorPriorTest, OffTheTiltItFusesTheHeightAlone) {
  // The IMU held the tilt (it includes the chassis's lean under the arm, which a level floor does
  // not describe): a prior with on_tilt false leaves the base's up axis and still fuses the height.
  const Case c = TiltedRegistration();
  Matrix6d cov = ScanCovariance(c.registered, c.workpiece_base);
  for (int k : {3, 4}) {  // held: the IMU's own uncertainty, uncorrelated with the scan's
    cov.row(k).setZero();
    cov.col(k).setZero();
    cov(k, k) = DegToRad(0.08) * DegToRad(0.08);
  }
  FloorPrior off_tilt{0.0, 0.004, DegToRad(0.1)};
  off_tilt.on_tilt = false;
  // (The full update may turn the pose about the vertical through the scan's correlations: the
  // tilt's size is what must stay.)
  for (const Pose3& fused : {FuseFloorPrior(c.registered, cov, off_tilt), FuseFloorPriorPerComponent(c.registered, cov, off_tilt)}) {
    EXPECT_NEAR(fused.linear()(2, 2), c.registered.linear()(2, 2), 1e-12);
    EXPECT_LT(std::abs(fused.translation().z()), 0.5 * std::abs(c.registered.translation().z()));
  }
  // The same tilt with the prior on it is pulled towards level (0.1 deg prior, 0.08 deg held).
  const Pose3 on = FuseFloorPrior(c.registered, cov, FloorPrior{0.0, 0.004, DegToRad(0.1)});
  EXPECT_LT(std::acos(std::min(1.0, on.linear()(2, 2))), 0.8 * DegToRad(1.0));
}

}  // namespace
}  // namespace ifab::sequencer
