#include "ifab/perception/sweep_io.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>

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
    if (!v.is_number()) Fail(where + "." + key, "a number");
    return v.get<double>();
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
  json j;
  try {
    j = json::parse(in);
  } catch (const json::parse_error& e) {
    ThrowInputError("{}: not valid JSON: {}", path, e.what());
  }
  const Reader r(path);
  if (!j.is_object() || j.value("format", "") != "ifab-sweep")
    ThrowInputError("{}: not an ifab sweep file (expected \"format\": \"ifab-sweep\")", path);
  if (j.value("version", 0) != 1) ThrowInputError("{}: version: expected 1", path);
  SweepRecording s;
  s.name = j.value("name", path);
  const bool raw = j.contains("sync_pulses");

  const json& scans = r.Array(j, "sweep", "scans");
  for (std::size_t i = 0; i < scans.size(); ++i) {
    const std::string where = fmt::format("scans[{}]", i);
    const json& e = scans[i];
    LaserScan scan;
    if (raw) {
      scan.stamp.t_device = r.Number(e, where, "t_device");
      scan.stamp.sequence = static_cast<std::uint64_t>(r.Number(e, where, "sequence"));
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
    const json& ranges = r.Array(e, where, "ranges");
    scan.ranges.reserve(ranges.size());
    for (std::size_t k = 0; k < ranges.size(); ++k) {
      if (ranges[k].is_null()) scan.ranges.push_back(LaserScan::kNoReturn);
      else if (ranges[k].is_number()) scan.ranges.push_back(ranges[k].get<double>());
      else r.Fail(fmt::format("{}.ranges[{}]", where, k), "a number or null");
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
      js.stamp.sequence = static_cast<std::uint64_t>(r.Number(e, where, "sequence"));
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

  if (raw) {
    const json& pulses = r.Array(j, "sweep", "sync_pulses");
    DeviceClockSync laser_sync, arm_sync;
    for (std::size_t i = 0; i < pulses.size(); ++i) {
      const std::string where = fmt::format("sync_pulses[{}]", i);
      SyncPulse p;
      p.device = ParseDevice(r, pulses[i], where);
      p.sequence = static_cast<std::uint64_t>(r.Number(pulses[i], where, "sequence"));
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

void SaveSweep(const std::string& path, const SweepRecording& s, bool raw_stamps) {
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
  std::ofstream out(path);
  if (!out) ThrowInputError("{}: cannot open for writing", path);
  out << j.dump();
  if (!out) ThrowInputError("{}: write failed", path);
}

}  // namespace ifab
