#include "ifab/base/estimator/carmen_log.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <string_view>
#include <algorithm>
#include <map>

#include "ifab/core/angles.h"
#include "ifab/core/error.h"

namespace ifab::base {
namespace {

// Whitespace-separated tokens of a line (views into it).
void Tokenize(std::string_view line, std::vector<std::string_view>* tokens) {
  tokens->clear();
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > start) tokens->push_back(line.substr(start, i - start));
  }
}

bool ParseDouble(std::string_view s, double* value) {
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), *value);
  return ec == std::errc() && ptr == s.data() + s.size() && std::isfinite(*value);
}

// Reads the tokens of one line in order, failing with the file, line and field.
class LineReader {
 public:
  LineReader(const std::vector<std::string_view>& tokens, const std::string& file, int line)
      : tokens_(tokens), file_(file), line_(line) {}

  double Number(const char* field) {
    if (next_ >= tokens_.size()) {
      ThrowInputError("{}:{}: {} line ends early: expected {} (token {}), got end of line", file_,
                      line_, tokens_[0], field, next_ + 1);
    }
    double v = 0.0;
    if (!ParseDouble(tokens_[next_], &v)) {
      ThrowInputError("{}:{}: {} line: expected a number for {} (token {}), got '{}'", file_, line_,
                      tokens_[0], field, next_ + 1, tokens_[next_]);
    }
    ++next_;
    return v;
  }

  int Count(const char* field, int max_count) {
    const double v = Number(field);
    if (v < 0 || v != std::floor(v) || v > max_count) {
      ThrowInputError("{}:{}: {} line: expected a count in [0, {}] for {}, got {}", file_, line_,
                      tokens_[0], max_count, field, tokens_[next_ - 1]);
    }
    return static_cast<int>(v);
  }

  Pose2 Pose(const char* field) {
    const double x = Number(field), y = Number(field), theta = Number(field);
    return {x, y, WrapAngle(theta)};
  }

  std::size_t Remaining() const { return tokens_.size() - next_; }

  // After the timestamp a line may carry "hostname logger_timestamp" and nothing else. Any
  // other leftover means the fields were misread (most often a wrong beam or remission count,
  // which shifts every field after it): an error, never a silent misread.
  void ExpectEnd(int declared_count) {
    const std::size_t left = Remaining();
    double v = 0.0;
    if (left == 0) return;
    if (left == 2 && !ParseDouble(tokens_[next_], &v) && ParseDouble(tokens_[next_ + 1], &v)) return;
    ThrowInputError(
        "{}:{}: {} line: expected the line to end after the timestamp (token {}) or to carry "
        "'hostname logger_timestamp', got {} more token(s) starting '{}': does the line hold the "
        "{} readings it declares?",
        file_, line_, tokens_[0], next_, left, tokens_[next_], declared_count);
  }

 private:
  const std::vector<std::string_view>& tokens_;
  const std::string& file_;
  int line_;
  std::size_t next_{1};
};

constexpr int kMaxBeams = 100000;

}  // namespace

