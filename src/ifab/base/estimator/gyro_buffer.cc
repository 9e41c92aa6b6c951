#include "ifab/base/estimator/gyro_buffer.h"

#include <algorithm>

namespace ifab::base {

GyroBuffer::GyroBuffer(std::size_t capacity) { samples_.reserve(capacity); }

void GyroBuffer::Push(Seconds t, double rate) {
  if (samples_.size() == samples_.capacity()) {
    // Full: move the live samples to the front (no reallocation), or drop the oldest half.
    if (head_ == 0) head_ = samples_.size() / 2;
    prev_t_ = samples_[head_ - 1].t;
    std::move(samples_.begin() + static_cast<std::ptrdiff_t>(head_), samples_.end(), samples_.begin());
    samples_.resize(samples_.size() - head_);
    head_ = 0;
  }
  samples_.push_back({t, rate});
}

bool GyroBuffer::Integrate(Seconds ta, Seconds tb, double* dtheta) const {
  constexpr double kNever = -std::numeric_limits<double>::infinity();
  *dtheta = 0.0;
  if (samples_.size() == head_) return false;
  if (tb <= ta) return samples_.back().t >= tb;
  Seconds prev_t = prev_t_;
  bool started = false;
  Seconds last_t = kNever;
  double last_rate = 0.0;
  for (std::size_t i = head_; i < samples_.size(); ++i) {
    const Seconds ti = samples_[i].t;
    const double rate = samples_[i].value;
    if (ti > ta) {
      // The first sample after ta must reach back to ta (or be the first sample ever).
      if (!started && !(prev_t <= ta + 1e-9 || prev_t == kNever)) return false;
      started = true;
      const Seconds lo = prev_t == kNever ? ta : std::max(prev_t, ta);
      const Seconds hi = std::min(ti, tb);
      if (hi > lo) *dtheta += rate * (hi - lo);
    }
    last_t = ti;
    last_rate = rate;
    prev_t = ti;
    if (ti >= tb) break;
  }
  if (!started) return false;
  // A short gap at the end (the next sample not yet arrived) is bridged with the last rate.
  constexpr double kMaxExtrapolation = 0.05;
  if (last_t < tb) {
    if (tb - last_t > kMaxExtrapolation) return false;
    *dtheta += last_rate * (tb - std::max(last_t, ta));
  }
  return true;
}

void GyroBuffer::DropUntil(Seconds t) {
  while (head_ < samples_.size() && samples_[head_].t <= t) {
    prev_t_ = samples_[head_].t;
    ++head_;
  }
  if (head_ == samples_.size()) {
    samples_.clear();
    head_ = 0;
  }
}

}  // namespace ifab::base
