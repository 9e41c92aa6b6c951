#include "ifab/model/robot_model.h"

#include <console_bridge/console.h>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <set>
#include <sstream>

#include "ifab/core/config.h"
#include "ifab/core/error.h"

namespace ifab {
namespace {

// urdfdom reports what is wrong through console_bridge; collect it for our error message.
class CollectingHandler : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_WARN) messages += (messages.empty() ? "" : "; ") + text;
  }
  std::string messages;
};

// TinyXML 2.6 (urdfdom's parser) steps over a multi-byte UTF-8 lead byte by the length it
// announces, so a file ending in a truncated or invalid sequence made it read past the end of the
// text (found by urdf_fuzz under ASan). XML files are UTF-8: check that before either parser runs.
void RequireUtf8(const std::string& text, const std::string& urdf_path) {
  int line = 1;
  for (std::size_t i = 0; i < text.size();) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c == '\n') ++line;
    std::size_t len = 1;
    if (c >= 0xC2 && c <= 0xDF) len = 2;
    else if (c >= 0xE0 && c <= 0xEF) len = 3;
    else if (c >= 0xF0 && c <= 0xF4) len = 4;
    else if (c >= 0x80) len = 0;
    bool ok = len > 0 && i + len <= text.size();
    for (std::size_t k = 1; ok && k < len; ++k) ok = (static_cast<unsigned char>(text[i + k]) & 0xC0) == 0x80;
    if (!ok)
      ThrowInputError("{}: line {}: byte {} (0x{:02x}) is not valid UTF-8; expected a UTF-8 XML file", urdf_path,
                      line, i, c);
    i += len;
  }
}

// Joints whose parent and child links form a loop (a joint from a link to itself, or a cycle)
// must be refused before urdfdom sees them: urdfdom links the tree before it looks for the
// root, and when that then fails ("two root links") it drops a model whose links own each other
// (shared pointers), which leaks (found by urdf_fuzz under LSan). We read the joints with the
// XML parser urdfdom itself uses (TinyXML), so both see the same <parent>/<child> names.
void RejectJointLoops(const std::string& urdf_text, const std::string& urdf_path) {
  TiXmlDocument doc;
  doc.Parse(urdf_text.c_str());
  if (doc.Error()) return;  // urdfdom reports the XML error
  const TiXmlElement* robot = doc.FirstChildElement("robot");
  if (!robot) return;
  std::map<std::string, std::vector<std::pair<std::string, std::string>>> children;  // parent -> (child, joint)
  for (const TiXmlElement* j = robot->FirstChildElement("joint"); j; j = j->NextSiblingElement("joint")) {
    const TiXmlElement* parent = j->FirstChildElement("parent");
    const TiXmlElement* child = j->FirstChildElement("child");
    const char* parent_link = parent ? parent->Attribute("link") : nullptr;
    const char* child_link = child ? child->Attribute("link") : nullptr;
    if (!parent_link || !child_link) continue;  // urdfdom reports it
    const char* name = j->Attribute("name");
    if (std::string(parent_link) == child_link)
      ThrowInputError("{}: line {}: joint '{}': parent and child are the same link '{}' (a loop)", urdf_path,
                      j->Row(), name ? name : "", parent_link);
    children[parent_link].emplace_back(child_link, name ? name : "");
  }
  // Depth-first search for a cycle; iterative, so a long chain cannot exhaust the stack.
  std::set<std::string> done, on_path;
  for (const auto& entry : children) {
    const std::string& start = entry.first;
    if (done.count(start)) continue;
    std::vector<std::pair<std::string, std::size_t>> stack{{start, 0}};
    on_path.insert(start);
    while (!stack.empty()) {
      auto& [link, next] = stack.back();
      const auto it = children.find(link);
      if (it == children.end() || next == it->second.size()) {
        on_path.erase(link);
        done.insert(link);
        stack.pop_back();
        continue;
      }
      const auto& [child, joint] = it->second[next++];
      if (on_path.count(child))
        ThrowInputError("{}: the joints form a loop: joint '{}' leads from link '{}' back to link '{}'", urdf_path,
                        joint, link, child);
      if (done.count(child)) continue;
      on_path.insert(child);
      stack.emplace_back(child, 0);
    }
  }
}

KDL::Vector ToKdl(const urdf::Vector3& v) { return {v.x, v.y, v.z}; }

