#include "ifab/base/estimator/scan_preprocessing.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

namespace ifab::base {

ScanPreprocessor::ScanPreprocessor(const EstimatorOptions& options, const Pose2& T_base_laser)
    : o_(options), T_base_laser_(T_base_laser) {
  const auto beams = static_cast<std::size_t>(o_.max_beams);
  valid_base_.reserve(beams);
  valid_gap_.reserve(beams);
  chain_before_.reserve(beams);
  chain_after_.reserve(beams);
}

void ScanPreprocessor::Extract(const LaserScan& scan, const Eigen::Vector2d& v_base, double omega) {
  valid_base_.clear();
  const double lo = std::max(o_.min_range, scan.range_min);
  const double hi = std::min(o_.max_range, scan.range_max);
  const bool deskew = scan.time_increment > 0.0 && (omega != 0.0 || v_base.squaredNorm() > 0.0);
  const double mid = 0.5 * static_cast<double>(scan.size() == 0 ? 0 : scan.size() - 1);
  for (std::size_t i = 0; i < scan.size(); ++i) {
    const double r = scan.ranges[i];
    if (!std::isfinite(r) || r < lo || r > hi) continue;
    const double a = scan.Angle(i);
    Eigen::Vector2d p = T_base_laser_ * Eigen::Vector2d(r * std::cos(a), r * std::sin(a));
    if (deskew) {
      // T_mid_i = exp(dt * twist); over a sweep (< 20 ms) the turn is < 0.01 rad, so the
      // rotation to second order and the translation to first are exact to ~1e-6 m.
      const double dt = (static_cast<double>(i) - mid) * scan.time_increment;
      const double th = omega * dt;
      const double c = 1.0 - 0.5 * th * th;
      p = Eigen::Vector2d(c * p.x() - th * p.y(), th * p.x() + c * p.y()) + dt * v_base;
    }
    valid_base_.push_back(p);
  }
  // Distance of each point to its nearer neighbour along the scan (sampling density).
  valid_gap_.resize(valid_base_.size());
  for (std::size_t i = 0; i < valid_base_.size(); ++i) {
    double g = std::numeric_limits<double>::infinity();
    if (i > 0) g = (valid_base_[i] - valid_base_[i - 1]).norm();
    if (i + 1 < valid_base_.size()) g = std::min(g, (valid_base_[i] - valid_base_[i + 1]).norm());
    valid_gap_[i] = g;
  }
}

void ScanPreprocessor::Thin(double spacing, double max_gap, int max_out, std::vector<Eigen::Vector2d>* out,
                            double end_margin, std::vector<char>* near_end) {
  out->clear();
  if (near_end) {
    near_end->clear();
    // Arc length to the previous and to the next chain break.
    const std::size_t n = valid_base_.size();
    chain_before_.resize(n);
    chain_after_.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const double step = i > 0 ? (valid_base_[i] - valid_base_[i - 1]).norm() : 0.0;
      chain_before_[i] = (i == 0 || step > max_gap) ? 0.0 : chain_before_[i - 1] + step;
    }
    for (std::size_t i = n; i-- > 0;) {
      const double step = i + 1 < n ? (valid_base_[i + 1] - valid_base_[i]).norm() : 0.0;
      chain_after_[i] = (i + 1 == n || step > max_gap) ? 0.0 : chain_after_[i + 1] + step;
    }
  }
  const double s2 = spacing * spacing;
  const bool independent = o_.thinning == Thinning::kNoiseIndependent;
  std::size_t prev = valid_base_.size(), prev2 = valid_base_.size();  // the last two candidates
  for (std::size_t i = 0; i < valid_base_.size(); ++i) {
    const Eigen::Vector2d& p = valid_base_[i];
    if (valid_gap_[i] > max_gap) continue;
    bool keep = out->empty();
    if (!keep && !independent) {
      keep = (p - out->back()).squaredNorm() >= s2;
    } else if (!keep && prev < valid_base_.size()) {
      // Decide from the earlier points only: the previous candidate's distance from the last
      // kept point plus one more step like the one before it reaches the spacing.
      const double step = prev2 < valid_base_.size() ? (valid_base_[prev] - valid_base_[prev2]).norm() : 0.0;
      keep = (valid_base_[prev] - out->back()).norm() + step >= spacing;
    }
    prev2 = prev;
    prev = i;
    if (keep) {
      out->push_back(p);
      if (near_end) near_end->push_back(std::min(chain_before_[i], chain_after_[i]) < end_margin);
    }
  }
  const int n = static_cast<int>(out->size());
  if (n > max_out) {
    for (int k = 0; k < max_out; ++k) {
      const auto from = static_cast<std::size_t>(static_cast<long>(k) * n / max_out);
      (*out)[static_cast<std::size_t>(k)] = (*out)[from];
      if (near_end) (*near_end)[static_cast<std::size_t>(k)] = (*near_end)[from];
    }
    out->resize(static_cast<std::size_t>(max_out));
    if (near_end) near_end->resize(static_cast<std::size_t>(max_out));
  }
}

