#pragma once
/// \file
/// The gyro side of eq. 2: a FIFO of yaw-rate samples and the rotation they integrate to between
/// two scans (sum of omega_i dt). Sized once; no allocation per sample in the steady state.

#include <cstddef>
#include <limits>
#include <vector>

#include "ifab/core/time.h"
#include "ifab/msgs/msgs.h"

namespace ifab::base {

class GyroBuffer {
 public:
  explicit GyroBuffer(std::size_t capacity = 8192);

  bool Empty() const { return samples_.size() == head_; }
  /// Time of the newest sample (requires !Empty()).
  Seconds BackTime() const { return samples_.back().t; }
  /// Append a sample (rate [rad/s] over (previous sample, t]); when full, the live samples move
  /// to the front, or the oldest half is dropped.
  void Push(Seconds t, double rate);
  /// Integrated rotation over (ta, tb]; false if the samples do not cover the interval (a gap
  /// at the end shorter than 50 ms is bridged with the last rate).
  bool Integrate(Seconds ta, Seconds tb, double* dtheta) const;
  /// Forget samples no later than t, keeping the time of the last one for the next interval.
  void DropUntil(Seconds t);

 private:
  std::vector<Stamped<double>> samples_;
  std::size_t head_{0};
  Seconds prev_t_{-std::numeric_limits<double>::infinity()};  // last dropped sample's time
};

}  // namespace ifab::base
