#include "ifab/base/planner/base_trajectory.h"

#include <fmt/format.h>

#include <ostream>

namespace ifab::base {

double BaseTrajectory::Length() const {
  double l = 0.0;
  for (std::size_t i = 1; i < points.size(); ++i) l += TranslationDistance(points[i - 1].pose, points[i].pose);
  return l;
}

void BaseTrajectory::WriteCsv(std::ostream& out) const {
  out << "index,x,y,theta,v,omega\n";
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Point& p = points[i];
    out << fmt::format("{},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f}\n", i, p.pose.x, p.pose.y, p.pose.theta, p.v,
                       p.omega);
  }
}

}  // namespace ifab::base