void ScanPreprocessor::ComputeNormals(const std::vector<Eigen::Vector2d>& points, double radius,
                                      std::vector<Eigen::Vector2d>* normals) const {
  normals->clear();
  const double r2 = radius * radius;
  std::size_t cursor = 0;
  for (const auto& p : points) {
    // p is one of the valid points, in the same order: advance the cursor to it.
    while (cursor < valid_base_.size() && (valid_base_[cursor] - p).squaredNorm() > 1e-18) ++cursor;
    if (cursor >= valid_base_.size()) cursor = 0;
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    Eigen::Matrix2d second = Eigen::Matrix2d::Zero();
    int n = 0;
    auto add = [&](const Eigen::Vector2d& q) {
      sum += q;
      second += q * q.transpose();
      ++n;
    };
    for (std::size_t j = cursor; j < valid_base_.size() && (valid_base_[j] - p).squaredNorm() <= r2; ++j) {
      add(valid_base_[j]);
    }
    for (std::size_t j = cursor; j-- > 0 && (valid_base_[j] - p).squaredNorm() <= r2;) add(valid_base_[j]);
    Eigen::Vector2d normal = Eigen::Vector2d::Zero();
    if (n >= 3) {
      const Eigen::Vector2d mean = sum / n;
      const Eigen::Matrix2d cov = second / n - mean * mean.transpose();
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(cov);
      if (es.eigenvalues()(0) < 0.1 * es.eigenvalues()(1)) normal = es.eigenvectors().col(0);
    }
    normals->push_back(normal);
  }
}

// Every sample of the polyline stands for the same length of surface, however sparse the beams
// were (far walls, grazing incidence), so eq. 1's sum does not pull towards where the reference
// happens to be dense nor stick to its sparse samples.
void ScanPreprocessor::Densify(double spacing, double max_link, double end_margin, ReferencePoints* out) {
  auto& pts = out->points;
  pts.clear();
  out->near_end.clear();
  out->normals.clear();
  out->weight.clear();
  const std::size_t n = valid_base_.size();
  const Eigen::Vector2d origin = T_base_laser_.translation();
  constexpr double kMinSinIncidence = 0.17;  // links within 10 deg of the beam are depth jumps
  auto linked = [&](std::size_t i) {  // i to i + 1
    const Eigen::Vector2d d = valid_base_[i + 1] - valid_base_[i];
    const double len = d.norm();
    if (len > max_link) return false;
    if (len < 1e-9) return true;
    const Eigen::Vector2d ray = (valid_base_[i] - origin).normalized();
    return std::abs(ray.x() * d.y() - ray.y() * d.x()) / len >= kMinSinIncidence;
  };
  std::size_t i = 0;
  while (i + 1 < n) {
    if (!linked(i)) {
      ++i;
      continue;
    }
    // A chain from i to j (all links i..j-1 present).
    std::size_t j = i + 1;
    while (j + 1 < n && linked(j)) ++j;
    const std::size_t first = pts.size();
    chain_before_.clear();  // arc position of each sample of this chain
    double arc = 0.0, next = 0.0;
    for (std::size_t k = i; k < j; ++k) {
      const Eigen::Vector2d a = valid_base_[k], b = valid_base_[k + 1];
      const double len = (b - a).norm();
      const Eigen::Vector2d dir = len > 0.0 ? Eigen::Vector2d((b - a) / len) : Eigen::Vector2d(1.0, 0.0);
      for (; next < arc + len; next += spacing) {
        pts.push_back(a + (next - arc) * dir);
        out->normals.emplace_back(-dir.y(), dir.x());
        out->weight.push_back(1.0);
        out->near_end.push_back(0);
        chain_before_.push_back(next);
      }
      arc += len;
    }
    // The chain's last point, unless a sample is already close to it.
    if (arc - chain_before_.back() > 0.5 * spacing) {
      pts.push_back(valid_base_[j]);
      out->normals.push_back(out->normals.back());
      out->weight.push_back(1.0);
      out->near_end.push_back(0);
      chain_before_.push_back(arc);
    }
    // Flag samples within end_margin of either end of the chain.
    for (std::size_t k = first; k < pts.size(); ++k) {
      const double from_start = chain_before_[k - first];
      out->near_end[k] = (from_start < end_margin || arc - from_start < end_margin) ? 1 : 0;
    }
    i = j;
  }
}

void ArcLengthWeights(const std::vector<Eigen::Vector2d>& points, double spacing, double max_gap,
                      ReferenceWeighting weighting, std::vector<double>* weight) {
  weight->assign(points.size(), 1.0);
  if (weighting != ReferenceWeighting::kArcLength) return;
  const double link = std::max(max_gap, 2.0 * spacing);
  for (std::size_t k = 0; k < points.size(); ++k) {
    double w = 0.0;
    for (int side : {-1, 1}) {
      const long j = static_cast<long>(k) + side;
      double half = 0.5 * spacing;
      if (j >= 0 && j < static_cast<long>(points.size())) {
        const double d = (points[static_cast<std::size_t>(j)] - points[k]).norm();
        if (d <= link) half = 0.5 * d;
      }
      w += half;
    }
    (*weight)[k] = w / spacing;
  }
}

}  // namespace ifab::base
