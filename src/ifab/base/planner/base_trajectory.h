#pragma once
/// \file
/// The planned base trajectory as the controller consumes it (paper Sec. III-C): a
/// time-independent sequence of 2D poses, each with the nominal linear and angular velocity.

#include <iosfwd>
#include <string>
#include <vector>

#include "ifab/core/se2.h"

namespace ifab::base {

struct BaseTrajectory {
  struct Point {
    Pose2 pose;          ///< T_site_base at this point
    double v{0.0};       ///< nominal linear velocity along base x [m/s] (negative: reversing)
    double omega{0.0};   ///< nominal angular velocity [rad/s]
  };
  std::vector<Point> points;
  double duration{0.0};  ///< nominal duration at the nominal velocities [s]

  bool empty() const { return points.empty(); }
  std::size_t size() const { return points.size(); }
  /// Path length of the translation [m].
  double Length() const;

  /// CSV with header "index,x,y,theta,v,omega" (SI units), to a stream (the module writes no
  /// files; `ifab plan-base --trajectory` saves it).
  void WriteCsv(std::ostream& out) const;
};

}  // namespace ifab::base
