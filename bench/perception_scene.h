#pragma once
// The registration benchmark's scene, shared by perception_bench (ours) and
// perception_open3d_bench (Open3D's point-to-plane ICP, built only where Open3D is installed):
// ten bricks stacked on the floor and one sweep of the arm laser across them, about 20k points
// synthesised by ray casting (perception/testing/synthetic.h).

#include <cmath>
#include <variant>
#include <vector>

#include "ifab/core/random.h"
#include "ifab/perception/registration.h"
#include "ifab/perception/testing/synthetic.h"

namespace ifab::bench {

struct StackScene {
  std::vector<RegistrationBody> truth;  ///< "ground", "stack"
  std::vector<RayPoint> cloud;
};

inline const StackScene& Scene20k() {
  static const StackScene scene = [] {
    StackScene s;
    RigidObject ground{"ground", Pose3::Identity(), {Plane{Eigen::Vector3d::UnitZ(), 0.0}}};
    RegistrationBody stack{"stack", Pose3::Identity(), {}, true};
    for (int k = 0; k < 10; ++k)
      stack.parts.push_back({"brick", PoseFromXyzRpy(0.0, 0.0, 0.026 + 0.052 * k, 0, 0, 0.002 * k),
                             {Box{Eigen::Vector3d(0.240, 0.115, 0.052)}}});
    // The stack seen from the robot: 1.3 m ahead, 0.6 m to the left, turned 30 deg.
    const Pose3 T_base_site = PoseFromXyzRpy(1.3, 0.6, 0.0, 0.0, 0.0, 0.5);
    s.truth = {{"ground", T_base_site, {ground}, true}, stack};
    s.truth[1].T_base_body = T_base_site;
    const Scene world(s.truth);
    testing::SyntheticLaser laser;
    RandomStream rng(1);
    auto laser_at = [](double t) {
      Pose3 T = Pose3::Identity();
      T.translation() = Eigen::Vector3d(0.4, 0.0, 1.1);
      T.linear() = RotationFromRpy(M_PI / 2, 0.0, 0.35 + 0.25 * t);
      return T;
    };
    // 0.5 rad of sweep across the stack in 2 s; keep every other point: about 20k.
    s.cloud = testing::SynthesizeCloud(world, laser_at, 0.0, 2.0, laser, rng);
    std::vector<RayPoint> kept;
    for (std::size_t i = 0; i < s.cloud.size(); i += 2) kept.push_back(s.cloud[i]);
    s.cloud = kept;
    return s;
  }();
  return scene;
}

/// Where every registration starts: each body 2 cm and 2 deg off the truth.
inline Pose3 GuessOffset() { return PoseFromXyzRpy(0.015, -0.012, 0.005, 0.01, -0.01, 0.03); }

/// Points with outward normals every `spacing` [m] over the bodies' boxes and, within `radius`
/// of `centre` (base), their planes, at the bodies' poses: the model for point-to-plane ICP.
/// Hidden surface (a face against another part, a box's bottom on the floor) is left out.
struct OrientedPoints {
  std::vector<Eigen::Vector3d> points, normals;
};
inline OrientedPoints SampleSurfaces(const std::vector<RegistrationBody>& bodies, double spacing,
                                     const Eigen::Vector3d& centre, double radius) {
  OrientedPoints out;
  const Scene scene(bodies);
  auto add = [&](const Pose3& T_base_primitive, const Eigen::Vector3d& p, const Eigen::Vector3d& n) {
    const Eigen::Vector3d p_base = T_base_primitive * p, n_base = T_base_primitive.linear() * n;
    if (scene.Closest(p_base + 0.002 * n_base).distance < 0.0015) return;  // against something
    out.points.push_back(p_base);
    out.normals.push_back(n_base);
  };
  for (const auto& body : bodies) {
    for (const auto& part : body.parts) {
      const Pose3 T = body.T_base_body * part.T_site_object;
      for (const auto& primitive : part.primitives) {
        if (const auto* box = std::get_if<Box>(&primitive)) {
          const Eigen::Vector3d h = 0.5 * box->size;
          for (int a = 0; a < 3; ++a) {
            const int b = (a + 1) % 3, c = (a + 2) % 3;
            const int nb = std::max(1, static_cast<int>(std::ceil(box->size[b] / spacing)));
            const int nc = std::max(1, static_cast<int>(std::ceil(box->size[c] / spacing)));
            for (double sign : {-1.0, 1.0}) {
              Eigen::Vector3d n = Eigen::Vector3d::Zero();
              n[a] = sign;
              for (int i = 0; i <= nb; ++i) {
                for (int j = 0; j <= nc; ++j) {
                  Eigen::Vector3d p = sign * h[a] * n.cwiseAbs();
                  p[b] = -h[b] + box->size[b] * i / nb;
                  p[c] = -h[c] + box->size[c] * j / nc;
                  add(T, p, n);
                }
              }
            }
          }
        } else if (const auto* plane = std::get_if<Plane>(&primitive)) {
          // A square patch about the point of the plane nearest to the centre.
          const Eigen::Vector3d n = plane->normal;
          const Eigen::Vector3d c_local = T.inverse() * centre;
          const Eigen::Vector3d foot = c_local - (n.dot(c_local) - plane->offset) * n;
          const Eigen::Vector3d u = AnyPerpendicular(n), v = n.cross(u);
          const int m = static_cast<int>(std::ceil(radius / spacing));
          for (int i = -m; i <= m; ++i)
            for (int j = -m; j <= m; ++j)
              if (i * i + j * j <= m * m) add(T, foot + spacing * (i * u + j * v), n);
        }
        // (Polygons do not occur in this scene.)
      }
    }
  }
  return out;
}

}  // namespace ifab::bench
