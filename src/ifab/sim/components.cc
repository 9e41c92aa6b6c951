#include "ifab/sim/components.h"

#include <cmath>

#include "ifab/core/angles.h"
#include "ifab/core/config.h"

namespace ifab::sim {
namespace {

void ReadWander(const ConfigNode& c, const char* key, Wander& w) {
  auto n = c.Find(key);
  if (!n) return;
  n->ExpectKeys({"mean", "sigma", "tau", "min", "max"});
  n->Read("mean", w.mean);
  n->ReadNonNegative("sigma", w.sigma);
  n->ReadPositive("tau", w.tau);
  n->Read("min", w.lo);
  n->Read("max", w.hi);
  if (w.lo > w.hi) (*n)["max"].Fail("max >= min");
}

}  // namespace

TrackOptions TrackOptions::FromConfig(const ConfigNode& c) {
  c.ExpectKeys({"track_gauge", "lag_tau", "max_track_accel", "max_track_speed", "steering_efficiency",
                "speed_factor", "icr_x_offset"});
  TrackOptions o;
  c.ReadPositive("track_gauge", o.track_gauge);
  c.ReadPositive("lag_tau", o.lag_tau);
  c.ReadPositive("max_track_accel", o.max_track_accel);
  c.ReadPositive("max_track_speed", o.max_track_speed);
  ReadWander(c, "steering_efficiency", o.steering_efficiency);
  ReadWander(c, "speed_factor", o.speed_factor);
  ReadWander(c, "icr_x_offset", o.icr_x_offset);
  return o;
}

TrackedBase::TrackedBase(TrackOptions options, Pose2 T_site_base, RandomStream rng)
    : o_(std::move(options)), pose_(T_site_base), rng_(std::move(rng)) {
  o_.steering_efficiency.Reset(rng_);
  o_.speed_factor.Reset(rng_);
  o_.icr_x_offset.Reset(rng_);
}

void TrackedBase::Command(double v_left, double v_right) {
  ref_left_ = std::clamp(v_left, -o_.max_track_speed, o_.max_track_speed);
  ref_right_ = std::clamp(v_right, -o_.max_track_speed, o_.max_track_speed);
}

void TrackedBase::Step(double dt) {
  auto follow = [&](double v, double ref) {
    const double dv = std::clamp((ref - v) * (1 - std::exp(-dt / o_.lag_tau)), -o_.max_track_accel * dt,
                                 o_.max_track_accel * dt);
    return v + dv;
  };
  v_left_ = follow(v_left_, ref_left_);
  v_right_ = follow(v_right_, ref_right_);
  const bool moving = std::abs(v_left_) + std::abs(v_right_) > 1e-4;
  if (moving) {  // slip conditions change only as the tracks move over the ground
    o_.steering_efficiency.Step(dt, rng_);
    o_.speed_factor.Step(dt, rng_);
    o_.icr_x_offset.Step(dt, rng_);
  }
  v_ = o_.speed_factor.value * 0.5 * (v_left_ + v_right_);
  omega_ = o_.steering_efficiency.value * (v_right_ - v_left_) / o_.track_gauge;
  const double v_lateral = o_.icr_x_offset.value * omega_;
  // Exact integration of constant body velocities over dt.
  const double th = pose_.theta + 0.5 * omega_ * dt;
  pose_.x += (v_ * std::cos(th) - v_lateral * std::sin(th)) * dt;
  pose_.y += (v_ * std::sin(th) + v_lateral * std::cos(th)) * dt;
  pose_.theta = WrapAngle(pose_.theta + omega_ * dt);
}

GyroOptions GyroOptions::FromConfig(const ConfigNode& c) {
  c.ExpectKeys({"rate_hz", "noise_density_deg_s_sqrt_hz", "bias_stability_deg_h", "turn_on_bias_sigma_deg_s",
                "range_deg_s"});
  GyroOptions o;
  c.ReadPositive("rate_hz", o.rate_hz);
  c.ReadNonNegative("noise_density_deg_s_sqrt_hz", o.noise_density_deg_s_sqrt_hz);
  c.ReadNonNegative("bias_stability_deg_h", o.bias_stability_deg_h);
  c.ReadNonNegative("turn_on_bias_sigma_deg_s", o.turn_on_bias_sigma_deg_s);
  c.ReadPositive("range_deg_s", o.range_deg_s);
  return o;
}

Gyro::Gyro(GyroOptions options, RandomStream rng) : o_(options), rng_(std::move(rng)) {
  for (int k = 0; k < 3; ++k) bias_[k] = DegToRad(rng_.Normal(o_.turn_on_bias_sigma_deg_s));
}

Eigen::Vector3d Gyro::Measure(const Eigen::Vector3d& omega) {
  const double dt = 1.0 / o_.rate_hz;
  const double white = DegToRad(o_.noise_density_deg_s_sqrt_hz) * std::sqrt(o_.rate_hz);
  // Bias random walk whose drift over 100 s matches the in-run stability figure.
  const double walk = DegToRad(o_.bias_stability_deg_h / 3600.0) / std::sqrt(100.0) * std::sqrt(dt);
  Eigen::Vector3d out;
  for (int k = 0; k < 3; ++k) {
    bias_[k] += rng_.Normal(walk);
    out[k] = std::clamp(omega[k] + bias_[k] + rng_.Normal(white), -DegToRad(o_.range_deg_s),
                        DegToRad(o_.range_deg_s));
  }
  return out;
}

AccelOptions AccelOptions::FromConfig(const ConfigNode& c) {
  c.ExpectKeys({"noise_density_ug_sqrt_hz", "bias_stability_ug", "turn_on_bias_sigma_mg", "range_m_s2"});
  AccelOptions o;
  c.ReadNonNegative("noise_density_ug_sqrt_hz", o.noise_density_ug_sqrt_hz);
  c.ReadNonNegative("bias_stability_ug", o.bias_stability_ug);
  c.ReadNonNegative("turn_on_bias_sigma_mg", o.turn_on_bias_sigma_mg);
  c.ReadPositive("range_m_s2", o.range_m_s2);
  return o;
}

Accelerometer::Accelerometer(AccelOptions options, double rate_hz, RandomStream rng)
    : o_(options), rate_hz_(rate_hz), rng_(std::move(rng)) {
  for (int k = 0; k < 3; ++k) bias_[k] = 9.80665e-3 * rng_.Normal(o_.turn_on_bias_sigma_mg);
}

Eigen::Vector3d Accelerometer::Measure(const Eigen::Vector3d& f) {
  constexpr double kG = 9.80665;
  const double dt = 1.0 / rate_hz_;
  const double white = kG * 1e-6 * o_.noise_density_ug_sqrt_hz * std::sqrt(rate_hz_);
  // Bias random walk whose drift over 100 s matches the in-run stability figure (as the gyro's).
  const double walk = kG * 1e-6 * o_.bias_stability_ug / std::sqrt(100.0) * std::sqrt(dt);
  Eigen::Vector3d out;
  for (int k = 0; k < 3; ++k) {
    bias_[k] += rng_.Normal(walk);
    out[k] = std::clamp(f[k] + bias_[k] + rng_.Normal(white), -o_.range_m_s2, o_.range_m_s2);
  }
  return out;
}

ClockOptions ClockOptions::FromConfig(const ConfigNode& c) {
  c.ExpectKeys({"offset", "skew_ppm", "stamp_jitter", "latency_mean", "latency_min", "pulse_jitter",
                "pulse_late_probability", "pulse_late_max"});
  ClockOptions o;
  c.Read("offset", o.offset);
  c.Read("skew_ppm", o.skew_ppm);
  c.ReadNonNegative("stamp_jitter", o.stamp_jitter);
  c.ReadNonNegative("latency_mean", o.latency_mean);
  c.ReadNonNegative("latency_min", o.latency_min);
  c.ReadNonNegative("pulse_jitter", o.pulse_jitter);
  c.ReadInRange("pulse_late_probability", o.pulse_late_probability, 0.0, 1.0);
  c.ReadNonNegative("pulse_late_max", o.pulse_late_max);
  return o;
}

Stamp DeviceClock::StampPacket(Seconds t_true, SyncPulse* pulse) {
  Stamp s;
  s.sequence = sequence_++;
  s.t_device = (1.0 + 1e-6 * o_.skew_ppm) * t_true + o_.offset + rng_.Normal(o_.stamp_jitter);
  const double delay = o_.latency_min + (o_.latency_mean > 0 ? -o_.latency_mean * std::log(1.0 - rng_.Uniform()) : 0.0);
  s.t_host_received = t_true + delay;
  s.t = s.t_host_received;  // what a driver without clock sync would use; sync replaces it
  if (pulse) {
    pulse->device = id_;
    pulse->sequence = s.sequence;
    double late = 0.0;
    if (rng_.Bernoulli(o_.pulse_late_probability)) late = rng_.Uniform(0.0, o_.pulse_late_max);
    pulse->t_host = t_true + std::abs(rng_.Normal(o_.pulse_jitter)) + late;
  }
  return s;
}

ServoOptions ServoOptions::FromConfig(const ConfigNode& c) {
  c.ExpectKeys({"bandwidth", "settle_tolerance", "encoder_offset_sigma_deg", "state_rate_hz"});
  ServoOptions o;
  c.ReadPositive("bandwidth", o.bandwidth);
  c.ReadPositive("settle_tolerance", o.settle_tolerance);
  c.ReadNonNegative("encoder_offset_sigma_deg", o.encoder_offset_sigma_deg);
  c.ReadPositive("state_rate_hz", o.state_rate_hz);
  return o;
}

ArmServo::ArmServo(ServoOptions options, const RobotModel& robot, Vector6d q0, RandomStream rng)
    : o_(options), robot_(&robot), q_(q0), qd_(Vector6d::Zero()) {
  for (int i = 0; i < 6; ++i) offsets_[i] = DegToRad(rng.Normal(o_.encoder_offset_sigma_deg));
  trajectory_.points.push_back({0.0, q0, Vector6d::Zero()});
}

void ArmServo::Follow(const JointTrajectory& trajectory, Seconds t_now) {
  if (trajectory.points.empty()) return;
  trajectory_ = trajectory;
  start_ = t_now;
}

Vector6d ArmServo::Reference(Seconds t_now) const {
  const auto& pts = trajectory_.points;
  const double t = t_now - start_;
  if (t <= pts.front().t) return pts.front().q;
  if (t >= pts.back().t) return pts.back().q;
  auto it = std::upper_bound(pts.begin(), pts.end(), t, [](double v, const auto& p) { return v < p.t; });
  const auto& b = *it;
  const auto& a = *(it - 1);
  const double s = (t - a.t) / std::max(1e-12, b.t - a.t);
  return a.q + s * (b.q - a.q);
}

void ArmServo::Step(double dt, Seconds t_now) {
  // Critically damped second-order tracking of the reference, speed-limited, within joint limits.
  const Vector6d ref = Reference(t_now).cwiseMax(robot_->q_min).cwiseMin(robot_->q_max);
  const double w = o_.bandwidth;
  const Vector6d qdd = w * w * (ref - q_) - 2.0 * w * qd_;
  qd_ = (qd_ + dt * qdd).cwiseMax(-robot_->qd_max).cwiseMin(robot_->qd_max);
  q_ = (q_ + dt * qd_).cwiseMax(robot_->q_min).cwiseMin(robot_->q_max);
}

bool ArmServo::Busy(Seconds t_now) const {
  if (t_now - start_ < trajectory_.Duration()) return true;
  return (q_ - trajectory_.points.back().q).cwiseAbs().maxCoeff() > o_.settle_tolerance ||
         qd_.cwiseAbs().maxCoeff() > 10 * o_.settle_tolerance;
}

}  // namespace ifab::sim
