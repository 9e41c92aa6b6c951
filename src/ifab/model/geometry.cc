#include "ifab/model/geometry.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ifab/core/error.h"

namespace ifab {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Closest point on segment [a, b] to p.
Eigen::Vector3d ClosestOnSegment(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                 const Eigen::Vector3d& p, double* s_out = nullptr) {
  const Eigen::Vector3d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double s = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  if (s_out) *s_out = s;
  return a + s * ab;
}

ClosestPoint ClosestPlane(const Plane& plane, const Eigen::Vector3d& p) {
  const double signed_distance = plane.normal.dot(p) - plane.offset;
  return {p - signed_distance * plane.normal, plane.normal, std::abs(signed_distance), Feature::kFace};
}

ClosestPoint ClosestPolygon(const ConvexPolygon& poly, const Eigen::Vector3d& p) {
  const double signed_distance = poly.normal().dot(p) - poly.offset();
  const Eigen::Vector3d projected = p - signed_distance * poly.normal();
  if (poly.ContainsProjected(projected))
    return {projected, poly.normal(), std::abs(signed_distance), Feature::kFace};
  ClosestPoint best;
  best.distance = kInf;
  best.normal = poly.normal();
  const auto& v = poly.vertices();
  for (std::size_t i = 0; i < v.size(); ++i) {
    double s = 0;
    const Eigen::Vector3d c = ClosestOnSegment(v[i], v[(i + 1) % v.size()], p, &s);
    const double d = (p - c).norm();
    if (d < best.distance) {
      best.point = c;
      best.distance = d;
      best.feature = (s <= 0.0 || s >= 1.0) ? Feature::kVertex : Feature::kEdge;
    }
  }
  return best;
}

ClosestPoint ClosestBox(const Box& box, const Eigen::Vector3d& p) {
  const Eigen::Vector3d h = 0.5 * box.size;
  const Eigen::Vector3d clamped = p.cwiseMax(-h).cwiseMin(h);
  ClosestPoint out;
  if ((clamped - p).squaredNorm() > 0.0) {  // outside
    out.point = clamped;
    out.distance = (p - clamped).norm();
    int on_faces = 0;
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) {
      if (std::abs(p[k]) > h[k]) {
        ++on_faces;
        n[k] = p[k] > 0 ? 1.0 : -1.0;
      }
    }
    out.normal = n.normalized();
    out.feature = on_faces == 1 ? Feature::kFace : on_faces == 2 ? Feature::kEdge : Feature::kVertex;
    if (on_faces > 1) {  // report the normal of the face nearest along the largest excess
      int kmax = 0;
      double emax = -1;
      for (int k = 0; k < 3; ++k) {
        const double e = std::abs(p[k]) - h[k];
        if (e > emax) { emax = e; kmax = k; }
      }
      out.normal = Eigen::Vector3d::Zero();
      out.normal[kmax] = p[kmax] > 0 ? 1.0 : -1.0;
    }
    return out;
  }
  // inside: nearest face
  int kbest = 0;
  double dbest = kInf;
  for (int k = 0; k < 3; ++k) {
    const double d = h[k] - std::abs(p[k]);
    if (d < dbest) { dbest = d; kbest = k; }
  }
  out.point = p;
  out.point[kbest] = p[kbest] >= 0 ? h[kbest] : -h[kbest];
  out.normal = Eigen::Vector3d::Zero();
  out.normal[kbest] = p[kbest] >= 0 ? 1.0 : -1.0;
  out.distance = dbest;
  out.feature = Feature::kFace;
  return out;
}

std::optional<RayHit> RayPlane(const Eigen::Vector3d& n, double offset, const Eigen::Vector3d& o,
                               const Eigen::Vector3d& d, double t_min, double t_max) {
  const double denom = n.dot(d);
  if (std::abs(denom) < 1e-12) return std::nullopt;
  const double t = (offset - n.dot(o)) / denom;
  if (!(t > t_min && t < t_max)) return std::nullopt;
  return RayHit{t, denom < 0 ? n : Eigen::Vector3d(-n)};
}

