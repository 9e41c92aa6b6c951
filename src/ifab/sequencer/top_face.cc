#include "ifab/sequencer/top_face.h"

#include <algorithm>
#include <cmath>

namespace ifab::sequencer {

std::optional<TopFaceMeasurement> MeasureTopFace(const std::vector<RayPoint>& cloud, const Pose3& T_site_base,
                                                 const SiteBox& box) {
  const Pose3 T_box_base = box.T_site_box.inverse(Eigen::Isometry) * T_site_base;
  const Eigen::Vector3d half = 0.5 * box.box.size;
  const double margin = 0.02, window = 0.03;
  std::vector<double> dz;
  for (const RayPoint& p : cloud) {
    const Eigen::Vector3d b = T_box_base * p.p;
    if (std::abs(b.x()) < half.x() - margin && std::abs(b.y()) < half.y() - margin &&
        std::abs(b.z() - half.z()) < window)
      dz.push_back(b.z() - half.z());
  }
  if (dz.size() < 30) return std::nullopt;
  const auto mid = dz.begin() + static_cast<std::ptrdiff_t>(dz.size() / 2);
  std::nth_element(dz.begin(), mid, dz.end());
  TopFaceMeasurement m;
  m.offset = *mid;
  m.points = static_cast<int>(dz.size());
  std::vector<double> dev;
  dev.reserve(dz.size());
  for (double d : dz) dev.push_back(std::abs(d - m.offset));
  const auto mid_dev = dev.begin() + static_cast<std::ptrdiff_t>(dev.size() / 2);
  std::nth_element(dev.begin(), mid_dev, dev.end());
  // sigma = 1.4826 MAD; the median's standard error is sqrt(pi / 2) sigma / sqrt(n).
  m.std = 1.2533 * 1.4826 * *mid_dev / std::sqrt(static_cast<double>(dz.size()));
  return m;
}


}  // namespace ifab::sequencer
