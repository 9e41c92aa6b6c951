#include "ifab/core/config.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "ifab/core/testing/error_of.h"

namespace ifab {
namespace {

using ::testing::HasSubstr;
using testing::ErrorOf;

TEST(Config, ReadsTypedFieldsAndKeepsDefaults) {
  const auto c = ConfigNode::FromString("a: 1.5\nb: 3\nname: x\nv: [1, 2, 3]\n", "t.yaml");
  double a = 0, d = 7;
  int b = 0;
  c.ReadPositive("a", a);
  c.ReadPositive("b", b);
  c.Read("d", d);
  EXPECT_EQ(a, 1.5);
  EXPECT_EQ(b, 3);
  EXPECT_EQ(d, 7);
  EXPECT_EQ(c.Get<std::string>("name"), "x");
  EXPECT_EQ(c["v"].AsVector3(), Eigen::Vector3d(1, 2, 3));
}

TEST(Config, ErrorsNameFileLineFieldAndExpectation) {
  const auto c = ConfigNode::FromString("lrf:\n  sigma: -1\n  beams: many\n", "lrf.yaml");
  double sigma = 1;
  int beams = 1;
  EXPECT_THAT(ErrorOf([&] { c["lrf"].ReadPositive("sigma", sigma); }),
              HasSubstr("lrf.yaml:2: lrf.sigma: expected a positive number, got -1"));
  EXPECT_THAT(ErrorOf([&] { c["lrf"].Read("beams", beams); }),
              HasSubstr("lrf.yaml:3: lrf.beams: expected an integer, got many"));
  EXPECT_THAT(ErrorOf([&] { c["lrf"].Get<double>("range"); }),
              HasSubstr("lrf.range: required field is missing"));
  EXPECT_THAT(ErrorOf([&] { c["lrf"].ExpectKeys({"sigma"}); }),
              HasSubstr("lrf.yaml:3: lrf.beams: unknown field"));
}

TEST(Config, BadYamlAndMissingFile) {
  EXPECT_THAT(ErrorOf([] { ConfigNode::FromString("a: [1, 2\n", "bad.yaml"); }),
              HasSubstr("bad.yaml:"));
  EXPECT_THAT(ErrorOf([] { ConfigNode::LoadFile("/nonexistent/x.yaml"); }),
              HasSubstr("/nonexistent/x.yaml: cannot open"));
}

// YAML keys are unique; yaml-cpp would keep both and read the first, dropping the other silently.
TEST(Config, AKeyGivenTwiceIsRefusedWhereItRepeats) {
  EXPECT_THAT(ErrorOf([] { ConfigNode::FromString("mission:\n  max_sweeps: 3\n  look: true\n  max_sweeps: 5\n", "exp.yaml"); }),
              HasSubstr("exp.yaml:4: mission.max_sweeps: given twice (first on line 2)"));
  EXPECT_THAT(ErrorOf([] { ConfigNode::FromString("sweeps:\n  - {joint: 1, joint: 2}\n", "plan.yaml"); }),
              HasSubstr("plan.yaml:2: sweeps[0].joint: given twice"));
  EXPECT_NO_THROW(ConfigNode::FromString("a: {x: 1}\nb: {x: 1}\n", "ok.yaml"));  // the same key in two maps
}

TEST(Config, SequencesNameTheirIndex) {
  const auto c = ConfigNode::FromString("bricks:\n  - size: [0.24, 0.1, 0.05]\n  - size: [0.24, -0.1]\n",
                                        "site.yaml");
  EXPECT_THAT(ErrorOf([&] { c["bricks"][1]["size"].AsNumbers(3); }),
              HasSubstr("site.yaml:3: bricks[1].size: expected a list of 3 numbers, got [0.24, -0.1]"));
}

TEST(ConfigNode, OverlayChangesOnlyTheKeysItNames) {
  const ConfigNode shipped = ConfigNode::FromString("registration: {restarts: 2, max_iterations: 30, noise: {a: 1, b: 2}}\nother: 5\n", "shipped.yaml");
  const ConfigNode user = ConfigNode::FromString("registration: {max_iterations: 40, noise: {b: 3}}\n", "user.yaml");
  const ConfigNode merged = shipped.Overlay(user);
  EXPECT_EQ(merged["registration"].Get<int>("restarts"), 2);
  EXPECT_EQ(merged["registration"].Get<int>("max_iterations"), 40);
  EXPECT_EQ(merged["registration"]["noise"].Get<int>("a"), 1);
  EXPECT_EQ(merged["registration"]["noise"].Get<int>("b"), 3);
  EXPECT_EQ(merged.Get<int>("other"), 5);
  EXPECT_EQ(shipped["registration"].Get<int>("max_iterations"), 30);  // the base is not changed
  EXPECT_THAT(merged["registration"].Where(), HasSubstr("user.yaml"));
}

TEST(ConfigNode, SettingsChangeDottedKeysAndKeepTheFile) {
  const ConfigNode c = ConfigNode::FromString("mission: {tilt_compensation: imu, max_sweeps: 3}\nworld: as-built\n", "exp.yaml");
  ConfigNode s = ConfigNode::FromString("mission: {tilt_compensation: imu, max_sweeps: 3}\nworld: as-built\n", "exp.yaml");
  s.ApplySettings({"mission.tilt_compensation=none", "world=exact", "new.section.key=[1, 2]"});
  EXPECT_EQ(s["mission"].Get<std::string>("tilt_compensation"), "none");
  EXPECT_EQ(s["mission"].Get<int>("max_sweeps"), 3);
  EXPECT_EQ(s.Get<std::string>("world"), "exact");
  EXPECT_EQ(s["new"]["section"]["key"].AsNumbers(2)[1], 2.0);
  // Untouched keys keep their file and line for messages.
  EXPECT_THAT(s["mission"].Where(), HasSubstr("exp.yaml:1"));
  ConfigNode bad = c;
  EXPECT_THAT(ErrorOf([&] { bad.ApplySettings({"mission.tilt_compensation"}); }), HasSubstr("expected KEY=VALUE"));
  EXPECT_THAT(ErrorOf([&] { bad.ApplySettings({"world.x=1"}); }), HasSubstr("not a section"));
  EXPECT_THAT(ErrorOf([&] { bad.ApplySettings({"mission..x=1"}); }), HasSubstr("empty key"));
}

}  // namespace
}  // namespace ifab
