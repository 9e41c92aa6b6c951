#include "ifab/sequencer/top_face.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <tuple>
#include <utility>

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

std::optional<FootprintMeasurement> MeasureTopFootprint(const std::vector<RayPoint>& cloud, const Pose3& T_site_base,
                                                        const SiteBox& box, double ground_z,
                                                        const std::vector<RayPoint>* edge_cloud) {
  const Pose3 T_box_base = box.T_site_box.inverse(Eigen::Isometry) * T_site_base;
  const Eigen::Vector3d half = 0.5 * box.box.size;
  // Windows: a return within 3 cm of the top plane or of the floor's design height along its ray
  // is on it (the laser's noise is 10-18 mm along the ray; DIN 18202 lets the floor stray 10 mm
  // over 4 m); the same on both, so a mixed pixel is as likely to count as either. Edges are
  // searched 25 mm either side of the modelled one (EN 771-1 T1 and R1 together put a brick's
  // length within about +-10 mm of its design), and a corner's 15 mm are left out.
  const double margin = 0.02, on_plane = 0.03, search = 0.025, corner = 0.015;
  // The top face's height in the box frame: the median of the points on it. The stack's height
  // drifts from its design brick by brick (T1 allows 2.9 mm a brick), so the face is first looked
  // for 8 cm either side of the modelled one (inside the footprint nothing else is seen from
  // above), then the points within 3 cm of that.
  std::vector<Eigen::Vector3d> inside;
  Eigen::Vector3d mean_origin = Eigen::Vector3d::Zero();
  for (const RayPoint& p : cloud) {
    const Eigen::Vector3d b = T_box_base * p.p;
    mean_origin += T_box_base * p.origin;
    if (std::abs(b.x()) < half.x() - margin && std::abs(b.y()) < half.y() - margin && std::abs(b.z() - half.z()) < 0.08)
      inside.push_back(b);
  }
  if (inside.size() < 30) return std::nullopt;
  mean_origin /= static_cast<double>(cloud.size());
  std::vector<double> top;
  for (const auto& b : inside) top.push_back(b.z());
  const double z_coarse = MedianAndSigma(top).first;
  top.clear();
  for (const auto& b : inside)
    if (std::abs(b.z() - z_coarse) < on_plane) top.push_back(b.z());
  if (top.size() < 30) return std::nullopt;
  const auto [z_top, z_sigma] = MedianAndSigma(top);
  const double z_se = 1.2533 * z_sigma / std::sqrt(static_cast<double>(top.size()));

  // Each ray cut with the top plane, weighted by where it returned: on the plane 1, on the floor 0,
  // in between 1/2. A beam that straddles an edge returns a mixed range between the two
  // surfaces; as often on one side of the edge as on the other, so a half each side balances.
  struct Cut {
    Eigen::Vector2d q;
    double weight;
    double cot;  // horizontal over vertical run of the ray: a height error moves q by this much
  };
  const Pose3 T_site_box_frame = box.T_site_box;
  std::vector<Cut> cuts;
  for (const RayPoint& p : edge_cloud ? *edge_cloud : cloud) {
    const Eigen::Vector3d o = T_box_base * p.origin, e = T_box_base * p.p;
    Eigen::Vector3d d = e - o;
    const double r = d.norm();
    if (r <= 0.0) continue;
    d /= r;
    if (d.z() > -0.1) continue;  // the plane is met too obliquely to place the cut
    const double s = (z_top - o.z()) / d.z();
    const Eigen::Vector3d o_site = T_site_box_frame * o, d_site = T_site_box_frame.linear() * d;
    const double s_floor = (ground_z - o_site.z()) / d_site.z();
    if (s <= 0.0 || s_floor <= s) continue;
    double weight;
    if (std::abs(r - s) < on_plane) weight = 1.0;
    else if (std::abs(r - s_floor) < on_plane) weight = 0.0;
    else if (r > s && r < s_floor) weight = 0.5;
    else continue;  // before the plane or beyond the floor: something else
    cuts.push_back({(o + s * d).head<2>(), weight, d.head<2>().norm() / -d.z()});
  }

  FootprintMeasurement m;
  for (int a = 0; a < 2; ++a) {
    const int other = 1 - a;
    const double far = mean_origin[a] < 0.0 ? 1.0 : -1.0;  // the edge away from the laser
    double edge = half[a];                                 // u: along the axis, towards the far edge
    int used = 0;
    double cot = 0.0, density = 0.0, spread = 0.0;
    for (int pass = 0; pass < 3; ++pass) {  // centre the window on the last estimate
      std::vector<std::pair<double, double>> u;  // (u, weight)
      cot = 0.0;
      for (const Cut& c : cuts) {
        const double v = far * c.q[a];
        if (std::abs(c.q[other]) < half[other] - corner && std::abs(v - edge) < search) {
          u.emplace_back(v, c.weight);
          cot += c.cot;
        }
      }
      // The weight well inside the face and well past it (8 mm from the edge: past the beam's
      // width and the mixed pixels), which the range noise keeps a little off 1 and 0.
      double in = 0.0, out = 0.0;
      int n_in = 0, n_out = 0;
      for (const auto& [v, w] : u) {
        if (v < edge - 0.008) in += w, ++n_in;
        if (v > edge + 0.008) out += w, ++n_out;
      }
      if (n_in < 10 || n_out < 10 || in / n_in - out / n_out < 0.5) {
        used = 0;
        break;
      }
      in /= n_in;
      out /= n_out;
      used = static_cast<int>(u.size());
      std::sort(u.begin(), u.end());
      // The edge has as much weight missing before it as there is extra weight past it; each ray
      // passed moves that balance by in - out, so it lies `k` rays along.
      double excess = 0.0;
      for (const auto& x : u) excess += x.second - out;
      const double k = excess / (in - out);
      const auto i = static_cast<std::size_t>(std::clamp(k, 0.0, static_cast<double>(u.size() - 1)));
      edge = 0.5 * (u[i == 0 ? 0 : i - 1].first + u[i].first);
      spread = 0.0;
      for (std::size_t j = 0; j < u.size(); ++j) spread += std::pow(u[j].second - (j < i ? in : out), 2);
      spread = std::sqrt(spread) / (in - out);  // in rays
      cot /= static_cast<double>(used);
      density = static_cast<double>(used) / (2.0 * search);
    }
    m.edge_rays[static_cast<std::size_t>(a)] = used;
    if (used == 0) continue;
    // The near face: the median of the points on it. A point counts when its ray meets the face's
    // plane 8 mm in from the face's top and bottom edges (the brick's height below the measured
    // top) and its corners, and returns within 3 cm of it: chosen by the ray's direction, as the
    // range's noise would mix in the top face and the brick below. Twice, the plane at the first
    // median the second time.
    double near_u = -half[a], near_sigma = 0.0;
    std::size_t near_points = 0;
    for (int pass = 0; pass < 2; ++pass) {
      std::vector<double> near;
      for (const RayPoint& p : cloud) {
        const Eigen::Vector3d o = T_box_base * p.origin, e = T_box_base * p.p;
        Eigen::Vector3d d = e - o;
        const double r = d.norm();
        if (r <= 0.0 || far * d[a] < 0.1 * r) continue;  // the face is met too obliquely
        d /= r;
        const double s = (far * near_u - o[a]) / d[a];
        const Eigen::Vector3d c = o + s * d;
        if (s > 0.0 && std::abs(r - s) < on_plane && std::abs(c[other]) < half[other] - corner &&
            c.z() < z_top - 0.008 && c.z() > z_top - box.box.size.z() + 0.008)
          near.push_back(far * e[a]);
      }
      near_points = near.size();
      if (near_points < 30) break;
      std::tie(near_u, near_sigma) = MedianAndSigma(near);
    }
    if (near_points < 30) continue;
    m.measured[static_cast<std::size_t>(a)] = true;
    m.size[a] = edge - near_u;
    m.centre_offset[a] = far * 0.5 * (edge + near_u);
    // The balance's noise (each ray's weight off the step, in rays, at the rays' spacing), the
    // plane's height error carried along the rays, and the near face's median.
    m.std[a] = std::hypot(std::hypot((spread + 0.3) / density, cot * z_se),
                          1.2533 * near_sigma / std::sqrt(static_cast<double>(near_points)));
  }
  if (!m.measured[0] && !m.measured[1]) return std::nullopt;
  return m;
}

}  // namespace ifab::sequencer
