// One conformance suite for every primitive type (STYLE.md): closest point and ray casting are
// checked against brute force and analytic cases the same way for planes, polygons and boxes.
#include "ifab/model/geometry.h"

#include <gtest/gtest.h>

#include "ifab/core/error.h"
#include "ifab/core/random.h"

namespace ifab {
namespace {

// A point drawn uniformly in the box [lo, hi], its coordinates in a fixed order. The order in
// which a call's arguments are evaluated is unspecified (gcc goes right to left, clang left to
// right), so Eigen::Vector3d(rng.Uniform(..), rng.Uniform(..), rng.Uniform(..)) gave each compiler
// other points, and the ray test fewer hits than it asks for under clang (found by the sanitizer
// build). z, y, x is the order gcc used, so the gcc figures stay as they were.
Eigen::Vector3d Draw(RandomStream& rng, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  const double z = rng.Uniform(lo.z(), hi.z());
  const double y = rng.Uniform(lo.y(), hi.y());
  const double x = rng.Uniform(lo.x(), hi.x());
  return {x, y, z};
}

// Dense samples of a primitive's surface (a square patch for the infinite plane).
std::vector<Eigen::Vector3d> SampleSurface(const Primitive& g, int n) {
  std::vector<Eigen::Vector3d> out;
  std::vector<ConvexPolygon> faces;
  if (const auto* poly = std::get_if<ConvexPolygon>(&g)) faces = {*poly};
  if (const auto* box = std::get_if<Box>(&g)) faces = BoxFaces(*box);
  if (const auto* plane = std::get_if<Plane>(&g)) {
    const Eigen::Vector3d u = plane->normal.unitOrthogonal(), v = plane->normal.cross(u);
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= n; ++j)
        out.push_back(plane->offset * plane->normal + (3.0 * i / n - 1.5) * u + (3.0 * j / n - 1.5) * v);
    return out;
  }
  for (const auto& f : faces) {
    const auto& v = f.vertices();
    for (std::size_t k = 1; k + 1 < v.size(); ++k)  // fan triangulation
      for (int i = 0; i <= n; ++i)
        for (int j = 0; i + j <= n; ++j)
          out.push_back(v[0] + (double(i) / n) * (v[k] - v[0]) + (double(j) / n) * (v[k + 1] - v[0]));
  }
  return out;
}

template <typename T>
class PrimitiveConformance : public ::testing::Test {
 public:
  static Primitive Make();
};
template <>
Primitive PrimitiveConformance<Plane>::Make() {
  return Plane{Eigen::Vector3d(0.2, -0.3, 1.0).normalized(), 0.1};
}
template <>
Primitive PrimitiveConformance<ConvexPolygon>::Make() {
  return ConvexPolygon({{0, 0, 0.2}, {0.5, 0, 0.25}, {0.6, 0.4, 0.3}, {0.1, 0.5, 0.26}});
}
template <>
Primitive PrimitiveConformance<Box>::Make() {
  return Box{{0.24, 0.115, 0.052}};
}
using PrimitiveTypes = ::testing::Types<Plane, ConvexPolygon, Box>;
TYPED_TEST_SUITE(PrimitiveConformance, PrimitiveTypes);

TYPED_TEST(PrimitiveConformance, ClosestPointIsOnSurfaceAndNoSampleIsCloser) {
  const Primitive g = TestFixture::Make();
  const auto samples = SampleSurface(g, std::holds_alternative<Plane>(g) ? 150 : 40);
  RandomStream rng(3);
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3d p = Draw(rng, Eigen::Vector3d::Constant(-0.5), Eigen::Vector3d::Constant(0.9));
    const ClosestPoint c = Closest(g, p);
    EXPECT_NEAR((p - c.point).norm(), c.distance, 1e-12);
    // The closest point is itself on the surface.
    EXPECT_NEAR(Closest(g, c.point).distance, 0.0, 1e-9);
    // No surface sample is (noticeably) closer; with 40 samples per edge the grid is fine.
    double best = 1e9;
    for (const auto& s : samples) best = std::min(best, (p - s).norm());
    EXPECT_LE(c.distance, best + 1e-9);
    EXPECT_GE(c.distance, best - 0.02);
    EXPECT_NEAR(c.normal.norm(), 1.0, 1e-12);
  }
}