KDL::Frame ToKdl(const urdf::Pose& p) {
  return {KDL::Rotation::Quaternion(p.rotation.x, p.rotation.y, p.rotation.z, p.rotation.w),
          ToKdl(p.position)};
}

KDL::Joint ToKdlJoint(const urdf::Joint& j) {
  const KDL::Frame origin = ToKdl(j.parent_to_joint_origin_transform);
  switch (j.type) {
    case urdf::Joint::REVOLUTE:
    case urdf::Joint::CONTINUOUS:
      return KDL::Joint(j.name, origin.p, origin.M * ToKdl(j.axis), KDL::Joint::RotAxis);
    case urdf::Joint::PRISMATIC:
      return KDL::Joint(j.name, origin.p, origin.M * ToKdl(j.axis), KDL::Joint::TransAxis);
    default:
      return KDL::Joint(j.name, KDL::Joint::Fixed);
  }
}

KDL::RigidBodyInertia ToKdlInertia(const urdf::Inertial& i) {
  const KDL::Frame origin = ToKdl(i.origin);
  const KDL::RigidBodyInertia about_cog(
      i.mass, origin.p, KDL::RotationalInertia(i.ixx, i.iyy, i.izz, i.ixy, i.ixz, i.iyz));
  // Inertia axes given in the inertial frame: rotate them into the link frame.
  return origin.M * about_cog;
}

bool Finite(const urdf::Vector3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
// Finite, and within a kilometre: urdfdom accepts 1e308, which overflows forward kinematics.
bool Finite(const urdf::Pose& p) {
  const auto& v = p.position;
  return Finite(v) && std::abs(v.x) <= 1e3 && std::abs(v.y) <= 1e3 && std::abs(v.z) <= 1e3 &&
         std::isfinite(p.rotation.x) && std::isfinite(p.rotation.y) && std::isfinite(p.rotation.z) &&
         std::isfinite(p.rotation.w);
}

// What the dynamics (arm/dynamics.h, KDL) rely on: finite origins and axes, and for each link
// with an <inertial> a positive mass and a positive-definite inertia that a real body can have
// (principal moments obey the triangle inequality). urdfdom accepts nan, inf and negative masses.
void CheckPhysical(const urdf::ModelInterface& m, const std::string& path) {
  for (const auto& [name, link] : m.links_) {
    if (!link->inertial) continue;
    const urdf::Inertial& i = *link->inertial;
    if (!(std::isfinite(i.mass) && i.mass > 0))
      ThrowInputError("{}: link '{}': inertial mass: expected a positive number [kg], got {}", path, name, i.mass);
    if (!Finite(i.origin))
      ThrowInputError("{}: link '{}': inertial origin: expected finite xyz (within 1 km) and rpy", path, name);
    Eigen::Matrix3d I;
    I << i.ixx, i.ixy, i.ixz, i.ixy, i.iyy, i.iyz, i.ixz, i.iyz, i.izz;
    const bool finite = I.allFinite();
    const Eigen::Vector3d e = finite ? Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(I).eigenvalues()
                                     : Eigen::Vector3d::Zero();
    // Relative slack for rounding of inertias written to a few digits.
    const double slack = 1e-9 * e.cwiseAbs().maxCoeff();
    if (!finite || !(e.minCoeff() > 0) || !(e[0] + e[1] >= e[2] - slack))
      ThrowInputError("{}: link '{}': inertia: expected a finite, positive-definite matrix whose principal "
                      "moments obey a + b >= c, got ixx={} iyy={} izz={} ixy={} ixz={} iyz={}",
                      path, name, i.ixx, i.iyy, i.izz, i.ixy, i.ixz, i.iyz);
  }
  for (const auto& [name, joint] : m.joints_) {
    if (!Finite(joint->parent_to_joint_origin_transform))
      ThrowInputError("{}: joint '{}': origin: expected finite xyz (within 1 km) and rpy", path, name);
    const bool moves = joint->type != urdf::Joint::FIXED && joint->type != urdf::Joint::FLOATING &&
                       joint->type != urdf::Joint::PLANAR;
    const double axis_norm = std::sqrt(joint->axis.x * joint->axis.x + joint->axis.y * joint->axis.y +
                                       joint->axis.z * joint->axis.z);
    if (moves && !(std::isfinite(axis_norm) && axis_norm > 1e-9))
      ThrowInputError("{}: joint '{}': axis: expected a finite non-zero vector", path, name);
    if (joint->limits && !(std::isfinite(joint->limits->velocity) && std::isfinite(joint->limits->effort) &&
                           !std::isnan(joint->limits->lower) && !std::isnan(joint->limits->upper)))
      ThrowInputError("{}: joint '{}': limit: expected numbers (finite velocity and effort)", path, name);
  }
}

void AddChildren(const urdf::LinkConstSharedPtr& link, KDL::Tree& tree) {
  for (const auto& child : link->child_links) {
    KDL::RigidBodyInertia inertia = KDL::RigidBodyInertia::Zero();
    if (child->inertial) inertia = ToKdlInertia(*child->inertial);
    const urdf::Joint& joint = *child->parent_joint;
    KDL::Segment segment(child->name, ToKdlJoint(joint), ToKdl(joint.parent_to_joint_origin_transform),
                         inertia);
    tree.addSegment(segment, link->name);
    AddChildren(child, tree);
  }
}

Pose3 FixedPose(const KDL::Tree& tree, const std::string& from, const std::string& to,
                const std::string& path) {
  KDL::Chain chain;
  if (!tree.getChain(from, to, chain)) ThrowInputError("{}: no link chain from '{}' to '{}'", path, from, to);
  KDL::Frame f = KDL::Frame::Identity();
  for (const auto& s : chain.segments) {
    if (s.getJoint().getType() != KDL::Joint::Fixed)
      ThrowInputError("{}: the mount from '{}' to '{}' must use fixed joints only", path, from, to);
    f = f * s.pose(0.0);
  }
  return ToPose3(f);
}

}  // namespace

