#include "ifab/experiments/sweep_io.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <ostream>
#include <istream>

#include "ifab/core/error.h"
#include "ifab/sync/clock_sync.h"

namespace ifab {
namespace {

using nlohmann::json;

// Field access that names the file and the field path on error.
class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  const json& Field(const json& j, const std::string& where, const char* key) const {
    if (!j.is_object()) Fail(where, "an object");
    auto it = j.find(key);
    if (it == j.end()) ThrowInputError("{}: {}: missing field '{}'", file_, where, key);
    return *it;
  }
  double Number(const json& j, const std::string& where, const char* key) const {
    const json& v = Field(j, where, key);
    if (!v.is_number() || !std::isfinite(v.get<double>())) Fail(where + "." + key, "a finite number");
    return v.get<double>();
  }
  // A packet counter: a whole number from 0 to 2^53 (a cast of a negative, fractional or huge
  // double to uint64 would be undefined or silently wrong).
  std::uint64_t Sequence(const json& j, const std::string& where) const {
    const json& v = Field(j, where, "sequence");
    if (v.is_number_unsigned()) return v.get<std::uint64_t>();
    const double d = v.is_number() ? v.get<double>() : -1.0;
    if (!(d >= 0.0 && d <= 9007199254740992.0 && std::floor(d) == d))
      Fail(where + ".sequence", "a whole number >= 0");
    return static_cast<std::uint64_t>(d);
  }
  std::string String(const json& j, const char* key, const std::string& fallback) const {
    auto it = j.find(key);
    if (it == j.end()) return fallback;
    if (!it->is_string()) Fail(key, "a string");
    return it->get<std::string>();
  }
  const json& Array(const json& j, const std::string& where, const char* key) const {
    const json& v = Field(j, where, key);
    if (!v.is_array()) Fail(where + "." + key, "an array");
    return v;
  }
  [[noreturn]] void Fail(const std::string& where, const std::string& expected) const {
    ThrowInputError("{}: {}: expected {}", file_, where, expected);
  }

 private:
  std::string file_;
};

DeviceId ParseDevice(const Reader& r, const json& j, const std::string& where) {
  const json& d = r.Field(j, where, "device");
  if (d == "arm_laser") return DeviceId::kArmLaser;
  if (d == "arm") return DeviceId::kArm;
  if (d == "base_laser") return DeviceId::kBaseLaser;
  if (d == "gyro") return DeviceId::kGyro;
  r.Fail(where + ".device", "one of arm_laser, arm, base_laser, gyro");
}

const char* DeviceKey(DeviceId id) {
  switch (id) {
    case DeviceId::kArmLaser: return "arm_laser";
    case DeviceId::kArm: return "arm";
    case DeviceId::kBaseLaser: return "base_laser";
    case DeviceId::kGyro: return "gyro";
  }
  return "unknown";
}

}  // namespace

SweepRecording LoadSweep(const std::string& path) {
  std::ifstream in(path);
  if (!in) ThrowInputError("{}: cannot open for reading", path);
  return ParseSweep(in, path);
}

