#pragma once
// Synthetic laser scans for the estimator's tests: ray casting in a 2D world of line segments.
// (Algorithm tests do not use the simulator; this is a minimal stand-in.)

#include <Eigen/Core>
#include <cmath>
#include <limits>
#include <vector>

#include "ifab/core/random.h"
#include "ifab/core/se2.h"
#include "ifab/msgs/msgs.h"

namespace ifab::base::testing {

struct Segment {
  Eigen::Vector2d a;
  Eigen::Vector2d b;
};
using World = std::vector<Segment>;

// Closed polygon through the vertices.
inline void AddPolygon(const std::vector<Eigen::Vector2d>& v, World* w) {
  for (std::size_t i = 0; i < v.size(); ++i) w->push_back({v[i], v[(i + 1) % v.size()]});
}

// An L-shaped room with a few boxes: rich enough to pin down x, y and theta.
inline World LRoom() {
  World w;
  AddPolygon({{-3, -2}, {6, -2}, {6, 1.5}, {2.5, 1.5}, {2.5, 4}, {-3, 4}}, &w);
  AddPolygon({{1.0, -1.0}, {1.6, -1.0}, {1.6, -0.4}, {1.0, -0.4}}, &w);
  AddPolygon({{-2.0, 2.5}, {-1.2, 2.5}, {-1.2, 3.0}, {-2.0, 3.0}}, &w);
  AddPolygon({{4.0, 0.3}, {4.4, 0.3}, {4.4, 0.7}, {4.0, 0.7}}, &w);
  return w;
}

// Regular polygon room of n sides (n large: a circle) of radius r about the origin.
inline World RegularRoom(int n, double r, double phase = 0.0) {
  std::vector<Eigen::Vector2d> v;
  for (int i = 0; i < n; ++i) {
    const double a = phase + 2.0 * M_PI * i / n;
    v.emplace_back(r * std::cos(a), r * std::sin(a));
  }
  World w;
  AddPolygon(v, &w);
  return w;
}

// Two long parallel walls along x (a featureless corridor).
inline World Corridor(double half_width = 1.0, double length = 200.0) {
  return {{{-length / 2, -half_width}, {length / 2, -half_width}},
          {{-length / 2, half_width}, {length / 2, half_width}}};
}

struct ScanSpec {
  int beams{1081};
  double fov{DegToRad(270.0)};
  double range_max{30.0};
  double sigma{0.0};  // range noise [m]
};

// Range along the ray from o in direction u to the nearest segment (inf if none).
inline double CastRay(const World& w, const Eigen::Vector2d& o, const Eigen::Vector2d& u) {
  double best = std::numeric_limits<double>::infinity();
  for (const Segment& s : w) {
    const Eigen::Vector2d e = s.b - s.a;
    const double den = u.x() * e.y() - u.y() * e.x();
    if (std::abs(den) < 1e-12) continue;
    const Eigen::Vector2d d = s.a - o;
    const double t = (d.x() * e.y() - d.y() * e.x()) / den;
    const double v = (d.x() * u.y() - d.y() * u.x()) / den;
    if (t > 0.0 && v >= 0.0 && v <= 1.0) best = std::min(best, t);
  }
  return best;
}

inline LaserScan CastScan(const World& w, const Pose2& T_world_laser, Seconds t,
                          const ScanSpec& spec = {}, RandomStream* rng = nullptr) {
  LaserScan scan;
  scan.stamp.t = t;
  scan.angle_min = -0.5 * spec.fov;
  scan.angle_increment = spec.fov / (spec.beams - 1);
  scan.range_max = spec.range_max;
  scan.ranges.resize(static_cast<std::size_t>(spec.beams));
  for (int i = 0; i < spec.beams; ++i) {
    const double a = T_world_laser.theta + scan.Angle(static_cast<std::size_t>(i));
    double r = CastRay(w, T_world_laser.translation(), {std::cos(a), std::sin(a)});
    if (rng && std::isfinite(r)) r += rng->Normal(spec.sigma);
    scan.ranges[static_cast<std::size_t>(i)] = r <= spec.range_max ? r : LaserScan::kNoReturn;
  }
  return scan;
}

inline GyroSample Gyro(Seconds t, double rate_z) {
  GyroSample g;
  g.stamp.t = t;
  g.rate.z() = rate_z;
  return g;
}

}  // namespace ifab::base::testing
