#pragma once
/// \file
/// Registration of a laser cloud to the parametric site model (paper Sec. V-B, eq. 7).
///
/// The paper's way (residual kClosest, loss kNone, restarts 0): every point is matched to the
/// primitive closest to it under the current body poses; its error is weighted by the laser
/// covariance rotated onto its ray; Ceres minimises the sum of squares over the poses of all free
/// bodies; matching and solving alternate (ICP style) until the poses stop moving. Shadow points:
/// a point whose ray passes within `shadow_edge_distance` of a primitive edge is flagged, and
/// gets zero error if it lies farther than `shadow_distance` from its closest primitive.
///
/// The defaults are improvements, each behind its switch: kRay matches a point to the face its
/// ray hits and uses its range error (eq. 7's Mahalanobis distance to the closest point is biased
/// by several mm under 18 mm along-ray noise: points pushed past a face's border or into a box
/// snap to the wrong face, and the point-to-plane form tilts planes); a Cauchy loss; and optional
/// restarts out of local minima.
///
/// Registration gives poses of bodies in the robot base frame; the robot's pose in the site
/// follows from the registered workpiece (LocalizeInSite).

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "ifab/core/se3.h"
#include "ifab/model/site.h"
#include "ifab/perception/cloud.h"
#include "ifab/perception/fit_quality.h"
#include "ifab/perception/laser_model.h"
#include "ifab/perception/scene.h"

namespace ifab {

class ConfigNode;

using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// Which error each point contributes (see residuals.h).
enum class RegistrationResidual {
  kClosest,  ///< eq. 7: S (p - cp(p, g*)), closest primitive g* (the paper)
  kRay,      ///< range error along the point's ray to the face it hits (improvement, residuals.h)
};

/// Robust weighting of whitened residuals, re-weighted at every correspondence step.
enum class RobustLoss { kNone, kHuber, kCauchy };

/// What must stop moving for the correspondence steps to end.
enum class Convergence {
  kPose,       ///< every free body's pose (translation_tolerance, rotation_tolerance): the paper
  kResiduals,  ///< the model under every inlier, along its normal (translation_tolerance): motion
               ///< the data do not see (a lone board sliding in its plane) does not hold it up
};

/// Where the noise scale comes from.
enum class NoiseSource {
  kModel,      ///< `noise` as given (a sensor profile, data/sensors/*.yaml)
  kEstimated,  ///< `noise`'s shape scaled to the residuals' robust spread (MAD), re-estimated at
               ///< every correspondence step (so the gate shrinks as the fit settles, as KISS-ICP's
               ///< adaptive threshold does)
};

/// How each correspondence step's least-squares problem is solved.
enum class LeastSquaresSolver {
  kNormalEquations,  ///< LM on J^T J, J^T r accumulated point by point (few parameters, many residuals)
  kCeres,            ///< a Ceres problem (dense Jacobian): the reference, same iteration
};

struct RegistrationOptions {
  LaserNoiseModel noise;                                       ///< point covariance (Sec. V-B)
  NoiseSource noise_source{NoiseSource::kModel};               ///< the scale of `noise`: given or estimated
  std::string noise_name{"utm30lx (built-in default)"};        ///< where `noise` came from (for the output)
  double gate_sigmas{0.0};             ///< points whose range error exceeds this many sigmas of the
                                       ///< noise model get zero error (0 = off; max_distance caps it)
  double fit_tolerance{2.0};           ///< usable only if the inliers' robust spread (1.4826 median
                                       ///< |whitened error|) is below this factor of the noise
                                       ///< model's (gate and loss are in sigmas: they cut too close
                                       ///< if sigma is too small); a narrower spread is safe (the
                                       ///< covariance is scaled to it); 0 = no test
  RegistrationResidual residual{RegistrationResidual::kRay};  ///< error per point (kClosest: the paper)
  int max_iterations{30};              ///< correspondence steps (match, then solve)
  int coarse_stride{1};                ///< the first steps use every n-th matched point, until a
                                       ///< step moves less than 10x the tolerances; then all
                                       ///< (speed-up for far guesses; 1 = off, the paper)
  int max_solver_iterations{25};       ///< LM iterations per step
  LeastSquaresSolver solver{LeastSquaresSolver::kNormalEquations};  ///< how each step is solved
  Convergence convergence{Convergence::kPose};  ///< what the tolerances apply to
  double translation_tolerance{1e-5};  ///< [m] converged when no body moves more in a step
  double rotation_tolerance{5e-5};     ///< [rad] ... and none turns more
  bool shadow_points{true};            ///< apply the shadow-point rule (Sec. V-B)
  double shadow_edge_distance{0.01};   ///< [m] a ray passing this close to an edge flags its point
  double shadow_distance{0.02};        ///< [m] a flagged point this far from its closest primitive
                                       ///< (kRay: range this far off the face hit) gets zero error
  double shadow_sigmas{3.0};           ///< kRay: ... and more than this many sigmas of its range
                                       ///< (a 2 cm cut alone would trim the 18 mm range noise near
                                       ///< every edge and bias the fit)
  double max_distance{0.15};           ///< [m] points farther from every primitive (kRay: range
                                       ///< off by more) get zero error (unmodelled things);
                                       ///< 0 = keep all (the paper)
  double max_incidence{M_PI / 2};      ///< [rad] kRay: points whose ray meets the face
                                       ///< more obliquely get zero error (range unreliable)
  double min_incidence{0.0};           ///< [rad] kRay: points whose ray meets the face closer to
                                       ///< its normal get zero error (improvement, 0 = off: the
                                       ///< UTM-30LX reads strong near-normal returns short, the
                                       ///< paper's Fig. 7 bump directly below the scanner)
  RobustLoss loss{RobustLoss::kCauchy};  ///< robust re-weighting (improvement; the paper: none)
  double loss_scale{3.0};              ///< [whitened units] where the robust loss bends
  double step_sigma_translation{0.01}; ///< [m] damping of each correspondence step (a prior on the
                                       ///< step, re-centred every step: it slows directions the
                                       ///< data barely fix, where wrong matches would throw the
                                       ///< pose around, without biasing the result)
  double step_sigma_rotation{0.02};    ///< [rad]
  int restarts{0};                     ///< rounds of restarts from the result moved +-restart_distance
                                       ///< along each finite body's 3 weakest directions and its
                                       ///< x and y (lowest cost kept; 0 = off, the paper). Each
                                       ///< round costs 10 more solves per finite free body.
  double restart_distance{0.006};      ///< [m] (rotations: at the body's extent)
  double prior_sigma_translation{1.0}; ///< [m] regularises the covariance of unconstrained directions
  double prior_sigma_rotation{1.0};    ///< [rad]
  double unconstrained_std{0.01};      ///< [m] a direction whose std (rotations times the body's
                                       ///< extent) exceeds this is reported unconstrained
  int num_threads{1};                  ///< threads for matching and evaluation

