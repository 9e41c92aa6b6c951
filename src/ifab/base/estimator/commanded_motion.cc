#include "ifab/base/estimator/commanded_motion.h"

#include <algorithm>
#include <cmath>

#include "ifab/core/error.h"

namespace ifab::base {

CommandedSpeedOptions CommandedSpeedOptions::FromConfig(const ConfigNode& node) {
  CommandedSpeedOptions o;
  node.ExpectKeys({"use", "noise"});
  node.Read("use", o.use);
  if (auto n = node.Find("noise")) o.noise = OdometryNoise::FromConfig(*n, CommandedSpeedNoise());
  return o;
}

TrackCommandHistory::TrackCommandHistory(double track_gauge, std::size_t capacity)
    : gauge_(track_gauge), capacity_(std::max<std::size_t>(capacity, 2)) {
  IFAB_THROW_UNLESS(track_gauge > 0.0, "track gauge must be positive, got {}", track_gauge);
  commands_.reserve(capacity_);
}

void TrackCommandHistory::Add(const TrackCommand& command) {
  if (!commands_.empty()) {
    IFAB_THROW_UNLESS(command.t >= commands_.back().t,
                      "track command at t = {} s is older than the previous one ({} s)", command.t,
                      commands_.back().t);
  }
  if (commands_.size() == capacity_) commands_.erase(commands_.begin(), commands_.begin() + static_cast<std::ptrdiff_t>(capacity_ / 2));
  commands_.push_back(command);
}

Pose2 TrackCommandHistory::Step(Seconds ta, Seconds tb) const {
  Pose2 T;
  if (!(tb > ta)) return T;
  // The first command in force after ta.
  auto it = std::upper_bound(commands_.begin(), commands_.end(), ta,
                             [](Seconds t, const TrackCommand& c) { return t < c.t; });
  Seconds t = ta;
  const TrackCommand* current = it == commands_.begin() ? nullptr : &*(it - 1);
  while (t < tb) {
    const Seconds t_next = it == commands_.end() ? tb : std::min(tb, it->t);
    const double dt = t_next - t;
    if (current && dt > 0.0) {
      const double v = 0.5 * (current->v_left + current->v_right);
      const double omega = (current->v_right - current->v_left) / gauge_;
      const double dth = omega * dt;
      // An arc of constant curvature: chord length v dt sinc(dth / 2) along the mean heading.
      const double half = 0.5 * dth;
      const double sinc = std::abs(half) < 1e-9 ? 1.0 : std::sin(half) / half;
      const double chord = v * dt * sinc;
      T = T * Pose2(chord * std::cos(half), chord * std::sin(half), dth);
    }
    t = t_next;
    if (it != commands_.end() && it->t <= t) current = &*(it++);
  }
  return T;
}

MotionMeasurement TrackCommandHistory::Measure(Seconds ta, Seconds tb, const OdometryNoise& noise) const {
  MotionMeasurement m;
  m.step = Step(ta, tb);
  m.covariance = StepCovariance(m.step, noise);
  return m;
}

void TrackCommandHistory::DropBefore(Seconds t) {
  auto it = std::upper_bound(commands_.begin(), commands_.end(), t,
                             [](Seconds s, const TrackCommand& c) { return s < c.t; });
  if (it == commands_.begin()) return;
  commands_.erase(commands_.begin(), it - 1);  // keep the one in force at t
}

}  // namespace ifab::base
