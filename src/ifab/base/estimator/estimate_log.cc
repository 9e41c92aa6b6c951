#include "ifab/base/estimator/estimate_log.h"

#include <fmt/format.h>
#include <fmt/os.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numeric>

#include "ifab/core/angles.h"
#include "ifab/core/error.h"

namespace ifab::base {

EstimateLogOptions EstimateLogOptions::FromConfig(const ConfigNode& node) {
  EstimateLogOptions o;
  node.ExpectKeys({"estimator", "log", "evaluation"});
  if (auto c = node.Find("estimator")) o.estimator = EstimatorOptions::FromConfig(*c);
  if (auto c = node.Find("log")) {
    c->ExpectKeys({"flaser_fov_deg", "flaser_step_deg", "flaser_first_deg", "range_max", "range_min", "T_base_laser",
                   "odometry_stall_jump_deg", "odometry_stall_jump_m", "odometry_translation_hint"});
    c->ReadPositive("odometry_stall_jump_m", o.odometry_stall_jump_m);
    c->Read("odometry_translation_hint", o.odometry_translation_hint);
    double stall_deg = RadToDeg(o.odometry_stall_jump_rad);
    c->ReadPositive("odometry_stall_jump_deg", stall_deg);
    o.odometry_stall_jump_rad = DegToRad(stall_deg);
    c->ReadInRange("flaser_fov_deg", o.reader.flaser_fov_deg, 1.0, 360.0);
    c->ReadInRange("flaser_step_deg", o.reader.flaser_step_deg, 0.0, 10.0);
    c->ReadInRange("flaser_first_deg", o.reader.flaser_first_deg, -360.0, 360.0);
    c->ReadPositive("range_max", o.reader.range_max);
    c->ReadNonNegative("range_min", o.reader.range_min);
    if (auto t = c->Find("T_base_laser")) {
      const auto v = t->AsNumbers(3);
      o.T_base_laser = Pose2(v[0], v[1], DegToRad(v[2]));
    }
  }
  if (auto c = node.Find("evaluation")) {
    c->ExpectKeys({"short_span", "stamp_tolerance"});
    c->ReadPositive("short_span", o.short_span);
    c->ReadPositive("stamp_tolerance", o.stamp_tolerance);
  }
  return o;
}

ErrorStats ErrorStats::Of(const std::vector<double>& values) {
  ErrorStats s;
  if (values.empty()) return s;
  const double n = static_cast<double>(values.size());
  s.mean = std::accumulate(values.begin(), values.end(), 0.0) / n;
  double var = 0.0;
  for (double v : values) {
    var += (v - s.mean) * (v - s.mean);
    s.max = std::max(s.max, v);
  }
  s.std = std::sqrt(var / n);
  return s;
}

RelationErrors EvaluateRelations(const std::vector<Seconds>& stamps, const std::vector<Pose2>& poses,
                                 const std::vector<Relation>& relations, double max_span,
                                 double tolerance) {
  IFAB_CHECK(stamps.size() == poses.size());
  std::vector<std::size_t> order(stamps.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return stamps[a] < stamps[b]; });
  auto find = [&](Seconds t) -> std::optional<std::size_t> {
    auto it = std::lower_bound(order.begin(), order.end(), t,
                               [&](std::size_t i, Seconds v) { return stamps[i] < v; });
    std::optional<std::size_t> best;
    double best_d = tolerance;
    for (auto c : {it, it == order.begin() ? it : std::prev(it)}) {
      if (c == order.end()) continue;
      const double d = std::abs(stamps[*c] - t);
      if (d <= best_d) {
        best_d = d;
        best = *c;
      }
    }
    return best;
  };
  RelationErrors out;
  std::vector<double> trans, rot;
  for (const Relation& rel : relations) {
    if (std::abs(rel.t2 - rel.t1) > max_span) continue;
    const auto i1 = find(rel.t1), i2 = find(rel.t2);
    if (!i1 || !i2) {
      ++out.unmatched;
      continue;
    }
    const Pose2 delta = poses[*i1].inverse() * poses[*i2];
    const Pose2 E = delta * rel.delta.inverse();
    trans.push_back(std::hypot(E.x, E.y));
    rot.push_back(RadToDeg(std::abs(WrapAngle(E.theta))));
    out.each.push_back({rel.t1, rel.t2, trans.back(), rot.back()});
  }
  out.relations = static_cast<int>(trans.size());
  out.translation_m = ErrorStats::Of(trans);
  out.rotation_deg = ErrorStats::Of(rot);
  return out;
}

