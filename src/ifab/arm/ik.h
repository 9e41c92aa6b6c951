#pragma once
/// \file
/// Inverse kinematics of the arm with Orocos KDL (as in the paper): KDL's Levenberg-Marquardt
/// solver (ChainIkSolverPos_LMA) started from the current configuration, its wrist-flipped twin
/// and a few seeded random configurations; solutions are shifted by whole turns towards the
/// current configuration, checked against the joint limits and by forward kinematics, and the
/// one nearest to the current configuration is returned. A pose no start reaches is reported
/// as out of reach (a status, not an exception).

#include <cstdint>
#include <memory>
#include <string>

#include "ifab/core/se3.h"
#include "ifab/model/robot_model.h"

namespace KDL {
class ChainIkSolverPos_LMA;
}

namespace ifab {
class ConfigNode;
}

namespace ifab::arm {

struct IkOptions {
  int random_starts{12};                 ///< random starting configurations besides the current one and its wrist flip
  double position_tolerance{1e-6};       ///< accepted flange position error [m]
  double orientation_tolerance{1e-6};    ///< accepted flange orientation error [rad]
  int max_iterations{300};               ///< per Levenberg-Marquardt solve
  std::uint64_t seed{1};                 ///< seed of the random starts (the same pose gives the same answer)
  Vector6d distance_weight{Vector6d::Ones()};  ///< weights of the joint distance that picks the nearest solution

  /// Read the `ik:` section (every key optional; unknown keys rejected).
  static IkOptions FromConfig(const ConfigNode& node);
};

enum class IkStatus {
  kSolved,       ///< a solution within the joint limits
  kOutOfReach,   ///< no start converged to the pose
  kJointLimits,  ///< the pose is reachable only outside the joint limits
};
const char* ToString(IkStatus status);

struct IkResult {
  IkStatus status{IkStatus::kOutOfReach};
  std::string message;
  Vector6d q{Vector6d::Zero()};    ///< the solution (valid when ok())
  double position_error{0.0};      ///< flange position error of the best attempt [m]
  double orientation_error{0.0};   ///< flange orientation error of the best attempt [rad]
  int solutions{0};                ///< distinct starts that converged within the limits
  bool ok() const { return status == IkStatus::kSolved; }
};

class IkSolver {
 public:
  explicit IkSolver(const RobotModel& robot, IkOptions options = {});
  ~IkSolver();
  IkSolver(IkSolver&&) noexcept;
  IkSolver& operator=(IkSolver&&) noexcept;

  /// Joint angles that put tool0 at T_arm_base_tool0, nearest to q_current.
  IkResult Solve(const Pose3& T_arm_base_tool0, const Vector6d& q_current);
  /// One solve started from q_seed only (for tracking a path in small steps).
  IkResult SolveFrom(const Pose3& T_arm_base_tool0, const Vector6d& q_seed);

  const IkOptions& options() const { return options_; }

 private:
  // Solve from one start; true if it converged (q then shifted towards q_near and checked).
  bool SolveOnce(const Pose3& target, const Vector6d& start, const Vector6d& q_near, Vector6d& q,
                 double& position_error, double& orientation_error, bool& within_limits);

  IkOptions options_;
  std::unique_ptr<KDL::Chain> chain_;  // the LMA solver keeps a reference: stable address
  std::unique_ptr<KDL::ChainIkSolverPos_LMA> lma_;
  Vector6d q_min_, q_max_;
};

}  // namespace ifab::arm
