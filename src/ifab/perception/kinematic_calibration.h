#pragma once
/// \file
/// The arm's kinematic errors from the laser's calibration views (an "absolute accuracy" step the
/// paper does not take). The cube calibration (calibration.h) fits one mount to every sweep, so
/// the mount it finds absorbs the arm's error averaged over the calibration postures; the scans
/// and placements of a mission happen at other postures, where the arm's error differs (an
/// uncalibrated industrial arm: millimetres at the flange, Nubiola and Bonev 2013).
///
/// Here every view is first solved alone for its own mount, against the targets held where the
/// joint solve put them: each such mount is the true mount seen through the arm's error at that
/// view's posture. A small per-segment error on the design chain (a 6-DoF pose after each
/// segment's frame to tip, as in Mooring et al.'s "complete" models; joint zero offsets are its
/// rotation about the next axis) is then fitted to all views at once, with one mount and one
/// correction of the targets' frame, Gauss-Newton with a Gaussian prior of the arm's tolerance on
/// each error (the directions the views do not see stay at the design).

#include <string>
#include <vector>

#include <kdl/chain.hpp>

#include "ifab/core/se3.h"
#include "ifab/model/robot_model.h"
#include "ifab/perception/registration.h"

namespace ifab {

class ConfigNode;

/// One calibration view: the mount that fits its sweep alone, and the posture it was seen from.
struct FlangeObservation {
  std::string name;
  Vector6d q{Vector6d::Zero()};               ///< joint angles at the sweep's middle [rad]
  Pose3 T_tool0_laser{Pose3::Identity()};     ///< this view's mount (design chain)
  Matrix6d covariance{Matrix6d::Identity()};  ///< of [x y z rx ry rz] (calibration.h's convention)
};

/// What the fit may change: each joint's zero (a rotation about its axis; joint 1's is a turn of
/// the whole arm, which the targets' frame takes) or a full 6-DoF error after every segment.
enum class KinematicModel { kJointOffsets, kLinks };

struct KinematicCalibrationOptions {
  /// Joint offsets by default: five numbers that a few views fix, where the 30 of the full model
  /// would follow the prior in the directions the views leave open.
  KinematicModel model{KinematicModel::kJointOffsets};
  double joint_offset_sigma{0.05 * 3.14159265358979323846 / 180.0};  ///< [rad] prior std of a joint's zero
  /// Prior std of each segment's error, per axis: an arm without an accuracy option, whose flange
  /// is a few millimetres from its nominal model (Nubiola and Bonev 2013: IRB 1600, 1-2 mm).
  double link_translation_sigma{0.001};  ///< [m]
  double link_rotation_sigma{0.02 * 3.14159265358979323846 / 180.0};  ///< [rad]
  int max_iterations{10};
  int min_views{4};  ///< fewer usable views: no fit (the model would follow the prior alone)

  /// Reads a `kinematics:` section: {model: joint_offsets | links, joint_offset_sigma_deg,
  /// link_translation_sigma_m, link_rotation_sigma_deg, max_iterations, min_views}.
  static KinematicCalibrationOptions FromConfig(const ConfigNode& config);
};

struct KinematicCalibration {
  bool usable{false};  ///< the fitted views agree within their stds (else keep the design chain)
  std::string message;
  std::vector<Pose3> link_errors;        ///< per segment of the chain: tip = design tip * error
  std::vector<double> joint_offsets;     ///< [rad] joints 2-5 with the joint-offset model (else empty;
                                         ///< joint 1's is the targets' turn, joint 6's the mount's)
  Pose3 T_tool0_laser{Pose3::Identity()};  ///< the mount that goes with the corrected chain
  Pose3 T_targets_correction{Pose3::Identity()};  ///< where the targets sit, against the joint solve
  int views{0};
  int iterations{0};
  /// Whitened rms of the views' mount residuals: with the design chain (one mount, one targets'
  /// correction fitted) and with the fitted errors.
  double rms_design{0.0}, rms_fitted{0.0};
  std::vector<double> view_rms_design, view_rms_fitted;  ///< per view, whitened rms
  std::string BriefReport() const;
};

/// Fit the chain's segment errors to the views (starting from the design chain and the mount guess).
KinematicCalibration CalibrateArmKinematics(const KDL::Chain& design, const std::vector<FlangeObservation>& views,
                                            const Pose3& T_tool0_laser_guess,
                                            const KinematicCalibrationOptions& options = {});

/// Flange pose of `chain` at q with a pose error after each segment's tip (empty: none).
Pose3 ChainForwardKinematics(const KDL::Chain& chain, const Vector6d& q, const std::vector<Pose3>& link_errors = {});

}  // namespace ifab
