#include "ifab/perception/kinematic_calibration.h"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>

#include "ifab/core/config.h"

namespace ifab {

KinematicCalibrationOptions KinematicCalibrationOptions::FromConfig(const ConfigNode& c) {
  c.ExpectKeys({"model", "joint_offset_sigma_deg", "link_translation_sigma_m", "link_rotation_sigma_deg",
                "max_iterations", "min_views"});
  KinematicCalibrationOptions o;
  if (auto m = c.Find("model")) {
    const auto v = m->As<std::string>();
    if (v == "joint_offsets") o.model = KinematicModel::kJointOffsets;
    else if (v == "links") o.model = KinematicModel::kLinks;
    else m->Fail("joint_offsets or links");
  }
  double offset_deg = o.joint_offset_sigma * 180.0 / M_PI;
  c.ReadPositive("joint_offset_sigma_deg", offset_deg);
  o.joint_offset_sigma = offset_deg * M_PI / 180.0;
  c.ReadPositive("link_translation_sigma_m", o.link_translation_sigma);
  double deg = o.link_rotation_sigma * 180.0 / M_PI;
  c.ReadPositive("link_rotation_sigma_deg", deg);
  o.link_rotation_sigma = deg * M_PI / 180.0;
  c.ReadPositive("max_iterations", o.max_iterations);
  c.ReadPositive("min_views", o.min_views);
  return o;
}

std::string KinematicCalibration::BriefReport() const {
  double t = 0.0, r = 0.0;
  for (const auto& e : link_errors) {
    t = std::max(t, e.translation().norm());
    r = std::max(r, LogSO3(e.linear()).norm());
  }
  std::string s = fmt::format(
      "arm kinematics {}: {} ({} views, {} steps): whitened rms of the views' mounts {:.2f} with the design chain, "
      "{:.2f} fitted; largest segment error {:.2f} mm, {:.4f} deg",
      usable ? "usable" : "not usable", message, views, iterations, rms_design, rms_fitted, 1e3 * t, r * 180 / M_PI);
  if (!joint_offsets.empty()) {
    s += "; joint offsets [deg]:";
    for (double o : joint_offsets) s += fmt::format(" {:.4f}", o * 180 / M_PI);
  }
  return s;
}

Pose3 ChainForwardKinematics(const KDL::Chain& chain, const Vector6d& q, const std::vector<Pose3>& link_errors) {
  Pose3 T = Pose3::Identity();
  int j = 0;
  for (unsigned i = 0; i < chain.getNrOfSegments(); ++i) {
    const KDL::Segment& s = chain.getSegment(i);
    const bool moves = s.getJoint().getType() != KDL::Joint::None;
    T = T * ToPose3(s.pose(moves ? q[j++] : 0.0));
    if (i < link_errors.size()) T = T * link_errors[i];
  }
  return T;
}

namespace {

// A small pose from [x y z rx ry rz].
Pose3 Exp6(const Eigen::Matrix<double, 6, 1>& v) {
  Pose3 p = Pose3::Identity();
  p.linear() = ExpSO3(v.tail<3>());
  p.translation() = v.head<3>();
  return p;
}

// The mount's residual in calibration.h's convention: translation difference, rotation vector of
// the rotation difference about tool0 axes.
Eigen::Matrix<double, 6, 1> MountDifference(const Pose3& a, const Pose3& b) {
  Eigen::Matrix<double, 6, 1> r;
  r.head<3>() = a.translation() - b.translation();
  r.tail<3>() = LogSO3(a.linear() * b.linear().transpose());
  return r;
}

// C^(-1/2) by eigen-decomposition (a direction with no information gets none).
Matrix6d Whitener(const Matrix6d& c) {
  Eigen::SelfAdjointEigenSolver<Matrix6d> es(0.5 * (c + c.transpose()));
  Eigen::Matrix<double, 6, 1> d = es.eigenvalues();
  const double floor = 1e-12 * std::max(d.maxCoeff(), 1e-30);
  for (int i = 0; i < 6; ++i) d[i] = d[i] > floor ? 1.0 / std::sqrt(d[i]) : 0.0;
  return es.eigenvectors() * d.asDiagonal() * es.eigenvectors().transpose();
}

struct Problem {
  const KDL::Chain& chain;
  const std::vector<FlangeObservation>& views;
  std::vector<Matrix6d> whiten;
  std::vector<Pose3> design_fk;  // per view
  Pose3 mount0;
  int segments;        // with an error of their own (all but the last: the mount holds that one)
  bool fit_links;      // false: only the mount and the targets' frame
  KinematicModel model;
  double sigma_t, sigma_r, sigma_offset;
  // Joint offsets: the segment whose tip carries joint k's zero turn (the one before its own),
  // and that turn's axis and a point on it in that tip frame.
  struct Offset {
    int segment;
    Eigen::Vector3d axis, origin;
  };
  std::vector<Offset> offsets;

