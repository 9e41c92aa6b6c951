#include "ifab/sequencer/top_face.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

namespace ifab::sequencer {
namespace {

// Median and 1.4826 MAD (a robust sigma).
std::pair<double, double> MedianAndSigma(std::vector<double> v) {
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  const double median = *mid;
  for (double& d : v) d = std::abs(d - median);
  std::nth_element(v.begin(), mid, v.end());
  return {median, 1.4826 * *mid};
}

}  // namespace

std::optional<TopFaceMeasurement> MeasureTopFace(const std::vector<RayPoint>& cloud, const Pose3& T_site_base,
                                                 const SiteBox& box, double ground_z) {
  const Pose3 T_box_base = box.T_site_box.inverse(Eigen::Isometry) * T_site_base;
  const Eigen::Vector3d half = 0.5 * box.box.size;
  const Eigen::Vector3d centre = box.T_site_box.translation();
  const double margin = 0.02, window = 0.03, floor_in = 0.25, floor_out = 0.6;
  std::vector<double> top;
  std::vector<Eigen::Vector3d> floor;  // site frame, relative to the box centre
  for (const RayPoint& p : cloud) {
    const Eigen::Vector3d b = T_box_base * p.p;
    if (std::abs(b.x()) < half.x() - margin && std::abs(b.y()) < half.y() - margin &&
        std::abs(b.z() - half.z()) < window) {
      top.push_back((T_site_base * p.p).z());
      continue;
    }
    const Eigen::Vector3d s = T_site_base * p.p - centre;
    const double r = s.head<2>().norm();
    if (r > floor_in && r < floor_out && std::abs(s.z() + centre.z() - ground_z) < window) floor.push_back(s);
  }
  if (top.size() < 30 || floor.size() < 30) return std::nullopt;
  TopFaceMeasurement m;
  m.points = static_cast<int>(top.size());
  const auto [top_z, top_sigma] = MedianAndSigma(top);
  // Floor plane z = a + b x + c y (x, y from the box centre): least squares, then again without
  // the points more than 3 robust sigmas off (a stray return, a brick's foot).
  Eigen::Vector3d abc = Eigen::Vector3d::Zero();
  double floor_sigma = 0.0;
  int used = 0;
  for (int pass = 0; pass < 2; ++pass) {
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    std::vector<double> residuals;
    used = 0;
    for (const auto& s : floor) {
      const Eigen::Vector3d row(1.0, s.x(), s.y());
      const double r = s.z() - row.dot(abc);
      if (pass > 0 && std::abs(r) > 3.0 * floor_sigma) continue;
      A += row * row.transpose();
      rhs += row * s.z();
      ++used;
    }
    if (used < 30) return std::nullopt;
    abc = A.ldlt().solve(rhs);
    for (const auto& s : floor) residuals.push_back(s.z() - Eigen::Vector3d(1.0, s.x(), s.y()).dot(abc));
    floor_sigma = std::max(1e-6, MedianAndSigma(residuals).second);
  }
  m.floor_points = used;
  // The face's median (standard error sqrt(pi / 2) sigma / sqrt(n)) above the plane's value under
  // the centre (about sigma / sqrt(n) for points spread around it).
  m.height = top_z - (abc[0] + centre.z());
  const double se_top = 1.2533 * top_sigma / std::sqrt(static_cast<double>(top.size()));
  const double se_floor = floor_sigma / std::sqrt(static_cast<double>(used));
  m.std = std::hypot(se_top, se_floor);
  return m;
}

}  // namespace ifab::sequencer
