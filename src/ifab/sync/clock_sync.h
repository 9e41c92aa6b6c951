#pragma once
/// \file
/// Mapping device clocks to host time (paper Sec. V-A, after TICSync, Harrison & Newman 2011).
///
/// Each device stamps its packets on its own clock (`Stamp::t_device`) and emits a digital sync
/// pulse when it does; the host's acquisition system time stamps the pulse (`SyncPulse::t_host`).
/// A (device time, host time) pair therefore relates the two clocks, except that the host time is
/// late by an unknown, non-negative delay. With t_host = a + b t_device + delay, delay >= 0, every
/// pair lies on or above the true line, and TICSync's one-way estimator takes the line below all
/// pairs that minimises the sum of the implied delays: the edge of the pairs' lower convex hull
/// above the mean device time. It is exact for the pairs with the least delay and ignores late
/// ones, however late. The minimum delay itself is not observable one way; a known constant
/// latency can be subtracted (`ClockSyncOptions::latency`).
///
/// ClockSync works online over a sliding window of device time, so a skew that drifts (crystal
/// temperature) is tracked. DeviceClockSync matches packets and pulses by sequence number.

#include <cstdint>
#include <deque>
#include <map>
#include <optional>

#include "ifab/core/time.h"
#include "ifab/msgs/msgs.h"

namespace ifab {

class ConfigNode;

/// An affine map from device time to host time: t_host = host_at_ref + rate (t_device - device_ref).
/// Kept relative to a reference so that large epoch times lose no precision.
struct ClockMapping {
  Seconds device_ref{0.0};   ///< a device time inside the data the map was fitted to
  Seconds host_at_ref{0.0};  ///< host time of device_ref
  double rate{1.0};          ///< host seconds per device second (1 + skew)

  Seconds ToHost(Seconds t_device) const { return host_at_ref + rate * (t_device - device_ref); }
  Seconds ToDevice(Seconds t_host) const { return device_ref + (t_host - host_at_ref) / rate; }
  /// Rate error of the device clock (host/device - 1), e.g. 5e-5 for 50 ppm.
  double Skew() const { return rate - 1.0; }
  /// Host time at device time zero.
  Seconds Offset() const { return host_at_ref - rate * device_ref; }
};

struct ClockSyncOptions {
  double window{60.0};           ///< [s] of device time whose pairs enter the estimate (tracks drift);
                                 ///< trimmed once they span 10 % more, so the hull is rebuilt rarely
  int max_pairs{20000};          ///< hard cap on pairs kept (oldest dropped first)
  double latency{0.0};           ///< [s] known minimum delay of the host's observations, subtracted
  double max_early{0.002};       ///< [s] a pair this far below the current line is rejected as
                                 ///< mismatched (0 = never reject)
  double max_late{0.5};          ///< [s] a pair this far above the current line is rejected too
                                 ///< (no pulse is that late; the device clock jumped)
  double min_span_to_reject{2.0};  ///< [s] reject only once the pairs span this much device time
  int max_consecutive_rejects{20};  ///< this many rejections in a row mean a clock jump: restart
  double max_abs_skew{1e-3};     ///< a fitted |skew| above this is not trusted: offset-only fit

  static ClockSyncOptions FromConfig(const ConfigNode& config);
};

/// Online one-way clock synchronisation of one device from (t_device, t_host) pairs.
class ClockSync {
 public:
  explicit ClockSync(ClockSyncOptions options = {});

  /// Add a pair whose host time is late by an unknown non-negative delay. Pairs may arrive out of
  /// order. Returns false if the pair was rejected: far below the current estimate (a pulse
  /// matched to the wrong packet) or absurdly far above it. A run of rejections means the device
  /// clock jumped, and the estimator starts over.
  bool AddPair(Seconds t_device, Seconds t_host);

  /// The current map; nullopt before the first pair.
  std::optional<ClockMapping> Mapping() const;
  /// Host time of a device time stamp under the current map.
  std::optional<Seconds> ToHost(Seconds t_device) const;

  std::size_t size() const { return pairs_.size(); }
  int rejected() const { return rejected_; }
  int restarts() const { return restarts_; }
  const ClockSyncOptions& options() const { return options_; }

 private:
  struct Pair {
    Seconds device;
    Seconds host;
  };
  struct Point {  // a pair relative to origin_ (precision with epoch times)
    double x, y;
  };
  void Trim();
  ClockMapping Fit() const;
  void RemoveEarlyOutliers();
  void RebuildHull() const;
  void AppendToHull(const Point& c) const;

  ClockSyncOptions options_;
  std::deque<Pair> pairs_;  // sorted by device time
  // The lower convex hull of pairs_, kept up to date as pairs arrive in order (O(1) amortised)
  // and rebuilt only when pairs leave or arrive out of order: the fit is then O(hull), not O(n).
  mutable std::vector<Point> hull_;
  mutable bool hull_valid_{false};
  mutable Pair origin_{0.0, 0.0};
  mutable double sum_x_{0.0};  // sum of (device - origin_.device) over pairs_, for the mean device time
  mutable std::optional<ClockMapping> cache_;
  std::optional<ClockMapping> gate_;  // slightly stale map used to judge new pairs (refit every 32)
  int since_gate_{0};
  Seconds gate_device_{0.0};  // newest device time when the gate was refitted
  int rejected_{0};
  int consecutive_rejects_{0};
  int restarts_{0};
};

/// One device's packets and sync pulses, matched by sequence number into ClockSync pairs.
class DeviceClockSync {
 public:
  explicit DeviceClockSync(ClockSyncOptions options = {}, std::size_t max_pending = 1000);

  /// A packet's stamp (t_device and sequence are read).
  void AddPacket(const Stamp& stamp);
  /// A pulse (sequence and t_host are read).
  void AddPulse(const SyncPulse& pulse);
  /// Fill stamp.t from stamp.t_device; false (stamp unchanged) before any pair.
  bool Apply(Stamp& stamp) const;

  const ClockSync& clock() const { return clock_; }

 private:
  void Match(std::uint64_t sequence);

  ClockSync clock_;
  std::size_t max_pending_;
  std::map<std::uint64_t, Seconds> packets_;  // device time by sequence, waiting for its pulse
  std::map<std::uint64_t, Seconds> pulses_;   // host time by sequence, waiting for its packet
};

/// Sees a device's clock jump from its raw stamps: (arrival - device stamp) steps by more than
/// transport lag and the clock's skew explain. It needs no sync pulses, so it sees a jump at the
/// first packets after it, even on a device that was silent for minutes (the arm laser between
/// sweeps), whatever the sync has learnt meanwhile.
class ClockStepDetector {
 public:
  /// max_lag: [s] how late a packet may arrive.
  explicit ClockStepDetector(double max_lag) : max_lag_(max_lag) {}
  /// One packet, in arrival order, with the device's skew as known (e.g. fitted by its sync) and
  /// how far that may be off (the offset drifts by skew x silence). Returns the step [s] of the
  /// device clock once two packets in a row are off (one alone is a late packet), else 0. After a
  /// step the new offset is learnt afresh.
  Seconds Add(const Stamp& stamp, double skew, double skew_uncertainty);

 private:
  double max_lag_;
  Seconds offset_{0.0}, device_{0.0}, arrival_{0.0};  // of the newest packet that agreed with its predecessor
  bool seen_{false};
  int stepped_{0};
};

}  // namespace ifab
