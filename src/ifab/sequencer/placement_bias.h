#pragma once
/// \file
/// Where the arm puts a brick relative to where it was sent, learned from the bricks already
/// placed. An industrial arm without absolute-accuracy calibration misses a Cartesian goal by
/// millimetres (link lengths and joint zeros off their nominal values), and the registration's
/// own systematic errors (range bias, mount) add to it; both repeat from stand to stand, where
/// the arm takes nearly the same posture. A constant miss walks a stack away from the stands
/// brick by brick. Each registration sees the last brick against the stack below it: one look,
/// along each measured axis, at the miss minus the correction that brick was sent with.

#include <Eigen/Core>
#include <map>
#include <string>

namespace ifab::sequencer {

struct PlacementBiasOptions {
  double prior_std{0.003};   ///< [m] per axis, before any look
  double scatter{0.0005};    ///< [m] one placement's spread about the bias, beyond the look's own error
  double walk{0.0002};       ///< [m] how far the bias may move from one placement to the next
  /// Scale the looks' noise (covariance plus scatter) by what the innovations show: the mean
  /// normalized innovation squared per degree of freedom, once it exceeds 1 (Mehra's
  /// covariance matching), counted from the third look (the first two meet the wide prior). A look whose reported covariance is too
  /// small then pulls the bias less, and the bias's covariance stays true.
  bool adapt_noise{false};
};

/// Whether a look at a placed brick can be a miss of the arm: `miss` [m] (where the look puts the
/// brick, from where it was meant to land) against what an uncalibrated arm may miss by (the
/// prior and the scatter) plus the look's own covariance `look_covariance` [m^2]. A look beyond
/// the chi-square bound of 2 dof at 99.9 % is a wrong registration (a brick fitted an edge off),
/// not a miss. `mahalanobis2`, if given, receives the squared Mahalanobis distance.
bool ArmCanExplainMiss(const Eigen::Vector2d& miss, const Eigen::Matrix2d& look_covariance,
                       const PlacementBiasOptions& options, double* mahalanobis2 = nullptr);
/// The chi-square quantile of 2 dof at 99.9 %: -2 ln(1 - 0.999) (closed form for 2 dof).
inline constexpr double kChi2Dof2P999 = 13.8155;

/// Mehra's covariance matching of the looks' noise (PlacementBiasOptions::adapt_noise): the mean
/// normalized innovation squared per degree of freedom, once above 1, scales the looks' noise.
/// The first two looks meet the wide prior (their innovation is mostly the bias itself) and are
/// not counted; from the third on, the innovations are mostly the looks' noise.
class LookNoiseScale {
 public:
  /// One innovation's normalized square `nis` over `dof`, before the filter's look number `looks` + 1.
  void Add(bool enabled, int looks, double nis, int dof);
  double scale() const { return scale_; }

 private:
  double nis_sum_{0.0};
  int nis_dof_{0};
  double scale_{1.0};
};

/// A Kalman filter on the miss (x, y in the frame the bricks are sent in: the base's).
class PlacementBiasFilter {
 public:
  explicit PlacementBiasFilter(PlacementBiasOptions options = {});

  /// One look: `z` [m] is the miss seen along the unit direction `u` (the brick's measured offset
  /// from where it should be, plus the correction it was sent with), `std` the look's own error.
  void Update(const Eigen::Vector2d& u, double z, double std);
  /// One look at both axes: `z` [m] the miss plus the correction sent, `covariance` [m^2] the
  /// look's own.
  void Update(const Eigen::Vector2d& z, const Eigen::Matrix2d& covariance);
  /// Where one placement truly missed (base frame [m]), from a look `z` at it (the miss plus the
  /// correction sent, as Update takes) with covariance `covariance`, fused with what the filter
  /// expected before the look (its bias, with its covariance and the placement's scatter). The
  /// look's noise is scaled as Update would scale it. Call before Update with the same look.
  Eigen::Vector2d FusedMiss(const Eigen::Vector2d& z, const Eigen::Matrix2d& covariance) const;
  /// The random walk to the next placement (after the looks at the last one).
  void Predict();

  const Eigen::Vector2d& bias() const { return bias_; }
  const Eigen::Matrix2d& covariance() const { return covariance_; }
  int looks() const { return looks_; }
  /// The factor the looks' noise is scaled by (adapt_noise; 1 otherwise).
  double noise_scale() const { return noise_.scale(); }

 private:
  PlacementBiasOptions o_;
  LookNoiseScale noise_;
  Eigen::Vector2d bias_{Eigen::Vector2d::Zero()};
  Eigen::Matrix2d covariance_;
  int looks_{0};
};

/// Which misses the mission keeps apart.
enum class PlacementBiasScope {
  kRobot,     ///< one for the robot (the arm's posture repeats at every stand)
  kPosition,  ///< one per building position (each stand also has its own floor under the tracks,
              ///< its own view of the stack's top, and the wrist turns by its own angle there)
  /// Both: a stand's miss is the robot's part, learned from every stand's looks, plus the stand's
  /// own, learned from its looks (a hierarchical model: the first brick at a stand is sent
  /// against what the other stands showed, and the stands' parts are kept apart thereafter).
  kRobotAndPosition,
};

/// The filters a mission keeps, by scope. Every filter walks at each placement: the stack grows
/// for all of them (with both parts, each walks by walk / sqrt(2), so a stand's miss walks by walk).
class PlacementBiasLearner {
 public:
  explicit PlacementBiasLearner(PlacementBiasOptions options = {},
                                PlacementBiasScope scope = PlacementBiasScope::kRobot);

  /// The miss expected at `position` [m] (base frame) and its covariance [m^2].
  Eigen::Vector2d Bias(const std::string& position);
  Eigen::Matrix2d Covariance(const std::string& position);
  /// One look at a brick placed from `position` (as PlacementBiasFilter::Update takes it).
  void Update(const std::string& position, const Eigen::Vector2d& u, double z, double std);
  void Update(const std::string& position, const Eigen::Vector2d& z, const Eigen::Matrix2d& covariance);
  /// As PlacementBiasFilter::FusedMiss, at `position`.
  Eigen::Vector2d FusedMiss(const std::string& position, const Eigen::Vector2d& z, const Eigen::Matrix2d& covariance);
  /// To the next placement: every filter's random walk.
  void Predict();

 private:
  PlacementBiasFilter& For(const std::string& position);
  // kRobotAndPosition: the joint state [robot; stand 1; stand 2; ...] (2 rows each, stands in the
  // order first seen) with its covariance, and a stand's rows (added with the prior on first use).
  int Block(const std::string& position);
  Eigen::MatrixXd H(int block) const;  // 2 x n: the stand's miss = robot part + its own
  void UpdateJoint(const Eigen::MatrixXd& Hm, const Eigen::VectorXd& z, const Eigen::MatrixXd& R);

  PlacementBiasOptions o_;
  PlacementBiasScope scope_;
  PlacementBiasFilter shared_;
  std::map<std::string, PlacementBiasFilter> by_position_;
  std::map<std::string, int> blocks_;
  Eigen::VectorXd x_;
  Eigen::MatrixXd P_;
  int looks_{0};
  LookNoiseScale noise_;
};

}  // namespace ifab::sequencer