CarmenLog ParseCarmenLog(std::istream& in, const std::string& name, const CarmenReadOptions& options) {
  CarmenLog log;
  log.file = name;
  std::string line;
  std::vector<std::string_view> tokens;
  int line_number = 0;
  std::string first_laser;
  while (std::getline(in, line)) {
    ++line_number;
    Tokenize(line, &tokens);
    if (tokens.empty() || tokens[0].front() == '#') {
      ++log.skipped_lines;
      continue;
    }
    LineReader r(tokens, name, line_number);
    if (first_laser.empty() && (tokens[0] == "FLASER" || tokens[0] == "ROBOTLASER1")) {
      first_laser = std::string(tokens[0]);
    }
    if (tokens[0] == "FLASER") {
      LogScan s;
      s.line = line_number;
      const int n = r.Count("num_readings", kMaxBeams);
      s.scan.ranges.resize(static_cast<std::size_t>(n));
      for (int i = 0; i < n; ++i) s.scan.ranges[static_cast<std::size_t>(i)] = r.Number("range reading");
      s.laser_pose = r.Pose("x y theta");
      s.odom = r.Pose("odom_x odom_y odom_theta");
      s.scan.stamp.t = r.Number("timestamp");
      r.ExpectEnd(n);
      const double fov = DegToRad(options.flaser_fov_deg);
      if (options.flaser_step_deg > 0.0) {
        s.scan.angle_min = DegToRad(options.flaser_first_deg);
        s.scan.angle_increment = DegToRad(options.flaser_step_deg);
      } else {
        s.scan.angle_min = -0.5 * fov;
        s.scan.angle_increment = n > 1 ? fov / (n % 2 == 1 ? n - 1 : n) : 0.0;
      }
      s.scan.range_min = options.range_min;
      s.scan.range_max = options.range_max;
      s.scan.stamp.t_device = s.scan.stamp.t;
      s.scan.stamp.t_host_received = s.scan.stamp.t;
      s.scan.stamp.sequence = log.scans.size();
      log.scans.push_back(std::move(s));
    } else if (tokens[0] == "ROBOTLASER1") {
      LogScan s;
      s.line = line_number;
      r.Number("laser_type");
      const double start_angle = r.Number("start_angle");
      r.Number("field_of_view");
      const double resolution = r.Number("angular_resolution");
      const double max_range = r.Number("maximum_range");
      r.Number("accuracy");
      r.Number("remission_mode");
      const int n = r.Count("num_readings", kMaxBeams);
      s.scan.ranges.resize(static_cast<std::size_t>(n));
      for (int i = 0; i < n; ++i) s.scan.ranges[static_cast<std::size_t>(i)] = r.Number("range reading");
      const int m = r.Count("num_remissions", kMaxBeams);
      for (int i = 0; i < m; ++i) r.Number("remission value");
      s.laser_pose = r.Pose("laser_pose_x laser_pose_y laser_pose_theta");
      s.odom = r.Pose("robot_pose_x robot_pose_y robot_pose_theta");
      r.Number("laser_tv");
      r.Number("laser_rv");
      r.Number("forward_safety_dist");
      r.Number("side_safety_dist");
      r.Number("turn_axis");
      s.scan.stamp.t = r.Number("timestamp");
      r.ExpectEnd(n);
      s.scan.angle_min = start_angle;
      s.scan.angle_increment = resolution;
      s.scan.range_min = options.range_min;
      s.scan.range_max = max_range > 0.0 ? std::min(max_range, options.range_max) : options.range_max;
      s.scan.stamp.t_device = s.scan.stamp.t;
      s.scan.stamp.t_host_received = s.scan.stamp.t;
      s.scan.stamp.sequence = log.scans.size();
      log.scans.push_back(std::move(s));
    } else if (tokens[0] == "ODOM") {
      LogOdometry o;
      o.line = line_number;
      o.pose = r.Pose("x y theta");
      r.Number("tv");
      r.Number("rv");
      r.Number("accel");
      o.t = r.Number("timestamp");
      r.ExpectEnd(0);
      log.odometry.push_back(o);
    } else {
      ++log.skipped_lines;
    }
  }
  log.geometry = DeriveLogGeometry(&log.scans, first_laser);
  return log;
}