std::vector<Seconds> RepairStamps(const std::vector<Seconds>& stamps, int* interpolated,
                                  int* nudged) {
  const std::size_t n = stamps.size();
  std::vector<Seconds> t(stamps);
  // A stamp is trustworthy if no later stamp is earlier (backward running minimum).
  std::vector<char> good(n, 1);
  double running_min = std::numeric_limits<double>::infinity();
  for (std::size_t k = n; k-- > 0;) {
    if (stamps[k] > running_min) good[k] = 0;
    running_min = std::min(running_min, stamps[k]);
  }
  int changed = 0, moved = 0;
  std::size_t prev_good = n;  // none yet
  for (std::size_t k = 0; k < n; ++k) {
    if (good[k]) {
      if (prev_good == n) {
        for (std::size_t j = 0; j < k; ++j) t[j] = stamps[k];  // leading bad stamps
      } else if (k > prev_good + 1) {
        for (std::size_t j = prev_good + 1; j < k; ++j) {
          const double s = static_cast<double>(j - prev_good) / static_cast<double>(k - prev_good);
          t[j] = stamps[prev_good] + s * (stamps[k] - stamps[prev_good]);
        }
      }
      prev_good = k;
    } else {
      ++changed;
    }
  }
  // Keep consecutive scans at least 1 ms apart (the gyro input needs a positive interval).
  constexpr double kMinStep = 1e-3;
  for (std::size_t k = 1; k < n; ++k) {
    if (t[k] < t[k - 1] + kMinStep) {
      t[k] = t[k - 1] + kMinStep;
      if (good[k]) ++moved;
    }
  }
  if (interpolated) *interpolated = changed;
  if (nudged) *nudged = moved;
  return t;
}

std::vector<Pose2> RepairOdometryStalls(const std::vector<Pose2>& odom, double stall_jump_m,
                                        double stall_jump_rad, int* repaired) {
  std::vector<Pose2> out(odom);
  const std::size_t n = odom.size();
  int count = 0;
  // Position and heading are repaired separately: logs show one frozen while the other moves.
  for (int part = 0; part < 2; ++part) {
    auto same = [&](std::size_t k) {
      return part == 0 ? (odom[k].x == odom[k - 1].x && odom[k].y == odom[k - 1].y)
                       : odom[k].theta == odom[k - 1].theta;
    };
    auto jump = [&](std::size_t k) {
      return part == 0 ? std::hypot(odom[k].x - odom[k - 1].x, odom[k].y - odom[k - 1].y) > stall_jump_m
                       : std::abs(WrapAngle(odom[k].theta - odom[k - 1].theta)) > stall_jump_rad;
    };
    std::size_t k = 1;
    while (k < n) {
      const std::size_t a = k;  // first repeated sample
      while (k < n && same(k)) ++k;
      if (k > a && k < n && jump(k)) {
        // Interpolate from the last moving sample (a - 1) to the one after the jump (k).
        const Pose2& p0 = odom[a - 1];
        const Pose2& p1 = odom[k];
        for (std::size_t j = a; j < k; ++j) {
          const double s = static_cast<double>(j - (a - 1)) / static_cast<double>(k - (a - 1));
          const Pose2 mid = Interpolate(p0, p1, s);
          if (part == 0) {
            out[j].x = mid.x;
            out[j].y = mid.y;
          } else {
            out[j].theta = mid.theta;
          }
        }
        ++count;
      }
      ++k;
    }
  }
  if (repaired) *repaired = count;
  return out;
}

