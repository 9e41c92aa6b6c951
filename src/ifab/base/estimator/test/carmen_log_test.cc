#include "ifab/base/estimator/carmen_log.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sstream>

#include "ifab/core/angles.h"
#include "ifab/core/error.h"
#include "ifab/core/testing/error_of.h"

namespace ifab::base {
namespace {

using ::testing::HasSubstr;

const std::string kData = ESTIMATOR_TEST_DATA;
using ::ifab::testing::ErrorOf;

TEST(CarmenLog, ReadsFlaserRobotlaserAndOdomAndSkipsTheRest) {
  const CarmenLog log = ReadCarmenLog(kData + "/good.clf");
  ASSERT_EQ(log.scans.size(), 3u);
  ASSERT_EQ(log.odometry.size(), 2u);
  // 2 comments, PARAM, an empty line, SYNC, UNKNOWNMESSAGE.
  EXPECT_EQ(log.skipped_lines, 6);

  // FLASER with an odd number of beams: -90..+90 degrees, both ends included.
  const LogScan& a = log.scans[0];
  EXPECT_EQ(a.line, 6);
  ASSERT_EQ(a.scan.size(), 5u);
  EXPECT_DOUBLE_EQ(a.scan.ranges[3], 81.9);
  EXPECT_NEAR(a.scan.angle_min, -kPi / 2, 1e-12);
  EXPECT_NEAR(a.scan.Angle(4), kPi / 2, 1e-12);
  EXPECT_DOUBLE_EQ(a.scan.stamp.t, 100.05);
  // One 81.9 m reading in a whole log is a reading, not a no-return code (a code repeats: see
  // CarmenLog.GeometryComesFromTheLog).
  EXPECT_TRUE(a.scan.IsValid(3));
  EXPECT_TRUE(a.scan.IsValid(0));
  EXPECT_DOUBLE_EQ(a.laser_pose.x, 0.10);
  EXPECT_DOUBLE_EQ(a.odom.x, 0.01);
  EXPECT_DOUBLE_EQ(a.odom.theta, 0.03);

  // FLASER with an even number of beams: 180 / n steps, the last one short of +90.
  const LogScan& b = log.scans[1];
  ASSERT_EQ(b.scan.size(), 4u);
  EXPECT_NEAR(b.scan.angle_increment, kPi / 4, 1e-12);
  EXPECT_NEAR(b.odom.theta, WrapAngle(-3.5), 1e-12);

  // ROBOTLASER1 carries its own angles and the robot pose.
  const LogScan& c = log.scans[2];
  ASSERT_EQ(c.scan.size(), 5u);
  EXPECT_DOUBLE_EQ(c.scan.angle_min, -1.5708);
  EXPECT_DOUBLE_EQ(c.scan.angle_increment, 0.7854);
  EXPECT_DOUBLE_EQ(c.scan.range_max, 30.0);
  EXPECT_DOUBLE_EQ(c.laser_pose.x, 1.0);
  EXPECT_DOUBLE_EQ(c.odom.x, 0.9);
  EXPECT_DOUBLE_EQ(c.scan.stamp.t, 100.45);

  EXPECT_DOUBLE_EQ(log.odometry[1].t, 100.50);
  EXPECT_DOUBLE_EQ(log.odometry[1].pose.x, 0.05);
}

TEST(CarmenLog, ConfigurableFlaserFieldOfView) {
  CarmenReadOptions options;
  options.flaser_fov_deg = 100.0;
  const CarmenLog log = ReadCarmenLog(kData + "/good.clf", options);
  EXPECT_NEAR(log.scans[0].scan.angle_min, DegToRad(-50.0), 1e-12);
  EXPECT_NEAR(log.scans[0].scan.angle_increment, DegToRad(25.0), 1e-12);
}

TEST(CarmenLog, BrokenLinesNameFileAndLine) {
  EXPECT_THAT(ErrorOf([] { ReadCarmenLog(kData + "/broken_count.clf"); }),
              HasSubstr("broken_count.clf:3: FLASER line ends early: expected odom_x odom_y odom_theta"));
  EXPECT_THAT(ErrorOf([] { ReadCarmenLog(kData + "/broken_number.clf"); }),
              HasSubstr("broken_number.clf:2: ODOM line: expected a number for x y theta (token 3), "
                        "got 'abc'"));
  EXPECT_THAT(ErrorOf([] { ReadCarmenLog(kData + "/missing.clf"); }),
              HasSubstr("missing.clf: cannot open"));
  std::istringstream bad_count("FLASER -3 1 2 3\n");
  EXPECT_THAT(ErrorOf([&] { ParseCarmenLog(bad_count, "x.clf"); }),
              HasSubstr("x.clf:1: FLASER line: expected a count in [0, 100000] for num_readings, got -3"));
}

// Small synthetic logs written the way CARMEN writes them. FLASER: 361 beams (SICK LMS at
// 0.5 deg), 81.91 m for no return; ROBOTLASER1: 181 beams at 1 deg and the laser 0.25 m ahead
// of and 0.05 m left of the robot centre, turned 2 deg. 5 Hz.
std::string FlaserLog(int scans) {
  std::ostringstream s;
  for (int k = 0; k < scans; ++k) {
    const double x = 0.1 * k;
    s << "FLASER 361";
    for (int i = 0; i < 361; ++i) s << ' ' << (i % 7 == 3 ? 81.91 : 2.0 + 0.01 * (i % 50));
    s << ' ' << x << " 0 0 " << x << " 0 0 " << 1000.0 + 0.2 * k << " nohost " << 0.2 * k << "\n";
  }
  return s.str();
}

std::string RobotLaserLog(int scans) {
  std::ostringstream s;
  const Pose2 T_robot_laser(0.25, 0.05, DegToRad(2.0));
  for (int k = 0; k < scans; ++k) {
    const Pose2 robot(0.2 * k, 0.1, DegToRad(10.0 * k));
    const Pose2 laser = robot * T_robot_laser;
    s << "ROBOTLASER1 0 " << -kPi / 2 << ' ' << kPi << ' ' << DegToRad(1.0) << " 50.0 0.01 0 181";
    for (int i = 0; i < 181; ++i) s << ' ' << (i % 9 == 0 ? 50.0 : 3.0 + 0.02 * (i % 30));
    s << " 0 " << laser.x << ' ' << laser.y << ' ' << laser.theta << ' ' << robot.x << ' ' << robot.y
      << ' ' << robot.theta << " 0.5 0.1 0.2 0.2 0 " << 2000.0 + 0.2 * k << " nohost " << 0.2 * k
      << "\n";
  }
  return s.str();
}

TEST(CarmenLog, GeometryComesFromTheLog) {
  {
    std::istringstream in(FlaserLog(30));
    const CarmenLog log = ParseCarmenLog(in, "flaser361.clf");
    const LogGeometry& g = log.geometry;
    EXPECT_EQ(g.message, "FLASER");
    EXPECT_EQ(g.beams, 361);
    EXPECT_NEAR(g.resolution, DegToRad(0.5), 1e-12);
    EXPECT_NEAR(g.fov, DegToRad(180.0), 1e-12);
    EXPECT_NEAR(g.angle_min, DegToRad(-90.0), 1e-12);
    EXPECT_DOUBLE_EQ(g.no_return_code, 81.91);
    EXPECT_NEAR(g.max_range, 2.49, 1e-9);
    EXPECT_NEAR(g.scan_rate, 5.0, 1e-6);
    EXPECT_FALSE(g.laser_offset_in_log);
    EXPECT_FALSE(log.scans[0].scan.IsValid(3)) << "the no-return code is no return";
    EXPECT_TRUE(log.scans[0].scan.IsValid(4));
  }
  {
    std::istringstream in(RobotLaserLog(30));
    const CarmenLog log = ParseCarmenLog(in, "robotlaser181.clf");
    const LogGeometry& g = log.geometry;
    EXPECT_EQ(g.message, "ROBOTLASER1");
    EXPECT_EQ(g.beams, 181);
    EXPECT_NEAR(g.resolution, DegToRad(1.0), 1e-6);
    EXPECT_NEAR(g.fov, DegToRad(180.0), 1e-4);
    EXPECT_DOUBLE_EQ(g.no_return_code, 50.0);
    EXPECT_NEAR(g.max_range, 3.58, 1e-9);
    EXPECT_NEAR(g.scan_rate, 5.0, 1e-6);
    EXPECT_TRUE(g.laser_offset_in_log);
    EXPECT_NEAR(g.T_base_laser.x, 0.25, 1e-5);
    EXPECT_NEAR(g.T_base_laser.y, 0.05, 1e-5);
    EXPECT_NEAR(g.T_base_laser.theta, DegToRad(2.0), 1e-5);
    EXPECT_FALSE(log.scans[0].scan.IsValid(0));
  }
}

// A line whose beam count is wrong shifts every field after the readings; the tokens left over
// (or missing) must be an error naming the line, never a silent misread.
TEST(CarmenLog, LeftoverTokensAfterAScanAreAnError) {
  std::string text = FlaserLog(2);
  const auto at = text.find("FLASER 361");
  text.replace(at, 10, "FLASER 360");  // one reading more than declared on line 1
  std::istringstream in(text);
  EXPECT_THAT(ErrorOf([&] { ParseCarmenLog(in, "wrong_count.clf"); }),
              HasSubstr("wrong_count.clf:1: FLASER line: expected the line to end after the timestamp"));
  std::istringstream odom("ODOM 0 0 0 0 0 0 100.0 nohost 0.0 extra\n");
  EXPECT_THAT(ErrorOf([&] { ParseCarmenLog(odom, "o.clf"); }), HasSubstr("o.clf:1: ODOM line"));
  std::istringstream fine("ODOM 0 0 0 0 0 0 100.0\nODOM 0 0 0 0 0 0 100.1 host 0.1\n");
  EXPECT_EQ(ParseCarmenLog(fine, "f.clf").odometry.size(), 2u);
}

TEST(Relations, ReadsWithHeaderAndComments) {
  const auto rel = ReadRelations(kData + "/good.relations");
  ASSERT_EQ(rel.size(), 2u);
  EXPECT_DOUBLE_EQ(rel[0].t1, 100.05);
  EXPECT_DOUBLE_EQ(rel[0].t2, 100.25);
  EXPECT_DOUBLE_EQ(rel[0].delta.x, 0.5);
  EXPECT_DOUBLE_EQ(rel[0].delta.y, 0.1);
  EXPECT_DOUBLE_EQ(rel[0].delta.theta, 0.2);
  EXPECT_NEAR(rel[1].delta.theta, WrapAngle(-3.0), 1e-12);
  EXPECT_EQ(rel[1].line, 4);
}

TEST(Relations, BrokenLinesNameFileAndLine) {
  EXPECT_THAT(ErrorOf([] { ReadRelations(kData + "/broken.relations"); }),
              HasSubstr("broken.relations:2: expected 8 numbers 't1 t2 x y z roll pitch yaw'"));
  std::istringstream late_header("1 2 0 0 0 0 0 0\nt1 t2 x y z roll pitch yaw\n");
  EXPECT_THAT(ErrorOf([&] { ParseRelations(late_header, "r.txt"); }), HasSubstr("r.txt:2: expected 8"));
  std::istringstream not_planar("1 2 0 0 0.5 0 0 0\n");
  EXPECT_THAT(ErrorOf([&] { ParseRelations(not_planar, "r.txt"); }),
              HasSubstr("r.txt:1: expected a planar relation"));
}

}  // namespace
}  // namespace ifab::base