Pose3 ToPose3(const KDL::Frame& f) {
  Pose3 p = Pose3::Identity();
  for (int r = 0; r < 3; ++r) {
    p.translation()[r] = f.p[r];
    for (int c = 0; c < 3; ++c) p.linear()(r, c) = f.M(r, c);
  }
  return p;
}

KDL::Frame ToKdl(const Pose3& p) {
  const Eigen::Matrix3d& r = p.linear();
  return {KDL::Rotation(r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2)),
          KDL::Vector(p.translation().x(), p.translation().y(), p.translation().z())};
}

RobotModel LoadRobotModel(const std::string& urdf_path) {
  std::ifstream in(urdf_path);
  if (!in) ThrowInputError("{}: cannot open the file", urdf_path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ParseRobotModel(ss.str(), urdf_path);
}

RobotModel ParseRobotModel(const std::string& urdf_text, const std::string& urdf_path) {
  RequireUtf8(urdf_text, urdf_path);
  RejectJointLoops(urdf_text, urdf_path);
  urdf::ModelInterfaceSharedPtr urdf_model;
  {
    static std::mutex mutex;  // console_bridge's handler is process-global
    std::lock_guard<std::mutex> lock(mutex);
    CollectingHandler handler;
    console_bridge::useOutputHandler(&handler);
    urdf_model = urdf::parseURDF(urdf_text);
    console_bridge::restorePreviousOutputHandler();
    if (!urdf_model) {
      ThrowInputError("{}: not a valid URDF: {}", urdf_path,
                      handler.messages.empty() ? "the parser gave no reason" : handler.messages);
    }
  }

  // Joints that form a loop make urdfdom's links own each other (child_links are shared
  // pointers): the model would leak (found by the fuzzer). Break every link's ownership of its
  // children when done, however this function ends, and reject the loop.
  struct BreakCycles {
    urdf::ModelInterface& m;
    ~BreakCycles() {
      for (auto& [name, link] : m.links_) {
        link->child_links.clear();
        link->child_joints.clear();
      }
    }
  } break_cycles{*urdf_model};

  RobotModel model;
  model.urdf_path = urdf_path;
  const auto root = urdf_model->getRoot();
  if (!root) ThrowInputError("{}: the URDF has no root link", urdf_path);
  {
    std::size_t reached = 0;
    std::vector<urdf::LinkConstSharedPtr> todo{root};
    while (!todo.empty() && reached <= urdf_model->links_.size()) {
      const urdf::LinkConstSharedPtr l = todo.back();
      todo.pop_back();
      ++reached;
      todo.insert(todo.end(), l->child_links.begin(), l->child_links.end());
    }
    if (reached != urdf_model->links_.size())
      ThrowInputError("{}: the joints form a loop: {} links, {} reached from the root link '{}' by its joints",
                      urdf_path, urdf_model->links_.size(), reached, root->name);
  }
  CheckPhysical(*urdf_model, urdf_path);
  model.tree = KDL::Tree(root->name);
  AddChildren(root, model.tree);

  for (const char* link : {"base_link", "arm_base", "tool0", "base_laser", "arm_laser", "gripper_tcp"}) {
    if (!urdf_model->getLink(link)) ThrowInputError("{}: link '{}' is required but missing", urdf_path, link);
  }
  if (!model.tree.getChain("arm_base", "tool0", model.arm_chain))
    ThrowInputError("{}: no chain from 'arm_base' to 'tool0'", urdf_path);

  std::vector<double> lo, hi, vel, eff;
  for (const auto& segment : model.arm_chain.segments) {
    if (segment.getJoint().getType() == KDL::Joint::Fixed) continue;
    const auto joint = urdf_model->getJoint(segment.getJoint().getName());
    if (joint->type != urdf::Joint::REVOLUTE)
      ThrowInputError("{}: joint '{}': expected a revolute joint in the arm chain", urdf_path, joint->name);
    if (!joint->limits)
      ThrowInputError("{}: joint '{}': expected a <limit> element", urdf_path, joint->name);
    if (!(joint->limits->lower < joint->limits->upper) || !(joint->limits->velocity > 0.0))
      ThrowInputError("{}: joint '{}': expected lower < upper and velocity > 0 in <limit>", urdf_path, joint->name);
    model.joint_names.push_back(joint->name);
    lo.push_back(joint->limits->lower);
    hi.push_back(joint->limits->upper);
    vel.push_back(joint->limits->velocity);
    eff.push_back(joint->limits->effort);
  }
  if (model.joint_names.size() != 6)
    ThrowInputError("{}: the arm chain arm_base -> tool0 has {} moving joints, expected 6", urdf_path,
                    model.joint_names.size());
  for (int i = 0; i < 6; ++i) {
    model.q_min[i] = lo[i];
    model.q_max[i] = hi[i];
    model.qd_max[i] = vel[i];
    model.effort_max[i] = eff[i];
  }
  model.T_base_arm_base = FixedPose(model.tree, "base_link", "arm_base", urdf_path);
  model.T_base_base_laser = FixedPose(model.tree, "base_link", "base_laser", urdf_path);
  model.T_tool0_arm_laser = FixedPose(model.tree, "tool0", "arm_laser", urdf_path);
  model.T_tool0_gripper = FixedPose(model.tree, "tool0", "gripper_tcp", urdf_path);
  return model;
}

void ApplyMountOverrides(const ConfigNode& mounts, RobotModel& model) {
  mounts.ExpectKeys({"base_laser", "arm_laser", "arm_base", "gripper"});
  auto read = [&](const char* key, Pose3& pose) {
    if (auto c = mounts.Find(key)) {
      const auto v = c->AsNumbers(6);
      pose = PoseFromXyzRpy(v[0], v[1], v[2], v[3], v[4], v[5]);
    }
  };
  read("base_laser", model.T_base_base_laser);
  read("arm_laser", model.T_tool0_arm_laser);
  read("arm_base", model.T_base_arm_base);
  read("gripper", model.T_tool0_gripper);
}

KDL::Chain ChainWithLinkErrors(const KDL::Chain& design, const std::vector<Pose3>& link_errors) {
  KDL::Chain chain;
  for (unsigned i = 0; i < design.getNrOfSegments(); ++i) {
    const KDL::Segment& s = design.getSegment(i);
    const Pose3 tip = i < link_errors.size() ? ToPose3(s.getFrameToTip()) * link_errors[i] : ToPose3(s.getFrameToTip());
    // KDL keeps the joint's own frame; the segment's frame to tip carries the link length.
    chain.addSegment(KDL::Segment(s.getName(), s.getJoint(), ToKdl(tip), s.getInertia()));
  }
  return chain;
}

Pose3 RobotModel::ArmForwardKinematics(const Vector6d& q) const {
  KDL::ChainFkSolverPos_recursive fk(arm_chain);
  KDL::JntArray joints(6);
  for (int i = 0; i < 6; ++i) joints(i) = q[i];
  KDL::Frame f;
  fk.JntToCart(joints, f);
  return ToPose3(f);
}

bool RobotModel::WithinLimits(const Vector6d& q, double tolerance) const {
  return ((q - q_min).array() >= -tolerance).all() && ((q_max - q).array() >= -tolerance).all();
}

}  // namespace ifab