TYPED_TEST(PrimitiveConformance, RayHitsLieOnSurfaceAndMissesAreMisses) {
  const Primitive g = TestFixture::Make();
  RandomStream rng(4);
  int hits = 0, misses = 0, close_misses = 0;
  for (int trial = 0; trial < 500; ++trial) {
    const Eigen::Vector3d o = Draw(rng, {-2, -2, 1.0}, {2, 2, 2.0});
    const Eigen::Vector3d target = Draw(rng, {-0.2, -0.2, -0.2}, {0.7, 0.7, 0.4});
    const Eigen::Vector3d d = (target - o).normalized();
    const auto hit = IntersectRay(g, o, d, 0.0, 10.0);
    if (hit) {
      ++hits;
      EXPECT_NEAR(Closest(g, o + hit->t * d).distance, 0.0, 1e-9);
      EXPECT_LT(hit->normal.dot(d), 0.0);  // entering from outside
    } else {
      // A miss: walking along the ray never touches the surface (rays may graze an edge).
      ++misses;
      double closest = 1e9;
      for (double t = 0; t < 10.0; t += 0.0005) closest = std::min(closest, Closest(g, o + t * d).distance);
      EXPECT_GT(closest, 0.0);
      close_misses += closest < 1e-3;
    }
  }
  EXPECT_GT(hits, 20);
  EXPECT_LE(close_misses, std::max(1, misses / 50));
}

TEST(Geometry, AnalyticCases) {
  const Box brick{{0.24, 0.115, 0.052}};
  const auto hit = IntersectRay(brick, {0, 0, 2}, {0, 0, -1}, 0, 10);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->t, 2 - 0.026, 1e-12);
  EXPECT_NEAR(hit->normal.z(), 1.0, 1e-12);
  const ClosestPoint c = Closest(brick, {0.2, 0.0, 0.0});
  EXPECT_NEAR(c.distance, 0.08, 1e-12);
  EXPECT_EQ(c.feature, Feature::kFace);
  EXPECT_EQ(Closest(brick, {0.2, 0.2, 0.0}).feature, Feature::kEdge);
  EXPECT_EQ(Closest(brick, {0.2, 0.2, 0.2}).feature, Feature::kVertex);
  EXPECT_EQ(BoxFaces(brick).size(), 6u);
  EXPECT_EQ(Edges(brick).size(), 12u);
  for (const auto& f : BoxFaces(brick)) {  // outward normals
    EXPECT_GT(f.normal().dot(f.vertices()[0]), 0.0);
  }
  EXPECT_NEAR(SegmentRayDistance({1, -1, 0.5}, {1, 1, 0.5}, {0, 0, 0}, {1, 0, 0}, 5), 0.5, 1e-12);
}

TEST(Geometry, BadPolygonsAreRejected) {
  EXPECT_THROW(ConvexPolygon({{0, 0, 0}, {1, 0, 0}}), InputError);
  EXPECT_THROW(ConvexPolygon({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}), InputError);
  EXPECT_THROW(ConvexPolygon({{0, 0, 0}, {1, 0, 0}, {0.2, 0.2, 0}, {0, 1, 0}}), InputError);
}

TEST(Geometry, AabbSlabTest) {
  Aabb b;
  b.Extend(Eigen::Vector3d(1, -0.5, -0.5));
  b.Extend(Eigen::Vector3d(2, 0.5, 0.5));
  const Eigen::Vector3d d(1, 0, 0);
  const Eigen::Vector3d inv = d.cwiseInverse();
  EXPECT_TRUE(b.HitByRay({0, 0, 0}, inv, 0, 10));
  EXPECT_FALSE(b.HitByRay({0, 0, 0}, inv, 0, 0.5));
  EXPECT_FALSE(b.HitByRay({0, 1, 0}, inv, 0, 10));
}

}  // namespace
}  // namespace ifab
