#include "ifab/experiments/estimate_log.h"

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

namespace ifab::experiments {

using base::BaseEstimate;
using base::BaseStateEstimator;
using base::CarmenLog;
using base::MotionMeasurement;

EstimateLogOptions EstimateLogOptions::FromConfig(const ConfigNode& node) {
  EstimateLogOptions o;
  node.ExpectKeys({"estimator", "log", "evaluation"});
  if (auto c = node.Find("estimator")) o.estimator = EstimatorOptions::FromConfig(*c);
  if (auto c = node.Find("log")) {
    c->ExpectKeys({"odometry", "odometry_noise", "flaser_fov_deg", "flaser_step_deg",
                   "flaser_first_deg", "range_max", "range_min"});
    if (auto k = c->Find("odometry")) {
      const auto s = k->As<std::string>();
      if (s == "factor") {
        o.odometry = LogOdometry::kFactor;
      } else if (s == "gyro") {
        o.odometry = LogOdometry::kGyro;
      } else {
        k->Fail("'factor' (the odometry step as a factor of eq. 3) or 'gyro' (eq. 2 with the odometry heading)");
      }
    }
    if (auto k = c->Find("odometry_noise")) o.odometry_noise = base::OdometryNoise::FromConfig(*k);
    c->ReadInRange("flaser_fov_deg", o.reader.flaser_fov_deg, 1.0, 360.0);
    c->ReadInRange("flaser_step_deg", o.reader.flaser_step_deg, 0.0, 10.0);
    c->ReadInRange("flaser_first_deg", o.reader.flaser_first_deg, -360.0, 360.0);
    c->ReadPositive("range_max", o.reader.range_max);
    c->ReadNonNegative("range_min", o.reader.range_min);
  }
  if (auto c = node.Find("evaluation")) {
    c->ExpectKeys({"short_span", "stamp_tolerance", "false_ok_span", "false_ok_error"});
    c->ReadPositive("short_span", o.short_span);
    c->ReadPositive("stamp_tolerance", o.stamp_tolerance);
    c->ReadPositive("false_ok_span", o.false_ok_span);
    c->ReadPositive("false_ok_error", o.false_ok_error);
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

namespace {

// Looks a relation's time up among the scan stamps (which may be out of order).
class StampIndex {
 public:
  StampIndex(const std::vector<Seconds>& stamps, double tolerance)
      : stamps_(stamps), tolerance_(tolerance), order_(stamps.size()) {
    std::iota(order_.begin(), order_.end(), std::size_t{0});
    std::sort(order_.begin(), order_.end(),
              [&](std::size_t a, std::size_t b) { return stamps_[a] < stamps_[b]; });
  }
  std::optional<std::size_t> Find(Seconds t) const {
    auto it = std::lower_bound(order_.begin(), order_.end(), t,
                               [&](std::size_t i, Seconds v) { return stamps_[i] < v; });
    std::optional<std::size_t> best;
    double best_d = tolerance_;
    for (auto c : {it, it == order_.begin() ? it : std::prev(it)}) {
      if (c == order_.end()) continue;
      const double d = std::abs(stamps_[*c] - t);
      if (d <= best_d) {
        best_d = d;
        best = *c;
      }
    }
    return best;
  }

 private:
  const std::vector<Seconds>& stamps_;
  double tolerance_;
  std::vector<std::size_t> order_;
};

double TranslationError(const Pose2& a, const Pose2& b, const Pose2& delta) {
  const Pose2 E = (a.inverse() * b) * delta.inverse();
  return std::hypot(E.x, E.y);
}

}  // namespace

RelationErrors EvaluateRelations(const std::vector<Seconds>& stamps, const std::vector<Pose2>& poses,
                                 const std::vector<Relation>& relations, double max_span,
                                 double tolerance) {
  IFAB_CHECK(stamps.size() == poses.size());
  const StampIndex index(stamps, tolerance);
  RelationErrors out;
  std::vector<double> trans, rot;
  for (const Relation& rel : relations) {
    if (std::abs(rel.t2 - rel.t1) > max_span) continue;
    const auto i1 = index.Find(rel.t1), i2 = index.Find(rel.t2);
    if (!i1 || !i2) {
      ++out.unmatched;
      continue;
    }
    const Pose2 E = (poses[*i1].inverse() * poses[*i2]) * rel.delta.inverse();
    trans.push_back(std::hypot(E.x, E.y));
    rot.push_back(RadToDeg(std::abs(WrapAngle(E.theta))));
  }
  out.relations = static_cast<int>(trans.size());
  out.translation_m = ErrorStats::Of(trans);
  out.rotation_deg = ErrorStats::Of(rot);
  return out;
}

FalseOk FalseOkRate(const std::vector<Seconds>& stamps, const std::vector<Pose2>& poses,
                    const std::vector<char>& usable, const std::vector<Relation>& relations,
                    double max_span, double max_error, double tolerance) {
  IFAB_CHECK(stamps.size() == poses.size() && stamps.size() == usable.size());
  const StampIndex index(stamps, tolerance);
  // flagged_before[k]: flagged scans among the first k (prefix sums).
  std::vector<int> flagged_before(usable.size() + 1, 0);
  for (std::size_t k = 0; k < usable.size(); ++k) flagged_before[k + 1] = flagged_before[k] + (usable[k] ? 0 : 1);
  FalseOk out;
  for (const Relation& rel : relations) {
    if (std::abs(rel.t2 - rel.t1) > max_span) continue;
    const auto i1 = index.Find(rel.t1), i2 = index.Find(rel.t2);
    if (!i1 || !i2) continue;
    ++out.relations;
    const std::size_t lo = std::min(*i1, *i2), hi = std::max(*i1, *i2);
    const bool all_ok = flagged_before[hi + 1] - flagged_before[lo] == 0;
    if (all_ok && TranslationError(poses[*i1], poses[*i2], rel.delta) > max_error) ++out.false_ok;
  }
  out.rate = out.relations > 0 ? static_cast<double>(out.false_ok) / out.relations : 0.0;
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
  const CarmenLog log = base::ReadCarmenLog(log_path, options.reader);
  IFAB_THROW_UNLESS(!log.scans.empty(), "{}: no FLASER or ROBOTLASER1 lines in the log", log_path);
  const base::LogGeometry& geometry = log.geometry;

  std::string relations_file = relations_path;
  if (relations_file.empty()) {
    std::filesystem::path p(log_path);
    p.replace_extension(".relations");
    if (std::filesystem::exists(p)) relations_file = p.string();
  }
  std::vector<Relation> relations;
  if (!relations_file.empty()) relations = base::ReadRelations(relations_file);

  const std::size_t n = log.scans.size();
  std::vector<Seconds> stamps;
  stamps.reserve(n);
  std::size_t max_beams = 0;
  for (const auto& s : log.scans) {
    stamps.push_back(s.scan.stamp.t);
    max_beams = std::max(max_beams, s.scan.size());
  }
  int interpolated = 0, nudged = 0;
  const std::vector<Seconds> clock = RepairStamps(stamps, &interpolated, &nudged);

  EstimatorOptions est_options = options.estimator;
  est_options.max_beams = std::max(est_options.max_beams, static_cast<int>(max_beams));
  BaseStateEstimator estimator(est_options, geometry.T_base_laser);
  estimator.Reset(Pose2(), clock[0]);

  std::vector<Pose2> poses;
  poses.reserve(n);
  std::vector<double> ms;
  ms.reserve(n);
  std::map<std::string, int> status_counts;
  std::vector<BaseEstimate> estimates;
  estimates.reserve(n);
  std::vector<char> usable;
  usable.reserve(n);
  const bool factor = options.odometry == LogOdometry::kFactor;

  // The last scan whose odometry pose changed: its index and the estimate there.
  std::size_t last_update = 0;
  int no_update_scans = 0;
  Pose2 velocity_step;  // the last estimated step per second, in the robot frame (x, y, theta)
  LaserScan scan;
  for (std::size_t k = 0; k < n; ++k) {
    scan = log.scans[k].scan;
    scan.stamp.t = clock[k];
    scan.time_increment = 0.0;
    std::optional<MotionMeasurement> motion;
    if (k > 0) {
      const Pose2& odom = log.scans[k].odom;
      const Pose2& odom_prev = log.scans[k - 1].odom;
      const bool updated = !(odom.x == odom_prev.x && odom.y == odom_prev.y && odom.theta == odom_prev.theta);
      const double dt = clock[k] - clock[k - 1];
      if (!factor) {
        // The paper's eq. 2 with the odometry heading change as the gyro; the step seeds the
        // guess. Without new odometry there is no gyro sample for the interval (the estimator's
        // constant-velocity prior predicts); with it, the odometry's motion since the last
        // updated scan, applied from the estimate there.
        if (updated) {
          const Pose2 odom_delta = log.scans[last_update].odom.inverse() * odom;
          const Pose2 step = poses[k - 1].inverse() * poses[last_update] * odom_delta;
          GyroSample g;
          g.stamp.t = clock[k];
          g.rate.z() = step.theta / dt;
          estimator.AddGyro(g);
          motion = MotionMeasurement{step, Eigen::Matrix3d::Zero()};
          last_update = k;
        } else {
          ++no_update_scans;
        }
      } else if (updated) {
        // The odometry's motion since the last updated scan, applied from the estimate there.
        const Pose2 odom_delta = log.scans[last_update].odom.inverse() * odom;
        const Pose2 step = poses[k - 1].inverse() * poses[last_update] * odom_delta;
        motion = MotionMeasurement{step, base::StepCovariance(odom_delta, options.odometry_noise)};
        last_update = k;
      } else {
        // No new odometry: the constant-velocity step, with the same noise model.
        ++no_update_scans;
        const Pose2 step(velocity_step.x * dt, velocity_step.y * dt, velocity_step.theta * dt);
        motion = MotionMeasurement{step, base::StepCovariance(step, options.odometry_noise)};
      }
    }
    const auto t0 = std::chrono::steady_clock::now();
    const BaseEstimate& e = estimator.AddScan(scan, motion);
    const auto t1 = std::chrono::steady_clock::now();
    ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    // The velocity over at least half the log's median scan interval (consecutive stamps can
    // be 1 ms apart after the clock repair: a step over them is no velocity).
    if (k > 0) {
      const double min_span = geometry.scan_rate > 0.0 ? 0.5 / geometry.scan_rate : 0.0;
      std::size_t j = k - 1;
      while (j > 0 && k - j < 10 && clock[k] - clock[j] < min_span) --j;
      const double span = clock[k] - clock[j];
      if (span > 1e-6) {
        const Pose2 step = poses[j].inverse() * e.T_world_base;
        velocity_step = Pose2(step.x / span, step.y / span, step.theta / span);
      }
    }
    poses.push_back(e.T_world_base);
    estimates.push_back(e);
    usable.push_back(e.IsUsable() ? 1 : 0);
    ++status_counts[base::StatusName(e.status)];
  }

  nlohmann::json metrics;
  metrics["log"] = log_path;
  metrics["relations_file"] = relations_file;
  metrics["scans"] = static_cast<int>(n);
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
  int flagged = 0;
  for (char u : usable) flagged += u ? 0 : 1;
  metrics["flagged_fraction"] = static_cast<double>(flagged) / static_cast<double>(n);
  const FalseOk false_ok = FalseOkRate(stamps, poses, usable, relations, options.false_ok_span,
                                       options.false_ok_error, options.stamp_tolerance);
  metrics["false_ok_rate"] = false_ok.rate;
  metrics["false_ok"] = {{"relations", false_ok.relations},
                         {"false_ok", false_ok.false_ok},
                         {"max_span_s", options.false_ok_span},
                         {"min_error_m", options.false_ok_error}};
  metrics["ms_per_scan_median"] = Median(ms);
  metrics["ms_per_scan_max"] = ms.empty() ? 0.0 : *std::max_element(ms.begin(), ms.end());
  metrics["odometry_input"] =
      factor ? "odometry step as a factor of eq. 3 (noise growing with distance and turn), no gyro term"
             : "paper eq. 2: odometry heading change per scan as the gyro; the odometry step seeds the guess";
  metrics["odometry_no_update_scans"] = no_update_scans;
  metrics["timestamps_late_interpolated"] = interpolated;
  metrics["timestamps_moved_to_1ms_steps"] = nudged;
  metrics["status_counts"] = status_counts;
  metrics["geometry"] = {{"message", geometry.message},
                         {"beams", geometry.beams},
                         {"fov_deg", RadToDeg(geometry.fov)},
                         {"angle_min_deg", RadToDeg(geometry.angle_min)},
                         {"resolution_deg", RadToDeg(geometry.resolution)},
                         {"no_return_code_m", geometry.no_return_code},
                         {"max_range_m", geometry.max_range},
                         {"scan_rate_hz", geometry.scan_rate},
                         {"T_base_laser", {geometry.T_base_laser.x, geometry.T_base_laser.y,
                                           RadToDeg(geometry.T_base_laser.theta)}},
                         {"laser_offset_in_log", geometry.laser_offset_in_log}};
  std::vector<Pose2> odom;
  odom.reserve(n);
  for (const auto& s : log.scans) odom.push_back(s.odom);
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
             "inlier_fraction,score,mahalanobis_sq,window_mahalanobis_sq,num_degenerate,degenerate_x,degenerate_y,"
             "degenerate_theta,iterations,ms,log_line\n";
      for (std::size_t k = 0; k < estimates.size(); ++k) {
        const BaseEstimate& e = estimates[k];
        const Eigen::Vector3d d = e.degenerate_directions.col(0);
        csv << fmt::format("{},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f},{},{:.3e},{:.3e},{:.3e},{:.3e},{:.4f},{:.4f},{:.4f},{:.3f},{:.3f},{},{:.3f},{:.3f},{:.3f},{},{:.4f},{}\n",
                           k, stamps[k], clock[k], e.T_world_base.x, e.T_world_base.y,
                           e.T_world_base.theta, base::StatusName(e.status), e.covariance(0, 0),
                           e.covariance(0, 1), e.covariance(1, 1), e.covariance(2, 2),
                           e.matched_fraction, e.inlier_fraction, e.score, e.mahalanobis_sq,
                           e.window_mahalanobis_sq,
                           e.num_degenerate, d.x(), d.y(), d.z(), e.iterations, ms[k],
                           log.scans[k].line);
      }
    }
    const std::string path = (std::filesystem::path(out_dir) / "metrics.json").string();
    std::ofstream out(path);
    IFAB_THROW_UNLESS(static_cast<bool>(out), "{}: cannot write", path);
    out << metrics.dump(2) << "\n";
  }
  return metrics;
}

}  // namespace ifab::experiments
