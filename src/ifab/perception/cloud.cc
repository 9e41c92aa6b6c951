#include "ifab/perception/cloud.h"

#include "ifab/core/error.h"

namespace ifab {

std::vector<RayPoint> ToBaseFrame(const std::vector<SweepPoint>& points, const Pose3& T_tool0_laser) {
  std::vector<RayPoint> out;
  out.reserve(points.size());
  for (const auto& s : points) {
    const Pose3 T_base_laser = s.T_base_tool0 * T_tool0_laser;
    out.push_back({T_base_laser * s.p_laser, T_base_laser.translation()});
  }
  return out;
}

const std::vector<double>* PointCloud::Find(const std::string& name) const {
  for (const auto& f : fields)
    if (f.name == name) return &f.values;
  return nullptr;
}

void PointCloud::SetField(const std::string& name, std::vector<double> values) {
  IFAB_CHECK(values.size() == points.size());
  for (auto& f : fields) {
    if (f.name == name) {
      f.values = std::move(values);
      return;
    }
  }
  fields.push_back({name, std::move(values)});
}

PointCloud ToPointCloud(const std::vector<RayPoint>& points) {
  PointCloud cloud;
  std::vector<double> ox, oy, oz;
  for (const auto& p : points) {
    cloud.points.push_back(p.p);
    ox.push_back(p.origin.x());
    oy.push_back(p.origin.y());
    oz.push_back(p.origin.z());
  }
  cloud.SetField("origin_x", std::move(ox));
  cloud.SetField("origin_y", std::move(oy));
  cloud.SetField("origin_z", std::move(oz));
  return cloud;
}

std::vector<RayPoint> ToRayPoints(const PointCloud& cloud, const std::string& what,
                                  const Eigen::Vector3d* fallback_origin) {
  const auto* ox = cloud.Find("origin_x");
  const auto* oy = cloud.Find("origin_y");
  const auto* oz = cloud.Find("origin_z");
  const bool have = ox && oy && oz;
  if (!have && !fallback_origin)
    ThrowInputError("{}: no per-point laser origin (properties origin_x, origin_y, origin_z) and no "
                    "fixed origin given: registration needs each point's ray", what);
  std::vector<RayPoint> out(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    out[i].p = cloud.points[i];
    out[i].origin = have ? Eigen::Vector3d((*ox)[i], (*oy)[i], (*oz)[i]) : *fallback_origin;
  }
  return out;
}

}  // namespace ifab
