#pragma once
/// \file
/// The reference points' neighbour search for eq. 1's association: a uniform grid of cells
/// about the search radius, the points stored cell by cell. A radius query visits the 3 x 3 (or
/// so) cells that cover its disc and hands every point in them to the result set, which keeps
/// the k nearest within the radius: the same pairs as a kd-tree (nanoflann, before), at a
/// fraction of the cost for a scan's few hundred points along walls. One allocation per
/// keyframe slot (the buffers keep their capacity).

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace ifab::base {

class PointGrid {
 public:
  /// Index (a copy of) `points` in cells of side at least `cell`.
  void Build(const std::vector<Eigen::Vector2d>& points, double cell);

  /// Every point within `radius` of q goes to result.addPoint(squared distance, index); the
  /// result set drops those beyond its radius and keeps the nearest.
  template <class ResultSet>
  void RadiusSearch(const Eigen::Vector2d& q, double radius, ResultSet& result) const {
    if (sorted_.empty()) return;
    const double x0 = (q.x() - radius - origin_.x()) * inv_cell_, x1 = (q.x() + radius - origin_.x()) * inv_cell_;
    const double y0 = (q.y() - radius - origin_.y()) * inv_cell_, y1 = (q.y() + radius - origin_.y()) * inv_cell_;
    if (!(x1 >= 0.0 && y1 >= 0.0 && x0 < nx_ && y0 < ny_)) return;  // the disc misses the grid (or NaN)
    const int ix0 = std::max(0, static_cast<int>(x0)), ix1 = std::min(nx_ - 1, static_cast<int>(x1));
    const int iy0 = std::max(0, static_cast<int>(y0)), iy1 = std::min(ny_ - 1, static_cast<int>(y1));
    for (int iy = iy0; iy <= iy1; ++iy) {
      // The cells ix0..ix1 of a row are contiguous in the sorted points.
      const std::uint32_t begin = cell_begin_[static_cast<std::size_t>(iy * nx_ + ix0)];
      const std::uint32_t end = cell_begin_[static_cast<std::size_t>(iy * nx_ + ix1 + 1)];
      for (std::uint32_t k = begin; k < end; ++k) {
        const double dx = q.x() - sorted_[k].x(), dy = q.y() - sorted_[k].y();
        result.addPoint(dx * dx + dy * dy, index_[k]);
      }
    }
  }

 private:
  double inv_cell_{1.0};
  Eigen::Vector2d origin_{Eigen::Vector2d::Zero()};
  int nx_{0}, ny_{0};
  std::vector<std::uint32_t> cell_begin_;  // nx * ny + 1 offsets into sorted_, row by row
  std::vector<Eigen::Vector2d> sorted_;    // the points, cell by cell
  std::vector<std::uint32_t> index_;       // their indices in the built vector
  std::vector<std::uint32_t> scratch_;     // Build's fill positions
};

}  // namespace ifab::base
