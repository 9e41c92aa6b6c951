#include "ifab/sync/clock_sync.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "ifab/core/config.h"

namespace ifab {

ClockSyncOptions ClockSyncOptions::FromConfig(const ConfigNode& c) {
  c.ExpectKeys({"window", "max_pairs", "latency", "max_early", "min_span_to_reject",
                "max_consecutive_rejects", "max_abs_skew", "max_late"});
  ClockSyncOptions o;
  c.ReadPositive("window", o.window);
  c.ReadPositive("max_pairs", o.max_pairs);
  c.ReadNonNegative("latency", o.latency);
  c.ReadNonNegative("max_early", o.max_early);
  c.ReadNonNegative("max_late", o.max_late);
  c.ReadNonNegative("min_span_to_reject", o.min_span_to_reject);
  c.ReadPositive("max_consecutive_rejects", o.max_consecutive_rejects);
  c.ReadNonNegative("max_abs_skew", o.max_abs_skew);
  return o;
}

ClockSync::ClockSync(ClockSyncOptions options) : options_(options) {}

bool ClockSync::AddPair(Seconds t_device, Seconds t_host) {
  if (!std::isfinite(t_device) || !std::isfinite(t_host)) return false;
  // A pair far below the current line cannot be a late observation of this clock: a pulse
  // matched to the wrong packet. Only judged once the estimate rests on a long enough span.
  if (pairs_.size() >= 2 &&
      pairs_.back().device - pairs_.front().device >= options_.min_span_to_reject) {
    if (!gate_ || (since_gate_ >= 32 && pairs_.back().device - gate_device_ >= 0.5)) {
      RemoveEarlyOutliers();
      gate_ = Mapping();
      since_gate_ = 0;
      gate_device_ = pairs_.back().device;
    }
    const double delay = t_host - gate_->ToHost(t_device) - options_.latency;
    if ((options_.max_early > 0.0 && delay < -options_.max_early) ||
        (options_.max_late > 0.0 && delay > options_.max_late)) {
      ++rejected_;
      if (++consecutive_rejects_ < options_.max_consecutive_rejects) return false;
      // Many in a row: the clock jumped (device reset). Start over from this pair.
      pairs_.clear();
      hull_valid_ = false;
      sum_x_ = 0.0;
      gate_.reset();
      ++restarts_;
    }
  }
  consecutive_rejects_ = 0;
  const Pair p{t_device, t_host};
  if (pairs_.empty()) {
    origin_ = p;
    sum_x_ = 0.0;
    hull_.clear();
    hull_valid_ = true;
  }
  auto it = std::upper_bound(pairs_.begin(), pairs_.end(), t_device,
                             [](Seconds d, const Pair& q) { return d < q.device; });
  if (it != pairs_.end()) hull_valid_ = false;  // out of order: the hull is rebuilt when needed
  pairs_.insert(it, p);
  sum_x_ += p.device - origin_.device;
  if (hull_valid_) AppendToHull({p.device - origin_.device, p.host - origin_.host});
  Trim();
  cache_.reset();
  ++since_gate_;
  return true;
}

void ClockSync::Trim() {
  // Trim in batches (the oldest pair is always on the hull, so every trim costs a rebuild).
  const Seconds newest = pairs_.back().device;
  const auto max_pairs = static_cast<std::size_t>(options_.max_pairs);
  if (newest - pairs_.front().device <= 1.1 * options_.window && pairs_.size() <= max_pairs + max_pairs / 10) return;
  while (pairs_.size() > 1 && (newest - pairs_.front().device > options_.window || pairs_.size() > max_pairs)) {
    sum_x_ -= pairs_.front().device - origin_.device;
    pairs_.pop_front();
    hull_valid_ = false;
  }
}

void ClockSync::AppendToHull(const Point& c) const {
  // One step of Andrew's monotone chain; among equal device times only the earliest host time
  // can be on the lower hull.
  if (!hull_.empty() && c.x == hull_.back().x) {
    if (c.y >= hull_.back().y) return;
    hull_.pop_back();
  }
  while (hull_.size() >= 2) {
    const Point& a = hull_[hull_.size() - 2];
    const Point& b = hull_.back();
    const double cross = (b.x - a.x) * (c.y - b.y) - (b.y - a.y) * (c.x - b.x);
    if (cross > 0.0) break;  // strictly convex turn: b stays
    hull_.pop_back();
  }
  hull_.push_back(c);
}

void ClockSync::RebuildHull() const {
  origin_ = pairs_.front();  // a new origin at the oldest pair
  hull_.clear();
  sum_x_ = 0.0;
  for (const auto& q : pairs_) {
    AppendToHull({q.device - origin_.device, q.host - origin_.host});
    sum_x_ += q.device - origin_.device;
  }
  hull_valid_ = true;
}

ClockMapping ClockSync::Fit() const {
  if (!hull_valid_) RebuildHull();
  // Work relative to the mean device time (precision with epoch times).
  const double mean = sum_x_ / static_cast<double>(pairs_.size());
  const Seconds device_ref = origin_.device + mean;
  const Seconds host0 = origin_.host;
  const std::vector<Point>& hull = hull_;  // x relative to origin_: the mean device time is at x = mean

  ClockMapping m;
  m.device_ref = device_ref;
  m.rate = 1.0;
  double y_at_ref = 0.0;
  bool line = false;
  if (hull.size() >= 2) {
    // TICSync: the hull edge over the mean device time minimises the summed delays.
    std::size_t i = 0;
    while (i + 2 < hull.size() && hull[i + 1].x < mean) ++i;
    const Point& a = hull[i];
    const Point& b = hull[i + 1];
    const double rate = (b.y - a.y) / (b.x - a.x);
    if (std::abs(rate - 1.0) <= options_.max_abs_skew) {
      m.rate = rate;
      y_at_ref = a.y + rate * (mean - a.x);
      line = true;
    }
  }
  if (!line) {
    // Offset only: the unit-rate line through the earliest pair.
    y_at_ref = std::numeric_limits<double>::infinity();
    for (const auto& q : pairs_) y_at_ref = std::min(y_at_ref, (q.host - host0) - (q.device - device_ref));
  }
  m.host_at_ref = host0 + y_at_ref - options_.latency;
  return m;
}

void ClockSync::RemoveEarlyOutliers() {
  // The hull rests on the earliest pairs, so one pulse matched to the wrong packet (early by a
  // packet period) would carry the line with it. Judge the pairs against a robust line instead:
  // in each of up to 8 chunks of device time take a low quantile of (host - device), fit a line
  // through those by Theil-Sen (median of slopes), and drop pairs far below it.
  if (options_.max_early <= 0.0 || pairs_.size() < 20) return;
  const std::size_t chunks = std::min<std::size_t>(8, pairs_.size() / 10);
  const Seconds device0 = pairs_.front().device, host0 = pairs_.front().host;
  std::vector<double> xs, ds, buffer;
  for (std::size_t c = 0; c < chunks; ++c) {
    const std::size_t lo = c * pairs_.size() / chunks, hi = (c + 1) * pairs_.size() / chunks;
    buffer.clear();
    double x = 0.0;
    for (std::size_t i = lo; i < hi; ++i) {
      const double xi = pairs_[i].device - device0;
      buffer.push_back((pairs_[i].host - host0) - xi);
      x += xi;
    }
    const std::size_t q = buffer.size() / 10;  // the 10 % quantile: outliers below it do not count
    std::nth_element(buffer.begin(), buffer.begin() + static_cast<std::ptrdiff_t>(q), buffer.end());
    xs.push_back(x / static_cast<double>(hi - lo));
    ds.push_back(buffer[q]);
  }
  std::vector<double> slopes;
  for (std::size_t i = 0; i < xs.size(); ++i)
    for (std::size_t j = i + 1; j < xs.size(); ++j)
      if (xs[j] > xs[i]) slopes.push_back((ds[j] - ds[i]) / (xs[j] - xs[i]));
  double slope = 0.0;
  if (!slopes.empty()) {
    std::nth_element(slopes.begin(), slopes.begin() + static_cast<std::ptrdiff_t>(slopes.size() / 2), slopes.end());
    slope = slopes[slopes.size() / 2];
  }
  std::vector<double> intercepts;
  for (std::size_t i = 0; i < xs.size(); ++i) intercepts.push_back(ds[i] - slope * xs[i]);
  std::nth_element(intercepts.begin(), intercepts.begin() + static_cast<std::ptrdiff_t>(intercepts.size() / 2), intercepts.end());
  const double intercept = intercepts[intercepts.size() / 2];
  const std::size_t before = pairs_.size();
  std::erase_if(pairs_, [&](const Pair& p) {
    const double x = p.device - device0;
    return (p.host - host0) - x < intercept + slope * x - options_.max_early;
  });
  if (pairs_.size() != before) {
    rejected_ += static_cast<int>(before - pairs_.size());
    cache_.reset();
    hull_valid_ = false;
    sum_x_ = 0.0;
    for (const auto& q : pairs_) sum_x_ += q.device - origin_.device;
  }
}

std::optional<ClockMapping> ClockSync::Mapping() const {
  if (pairs_.empty()) return std::nullopt;
  if (!cache_) cache_ = Fit();
  return cache_;
}

std::optional<Seconds> ClockSync::ToHost(Seconds t_device) const {
  const auto m = Mapping();
  if (!m) return std::nullopt;
  return m->ToHost(t_device);
}

DeviceClockSync::DeviceClockSync(ClockSyncOptions options, std::size_t max_pending)
    : clock_(options), max_pending_(max_pending) {}

void DeviceClockSync::AddPacket(const Stamp& stamp) {
  packets_[stamp.sequence] = stamp.t_device;
  Match(stamp.sequence);
}

void DeviceClockSync::AddPulse(const SyncPulse& pulse) {
  pulses_[pulse.sequence] = pulse.t_host;
  Match(pulse.sequence);
}

void DeviceClockSync::Match(std::uint64_t sequence) {
  auto packet = packets_.find(sequence);
  auto pulse = pulses_.find(sequence);
  if (packet != packets_.end() && pulse != pulses_.end()) {
    clock_.AddPair(packet->second, pulse->second);
    packets_.erase(packet);
    pulses_.erase(pulse);
  }
  // Lost pulses or packets leave orphans: drop the oldest (lowest sequence) beyond the cap.
  while (packets_.size() > max_pending_) packets_.erase(packets_.begin());
  while (pulses_.size() > max_pending_) pulses_.erase(pulses_.begin());
}

bool DeviceClockSync::Apply(Stamp& stamp) const {
  const auto t = clock_.ToHost(stamp.t_device);
  if (!t) return false;
  stamp.t = *t;
  return true;
}

Seconds ClockStepDetector::Add(const Stamp& stamp, double skew, double skew_uncertainty) {
  // t_host = a + (1 + skew) t_device + delay, so the offset moves by skew per device second.
  const Seconds d = stamp.t_host_received - stamp.t_device;
  const Seconds predicted = offset_ + skew * (stamp.t_device - device_);
  const Seconds tolerance = max_lag_ + skew_uncertainty * std::abs(stamp.t_host_received - arrival_);
  if (seen_ && std::abs(d - predicted) > tolerance) {
    if (++stepped_ < 2) return 0.0;
    seen_ = false;
    stepped_ = 0;
    return predicted - d;  // the device clock moved forward by this much
  }
  offset_ = d;
  device_ = stamp.t_device;
  arrival_ = stamp.t_host_received;
  seen_ = true;
  stepped_ = 0;
  return 0.0;
}

}  // namespace ifab