  int PerError() const { return model == KinematicModel::kLinks ? 6 : 1; }
  int NumErrors() const { return model == KinematicModel::kLinks ? segments : static_cast<int>(offsets.size()); }
  int NumParams() const { return 12 + (fit_links ? PerError() * NumErrors() : 0); }
  int NumResiduals() const {
    return 6 * static_cast<int>(views.size()) + (fit_links ? PerError() * NumErrors() : 0);
  }

  std::vector<Pose3> Links(const Eigen::VectorXd& x) const {
    std::vector<Pose3> e(chain.getNrOfSegments(), Pose3::Identity());
    if (!fit_links) return e;
    if (model == KinematicModel::kLinks) {
      for (int i = 0; i < segments; ++i) e[static_cast<std::size_t>(i)] = Exp6(x.segment<6>(12 + 6 * i));
    } else {
      for (std::size_t k = 0; k < offsets.size(); ++k) {
        const Offset& o = offsets[k];
        Pose3 turn = Pose3::Identity();  // about the axis through o.origin
        turn.linear() = ExpSO3(o.axis * x[12 + static_cast<int>(k)]);
        turn.translation() = o.origin - turn.linear() * o.origin;
        e[static_cast<std::size_t>(o.segment)] = turn;
      }
    }
    return e;
  }
  Pose3 Mount(const Eigen::VectorXd& x) const {
    Pose3 m = mount0;
    m.translation() += x.segment<3>(6);
    m.linear() = ExpSO3(x.segment<3>(9)) * mount0.linear();
    return m;
  }

  Eigen::VectorXd Residuals(const Eigen::VectorXd& x) const {
    Eigen::VectorXd r(NumResiduals());
    const Pose3 W = Exp6(x.head<6>());
    const Pose3 M = Mount(x);
    const std::vector<Pose3> links = Links(x);
    for (std::size_t v = 0; v < views.size(); ++v) {
      // The view's mount as the model predicts it: what the design chain needs at this posture to
      // put the laser where the corrected chain and the one mount put it, in the targets' frame.
      const Pose3 predicted = design_fk[v].inverse() * W * ChainForwardKinematics(chain, views[v].q, links) * M;
      r.segment<6>(6 * static_cast<int>(v)) = whiten[v] * MountDifference(predicted, views[v].T_tool0_laser);
    }
    const int o = 6 * static_cast<int>(views.size());
    if (fit_links && model == KinematicModel::kLinks) {
      for (int i = 0; i < segments; ++i) {
        r.segment<3>(o + 6 * i) = x.segment<3>(12 + 6 * i) / sigma_t;
        r.segment<3>(o + 6 * i + 3) = x.segment<3>(15 + 6 * i) / sigma_r;
      }
    } else if (fit_links) {
      for (int k = 0; k < static_cast<int>(offsets.size()); ++k) r[o + k] = x[12 + k] / sigma_offset;
    }
    return r;
  }

