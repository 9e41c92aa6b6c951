// Issue 14: hostile sweep files. Each case here was accepted (or undefined behaviour) before.
#include <gtest/gtest.h>

#include <sstream>

#include "ifab/core/testing/error_of.h"
#include "ifab/experiments/sweep_io.h"

namespace ifab {
namespace {

using testing::ErrorOf;

std::string ErrorOfSweep(const std::string& text) {
  return ErrorOf([&] {
    std::istringstream in(text);
    ParseSweep(in, "hostile.json");
  });
}

// A valid sweep (host stamps) with one scan field replaced.
std::string HostSweep(const std::string& scan0 = R"("t": 1.0, "range_min": 0.1, "range_max": 30.0, "ranges": [1.0, null])",
                      const std::string& t1 = "1.1") {
  return R"({"format": "ifab-sweep", "version": 1, "scans": [
      {"angle_min": -1, "angle_increment": 0.01, "time_increment": 1e-5, )" + scan0 + R"(},
      {"t": )" + t1 + R"(, "angle_min": -1, "angle_increment": 0.01, "time_increment": 1e-5, "range_min": 0.1,
       "range_max": 30.0, "ranges": [1.0]}],
    "joint_states": [{"t": 0.9, "q": [0,0,0,0,0,0]}, {"t": 1.2, "q": [0,0,0,0,0,0]}]})";
}

TEST(SweepHostile, AValidSweepLoads) {
  std::istringstream in(HostSweep());
  const SweepRecording s = ParseSweep(in, "ok.json");
  ASSERT_EQ(s.scans.size(), 2u);
  EXPECT_TRUE(std::isnan(s.scans[0].ranges[1]));
}

TEST(SweepHostile, RejectsRangeMinNotBelowRangeMax) {
  const std::string e = ErrorOfSweep(HostSweep(R"("t": 1.0, "range_min": 30.0, "range_max": 0.1, "ranges": [1.0])"));
  EXPECT_NE(e.find("hostile.json: scans[0].range_max: expected a number > range_min"), std::string::npos) << e;
}

TEST(SweepHostile, RejectsNegativeRanges) {
  const std::string e = ErrorOfSweep(HostSweep(R"("t": 1.0, "range_min": 0.1, "range_max": 30.0, "ranges": [1.0, -2.0])"));
  EXPECT_NE(e.find("scans[0].ranges[1]: expected a distance >= 0 [m] or null"), std::string::npos) << e;
}

TEST(SweepHostile, RejectsStampsOutOfOrder) {
  const std::string e = ErrorOfSweep(HostSweep(R"("t": 1.0, "range_min": 0.1, "range_max": 30.0, "ranges": [1.0])", "0.5"));
  EXPECT_NE(e.find("scans[1].t: expected a time after scans[0]'s"), std::string::npos) << e;
}

TEST(SweepHostile, RejectsNumbersBeyondADouble) {
  // Found by sweep_fuzz (tests/fuzz/corpus/sweep/regression_number_overflow.json): nlohmann's
  // parser throws out_of_range, not parse_error, for 1e405, and it escaped the loader.
  const std::string e = ErrorOfSweep(HostSweep(R"("t": 1.0, "range_min": 0.1, "range_max": 1e405, "ranges": [1.0])"));
  EXPECT_NE(e.find("hostile.json: not valid JSON (expected numbers within a double's range)"), std::string::npos) << e;
  EXPECT_NE(e.find("1e405"), std::string::npos) << e;
}

TEST(SweepHostile, RejectsNonNumericFormatVersionAndName) {
  // json::value() threw nlohmann's type_error (no InputError, no file name) for these.
  EXPECT_NE(ErrorOfSweep(R"({"format": 3})").find("not an ifab sweep file"), std::string::npos);
  EXPECT_NE(ErrorOfSweep(R"({"format": "ifab-sweep", "version": "one"})").find("version: expected 1"), std::string::npos);
  std::string named = HostSweep();
  named.insert(1, R"("name": [1], )");
  EXPECT_NE(ErrorOfSweep(named).find("hostile.json: name: expected a string"), std::string::npos);
}

// Raw stamps: a sequence cast from a negative or huge double was undefined behaviour.
std::string RawSweep(const std::string& sequence) {
  return R"({"format": "ifab-sweep", "version": 1, "scans": [
      {"t_device": 1.0, "sequence": )" + sequence + R"(, "angle_min": -1, "angle_increment": 0.01,
       "time_increment": 1e-5, "range_min": 0.1, "range_max": 30, "ranges": [1.0]}],
    "joint_states": [{"t_device": 0.9, "sequence": 1, "q": [0,0,0,0,0,0]},
                     {"t_device": 1.2, "sequence": 2, "q": [0,0,0,0,0,0]}],
    "sync_pulses": [{"device": "arm_laser", "sequence": 0, "t_host": 5.0}]})";
}

TEST(SweepHostile, RejectsSequencesThatAreNotWholeNonNegativeNumbers) {
  for (const char* bad : {"-1", "1e30", "2.5"}) {
    const std::string e = ErrorOfSweep(RawSweep(bad));
    EXPECT_NE(e.find("hostile.json: scans[0].sequence: expected a whole number >= 0"), std::string::npos)
        << bad << ": " << e;
  }
}

}  // namespace
}  // namespace ifab
