// Issue 7's integration test: the short brick stacking variant (3 bricks, 2 building positions,
// 2 repositionings) runs the whole Fig. 2 loop in the simulator (slip, laser noise and bias,
// gyro, clocks, arm and gripper errors all on). Issue 12: in the exact world (`world: exact`) the
// old figures return; in the as-built world (the default) the mission still completes.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <regex>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "ifab/core/data_path.h"
#include "ifab/core/error.h"
#include "ifab/experiments/experiment.h"

namespace ifab::experiments {
namespace {

// The short variant's config with one line replaced (`key: value`), written beside the test's output.
std::string ShortConfigWith(const std::vector<std::pair<std::string, std::string>>& keys, const std::string& name) {
  std::ifstream in(DataPath("experiments/brick-stack-short.yaml"));
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  for (const auto& [key, value] : keys) {
    if (value.empty() || value.front() != '\n') {
      s = std::regex_replace(s, std::regex("\\n" + key + ":[^\\n]*"), "\n" + key + ": " + value);
      continue;
    }
    // A block of keys for a section ("\n  k: v" lines): each replaces the section's own line of
    // that key, or joins the section (a key given twice is an error).
    const std::size_t head = s.find("\n" + key + ":");
    if (head == std::string::npos) throw std::runtime_error("no section " + key);
    const std::size_t body = s.find('\n', head + 1);
    std::smatch next;
    const std::string rest = s.substr(body);
    const std::size_t end =
        std::regex_search(rest, next, std::regex("\\n[^ #\\n]")) ? body + static_cast<std::size_t>(next.position(0)) : s.size();
    std::string section = s.substr(body, end - body);
    std::istringstream lines(value.substr(1));
    for (std::string line; std::getline(lines, line);) {
      const std::string field = line.substr(0, line.find(':'));
      const std::regex own("\\n" + field + ":[^\\n]*");
      if (std::regex_search(section, own)) section = std::regex_replace(section, own, "\n" + line);
      else section = "\n" + line + section;
    }
    s = s.substr(0, body) + section + s.substr(end);
  }
  // Paths in the file are relative to data/experiments/.
  s = std::regex_replace(s, std::regex(": \\.\\./"), ": " + DataPath("") + "/");
  const auto path = std::filesystem::path(::testing::TempDir()) / (name + ".yaml");
  std::ofstream(path) << s;
  return path.string();
}

std::string ShortConfigWith(const std::string& key, const std::string& value, const std::string& name) {
  return ShortConfigWith({{key, value}}, name);
}

RunOptions ShortRun(const std::string& config, const std::string& name) {
  RunOptions o;
  o.experiment = "brick-stack";
  o.config_path = config;
  o.out_dir = (std::filesystem::path(::testing::TempDir()) / name).string();
  o.force = true;  // ctest may run again over the same folder
  o.progress = false;
  return o;
}

// `world: exact` with eq. 6 as written (no range-bias compensation): the pipeline and world of
// main before issue 12. The old figures (main before issue 12, seed 1: long /
// short 0.60 / 0.63 mm, worst 1.66 mm, the same calibrated mount) return within noise: the
// mission now waits for the accelerometers and uses the registered attitude, so the random
// streams run differently after the first brick.
TEST(BrickStack, ShortVariantPlacesEveryBrickNearItsDesignedPose) {
  // ... and the six-sweep calibration plan those figures were measured with.
  const RunOptions o = ShortRun(ShortConfigWith({{"world", "exact\nrange_bias_compensation: false"},
                                                 {"laser_calibration", "../perception/arm_laser_calibration.yaml"}},
                                                "brick_stack_short_exact"),
                                "ifab_brick_stack_short");
  const auto r = RunExperiment(o);
  EXPECT_FALSE(r["failed"].get<bool>()) << r.dump(2);
  EXPECT_EQ(r["bricks_placed"].get<int>(), 3);
  EXPECT_EQ(r["repositionings"].get<int>(), 2);
  // The arm laser's mount was calibrated first; the paper's figures bound the mean errors, and
  // no brick may be off by more than 5 mm.
  EXPECT_EQ(r["arm_laser_mount"]["source"].get<std::string>(), "calibrated");
  EXPECT_LE(r["brick_error_long_mm_mean"].get<double>(), 4.6);
  EXPECT_LE(r["brick_error_short_mm_mean"].get<double>(), 3.5);
  EXPECT_LE(r["brick_error_mm_max"].get<double>(), 5.0);
  EXPECT_LE(r["after_localization_vs_desired_m_max"].get<double>(), 0.08);
  EXPECT_LE(r["after_localization_vs_desired_deg_max"].get<double>(), 4.0);
  for (const char* f : {"brick_errors.csv", "trajectory_planned.csv", "trajectory_estimated.csv",
                        "trajectory_true.csv", "visits.csv", "results.json"})
    EXPECT_TRUE(std::filesystem::exists(std::filesystem::path(o.out_dir) / f)) << f;
  // Within noise of the old figures: the calibration is pinned (it runs before the mission, so
  // a change there shows here first), the placed bricks within a millimetre. Pinned value since
  // the simulated laser's beams straddle and cross an edge with the width they have at the edge
  // (issue 12, session 15): 3.462 mm; 3.648 mm before (the footprint at the beam's own range),
  // 3.724 mm with the polar method's draws before the ziggurat (issue 15). 4.722 mm since each
  // calibration scan is levelled by the accelerometer (issue 12, session 25): the exact world's base
  // does not tilt, so here the levelling brings only the accelerometer's noise, and the six-sweep
  // plan fixes the mount's x (along the flange) weakly, so it moved by 1.3 mm.
  EXPECT_EQ(r["as_built"]["world"].get<std::string>(), "exact");
  EXPECT_NEAR(r["arm_laser_mount"]["error_vs_true_mm"][0].get<double>(), 4.722, 0.01);
  EXPECT_NEAR(r["brick_error_long_mm_mean"].get<double>(), 0.60, 1.0);
  EXPECT_NEAR(r["brick_error_short_mm_mean"].get<double>(), 0.63, 1.0);
  EXPECT_LE(r["brick_error_mm_max"].get<double>(), 1.66 + 1.5);
}

// The default, as-built world: every brick placed, and results.json says what was drawn. Its
// accuracy is measured over seeds in the README, not asserted here (one short run is noise).
TEST(BrickStack, AsBuiltWorldCompletesAndSummarisesItsDraws) {
  const RunOptions o = ShortRun(DataPath("experiments/brick-stack-short.yaml"), "ifab_brick_stack_short_as_built");
  const auto r = RunExperiment(o);
  EXPECT_FALSE(r["failed"].get<bool>()) << r.dump(2);
  EXPECT_EQ(r["bricks_placed"].get<int>(), 3);
  const auto& a = r["as_built"];
  EXPECT_EQ(a["world"].get<std::string>(), "as-built");
  for (const char* key : {"brick_batch_mean_deviation_mm", "floor_worst_step_mm", "arm_flange_error_mm", "arm_laser",
                          "arm_laser_mount_error", "base_compliance_deg_per_knm"})
    EXPECT_TRUE(a.contains(key)) << key;
  EXPECT_LE(a["floor_worst_step_mm"]["1m"].get<double>(), 4.0);  // DIN 18202
  EXPECT_LE(r["brick_error_mm_max"].get<double>(), 20.0);       // placed on the stack, not beside it
  EXPECT_GT(r["tilt_change_measured_deg_max"].get<double>(), 0.0);  // the accelerometers were used
}

// One CSV file's rows as column name -> text (fields in double quotes may hold commas).
std::vector<std::map<std::string, std::string>> ReadCsv(const std::filesystem::path& path) {
  std::ifstream in(path);
  const auto split = [](const std::string& line) {
    std::vector<std::string> fields(1);
    bool quoted = false;
    for (char c : line) {
      if (c == '"') quoted = !quoted;
      else if (c == ',' && !quoted) fields.emplace_back();
      else fields.back() += c;
    }
    return fields;
  };
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> header = split(line);
  std::vector<std::map<std::string, std::string>> rows;
  while (std::getline(in, line)) {
    const std::vector<std::string> fields = split(line);
    EXPECT_EQ(fields.size(), header.size()) << path << ": " << line;
    auto& row = rows.emplace_back();
    for (std::size_t i = 0; i < std::min(fields.size(), header.size()); ++i) row[header[i]] = fields[i];
  }
  return rows;
}

// The look after placing at brick 0, read back with its truth (brick 0 is designed at the site's
// origin, heading 0: its true x, y are its offset); nullopt (with a failure) when it is missing.
struct FirstBrickLook {
  double look[2]{}, stddev[2]{}, truth[2]{};  // [mm] along the site's x and y
  std::map<std::string, std::string> brick;   // brick_errors.csv's row
};
std::optional<FirstBrickLook> LookAtFirstBrick(const RunOptions& o) {
  const auto r = RunExperiment(o);
  EXPECT_FALSE(r["failed"].get<bool>()) << r.dump(2);
  const auto visits = ReadCsv(std::filesystem::path(o.out_dir) / "visits.csv");
  const auto bricks = ReadCsv(std::filesystem::path(o.out_dir) / "brick_errors.csv");
  if (visits.empty() || bricks.empty() || bricks[0].at("brick") != "0") {
    ADD_FAILURE() << o.out_dir << ": no visit or no brick 0";
    return std::nullopt;
  }
  FirstBrickLook f;
  f.brick = bricks[0];
  const char* axes[2] = {"x", "y"};
  for (int a = 0; a < 2; ++a) {
    const std::string& look = visits[0].at(std::string("check_offset_") + axes[a] + "_mm");
    const std::string& stddev = visits[0].at(std::string("check_std_") + axes[a] + "_mm");
    if (look.empty() || stddev.empty()) {
      ADD_FAILURE() << o.out_dir << ": brick 0 was not measured";
      return std::nullopt;
    }
    f.look[a] = std::stod(look);
    f.stddev[a] = std::stod(stddev);
    f.truth[a] = 1e3 * std::stod(bricks[0].at(std::string(axes[a]) + "_m"));
  }
  return f;
}

// The look after placing (mission.check_placement) in the exact world: the first brick, seen
// from the start pose, lies where the look says, within four times the std it reports. Before
// the look compensated the range bias at the registered model's incidence, it put the brick
// 1.5 / 2.5 mm off (README, issue 12, session 19).
TEST(BrickStack, LookAfterPlacingFindsTheFirstBrickWithinItsStd) {
  const RunOptions o = ShortRun(ShortConfigWith({{"world", "exact"},
                                                 {"write_clouds", "false"},
                                                 {"mission", "\n  check_placement: true"},
                                                 {"  bricks", "1"}},  // the first brick alone
                                                "brick_stack_short_check"),
                                "ifab_brick_stack_short_check");
  const auto f = LookAtFirstBrick(o);
  ASSERT_TRUE(f);
  for (int a = 0; a < 2; ++a) {
    EXPECT_GT(f->stddev[a], 0.0);
    EXPECT_LT(f->stddev[a], 1.0) << a;  // a look that knows the brick to about a millimetre
    EXPECT_NEAR(f->look[a], f->truth[a], 4.0 * f->stddev[a]) << "axis " << a << ": std " << f->stddev[a] << " mm";
  }
}

// The look at a brick whose size is off its design (look_footprint), in a world where only the
// bricks' size is as built (tests/data/as_built_bricks_only.yaml): the first brick, seen from the
// start pose, is found within four times the std the look reports once the look takes its centre
// between the near faces and the far edges; registered at its design size, it sits half the size
// error towards the laser, farther off.
TEST(BrickStack, LookWithTheBricksFootprintFindsABrickOfAnotherSize) {
  std::map<bool, double> worst;  // look_footprint -> the look's largest axis error [mm]
  for (const bool footprint : {false, true}) {
    const std::string name = footprint ? "brick_stack_short_look_footprint" : "brick_stack_short_look_design";
    const RunOptions o = ShortRun(
        ShortConfigWith({{"as_built", std::string(IFAB_TEST_DATA_DIR) + "/as_built_bricks_only.yaml"},
                         {"write_clouds", "false"},
                         {"mount", "design"},  // this world's mount is the design's: no calibration needed
                         {"mission", std::string("\n  check_placement: true\n  look_footprint: ") +
                                         (footprint ? "true" : "false")},
                         {"  bricks", "1"}},
                        name),
        "ifab_" + name);
    const auto f = LookAtFirstBrick(o);
    ASSERT_TRUE(f);
    // The drawn brick is millimetres off its design (else this test shows nothing).
    EXPECT_GT(std::max(std::abs(std::stod(f->brick.at("true_length_mm")) - 240.0),
                       std::abs(std::stod(f->brick.at("true_width_mm")) - 115.0)),
              2.0);
    worst[footprint] = 0.0;
    for (int a = 0; a < 2; ++a) {
      const double error = f->look[a] - f->truth[a];
      worst[footprint] = std::max(worst[footprint], std::abs(error));
      if (footprint) {
        EXPECT_LT(std::abs(error), 4.0 * f->stddev[a]) << "axis " << a << ": std " << f->stddev[a] << " mm";
      }
    }
  }
  EXPECT_LT(worst[true], worst[false]);
}

// The look against the localization (check_against: localization) in the exact world, where the
// scan chain has no systematic error: at the start and after the first repositioning, each look
// puts its brick where the brick truly lies in the frame it was sent in (the visit's registered
// pose), within four times the std it reports; and each look reaches the miss filter.
TEST(BrickStack, LookAgainstTheLocalizationFindsEachBrickInTheFrameItWasSentIn) {
  const RunOptions o = ShortRun(ShortConfigWith({{"world", "exact"},
                                                 {"write_clouds", "false"},
                                                 {"mission", "\n  check_placement: true\n  check_against: localization"
                                                             "\n  learn_placement_bias: true"},
                                                 {"  bricks", "2"}},
                                                "brick_stack_short_check_localization"),
                                "ifab_brick_stack_short_check_localization");
  const auto r = RunExperiment(o);
  EXPECT_FALSE(r["failed"].get<bool>()) << r.dump(2);
  const auto visits = ReadCsv(std::filesystem::path(o.out_dir) / "visits.csv");
  const auto bricks = ReadCsv(std::filesystem::path(o.out_dir) / "brick_errors.csv");
  ASSERT_EQ(visits.size(), 2u);
  ASSERT_EQ(bricks.size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    const auto& v = visits[k];
    const auto num = [&](const std::string& key) { return std::stod(v.at(key)); };
    // The pose the brick was sent from (the start, given; then the registered one) and the true one.
    const bool localized = v.at("localized") == "1" || v.at("localized") == "true";
    const Eigen::Rotation2Dd R_est(localized ? num("loc_theta") : num("desired_theta"));
    const Eigen::Vector2d t_est = localized ? Eigen::Vector2d(num("loc_x"), num("loc_y"))
                                            : Eigen::Vector2d(num("desired_x"), num("desired_y"));
    const Eigen::Rotation2Dd R_true(num("true_theta"));
    const Eigen::Vector2d t_true(num("true_x"), num("true_y"));
    // Brick k is designed at the site's origin: where it truly lies, in the frame it was sent in.
    const Eigen::Vector2d p(std::stod(bricks[k].at("x_m")), std::stod(bricks[k].at("y_m")));
    const Eigen::Vector2d truth = 1e3 * (R_est * (R_true.inverse() * (p - t_true)) + t_est);
    const char* axes[2] = {"x", "y"};
    for (int a = 0; a < 2; ++a) {
      const std::string& look = v.at(std::string("check_offset_") + axes[a] + "_mm");
      const std::string& stddev = v.at(std::string("check_std_") + axes[a] + "_mm");
      ASSERT_FALSE(look.empty() || stddev.empty()) << "brick " << k << " was not measured";
      const double sigma = std::stod(stddev);
      EXPECT_GT(sigma, 0.0);
      EXPECT_NEAR(std::stod(look), truth[a], 4.0 * sigma) << "brick " << k << " " << axes[a] << ": std " << sigma;
      EXPECT_FALSE(v.at(std::string("placement_bias_") + axes[a] + "_mm").empty()) << "the look fed no filter";
    }
  }
}

// The stack's side opens design files only: a "robot" YAML with the simulator's section is refused.
TEST(BrickStack, StackRefusesADesignFileWithASimulatorSection) {
  const RunOptions o = ShortRun(ShortConfigWith("robot", DataPath("sim/insitu_fabricator.yaml"), "brick_stack_sim_robot"),
                                "ifab_brick_stack_sim_robot");
  try {
    RunExperiment(o);
    FAIL() << "expected an error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no sim: section in a design file"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ifab::experiments