std::optional<RayHit> RayBox(const Box& box, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                             double t_min, double t_max) {
  const Eigen::Vector3d h = 0.5 * box.size;
  double t0 = -kInf, t1 = kInf;
  int axis0 = -1;
  for (int k = 0; k < 3; ++k) {
    if (std::abs(d[k]) < 1e-15) {
      if (o[k] < -h[k] || o[k] > h[k]) return std::nullopt;
      continue;
    }
    double ta = (-h[k] - o[k]) / d[k], tb = (h[k] - o[k]) / d[k];
    if (ta > tb) std::swap(ta, tb);
    if (ta > t0) { t0 = ta; axis0 = k; }
    t1 = std::min(t1, tb);
  }
  if (t0 > t1 || axis0 < 0) return std::nullopt;
  if (!(t0 > t_min && t0 < t_max)) return std::nullopt;  // only entering hits from outside
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  n[axis0] = d[axis0] > 0 ? -1.0 : 1.0;
  return RayHit{t0, n};
}

}  // namespace

ConvexPolygon::ConvexPolygon(std::vector<Eigen::Vector3d> vertices) : vertices_(std::move(vertices)) {
  IFAB_THROW_UNLESS(vertices_.size() >= 3, "polygon: expected at least 3 vertices, got {}", vertices_.size());
  Eigen::Vector3d n = Eigen::Vector3d::Zero();  // Newell's method: robust polygon normal
  for (std::size_t i = 0; i < vertices_.size(); ++i) n += vertices_[i].cross(vertices_[(i + 1) % vertices_.size()]);
  IFAB_THROW_UNLESS(n.norm() > 1e-12, "polygon: vertices are collinear or repeated (zero area)");
  normal_ = n.normalized();
  offset_ = normal_.dot(vertices_[0]);
  for (std::size_t i = 0; i < vertices_.size(); ++i) {
    const Eigen::Vector3d& a = vertices_[i];
    IFAB_THROW_UNLESS(std::abs(normal_.dot(a) - offset_) < 1e-6, "polygon: vertex {} is off the plane of the others", i);
    const Eigen::Vector3d& b = vertices_[(i + 1) % vertices_.size()];
    const Eigen::Vector3d& c = vertices_[(i + 2) % vertices_.size()];
    IFAB_THROW_UNLESS((b - a).cross(c - b).dot(normal_) >= -1e-12, "polygon: not convex at vertex {}",
                      (i + 1) % vertices_.size());
  }
}

bool ConvexPolygon::ContainsProjected(const Eigen::Vector3d& p) const {
  for (std::size_t i = 0; i < vertices_.size(); ++i) {
    const Eigen::Vector3d& a = vertices_[i];
    const Eigen::Vector3d& b = vertices_[(i + 1) % vertices_.size()];
    if ((b - a).cross(p - a).dot(normal_) < -1e-12) return false;
  }
  return true;
}

ClosestPoint Closest(const Primitive& primitive, const Eigen::Vector3d& p) {
  return std::visit(
      [&](const auto& g) -> ClosestPoint {
        using G = std::decay_t<decltype(g)>;
        if constexpr (std::is_same_v<G, Plane>) return ClosestPlane(g, p);
        else if constexpr (std::is_same_v<G, ConvexPolygon>) return ClosestPolygon(g, p);
        else return ClosestBox(g, p);
      },
      primitive);
}

std::optional<RayHit> IntersectRay(const Primitive& primitive, const Eigen::Vector3d& o,
                                   const Eigen::Vector3d& d, double t_min, double t_max) {
  return std::visit(
      [&](const auto& g) -> std::optional<RayHit> {
        using G = std::decay_t<decltype(g)>;
        if constexpr (std::is_same_v<G, Plane>) {
          return RayPlane(g.normal, g.offset, o, d, t_min, t_max);
        } else if constexpr (std::is_same_v<G, ConvexPolygon>) {
          auto hit = RayPlane(g.normal(), g.offset(), o, d, t_min, t_max);
          if (hit && g.ContainsProjected(o + hit->t * d)) return hit;
          return std::nullopt;
        } else {
          return RayBox(g, o, d, t_min, t_max);
        }
      },
      primitive);
}