LogGeometry DeriveLogGeometry(std::vector<LogScan>* scans, const std::string& message) {
  LogGeometry g;
  g.message = message;
  if (scans->empty()) return g;
  // Beam count and angles: the most common count; the angles of its first scan.
  std::map<std::size_t, int> counts;
  for (const auto& s : *scans) ++counts[s.scan.size()];
  const auto most = std::max_element(counts.begin(), counts.end(),
                                     [](const auto& a, const auto& b) { return a.second < b.second; });
  g.beams = static_cast<int>(most->first);
  for (const auto& s : *scans) {
    if (s.scan.size() != most->first) continue;
    g.angle_min = s.scan.angle_min;
    g.resolution = s.scan.angle_increment;
    break;
  }
  g.fov = g.beams > 1 ? (g.beams - 1) * g.resolution : 0.0;
  // The no-return code: the largest reading, if it repeats at least 10 times and more than 10
  // times as often as all readings within a metre below it (a real wall at one range does not).
  double top = 0.0;
  for (const auto& s : *scans) {
    for (double r : s.scan.ranges) {
      if (std::isfinite(r)) top = std::max(top, r);
    }
  }
  long at_top = 0, below_top = 0;
  for (const auto& s : *scans) {
    for (double r : s.scan.ranges) {
      if (!std::isfinite(r)) continue;
      if (r >= top - 1e-3) {
        ++at_top;
      } else if (r >= top - 1.0) {
        ++below_top;
      }
    }
  }
  if (top > 0.0 && at_top >= 10 && at_top > 10 * below_top) g.no_return_code = top;
  // Apply: codes (and readings at or beyond a line's own maximum range) are no returns.
  for (auto& s : *scans) {
    for (double& r : s.scan.ranges) {
      if (!std::isfinite(r)) continue;
      if ((g.no_return_code > 0.0 && r >= g.no_return_code - 1e-3) || r >= s.scan.range_max) {
        r = LaserScan::kNoReturn;
      } else {
        g.max_range = std::max(g.max_range, r);
      }
    }
  }
  for (auto& s : *scans) s.scan.range_max = std::min(s.scan.range_max, g.max_range + 1e-3);
  // Scan rate from the median positive interval.
  std::vector<double> steps;
  steps.reserve(scans->size());
  for (std::size_t k = 1; k < scans->size(); ++k) {
    const double d = (*scans)[k].scan.stamp.t - (*scans)[k - 1].scan.stamp.t;
    if (d > 0.0) steps.push_back(d);
  }
  if (!steps.empty()) {
    auto mid = steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2);
    std::nth_element(steps.begin(), mid, steps.end());
    g.scan_rate = *mid > 0.0 ? 1.0 / *mid : 0.0;
  }
  // The laser's mount: T_robot_laser per line, the median of each component.
  std::vector<double> xs, ys, ths;
  for (const auto& s : *scans) {
    const Pose2 T = s.odom.inverse() * s.laser_pose;
    xs.push_back(T.x);
    ys.push_back(T.y);
    ths.push_back(T.theta);
  }
  auto median = [](std::vector<double>& v) {
    auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
  };
  g.T_base_laser = Pose2(median(xs), median(ys), WrapAngle(median(ths)));
  g.laser_offset_in_log = std::hypot(g.T_base_laser.x, g.T_base_laser.y) > 1e-6 ||
                          std::abs(g.T_base_laser.theta) > 1e-6;
  return g;
}

CarmenLog ReadCarmenLog(const std::string& path, const CarmenReadOptions& options) {
  std::ifstream in(path);
  if (!in) ThrowInputError("{}: cannot open the log", path);
  return ParseCarmenLog(in, path, options);
}

std::vector<Relation> ParseRelations(std::istream& in, const std::string& name) {
  std::vector<Relation> out;
  std::string line;
  std::vector<std::string_view> tokens;
  int line_number = 0;
  bool seen_data = false;
  bool seen_header = false;
  while (std::getline(in, line)) {
    ++line_number;
    Tokenize(line, &tokens);
    if (tokens.empty() || tokens[0].front() == '#') continue;
    double v[8];
    bool numeric = tokens.size() >= 1;
    for (std::size_t i = 0; i < tokens.size() && i < 8; ++i) numeric = numeric && ParseDouble(tokens[i], &v[i]);
    if (!numeric && !seen_data && !seen_header) {
      seen_header = true;  // one header line before the data is allowed
      continue;
    }
    if (tokens.size() != 8 || !numeric) {
      ThrowInputError("{}:{}: expected 8 numbers 't1 t2 x y z roll pitch yaw', got '{}'", name,
                      line_number, line);
    }
    seen_data = true;
    if (std::abs(v[4]) > 1e-6 || std::abs(v[5]) > 1e-6 || std::abs(v[6]) > 1e-6) {
      ThrowInputError("{}:{}: expected a planar relation (z, roll, pitch = 0), got z {} roll {} pitch {}",
                      name, line_number, v[4], v[5], v[6]);
    }
    out.push_back({v[0], v[1], Pose2(v[2], v[3], WrapAngle(v[7])), line_number});
  }
  return out;
}

std::vector<Relation> ReadRelations(const std::string& path) {
  std::ifstream in(path);
  if (!in) ThrowInputError("{}: cannot open the relations file", path);
  return ParseRelations(in, path);
}

}  // namespace ifab::base