namespace {

nlohmann::json StatsJson(const ErrorStats& s) {
  return {{"mean", s.mean}, {"std", s.std}, {"max", s.max}};
}

nlohmann::json ErrorsJson(const RelationErrors& e) {
  return {{"relations", e.relations},
          {"translation_error_m", StatsJson(e.translation_m)},
          {"rotation_error_deg", StatsJson(e.rotation_deg)}};
}

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace

nlohmann::json RunEstimateOnLog(const std::string& log_path, const std::string& relations_path,
                                const EstimateLogOptions& options, const std::string& out_dir) {
  const CarmenLog log = ReadCarmenLog(log_path, options.reader);
  IFAB_THROW_UNLESS(!log.scans.empty(), "{}: no FLASER or ROBOTLASER1 lines in the log", log_path);

  std::string relations_file = relations_path;
  if (relations_file.empty()) {
    std::filesystem::path p(log_path);
    p.replace_extension(".relations");
    if (std::filesystem::exists(p)) relations_file = p.string();
  }
  std::vector<Relation> relations;
  if (!relations_file.empty()) relations = ReadRelations(relations_file);

  std::vector<Seconds> stamps;
  stamps.reserve(log.scans.size());
  std::size_t max_beams = 0;
  for (const auto& s : log.scans) {
    stamps.push_back(s.scan.stamp.t);
    max_beams = std::max(max_beams, s.scan.size());
  }
  int interpolated = 0, nudged = 0;
  const std::vector<Seconds> clock = RepairStamps(stamps, &interpolated, &nudged);

  EstimatorOptions est_options = options.estimator;
  est_options.max_beams = std::max(est_options.max_beams, static_cast<int>(max_beams));
  BaseStateEstimator estimator(est_options, options.T_base_laser);
  estimator.Reset(Pose2(), clock[0]);

  std::vector<Pose2> poses;
  poses.reserve(log.scans.size());
  std::vector<double> ms;
  ms.reserve(log.scans.size());
  std::map<std::string, int> status_counts;
  std::vector<BaseEstimate> estimates;
  estimates.reserve(log.scans.size());
  std::vector<Pose2> odom;
  odom.reserve(log.scans.size());
  for (const auto& s : log.scans) odom.push_back(s.odom);
  int stalls = 0;
  const std::vector<Pose2> odom_repaired = RepairOdometryStalls(
      odom, options.odometry_stall_jump_m, options.odometry_stall_jump_rad, &stalls);
  std::vector<Pose2> odom_steps(odom.size());
  for (std::size_t k = 1; k < odom.size(); ++k) odom_steps[k] = odom_repaired[k - 1].inverse() * odom_repaired[k];

  LaserScan scan;
  for (std::size_t k = 0; k < log.scans.size(); ++k) {
    scan = log.scans[k].scan;
    scan.stamp.t = clock[k];
    scan.time_increment = 0.0;
    if (k > 0) {
      // The rotation input: odometry heading change over the interval, as a rate.
      GyroSample g;
      g.stamp.t = clock[k];
      g.rate.z() = odom_steps[k].theta / (clock[k] - clock[k - 1]);
      estimator.AddGyro(g);
    }
    const auto t0 = std::chrono::steady_clock::now();
    std::optional<Pose2> hint;
    if (k > 0 && options.odometry_translation_hint) hint = odom_steps[k];
    const BaseEstimate& e = estimator.AddScan(scan, hint);
    const auto t1 = std::chrono::steady_clock::now();
    ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    poses.push_back(e.T_world_base);
    estimates.push_back(e);
    ++status_counts[StatusName(e.status)];
  }

  nlohmann::json metrics;
  metrics["log"] = log_path;
  metrics["relations_file"] = relations_file;
  metrics["scans"] = static_cast<int>(log.scans.size());
  const RelationErrors all = EvaluateRelations(stamps, poses, relations,
                                               std::numeric_limits<double>::infinity(),
                                               options.stamp_tolerance);
  const RelationErrors short_span =
      EvaluateRelations(stamps, poses, relations, options.short_span, options.stamp_tolerance);
  metrics["relations"] = all.relations;
  metrics["relations_unmatched"] = all.unmatched;
  metrics["translation_error_m"] = StatsJson(all.translation_m);
  metrics["rotation_error_deg"] = StatsJson(all.rotation_deg);
  metrics["short_span"] = ErrorsJson(short_span);
  metrics["short_span"]["max_span_s"] = options.short_span;
  metrics["ms_per_scan_median"] = Median(ms);
  metrics["ms_per_scan_max"] = ms.empty() ? 0.0 : *std::max_element(ms.begin(), ms.end());
  metrics["rotation_input"] =
      "wheel odometry heading change between consecutive scans (CARMEN logs have no gyro), fed "
      "to eq. 2 as one rate sample per scan";
  metrics["timestamps_late_interpolated"] = interpolated;
  metrics["timestamps_moved_to_1ms_steps"] = nudged;
  metrics["odometry_stalls_repaired"] = stalls;
  metrics["initial_guess"] = options.odometry_translation_hint
                                 ? "previous pose composed with the odometry step (not in the cost)"
                                 : "previous pose with the estimator's motion prior";
  metrics["status_counts"] = status_counts;
  const RelationErrors odo = EvaluateRelations(stamps, odom, relations,
                                               std::numeric_limits<double>::infinity(),
                                               options.stamp_tolerance);
  metrics["odometry_baseline"] = {{"translation_error_m", StatsJson(odo.translation_m)},
                                  {"rotation_error_deg", StatsJson(odo.rotation_deg)}};

  if (!out_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(out_dir, ec);
    IFAB_THROW_UNLESS(!ec, "{}: cannot create the output folder: {}", out_dir, ec.message());
    {
      const std::string path = (std::filesystem::path(out_dir) / "trajectory.csv").string();
      std::ofstream csv(path);
      IFAB_THROW_UNLESS(static_cast<bool>(csv), "{}: cannot write", path);
      csv << "index,t,t_processing,x,y,theta,status,cov_xx,cov_xy,cov_yy,cov_thth,matched_fraction,"
             "score,gyro_error_rad,iterations,ms,log_line\n";
      for (std::size_t k = 0; k < estimates.size(); ++k) {
        const BaseEstimate& e = estimates[k];
        csv << fmt::format("{},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f},{},{:.3e},{:.3e},{:.3e},{:.3e},{:.4f},{:.4f},{:.6f},{},{:.4f},{}\n",
                           k, stamps[k], clock[k], e.T_world_base.x, e.T_world_base.y,
                           e.T_world_base.theta, StatusName(e.status), e.covariance(0, 0),
                           e.covariance(0, 1), e.covariance(1, 1), e.covariance(2, 2),
                           e.matched_fraction, e.score, e.gyro_error_rad, e.iterations, ms[k],
                           log.scans[k].line);
      }
    }
    {
      const std::string path = (std::filesystem::path(out_dir) / "relations.csv").string();
      std::ofstream csv(path);
      IFAB_THROW_UNLESS(static_cast<bool>(csv), "{}: cannot write", path);
      csv << "t1,t2,translation_error_m,rotation_error_deg\n";
      for (const auto& e : all.each) csv << fmt::format("{:.6f},{:.6f},{:.5f},{:.4f}\n", e[0], e[1], e[2], e[3]);
    }
    const std::string path = (std::filesystem::path(out_dir) / "metrics.json").string();
    std::ofstream out(path);
    IFAB_THROW_UNLESS(static_cast<bool>(out), "{}: cannot write", path);
    out << metrics.dump(2) << "\n";
  }
  return metrics;
}

}  // namespace ifab::base
