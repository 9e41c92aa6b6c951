#pragma once
/// \file
/// The arm laser's range bias (the paper's Sec. VII names it the largest error and leaves its
/// compensation as future work): a model b(range, incidence) of how much longer than the truth the
/// laser reads, identified with its covariance from sweeps of known geometry (a cube on the floor,
/// the floor seen from several heights as in Fig. 7) together with the laser mount and the
/// targets' poses, and its compensation of a sweep's ranges before eq. 6.
///
/// The model is a tensor-product linear B-spline ("hat" functions) over knots in range and in
/// incidence angle: no shape is assumed (the literature's cos^n laws, the UTM-30LX's walk), only
/// that the bias varies smoothly on the scale of the knots. Where the sweeps give no data the
/// coefficients keep their prior (zero, with a wide std), so the model's own uncertainty says
/// where it may be used: compensation keeps a return only where the compensated bias's std is a
/// small fraction of the range noise (this replaces a fixed minimum range and incidence).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "ifab/core/se3.h"
#include "ifab/perception/calibration.h"
#include "ifab/perception/cloud.h"
#include "ifab/perception/scene.h"

namespace ifab {

class ConfigNode;

/// b(r, incidence) = sum_k c_k phi_k(r, incidence), phi the products of hat functions over the
/// knots (clamped outside them). Positive = the laser reads long.
struct RangeBiasModel {
  std::vector<double> range_knots;      ///< [m] increasing
  std::vector<double> incidence_knots;  ///< [rad] increasing, within [0, pi/2]
  Eigen::VectorXd coefficients;         ///< [m] the bias at each knot pair, range-major
  Eigen::MatrixXd covariance;           ///< of the coefficients [m^2]

  bool empty() const { return coefficients.size() == 0; }
  int size() const { return static_cast<int>(range_knots.size() * incidence_knots.size()); }
  /// The (at most 4) basis functions that are non-zero at (range, incidence): indices, weights.
  int Basis(double range, double incidence, int index[4], double weight[4]) const;
  double Bias(double range, double incidence) const;  ///< [m]
  double Std(double range, double incidence) const;   ///< [m] std of Bias from the covariance

  /// Reads {range_knots: [m], incidence_knots_deg: [deg], coefficients: [m], covariance: [[...]]}
  /// (coefficients and covariance optional: zero); throws InputError naming the field.
  static RangeBiasModel FromConfig(const ConfigNode& config);
  /// The same as YAML text (a map at `indent` spaces), for a file `FromConfig` reads back.
  std::string ToYaml(int indent = 0) const;
};

/// How the bias is identified (IdentifyRangeBias).
struct RangeBiasOptions {
  std::vector<double> range_knots{0.1, 0.2, 0.3, 0.4, 0.5, 0.65, 0.8, 1.0, 1.25, 1.6, 2.0, 2.5, 3.2};  ///< [m]
  std::vector<double> incidence_knots{0.0, 0.175, 0.349, 0.524, 0.698, 0.873, 1.047, 1.222, 1.396, 1.571};  ///< [rad] every 10 deg
  double sigma_along{0.018};       ///< [m] range noise (the registration's noise model)
  double prior_sigma{0.05};        ///< [m] prior std of each knot's bias (about 0: the data sheet's +-30 mm)
  double smoothness_sigma{0.01};   ///< [m] prior std of the difference between neighbouring knots
  double max_residual{0.1};        ///< [m] returns whose range is off by more are not the target
  double edge_distance{0.015};     ///< [m] rays passing this close to a model edge are left out (mixed pixels)
  double max_incidence{1.31};      ///< [rad] rays more oblique to the face hit are left out (75 deg: the
                                   ///< footprint and mixed returns of grazing beams are not a range bias;
                                   ///< the model keeps its prior there, so compensation leaves them out)
  double loss_scale{3.0};          ///< [sigmas] Cauchy re-weighting (objects not in the model)
  int max_iterations{10};          ///< Gauss-Newton steps
  double step_tolerance{1e-4};     ///< [m, rad] converged when no coefficient or pose moves more
                                   ///< (0.1 mm: small against the 18 mm noise)
  double pose_prior_sigma_translation{1.0};  ///< [m] on the mount's and bodies' change (gauge of the ground)
  double pose_prior_sigma_rotation{1.0};     ///< [rad]
  int point_stride{2};             ///< use every n-th point (speed: a calibration has about 1e6)
  /// The covariance also holds the errors that repeat along a sweep, from how the sweeps' gradients
  /// scatter (a cluster-robust covariance); false: independent noise only (narrower, optimistic
  /// when the floor is uneven or the arm's kinematics are off).
  bool sweep_correlated_errors{true};