SweepRecording ParseSweep(std::istream& in, const std::string& path) {
  json j;
  try {
    j = json::parse(in);
  } catch (const json::exception& e) {
    // parse_error, and out_of_range for a number beyond a double (1e405; found by sweep_fuzz).
    ThrowInputError("{}: not valid JSON (expected numbers within a double's range): {}", path, e.what());
  }
  const Reader r(path);
  if (!j.is_object() || !j.contains("format") || j["format"] != "ifab-sweep")
    ThrowInputError("{}: not an ifab sweep file (expected \"format\": \"ifab-sweep\")", path);
  if (!j.contains("version") || j["version"] != 1) ThrowInputError("{}: version: expected 1", path);
  SweepRecording s;
  s.name = r.String(j, "name", path);
  const bool raw = j.contains("sync_pulses");

  const json& scans = r.Array(j, "sweep", "scans");
  for (std::size_t i = 0; i < scans.size(); ++i) {
    const std::string where = fmt::format("scans[{}]", i);
    const json& e = scans[i];
    LaserScan scan;
    if (raw) {
      scan.stamp.t_device = r.Number(e, where, "t_device");
      scan.stamp.sequence = r.Sequence(e, where);
    } else {
      scan.stamp.t = r.Number(e, where, "t");
    }
    scan.angle_min = r.Number(e, where, "angle_min");
    scan.angle_increment = r.Number(e, where, "angle_increment");
    scan.time_increment = r.Number(e, where, "time_increment");
    scan.range_min = r.Number(e, where, "range_min");
    scan.range_max = r.Number(e, where, "range_max");
    if (!(scan.angle_increment > 0)) r.Fail(where + ".angle_increment", "a positive number");
    if (!(scan.time_increment >= 0)) r.Fail(where + ".time_increment", "a number >= 0");
    if (!(scan.range_min >= 0)) r.Fail(where + ".range_min", "a number >= 0");
    if (!(scan.range_min < scan.range_max)) r.Fail(where + ".range_max", "a number > range_min");
    const json& ranges = r.Array(e, where, "ranges");
    scan.ranges.reserve(ranges.size());
    for (std::size_t k = 0; k < ranges.size(); ++k) {
      // A beam without a return is null; every other range is a distance (finite, >= 0).
      if (ranges[k].is_null()) scan.ranges.push_back(LaserScan::kNoReturn);
      else if (ranges[k].is_number() && std::isfinite(ranges[k].get<double>()) && ranges[k].get<double>() >= 0)
        scan.ranges.push_back(ranges[k].get<double>());
      else r.Fail(fmt::format("{}.ranges[{}]", where, k), "a distance >= 0 [m] or null");
    }
    s.scans.push_back(std::move(scan));
  }
  const json& joints = r.Array(j, "sweep", "joint_states");
  for (std::size_t i = 0; i < joints.size(); ++i) {
    const std::string where = fmt::format("joint_states[{}]", i);
    const json& e = joints[i];
    JointState js;
    if (raw) {
      js.stamp.t_device = r.Number(e, where, "t_device");
      js.stamp.sequence = r.Sequence(e, where);
    } else {
      js.stamp.t = r.Number(e, where, "t");
    }
    const json& q = r.Array(e, where, "q");
    if (q.size() != 6) r.Fail(where + ".q", "6 joint angles [rad]");
    for (int k = 0; k < 6; ++k) {
      if (!q[static_cast<std::size_t>(k)].is_number()) r.Fail(fmt::format("{}.q[{}]", where, k), "a number");
      js.q[k] = q[static_cast<std::size_t>(k)].get<double>();
    }
    s.joint_states.push_back(js);
  }
  if (s.joint_states.size() < 2) ThrowInputError("{}: joint_states: expected at least 2 samples", path);
  // Scans and joint states are interpolated in time: their stamps must increase.
  const auto stamp_of = [&](const Stamp& st) { return raw ? st.t_device : st.t; };
  const char* stamp_key = raw ? "t_device" : "t";
  for (std::size_t i = 1; i < s.scans.size(); ++i)
    if (!(stamp_of(s.scans[i].stamp) > stamp_of(s.scans[i - 1].stamp)))
      r.Fail(fmt::format("scans[{}].{}", i, stamp_key), fmt::format("a time after scans[{}]'s (stamps in time order)", i - 1));
  for (std::size_t i = 1; i < s.joint_states.size(); ++i)
    if (!(stamp_of(s.joint_states[i].stamp) > stamp_of(s.joint_states[i - 1].stamp)))
      r.Fail(fmt::format("joint_states[{}].{}", i, stamp_key),
             fmt::format("a time after joint_states[{}]'s (stamps in time order)", i - 1));

  if (raw) {
    const json& pulses = r.Array(j, "sweep", "sync_pulses");
    DeviceClockSync laser_sync, arm_sync;
    for (std::size_t i = 0; i < pulses.size(); ++i) {
      const std::string where = fmt::format("sync_pulses[{}]", i);
      SyncPulse p;
      p.device = ParseDevice(r, pulses[i], where);
      p.sequence = r.Sequence(pulses[i], where);
      p.t_host = r.Number(pulses[i], where, "t_host");
      s.sync_pulses.push_back(p);
      if (p.device == DeviceId::kArmLaser) laser_sync.AddPulse(p);
      else if (p.device == DeviceId::kArm) arm_sync.AddPulse(p);
    }
    for (const auto& scan : s.scans) laser_sync.AddPacket(scan.stamp);
    for (const auto& js : s.joint_states) arm_sync.AddPacket(js.stamp);
    for (auto& scan : s.scans)
      if (!laser_sync.Apply(scan.stamp)) ThrowInputError("{}: no sync pulse of the arm laser matches any scan", path);
    for (auto& js : s.joint_states)
      if (!arm_sync.Apply(js.stamp)) ThrowInputError("{}: no sync pulse of the arm matches any joint state", path);
  }
  return s;
}

void WriteSweep(std::ostream& out, const SweepRecording& s, bool raw_stamps) {
  json j = {{"format", "ifab-sweep"}, {"version", 1}, {"name", s.name}};
  json scans = json::array();
  for (const auto& scan : s.scans) {
    json e = {{"angle_min", scan.angle_min}, {"angle_increment", scan.angle_increment},
              {"time_increment", scan.time_increment}, {"range_min", scan.range_min}, {"range_max", scan.range_max}};
    if (raw_stamps) {
      e["t_device"] = scan.stamp.t_device;
      e["sequence"] = scan.stamp.sequence;
    } else {
      e["t"] = scan.stamp.t;
    }
    json ranges = json::array();
    for (double r : scan.ranges) ranges.push_back(std::isfinite(r) ? json(r) : json(nullptr));
    e["ranges"] = std::move(ranges);
    scans.push_back(std::move(e));
  }
  j["scans"] = std::move(scans);
  json joints = json::array();
  for (const auto& js : s.joint_states) {
    json e = {{"q", std::vector<double>(js.q.data(), js.q.data() + 6)}};
    if (raw_stamps) {
      e["t_device"] = js.stamp.t_device;
      e["sequence"] = js.stamp.sequence;
    } else {
      e["t"] = js.stamp.t;
    }
    joints.push_back(std::move(e));
  }
  j["joint_states"] = std::move(joints);
  if (raw_stamps) {
    json pulses = json::array();
    for (const auto& p : s.sync_pulses)
      pulses.push_back({{"device", DeviceKey(p.device)}, {"sequence", p.sequence}, {"t_host", p.t_host}});
    j["sync_pulses"] = std::move(pulses);
  }
  out << j.dump();
}

}  // namespace ifab