  /// Reads a `registration:` section over `base`; every key optional, unknown keys rejected.
  static RegistrationOptions FromConfig(const ConfigNode& config, RegistrationOptions base);
  static RegistrationOptions FromConfig(const ConfigNode& config) { return FromConfig(config, RegistrationOptions{}); }
};

/// Per-point outcome, for inspection (e.g. colouring a PLY as in the paper's Fig. 4).
enum class PointLabel : std::uint8_t {
  kInlier = 0,   ///< contributes an error
  kShadow = 1,   ///< flagged shadow point beyond shadow_distance: zero error
  kOutlier = 2,  ///< farther than max_distance from every primitive: zero error
  kFixed = 3,    ///< matched to a body held fixed: no parameter to inform
  kGrazing = 4,  ///< its ray meets the face hit beyond max_incidence or within min_incidence:
                 ///< zero error (kRay only)
};

enum class RegistrationStatus { kConverged, kMaxIterations, kNoPoints, kSolverFailed };
const char* ToString(RegistrationStatus status);

struct RegisteredBody {
  std::string name;
  bool free{true};
  Pose3 T_base_body{Pose3::Identity()};
  /// Covariance of [x y z rx ry rz]: the body origin in base and a rotation vector about base
  /// axes through that origin (left perturbation). Unconstrained directions show the step prior.
  Matrix6d covariance{Matrix6d::Zero()};
  int inliers{0};                          ///< points contributing an error to this body
  std::vector<std::string> unconstrained;  ///< e.g. "translation along x", "rotation about z"
  std::vector<std::string> fixed;          ///< components held at the guess (RegistrationBody::fixed)
  /// Every direction of the pose is fixed by the data (or held): the pose may be used.
  bool Constrained() const { return unconstrained.empty(); }
};

struct RegistrationSummary {
  RegistrationStatus status{RegistrationStatus::kNoPoints};
  std::string message;
  int iterations{0};    ///< correspondence steps
  double cost{0.0};     ///< final 0.5 sum of squared whitened errors
  double seconds{0.0};
  std::vector<RegisteredBody> bodies;  ///< in the order given
  int num_points{0};
  int num_inliers{0};
  int num_shadow_flagged{0};  ///< rays near an edge
  int num_shadow_removed{0};  ///< ... and far from the model: zero error
  int num_outliers{0};
  int num_grazing{0};         ///< kRay: rays too oblique to their face
  double rms_whitened{0.0};   ///< sqrt(sum r^2 / #residuals): about 1 if the noise model fits
  FitQuality fit;             ///< noise model used, variance factor, test of the fit (fit_quality.h)
  std::vector<PointLabel> labels;  ///< per input point
  std::vector<int> point_body;     ///< per input point: body matched (-1: none)
  std::vector<std::string> warnings;