std::vector<ConvexPolygon> BoxFaces(const Box& box) {
  const Eigen::Vector3d h = 0.5 * box.size;
  std::vector<ConvexPolygon> faces;
  for (int k = 0; k < 3; ++k) {
    const int u = (k + 1) % 3, v = (k + 2) % 3;
    for (double sign : {1.0, -1.0}) {
      std::vector<Eigen::Vector3d> verts;
      for (auto [su, sv] : {std::pair{-1.0, -1.0}, {1.0, -1.0}, {1.0, 1.0}, {-1.0, 1.0}}) {
        Eigen::Vector3d p;
        p[k] = sign * h[k];
        p[u] = su * h[u];
        p[v] = sign * sv * h[v];  // flips winding on the negative side: normals point out
        verts.push_back(p);
      }
      faces.emplace_back(verts);
    }
  }
  return faces;
}

std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> Edges(const Primitive& primitive) {
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> edges;
  if (const auto* poly = std::get_if<ConvexPolygon>(&primitive)) {
    const auto& v = poly->vertices();
    for (std::size_t i = 0; i < v.size(); ++i) edges.emplace_back(v[i], v[(i + 1) % v.size()]);
  } else if (const auto* box = std::get_if<Box>(&primitive)) {
    const Eigen::Vector3d h = 0.5 * box->size;
    for (int k = 0; k < 3; ++k) {
      const int u = (k + 1) % 3, v = (k + 2) % 3;
      for (double su : {-1.0, 1.0}) {
        for (double sv : {-1.0, 1.0}) {
          Eigen::Vector3d a, b;
          a[k] = -h[k];
          b[k] = h[k];
          a[u] = b[u] = su * h[u];
          a[v] = b[v] = sv * h[v];
          edges.emplace_back(a, b);
        }
      }
    }
  }
  return edges;
}

bool Aabb::HitByRay(const Eigen::Vector3d& o, const Eigen::Vector3d& inv_d, double t_min, double t_max) const {
  double t0 = t_min, t1 = t_max;
  for (int k = 0; k < 3; ++k) {
    double ta = (lo[k] - o[k]) * inv_d[k], tb = (hi[k] - o[k]) * inv_d[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = ta > t0 ? ta : t0;  // NaN-safe for axis-parallel rays through the slab
    t1 = tb < t1 ? tb : t1;
    if (t0 > t1) return false;
  }
  return true;
}

std::optional<Aabb> Bounds(const Primitive& primitive, const Pose3& T_site_object) {
  Aabb box;
  if (std::holds_alternative<Plane>(primitive)) return std::nullopt;
  if (const auto* poly = std::get_if<ConvexPolygon>(&primitive)) {
    for (const auto& v : poly->vertices()) box.Extend(T_site_object * v);
  } else {
    const Eigen::Vector3d h = 0.5 * std::get<Box>(primitive).size;
    for (double sx : {-1.0, 1.0})
      for (double sy : {-1.0, 1.0})
        for (double sz : {-1.0, 1.0}) box.Extend(T_site_object * Eigen::Vector3d(sx * h.x(), sy * h.y(), sz * h.z()));
  }
  return box;
}

double SegmentRayDistance(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& o,
                          const Eigen::Vector3d& d, double t_max) {
  // Minimise |a + s (b - a) - (o + t d)| over s in [0, 1], t in [0, t_max]: a 2x2 box-constrained
  // quadratic; check the interior solution and the four borders.
  const Eigen::Vector3d u = b - a;
  auto dist = [&](double s, double t) { return (a + s * u - o - t * d).norm(); };
  auto t_for = [&](double s) { return std::clamp((a + s * u - o).dot(d), 0.0, t_max); };
  auto s_for = [&](double t) {
    const double uu = u.squaredNorm();
    return uu > 0 ? std::clamp((o + t * d - a).dot(u) / uu, 0.0, 1.0) : 0.0;
  };
  double best = kInf;
  const double uu = u.squaredNorm(), ud = u.dot(d);
  const double det = uu - ud * ud;  // |d| = 1
  if (det > 1e-14) {
    const Eigen::Vector3d w = a - o;
    const double s = (ud * w.dot(d) - w.dot(u)) / det;
    const double t = (uu * w.dot(d) - ud * w.dot(u)) / det;
    if (s >= 0 && s <= 1 && t >= 0 && t <= t_max) best = dist(s, t);
  }
  for (double s : {0.0, 1.0}) best = std::min(best, dist(s, t_for(s)));
  for (double t : {0.0, t_max}) best = std::min(best, dist(s_for(t), t));
  return best;
}

}  // namespace ifab