  /// Reads {range_knots, incidence_knots_deg, sigma_along, prior_sigma, smoothness_sigma,
  /// max_residual, edge_distance, max_incidence_deg, loss_scale, max_iterations, step_tolerance,
  /// pose_prior_sigma_translation, pose_prior_sigma_rotation, point_stride, sweep_correlated_errors}.
  static RangeBiasOptions FromConfig(const ConfigNode& config);
};

struct RangeBiasSummary {
  bool usable{false};
  std::string message;
  RangeBiasModel model;
  Pose3 T_tool0_laser{Pose3::Identity()};  ///< the mount solved with the bias
  Matrix6d mount_covariance{Matrix6d::Zero()};
  std::vector<Pose3> T_base_body;          ///< the bodies solved with it, in the order given
  int num_points{0};                       ///< points offered
  int num_used{0};                         ///< ... that hit the model, off edges, within max_residual
  double rms_whitened{0.0};                ///< of the used ranges after the fit (about 1 if the model fits)
  double variance_factor{1.0};             ///< the covariance was scaled by this (>= 1: chi^2 per point)
  int iterations{0};
  double seconds{0.0};
  std::vector<std::string> warnings;
  std::string BriefReport() const;
};

/// Identify the bias together with the mount and the free bodies' poses (a joint Gauss-Newton on
/// the range errors along each ray to the face it hits), from the guesses (e.g. a mount
/// calibration's result). The sweeps are raw (scan_assembly's AssembleSweep: no compensation).
RangeBiasSummary IdentifyRangeBias(const std::vector<CalibrationSweep>& sweeps,
                                   const std::vector<RegistrationBody>& bodies, const Pose3& T_tool0_laser_guess,
                                   const RangeBiasOptions& options = {});

/// How a sweep's ranges are corrected (scan assembly applies it; an empty model = off, eq. 6 as
/// the paper writes it).
struct RangeBiasCompensation {
  RangeBiasModel model;           ///< identified; empty: no compensation
  bool compensate{true};          ///< false: eq. 6 as written even if a model is given
  double normal_radius{0.1};      ///< [m] half-size of the neighbourhood that gives a point its surface
                                  ///< normal (incidence); below a cube face, above the range noise
  int min_neighbours{12};         ///< fewer: the incidence is unknown and the point is dropped
  /// Keep a return only where the compensated bias's std is below this fraction of sigma_along:
  /// there the bias left after compensation is small against the noise every point has anyway.
  double max_std_fraction{0.25};
  double sigma_along{0.018};      ///< [m] range noise
  /// Where a return's incidence comes from when a model of the targets is at hand (the
  /// calibration's cube after the joint solve, the workpiece after a first registration): the
  /// face its ray meets in the model (true), or always the PCA normal of its neighbours (false).
  /// The neighbourhood (about +-normal_radius) spans two faces near any edge and all of a brick's
  /// 52 mm side, and the bias is steep in incidence near the normal (cos^n), so normals there bias
  /// the correction: in the exact world the mount solved on normal-compensated cube sweeps moved
  /// 1.8 mm along the beam from the joint solve's (README, issue 12).
  bool incidence_from_model{true};
  double model_gap{0.05};         ///< [m] a ray's model hit counts when within this of its range

  bool active() const { return compensate && !model.empty(); }
  /// Reads {compensate, normal_radius, min_neighbours, max_std_fraction, sigma_along,
  /// incidence: model | normals, model_gap, model: {...}}.
  static RangeBiasCompensation FromConfig(const ConfigNode& config);
};

struct RangeBiasCompensationStats {
  int compensated{0};
  int dropped_uncertain{0};  ///< the model's std there is above the guard
  int dropped_no_normal{0};  ///< too few neighbours for an incidence
  int incidence_from_model{0};  ///< of the compensated: incidence from the model's face
  double mean_correction{0.0};  ///< [m] mean of -b over the compensated points
};

/// Correct each point's range by -b(range, incidence) in place (the point stays on its ray), the
/// incidence from the surface normal of its neighbours (base frame through T_tool0_laser; the
/// along-ray noise is taken out of the neighbourhood's covariance so the normal is unbiased), and
/// drop the points the guard rejects.
/// With `scene` (the targets at their solved poses, base frame) and incidence_from_model, a return
/// whose ray meets a face of the scene within model_gap of its range takes that face's incidence;
/// the others keep their PCA normal's.
RangeBiasCompensationStats CompensateRangeBias(std::vector<SweepPoint>& points, const Pose3& T_tool0_laser,
                                               const RangeBiasCompensation& compensation,
                                               const Scene* scene = nullptr);
/// The same on an assembled cloud (base frame): each point moves along its ray.
RangeBiasCompensationStats CompensateRangeBias(std::vector<RayPoint>& cloud, const RangeBiasCompensation& compensation,
                                               const Scene* scene = nullptr);

/// Surface normals (base frame, unit, facing the ray origins) of the points by PCA of the points
/// within about +-radius (a hash grid's 3x3x3 block of cells); zero where fewer than
/// min_neighbours are there. along_sigma: the range noise taken out of the covariance.
std::vector<Eigen::Vector3d> EstimateNormals(const std::vector<RayPoint>& cloud, double radius, int min_neighbours,
                                             double along_sigma);

}  // namespace ifab