  // Gauss-Newton with forward-difference Jacobians (a few dozen unknowns, a few dozen residuals).
  Eigen::VectorXd Solve(int max_iterations, int* iterations) const {
    Eigen::VectorXd x = Eigen::VectorXd::Zero(NumParams());
    *iterations = 0;
    double cost = Residuals(x).squaredNorm();
    for (int it = 0; it < max_iterations; ++it) {
      const Eigen::VectorXd r = Residuals(x);
      Eigen::MatrixXd J(r.size(), x.size());
      for (int k = 0; k < x.size(); ++k) {
        Eigen::VectorXd xk = x;
        const double h = 1e-7;
        xk[k] += h;
        J.col(k) = (Residuals(xk) - r) / h;
      }
      // A tiny damping keeps the directions nothing sees (without a prior: W and M share some) finite.
      Eigen::MatrixXd H = J.transpose() * J;
      H.diagonal().array() += 1e-9 * (1.0 + H.diagonal().array());
      const Eigen::VectorXd dx = -H.ldlt().solve(J.transpose() * r);
      x += dx;
      *iterations = it + 1;
      const double next = Residuals(x).squaredNorm();
      const bool done = dx.norm() < 1e-10 || cost - next < 1e-10 * (1.0 + cost);
      cost = next;
      if (done) break;
    }
    return x;
  }
};

double Rms(const Eigen::VectorXd& r, int n) { return n > 0 ? std::sqrt(r.head(n).squaredNorm() / n) : 0.0; }

}  // namespace

KinematicCalibration CalibrateArmKinematics(const KDL::Chain& design, const std::vector<FlangeObservation>& views,
                                            const Pose3& T_tool0_laser_guess,
                                            const KinematicCalibrationOptions& options) {
  KinematicCalibration out;
  out.views = static_cast<int>(views.size());
  out.link_errors.assign(design.getNrOfSegments(), Pose3::Identity());
  out.T_tool0_laser = T_tool0_laser_guess;
  if (out.views < options.min_views) {
    out.message = fmt::format("{} usable views, {} needed", out.views, options.min_views);
    return out;
  }
  Problem p{design,
            views,
            {},
            {},
            T_tool0_laser_guess,
            static_cast<int>(design.getNrOfSegments()) - 1,
            false,
            options.model,
            options.link_translation_sigma,
            options.link_rotation_sigma,
            options.joint_offset_sigma,
            {}};
  // Joint k's zero turn sits at the tip of the segment before its own (KDL gives the joint's axis
  // and origin in that frame). The first joint's has no such segment: the targets' frame takes it;
  // the last joint's turns the mount about its own axis, and the mount takes it.
  int last_joint = -1;
  for (unsigned i = 0; i < design.getNrOfSegments(); ++i)
    if (design.getSegment(i).getJoint().getType() != KDL::Joint::None) last_joint = static_cast<int>(i);
  for (int i = 1; i < last_joint; ++i) {
    const KDL::Joint& j = design.getSegment(static_cast<unsigned>(i)).getJoint();
    if (j.getType() == KDL::Joint::None) continue;
    const KDL::Vector a = j.JointAxis(), o = j.JointOrigin();
    p.offsets.push_back({i - 1, Eigen::Vector3d(a.x(), a.y(), a.z()).normalized(),
                         Eigen::Vector3d(o.x(), o.y(), o.z())});
  }
  for (const auto& v : views) {
    p.whiten.push_back(Whitener(v.covariance));
    p.design_fk.push_back(ChainForwardKinematics(design, v.q));
  }
  const int n = 6 * out.views;
  int iterations = 0;
  // The design chain: one mount and the targets' correction only.
  const Eigen::VectorXd x0 = p.Solve(options.max_iterations, &iterations);
  const Eigen::VectorXd r0 = p.Residuals(x0);
  out.rms_design = Rms(r0, n);
  p.fit_links = true;
  const Eigen::VectorXd x = p.Solve(options.max_iterations, &out.iterations);
  const Eigen::VectorXd r = p.Residuals(x);
  out.rms_fitted = Rms(r, n);
  for (int v = 0; v < out.views; ++v) {
    out.view_rms_design.push_back(std::sqrt(r0.segment<6>(6 * v).squaredNorm() / 6));
    out.view_rms_fitted.push_back(std::sqrt(r.segment<6>(6 * v).squaredNorm() / 6));
  }
  out.link_errors = p.Links(x);
  if (options.model == KinematicModel::kJointOffsets)
    for (std::size_t k = 0; k < p.offsets.size(); ++k) out.joint_offsets.push_back(x[12 + static_cast<int>(k)]);
  out.T_tool0_laser = p.Mount(x);
  out.T_targets_correction = Exp6(x.head<6>());
  // Usable only when the fitted model explains the views to the std each one reports, and its errors
  // stay within their prior (a chi-square test at about 3 sigma): a fit that leaves the views
  // disagreeing has put into the arm what belongs elsewhere, and the design chain is kept.
  // With the prior's residuals counted, each error brings one residual and one unknown: what is
  // left is the views' 6 per view less the mount and the targets' frame.
  const double dof = std::max(1, n - 12);
  const double sum_sq = r.squaredNorm();
  const double bound = dof + 3.0 * std::sqrt(2.0 * dof);
  out.usable = std::isfinite(sum_sq) && sum_sq <= bound;
  out.message = out.usable ? "fitted"
                           : fmt::format("the fitted views still disagree beyond their std (chi-square {:.1f} > {:.1f})",
                                         sum_sq, bound);
  return out;
}

}  // namespace ifab
