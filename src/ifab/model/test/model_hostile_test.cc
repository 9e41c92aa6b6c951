// Issue 14: hostile URDF and site files. Each case here was accepted before.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "ifab/core/config.h"
#include "ifab/core/data_path.h"
#include "ifab/core/testing/error_of.h"
#include "ifab/model/robot_model.h"
#include "ifab/model/site.h"

namespace ifab {
namespace {

using ::testing::HasSubstr;
using testing::ErrorOf;

std::string Urdf() {
  std::ifstream in(DataPath("robots/insitu_fabricator.urdf"));
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The robot's URDF with the first occurrence of `from` replaced.
std::string UrdfError(const std::string& from, const std::string& to) {
  std::string text = Urdf();
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  text.replace(at, from.size(), to);
  return ErrorOf([&] { ParseRobotModel(text, "hostile.urdf"); });
}

TEST(UrdfHostile, TheRobotLoadsFromText) {
  EXPECT_EQ(ParseRobotModel(Urdf(), "robot.urdf").joint_names.size(), 6u);
}

TEST(UrdfHostile, RejectsJointsThatFormALoop) {
  // Found by the fuzzer: urdfdom accepts a loop (its links then own each other and leak under
  // ASan); before, the loader failed later for a missing chain.
  EXPECT_THAT(UrdfError("<joint name=\"joint_4\" type=\"revolute\">\n    <parent link=\"link_3\"/>",
                        "<joint name=\"joint_4\" type=\"revolute\">\n    <parent link=\"link_6\"/>"),
              HasSubstr("hostile.urdf: the joints form a loop"));
}

TEST(UrdfHostile, RejectsAJointFromALinkToItself) {
  // Found by the fuzzer (tests/fuzz/corpus/urdf/regression_self_joint_leak.urdf): urdfdom links the
  // tree, then fails ("two root links") and drops links that own each other: a leak under LSan.
  // Before, the message did not name the joint either.
  EXPECT_THAT(UrdfError("<parent link=\"link_4\"/>\n    <child link=\"link_5\"/>",
                        "<parent link=\"link_4\"/>\n    <child link=\"link_4\"/>"),
              HasSubstr("hostile.urdf: line "));
  EXPECT_THAT(UrdfError("<parent link=\"link_4\"/>\n    <child link=\"link_5\"/>",
                        "<parent link=\"link_4\"/>\n    <child link=\"link_4\"/>"),
              HasSubstr("joint 'joint_5': parent and child are the same link 'link_4' (a loop)"));
}

TEST(UrdfHostile, RejectsTextThatIsNotUtf8) {
  // Found by urdf_fuzz (tests/fuzz/corpus/urdf/regression_tinyxml_overread.urdf): TinyXML read past
  // the end of a file that ends in a truncated UTF-8 sequence (ASan: heap-buffer-overflow).
  std::string text = Urdf();
  text.resize(text.rfind("</robot>"));
  text += "J3 z \xff\xff\xff\xee";
  const std::string e = ErrorOf([&] { ParseRobotModel(text, "hostile.urdf"); });
  EXPECT_THAT(e, HasSubstr("hostile.urdf: line "));
  EXPECT_THAT(e, HasSubstr("(0xff) is not valid UTF-8; expected a UTF-8 XML file"));
  EXPECT_THAT(ErrorOf([&] { ParseRobotModel(Urdf() + "\xe2\x82", "cut.urdf"); }), HasSubstr("not valid UTF-8"));
}

TEST(UrdfHostile, RejectsNonFiniteMasses) {
  // urdfdom reads these without complaint, as a mass of 0.
  EXPECT_THAT(UrdfError("<mass value=\"965\"/>", "<mass value=\"nan\"/>"),
              HasSubstr("link 'base_link': inertial mass: expected a positive number [kg]"));
  EXPECT_THAT(UrdfError("<mass value=\"965\"/>", "<mass value=\"inf\"/>"),
              HasSubstr("inertial mass: expected a positive number [kg]"));
}

TEST(UrdfHostile, RejectsNonPositiveMasses) {
  EXPECT_THAT(UrdfError("<mass value=\"965\"/>", "<mass value=\"-965\"/>"),
              HasSubstr("hostile.urdf: link 'base_link': inertial mass: expected a positive number [kg], got -965"));
  EXPECT_THAT(UrdfError("<mass value=\"95\"/>", "<mass value=\"0\"/>"), HasSubstr("inertial mass: expected a positive"));
}

TEST(UrdfHostile, RejectsInertiasThatAreNotPositiveDefinite) {
  EXPECT_THAT(UrdfError("ixx=\"155.2\"", "ixx=\"-155.2\""),
              HasSubstr("link 'base_link': inertia: expected a finite, positive-definite matrix"));
  // Positive diagonal, but the off-diagonal makes it indefinite.
  EXPECT_THAT(UrdfError("ixx=\"3.62\" ixy=\"0\"", "ixx=\"3.62\" ixy=\"50\""), HasSubstr("positive-definite"));
  // Positive definite but no real body: 1 + 1 < 5.
  EXPECT_THAT(UrdfError("ixx=\"6.10\" ixy=\"0\" ixz=\"0\" iyy=\"6.10\" iyz=\"0\" izz=\"7.20\"",
                        "ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"5\""),
              HasSubstr("a + b >= c"));
}

TEST(UrdfHostile, RejectsNonFiniteOrigins) {
  std::string text = Urdf();
  const auto joint = text.find("<joint name=\"joint_2\"");
  ASSERT_NE(joint, std::string::npos);
  // urdfdom itself refuses "nan" and "1e999" but takes 1e308 (forward kinematics then overflow).
  const auto xyz = text.find("xyz=\"0.175", joint);
  ASSERT_NE(xyz, std::string::npos);
  text.replace(xyz, 10, "xyz=\"1e308");
  EXPECT_THAT(ErrorOf([&] { ParseRobotModel(text, "hostile.urdf"); }),
              HasSubstr("hostile.urdf: joint 'joint_2': origin: expected finite xyz (within 1 km) and rpy"));
}

std::string SiteError(const std::string& boundary) {
  return ErrorOf([&] { SiteFromConfig(ConfigNode::FromString("boundary: " + boundary + "\n", "site.yaml")); });
}

TEST(SiteHostile, RejectsRepeatedBoundaryPoints) {
  // Before: a wall of zero length, its direction normalised to NaN.
  EXPECT_THAT(SiteError("[[0, 0], [4, 0], [4, 0], [4, 3], [0, 3]]"),
              HasSubstr("site.yaml:1: boundary[2]: expected a point different from boundary[1]"));
  EXPECT_THAT(SiteError("[[0, 0], [4, 0], [4, 3], [0, 0]]"), HasSubstr("boundary[3]: expected a point different from boundary[0]"));
}

TEST(SiteHostile, RejectsSelfIntersectingBoundaries) {
  // A bow tie: its signed area is 0 for a symmetric one, so take an asymmetric one.
  EXPECT_THAT(SiteError("[[0, 0], [4, 3], [4, 0], [0, 4]]"),
              HasSubstr("boundary: expected a simple polygon (edges 0-1 and 2-3 cross)"));
  // A simple non-convex polygon is fine.
  EXPECT_EQ(SiteError("[[0, 0], [4, 0], [4, 3], [2, 1], [0, 3]]"), "");
}

}  // namespace
}  // namespace ifab
