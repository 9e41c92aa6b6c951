#include "ifab/arm/ik.h"

#include <fmt/format.h>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainiksolverpos_lma.hpp>

#include <cmath>
#include <limits>

#include "ifab/core/angles.h"
#include "ifab/core/config.h"
#include "ifab/core/random.h"

namespace ifab::arm {

const char* ToString(IkStatus status) {
  switch (status) {
    case IkStatus::kSolved: return "solved";
    case IkStatus::kOutOfReach: return "out_of_reach";
    case IkStatus::kJointLimits: return "joint_limits";
  }
  return "?";
}

IkOptions IkOptions::FromConfig(const ConfigNode& node) {
  node.ExpectMap();
  node.ExpectKeys({"random_starts", "position_tolerance", "orientation_tolerance", "max_iterations", "seed",
                   "distance_weight"});
  IkOptions o;
  node.ReadNonNegative("random_starts", o.random_starts);
  node.ReadPositive("position_tolerance", o.position_tolerance);
  node.ReadPositive("orientation_tolerance", o.orientation_tolerance);
  node.ReadPositive("max_iterations", o.max_iterations);
  node.Read("seed", o.seed);
  if (auto c = node.Find("distance_weight")) {
    const auto v = c->AsNumbers(6);
    for (int i = 0; i < 6; ++i) {
      if (!(v[i] > 0.0)) c->Fail("6 positive numbers");
      o.distance_weight[i] = v[i];
    }
  }
  return o;
}

IkSolver::IkSolver(const RobotModel& robot, IkOptions options)
    : options_(std::move(options)),
      chain_(std::make_unique<KDL::Chain>(robot.arm_chain)),
      q_min_(robot.q_min),
      q_max_(robot.q_max) {
  // Equal weights on metres and radians; stop when the squared weighted error is ~1e-16.
  const Eigen::Matrix<double, 6, 1> weights = Eigen::Matrix<double, 6, 1>::Ones();
  lma_ = std::make_unique<KDL::ChainIkSolverPos_LMA>(*chain_, weights, 1e-16, options_.max_iterations, 1e-15);
}

IkSolver::~IkSolver() = default;
IkSolver::IkSolver(IkSolver&&) noexcept = default;
IkSolver& IkSolver::operator=(IkSolver&&) noexcept = default;

bool IkSolver::SolveOnce(const Pose3& target, const Vector6d& start, const Vector6d& q_near, Vector6d& q,
                         double& position_error, double& orientation_error, bool& within_limits) {
  KDL::JntArray init(6), out(6);
  for (int i = 0; i < 6; ++i) init(i) = start[i];
  lma_->CartToJnt(init, ToKdl(target), out);  // the result is judged by forward kinematics below
  for (int i = 0; i < 6; ++i) q[i] = out(i);
  if (!q.allFinite()) {
    position_error = orientation_error = std::numeric_limits<double>::infinity();
    within_limits = false;
    return false;
  }
  // Whole turns towards the configuration we want to stay near, then into the limits.
  for (int i = 0; i < 6; ++i) {
    q[i] = q_near[i] + std::remainder(q[i] - q_near[i], 2.0 * kPi);
    while (q[i] > q_max_[i] && q[i] - 2.0 * kPi >= q_min_[i]) q[i] -= 2.0 * kPi;
    while (q[i] < q_min_[i] && q[i] + 2.0 * kPi <= q_max_[i]) q[i] += 2.0 * kPi;
  }
  KDL::ChainFkSolverPos_recursive fk(*chain_);
  KDL::JntArray joints(6);
  for (int i = 0; i < 6; ++i) joints(i) = q[i];
  KDL::Frame f;
  fk.JntToCart(joints, f);
  const Pose3 reached = ToPose3(f);
  position_error = TranslationDistance(reached, target);
  orientation_error = RotationAngle(reached, target);
  within_limits = ((q - q_min_).array() >= 0.0).all() && ((q_max_ - q).array() >= 0.0).all();
  return position_error <= options_.position_tolerance && orientation_error <= options_.orientation_tolerance;
}

IkResult IkSolver::SolveFrom(const Pose3& T_arm_base_tool0, const Vector6d& q_seed) {
  IkResult r;
  Vector6d q;
  bool within = false;
  const bool converged =
      SolveOnce(T_arm_base_tool0, q_seed, q_seed, q, r.position_error, r.orientation_error, within);
  r.q = q;
  if (converged && within) {
    r.status = IkStatus::kSolved;
    r.solutions = 1;
  } else {
    r.status = converged ? IkStatus::kJointLimits : IkStatus::kOutOfReach;
    r.message = fmt::format("IK from the seed: {} (position error {:.3g} m, orientation error {:.3g} rad)",
                            converged ? "solution outside the joint limits" : "did not converge",
                            r.position_error, r.orientation_error);
  }
  return r;
}

IkResult IkSolver::Solve(const Pose3& T_arm_base_tool0, const Vector6d& q_current) {
  // Starts: the current configuration (clamped into the limits), its wrist flip, random ones.
  std::vector<Vector6d> starts;
  const Vector6d current = q_current.cwiseMax(q_min_).cwiseMin(q_max_);
  starts.push_back(current);
  Vector6d flip = current;
  flip[3] += flip[3] > 0.0 ? -kPi : kPi;
  flip[4] = -flip[4];
  flip[5] += flip[5] > 0.0 ? -kPi : kPi;
  starts.push_back(flip);
  RandomStream rng(options_.seed);
  for (int s = 0; s < options_.random_starts; ++s) {
    Vector6d q;
    for (int i = 0; i < 6; ++i) {
      // Keep the random starts within one turn for the wrist joints with +-400 deg ranges.
      q[i] = rng.Uniform(std::max(q_min_[i], -kPi), std::min(q_max_[i], kPi));
    }
    starts.push_back(q);
  }

  IkResult best;
  best.position_error = best.orientation_error = std::numeric_limits<double>::infinity();
  double best_distance = std::numeric_limits<double>::infinity();
  bool any_converged = false;
  for (const Vector6d& start : starts) {
    Vector6d q;
    double pe = 0.0, oe = 0.0;
    bool within = false;
    const bool converged = SolveOnce(T_arm_base_tool0, start, q_current, q, pe, oe, within);
    any_converged = any_converged || converged;
    if (!converged || !within) {
      if (best.status != IkStatus::kSolved && pe + oe < best.position_error + best.orientation_error) {
        best.position_error = pe;
        best.orientation_error = oe;
        best.q = q;
      }
      continue;
    }
    ++best.solutions;
    const double distance = (q - q_current).cwiseProduct(options_.distance_weight).norm();
    if (distance < best_distance) {
      best_distance = distance;
      best.status = IkStatus::kSolved;
      best.q = q;
      best.position_error = pe;
      best.orientation_error = oe;
    }
  }
  if (best.status != IkStatus::kSolved) {
    best.status = any_converged ? IkStatus::kJointLimits : IkStatus::kOutOfReach;
    const Eigen::Vector3d p = T_arm_base_tool0.translation();
    best.message = any_converged
                       ? fmt::format("flange pose at ({:.3f}, {:.3f}, {:.3f}) m in arm_base is reachable only "
                                     "outside the joint limits",
                                     p.x(), p.y(), p.z())
                       : fmt::format("flange pose at ({:.3f}, {:.3f}, {:.3f}) m in arm_base is out of reach: no "
                                     "start of {} converged (best position error {:.3g} m, orientation error "
                                     "{:.3g} rad)",
                                     p.x(), p.y(), p.z(), starts.size(), best.position_error,
                                     best.orientation_error);
  }
  return best;
}

}  // namespace ifab::arm
