#include "ifab/base/estimator/point_grid.h"

#include <limits>

namespace ifab::base {

void PointGrid::Build(const std::vector<Eigen::Vector2d>& points, double cell) {
  sorted_.clear();
  index_.clear();
  cell_begin_.clear();
  nx_ = ny_ = 0;
  if (points.empty()) return;
  Eigen::Vector2d lo = points.front(), hi = points.front();
  for (const auto& p : points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  // Cells no smaller than asked; larger when a huge, sparse scene would need too many (the
  // search stays exact for any cell size, only slower).
  const Eigen::Vector2d extent = hi - lo;
  constexpr double kMaxCells = 1 << 20;
  double side = std::max(cell, 1e-6);
  while ((std::floor(extent.x() / side) + 1.0) * (std::floor(extent.y() / side) + 1.0) > kMaxCells) side *= 2.0;
  inv_cell_ = 1.0 / side;
  origin_ = lo;
  nx_ = static_cast<int>(extent.x() * inv_cell_) + 1;
  ny_ = static_cast<int>(extent.y() * inv_cell_) + 1;
  const auto cells = static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_);
  // Counting sort by cell.
  cell_begin_.assign(cells + 1, 0);
  auto cell_of = [&](const Eigen::Vector2d& p) {
    const int ix = std::min(nx_ - 1, static_cast<int>((p.x() - origin_.x()) * inv_cell_));
    const int iy = std::min(ny_ - 1, static_cast<int>((p.y() - origin_.y()) * inv_cell_));
    return static_cast<std::size_t>(iy) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(ix);
  };
  for (const auto& p : points) ++cell_begin_[cell_of(p) + 1];
  for (std::size_t c = 0; c < cells; ++c) cell_begin_[c + 1] += cell_begin_[c];
  sorted_.resize(points.size());
  index_.resize(points.size());
  std::vector<std::uint32_t>& next = scratch_;
  next.assign(cell_begin_.begin(), cell_begin_.end() - 1);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const std::uint32_t k = next[cell_of(points[i])]++;
    sorted_[k] = points[i];
    index_[k] = static_cast<std::uint32_t>(i);
  }
}

}  // namespace ifab::base