  /// Converged, and the residuals agree with the noise model. A body's pose is usable only if it
  /// is also Constrained() (a single face leaves its in-plane directions free).
  bool IsUsable() const { return status == RegistrationStatus::kConverged && fit.consistent; }
  const RegisteredBody* Find(const std::string& name) const;
  std::string BriefReport() const;
};

/// Register a cloud (base frame) to the bodies, starting from their T_base_body. `seconds` counts
/// every solve (restarts included).
RegistrationSummary Register(const std::vector<RayPoint>& cloud, const std::vector<RegistrationBody>& bodies,
                             const RegistrationOptions& options = {});

/// The site as registration bodies, T_site_base_guess the robot's pose guess: "ground" (the
/// ground plane alone, when `separate_ground`, as the paper locates ground and workpiece apart)
/// and "site" (everything else, rigid, its pose T_base_site).
std::vector<RegistrationBody> SiteBodies(const Site& site, const Pose3& T_site_base_guess,
                                         bool separate_ground = true);
/// The site's objects as separate bodies in the cloud's own frame (`ifab register --frame
/// sensor`): the site YAML gives each object's pose guess in that frame; each is solved apart.
std::vector<RegistrationBody> SensorFrameBodies(const Site& site);

/// A plane of a registered body in the cloud's frame, n . p = offset, with its uncertainty.
struct RegisteredPlane {
  std::string body;
  Eigen::Vector3d normal{Eigen::Vector3d::UnitZ()};
  double offset{0.0};       ///< [m]
  double offset_std{0.0};   ///< [m]
  double tilt_std{0.0};     ///< [rad] of the normal (larger of the two axes across it)
  bool constrained{false};  ///< offset and tilt fixed by the data (std below unconstrained_std)
};
/// The planes and polygon faces of the registered bodies (boxes excluded), in the cloud's frame.
std::vector<RegisteredPlane> RegisteredPlanes(const RegistrationSummary& summary,
                                              const std::vector<RegistrationBody>& bodies, double max_std);

/// The robot's pose in the site from a registration of SiteBodies.
struct SiteLocalization {
  RegistrationSummary registration;
  Pose3 T_site_base{Pose3::Identity()};
  Matrix6d covariance{Matrix6d::Zero()};  ///< of T_site_base, [x y z rx ry rz] as in RegisteredBody
  std::vector<std::string> unconstrained;  ///< directions of the site body the cloud leaves free
  bool IsUsable() const { return registration.IsUsable() && unconstrained.empty(); }
};
/// `site_fixed`: components of the site body ([x y z rx ry rz], base axes through the site
/// origin) held at the guess, e.g. roll and pitch set by the IMU's gravity direction.
SiteLocalization LocalizeInSite(const std::vector<RayPoint>& cloud, const Site& site,
                                const Pose3& T_site_base_guess, const RegistrationOptions& options = {},
                                bool separate_ground = true, const std::array<bool, 6>& site_fixed = {});

/// Covariance of T^-1 from the covariance of T, both in the [x y z rx ry rz] convention above.
Matrix6d InverseCovariance(const Pose3& T, const Matrix6d& covariance);

/// Unconstrained directions of an information matrix over one pose's [x y z rx ry rz], rotations
/// scaled by `extent` [m]: the eigen-directions whose std exceeds `max_std` [m], named by axis
/// ("translation along x", "rotation about z") or, if not axis-aligned, written out.
std::vector<std::string> UnconstrainedDirections(const Matrix6d& information, double extent, double max_std);

}  // namespace ifab
