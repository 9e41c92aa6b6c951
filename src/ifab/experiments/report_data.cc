#include "ifab/experiments/report_data.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

#include "ifab/core/error.h"
#include "ifab/perception/cloud.h"
#include "ifab/experiments/ply_file.h"
#include "ifab/perception/ply.h"

namespace ifab::experiments {
namespace fs = std::filesystem;

namespace {

// Column-major 4x4, as three.js's Matrix4.fromArray reads it.
nlohmann::json Matrix(const Pose3& T) {
  const Eigen::Matrix4d m = T.matrix();
  nlohmann::json a = nlohmann::json::array();
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) a.push_back(std::round(m(r, c) * 1e6) / 1e6);
  return a;
}

nlohmann::json Boxes(const std::vector<SiteBox>& boxes) {
  nlohmann::json a = nlohmann::json::array();
  for (const SiteBox& b : boxes)
    a.push_back({{"name", b.name}, {"pose", Matrix(b.T_site_box)}, {"size", {b.box.size.x(), b.box.size.y(), b.box.size.z()}}});
  return a;
}

nlohmann::json SiteJson(const Site& site) {
  nlohmann::json boundary = nlohmann::json::array();
  for (const auto& p : site.boundary) boundary.push_back({p.x(), p.y()});
  return {{"ground_z", site.ground_z},
          {"boundary", boundary},
          {"walls", Boxes(site.walls)},
          {"obstacles", Boxes(site.obstacles)},
          {"brick", {site.brick.size.x(), site.brick.size.y(), site.brick.size.z()}}};
}

void WriteJsonFile(const fs::path& path, const nlohmann::json& j) {
  std::ofstream out(path);
  IFAB_THROW_UNLESS(out.good(), "{}: cannot write the file", path.string());
  out << j.dump() << "\n";
}

}  // namespace

void ReplayRecorder::Offer(const Sample& s) {
  if (!samples_.empty() && s.t < samples_.back().t + period) return;
  samples_.push_back(s);
}

void ReplayRecorder::ArmLaser(double t, bool active) {
  if (active && on_ < 0) on_ = t;
  if (!active && on_ >= 0) {
    sweeps_.emplace_back(on_, t);
    on_ = -1.0;
  }
}

void ReplayRecorder::Write(const std::string& dir) const {
  const fs::path path = fs::path(dir) / "replay.csv";
  std::ofstream csv(path);
  IFAB_THROW_UNLESS(csv.good(), "{}: cannot write the file", path.string());
  csv << "t,x,y,theta,q1,q2,q3,q4,q5,q6,holding,bricks\n";
  for (const Sample& s : samples_) {
    csv << fmt::format("{:.2f},{:.4f},{:.4f},{:.4f}", s.t, s.T_site_base.x, s.T_site_base.y, s.T_site_base.theta);
    for (int i = 0; i < 6; ++i) csv << fmt::format(",{:.4f}", s.q[i]);
    csv << fmt::format(",{},{}\n", s.holding ? 1 : 0, s.bricks);
  }
  std::ofstream sweeps(fs::path(dir) / "sweeps.csv");
  sweeps << "t_on,t_off\n";
  for (const auto& [on, off] : sweeps_) sweeps << fmt::format("{:.3f},{:.3f}\n", on, off);
}

void WriteSceneJson(const std::string& dir, const sequencer::MissionComponents& parts,
                    const sequencer::BuildingPlan& plan, const Site& workpiece,
                    const std::vector<sequencer::VisitLog>& logs) {
  nlohmann::json j;
  j["site"] = SiteJson(parts.site);
  const auto& g = parts.base_geometry;
  j["footprint"] = {{"length", g.length}, {"width", g.width}, {"offset", {g.footprint_offset.x(), g.footprint_offset.y()}},
                    {"track_gauge", g.track_gauge}};
  // The arm chain as KDL holds it: each segment's joint turns about `axis` through `origin` (both
  // in the segment's root frame), then `tip` leads to the next segment (q = 0).
  nlohmann::json segments = nlohmann::json::array();
  for (unsigned i = 0; i < parts.robot.arm_chain.getNrOfSegments(); ++i) {
    const KDL::Segment& s = parts.robot.arm_chain.getSegment(i);
    const KDL::Joint& joint = s.getJoint();
    const bool moves = joint.getType() != KDL::Joint::None;
    const KDL::Vector axis = moves ? joint.JointAxis() : KDL::Vector(0, 0, 1);
    const KDL::Vector origin = moves ? joint.JointOrigin() : KDL::Vector::Zero();
    segments.push_back({{"name", s.getName()},
                        {"moves", moves},
                        {"axis", {axis.x(), axis.y(), axis.z()}},
                        {"origin", {origin.x(), origin.y(), origin.z()}},
                        {"tip", Matrix(ToPose3(s.getFrameToTip()))}});
  }
  j["arm"] = {{"T_base_arm_base", Matrix(parts.robot.T_base_arm_base)},
              {"T_tool0_arm_laser", Matrix(parts.T_tool0_arm_laser)},
              {"T_tool0_gripper", Matrix(parts.robot.T_tool0_gripper)},
              {"segments", segments}};
  nlohmann::json positions = nlohmann::json::array();
  for (const auto& p : plan.positions)
    positions.push_back({{"name", p.name}, {"x", p.T_site_base.x}, {"y", p.T_site_base.y}, {"theta", p.T_site_base.theta}});
  j["positions"] = positions;
  nlohmann::json bricks = nlohmann::json::array();
  for (std::size_t k = 0; k < workpiece.bricks.size(); ++k) bricks.push_back(Matrix(workpiece.DesignedBrickPose(static_cast<int>(k))));
  j["designed_bricks"] = bricks;
  nlohmann::json visits = nlohmann::json::array();
  for (const auto& log : logs)
    visits.push_back({{"visit", log.visit},
                      {"position", log.position},
                      {"t_start", log.t_start},
                      {"t_end", log.t_end},
                      {"bricks_placed", log.bricks_placed},
                      {"localized", log.localized},
                      {"sweeps", log.sweeps},
                      {"registration", log.registration_report},
                      {"failure", log.failure}});
  j["visits"] = visits;
  WriteJsonFile(fs::path(dir) / "scene.json", j);
}

void WriteSiteSceneJson(const std::string& dir, const Site& site) {
  WriteJsonFile(fs::path(dir) / "scene.json", {{"site", SiteJson(site)}});
}

void WriteVisitCloud(const std::string& path, const sequencer::VisitLog& log) {
  PointCloud cloud = ToPointCloud(log.cloud);
  if (log.cloud_labels.size() == log.cloud.size()) {
    PointCloud::Field label{"label", {}};
    label.values.reserve(log.cloud_labels.size());
    for (PointLabel l : log.cloud_labels) label.values.push_back(static_cast<double>(l));
    cloud.fields.push_back(std::move(label));
  }
  SavePly(path, cloud);
}

}  // namespace ifab::experiments
