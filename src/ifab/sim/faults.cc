#include "ifab/sim/faults.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "ifab/core/angles.h"
#include "ifab/sim/sim_robot.h"

namespace ifab::sim {

const char* FaultName(FaultKind kind) {
  switch (kind) {
    case FaultKind::kBaseLaserBlackout: return "base_laser_blackout";
    case FaultKind::kArmLaserBlackout: return "arm_laser_blackout";
    case FaultKind::kDroppedScans: return "dropped_scans";
    case FaultKind::kTrackSlip: return "track_slip";
    case FaultKind::kTrackStall: return "track_stall";
    case FaultKind::kGyroSpikes: return "gyro_spikes";
    case FaultKind::kGyroBiasStep: return "gyro_bias_step";
    case FaultKind::kClockJump: return "clock_jump";
    case FaultKind::kArmTrajectoryRejected: return "arm_trajectory_rejected";
    case FaultKind::kBrickDropped: return "brick_dropped";
    case FaultKind::kStackBumped: return "stack_bumped";
    case FaultKind::kPersonOnPath: return "person_on_path";
    case FaultKind::kHalfSweep: return "half_sweep";
  }
  return "unknown";
}

namespace {
bool DrivenByDriveTime(FaultKind k) {
  return k == FaultKind::kBaseLaserBlackout || k == FaultKind::kTrackSlip || k == FaultKind::kTrackStall ||
         k == FaultKind::kGyroSpikes || k == FaultKind::kGyroBiasStep || k == FaultKind::kClockJump ||
         k == FaultKind::kStackBumped || k == FaultKind::kPersonOnPath ||
         k == FaultKind::kDroppedScans;
}
}  // namespace

FaultInjector::FaultInjector(std::vector<FaultSpec> faults, std::uint64_t seed) : rng_(seed) {
  for (auto& f : faults) records_.push_back({f, false, 0.0, 0.0, ""});
  scans_to_drop_.assign(records_.size(), 0);
}

std::vector<FaultSpec> FaultInjector::Draw(RandomStream& rng, const FaultDrawOptions& o) {
  std::vector<int> kinds(kNumFaultKinds);
  for (int i = 0; i < kNumFaultKinds; ++i) kinds[static_cast<std::size_t>(i)] = i;
  std::shuffle(kinds.begin(), kinds.end(), rng.engine());
  std::vector<FaultSpec> out;
  const int n = std::clamp(o.faults_per_run, 0, kNumFaultKinds);
  for (int i = 0; i < n; ++i) {
    FaultSpec f;
    f.kind = static_cast<FaultKind>(kinds[static_cast<std::size_t>(i)]);
    f.drive_time = rng.Uniform(1.0, o.max_drive_time);
    switch (f.kind) {
      case FaultKind::kBaseLaserBlackout: f.duration = rng.Uniform(0.5, 5.0); break;
      case FaultKind::kArmLaserBlackout:
        f.index = rng.UniformInt(1, o.max_sweep_index);
        f.duration = rng.Uniform(0.5, 5.0);
        f.drive_time = rng.Uniform(0.0, 1.0);  // seconds into the sweep
        break;
      case FaultKind::kDroppedScans:
        f.device = rng.Bernoulli(0.5) ? DeviceId::kBaseLaser : DeviceId::kArmLaser;
        f.count = rng.UniformInt(3, 12);
        f.index = rng.UniformInt(1, o.max_sweep_index);
        break;
      case FaultKind::kTrackSlip:
        f.duration = rng.Uniform(1.0, 3.0);
        f.magnitude = rng.Bernoulli(0.5) ? 1 : -1;  // a product's operands are unsequenced: draw the sign first
        f.magnitude *= rng.Uniform(0.3, 0.6);
        break;
      case FaultKind::kTrackStall:
        f.duration = rng.Uniform(1.0, 4.0);
        f.magnitude = rng.Bernoulli(0.5) ? 1 : -1;
        break;
      case FaultKind::kGyroSpikes:
        f.count = rng.UniformInt(2, 8);
        f.magnitude = rng.Uniform(3.0, 8.0);  // rad/s: shocks, far beyond any turn of the base
        break;
      case FaultKind::kGyroBiasStep:  // size, then sign (one draw per statement: a fixed order)
        f.magnitude = DegToRad(rng.Uniform(0.2, 1.0));
        f.magnitude *= rng.Bernoulli(0.5) ? 1 : -1;
        break;
      case FaultKind::kClockJump: {
        const DeviceId devices[] = {DeviceId::kBaseLaser, DeviceId::kArmLaser, DeviceId::kGyro, DeviceId::kArm};
        f.device = devices[rng.UniformInt(0, 3)];
        f.magnitude = rng.Uniform(0.5, 2.0);  // size, then sign
        f.magnitude *= rng.Bernoulli(0.5) ? 1 : -1;
        break;
      }
      case FaultKind::kArmTrajectoryRejected: f.index = rng.UniformInt(2, o.max_trajectory_index); break;
      case FaultKind::kBrickDropped:
        f.index = rng.UniformInt(1, o.max_grip_index);
        f.duration = rng.Uniform(0.5, 3.0);
        break;
      case FaultKind::kStackBumped:
        f.magnitude = rng.Uniform(0.01, 0.03);
        f.angle = rng.Uniform(-kPi, kPi);
        break;
      case FaultKind::kPersonOnPath:
        f.magnitude = rng.Uniform(0.8, 1.4);
        f.duration = rng.Uniform(3.0, 8.0);
        break;
      case FaultKind::kHalfSweep: f.index = rng.UniformInt(1, o.max_sweep_index); break;
    }
    out.push_back(f);
  }
  return out;
}

void FaultInjector::Start(FaultRecord& r, Seconds t, double duration, std::string detail) {
  r.injected = true;
  r.t_start = t;
  r.t_end = t + duration;
  r.detail = std::move(detail);
}

void FaultInjector::OnStep(SimRobot& sim, Seconds t, double dt) {
  now_ = t;
  const bool driving = std::abs(v_left_cmd_) + std::abs(v_right_cmd_) > 1e-3;
  if (driving) drive_time_ += dt;
  for (std::size_t i = 0; i < records_.size(); ++i) {
    FaultRecord& r = records_[i];
    const FaultSpec& f = r.spec;
    if (!r.injected && DrivenByDriveTime(f.kind) && driving && drive_time_ >= f.drive_time &&
        !(f.kind == FaultKind::kDroppedScans && f.device == DeviceId::kArmLaser)) {
      switch (f.kind) {
        case FaultKind::kBaseLaserBlackout:
          Start(r, t, f.duration, fmt::format("base laser silent for {:.1f} s", f.duration));
          break;
        case FaultKind::kDroppedScans:
          scans_to_drop_[i] = f.count;
          Start(r, t, 0.0, fmt::format("{} consecutive base laser scans lost", f.count));
          break;
        case FaultKind::kTrackSlip:
          Start(r, t, f.duration, fmt::format("{} track loses {:.0f}% of its speed for {:.1f} s",
                                              f.magnitude > 0 ? "left" : "right", 100 * std::abs(f.magnitude), f.duration));
          break;
        case FaultKind::kTrackStall:
          Start(r, t, f.duration, fmt::format("{} track stalls for {:.1f} s", f.magnitude > 0 ? "left" : "right", f.duration));
          break;
        case FaultKind::kGyroSpikes:
          for (int k = 0; k < f.count; ++k) spike_times_.push_back(t + rng_.Uniform(0.0, 1.0));
          std::sort(spike_times_.begin(), spike_times_.end());
          spike_magnitude_ = f.magnitude;
          Start(r, t, 1.0, fmt::format("{} gyro spikes of {:.1f} rad/s within 1 s", f.count, f.magnitude));
          break;
        case FaultKind::kGyroBiasStep:
          gyro_bias_ += f.magnitude;
          Start(r, t, 0.0, fmt::format("gyro bias steps by {:+.2f} deg/s", RadToDeg(f.magnitude)));
          break;
        case FaultKind::kClockJump:
          Start(r, t, 0.0, fmt::format("{} clock jumps by {:+.2f} s", DeviceName(f.device), f.magnitude));
          break;
        case FaultKind::kStackBumped: {
          const Eigen::Vector3d d(f.magnitude * std::cos(f.angle), f.magnitude * std::sin(f.angle), 0.0);
          Pose3 T = Pose3::Identity();
          T.translation() = d;
          sim.mutable_world().MoveBricks(T);
          T_bump_ = T * T_bump_;
          Start(r, t, 0.0, fmt::format("stack slides by {:.1f} cm ({:.0f} deg)", 100 * f.magnitude, RadToDeg(f.angle)));
          break;
        }
        case FaultKind::kPersonOnPath: {
          // Ahead of the footprint in the direction of travel (the next metre of any path).
          const double dir = v_left_cmd_ + v_right_cmd_ >= 0 ? 1.0 : -1.0;
          const Pose2 b = sim.true_base_pose();
          const double ahead = dir * (1.2 + f.magnitude);  // from the base centre: half the footprint + gap
          SiteBox person;
          person_name_ = fmt::format("person_{}", i);
          person.name = person_name_;
          person.box.size = {0.45, 0.45, 1.75};
          person.T_site_box = PoseFromXyzRpy(b.x + ahead * std::cos(b.theta), b.y + ahead * std::sin(b.theta),
                                             sim.world().site().ground_z + 0.875, 0, 0, b.theta);
          sim.mutable_world().AddObstacle(person);
          Start(r, t, f.duration, fmt::format("a person stands {:.1f} m {} the base for {:.1f} s", f.magnitude,
                                              dir > 0 ? "ahead of" : "behind", f.duration));
          break;
        }
        default: break;
      }
    }
    if (f.kind == FaultKind::kPersonOnPath && r.injected && t >= r.t_end && sim.mutable_world().RemoveObstacle(person_name_))
      r.detail += "; then walks away";
    if (f.kind == FaultKind::kBrickDropped && !r.injected && grips_ >= f.index && sim.holding_brick() &&
        t >= grip_time_ + f.duration) {
      sim.DropHeldBrick();
      Start(r, t, 0.0, fmt::format("the gripper loses the brick {:.1f} s after grip {}", f.duration, f.index));
    }
  }
}

void FaultInjector::FilterTracks(double* v_left, double* v_right) {
  v_left_cmd_ = *v_left;
  v_right_cmd_ = *v_right;
  for (const auto& r : records_) {
    if (!Active(r, now_)) continue;
    double& v = r.spec.magnitude > 0 ? *v_left : *v_right;
    if (r.spec.kind == FaultKind::kTrackSlip) v *= 1.0 - std::abs(r.spec.magnitude);
    if (r.spec.kind == FaultKind::kTrackStall) v = 0.0;
  }
}

void FaultInjector::FilterGyro(Seconds t, GyroSample* g) {
  g->rate.z() += gyro_bias_;
  while (!spike_times_.empty() && spike_times_.front() <= t) {
    g->rate.z() += (rng_.Bernoulli(0.5) ? 1 : -1) * spike_magnitude_;
    spike_times_.erase(spike_times_.begin());
  }
}

void FaultInjector::FilterStamp(DeviceId device, Stamp* stamp) const {
  for (const auto& r : records_)
    if (r.injected && r.spec.kind == FaultKind::kClockJump && r.spec.device == device) stamp->t_device += r.spec.magnitude;
}

bool FaultInjector::KeepScan(bool arm_laser, Seconds t, LaserScan* scan) {
  for (std::size_t i = 0; i < records_.size(); ++i) {
    FaultRecord& r = records_[i];
    const FaultSpec& f = r.spec;
    if (!arm_laser && f.kind == FaultKind::kBaseLaserBlackout && Active(r, t)) return false;
    if (f.kind == FaultKind::kDroppedScans && scans_to_drop_[i] > 0 &&
        (f.device == DeviceId::kArmLaser) == arm_laser) {
      --scans_to_drop_[i];
      return false;
    }
    if (!arm_laser) continue;
    if (f.kind == FaultKind::kArmLaserBlackout && Active(r, t)) return false;
    if (f.kind == FaultKind::kHalfSweep && r.injected && arm_laser_on_ && sweeps_ == f.index) {
      for (double& range : scan->ranges)
        if (rng_.Bernoulli(0.5)) range = LaserScan::kNoReturn;
    }
  }
  return true;
}

std::optional<std::string> FaultInjector::RejectTrajectory(Seconds t) {
  ++trajectories_;
  for (auto& r : records_)
    if (r.spec.kind == FaultKind::kArmTrajectoryRejected && !r.injected && trajectories_ == r.spec.index) {
      Start(r, t, 0.0, fmt::format("the arm controller rejects trajectory {}", trajectories_));
      return "motion supervision: trajectory refused (simulated controller fault)";
    }
  return std::nullopt;
}

void FaultInjector::OnGrip(Seconds t) {
  ++grips_;
  grip_time_ = t;
}

void FaultInjector::OnLaserActive(DeviceId laser, bool active, Seconds t) {
  if (laser != DeviceId::kArmLaser || active == arm_laser_on_) return;
  arm_laser_on_ = active;
  if (!active) return;
  ++sweeps_;
  for (std::size_t i = 0; i < records_.size(); ++i) {
    FaultRecord& r = records_[i];
    const FaultSpec& f = r.spec;
    if (r.injected || f.index != sweeps_) continue;
    if (f.kind == FaultKind::kArmLaserBlackout)
      Start(r, t + f.drive_time, f.duration,
            fmt::format("arm laser silent for {:.1f} s, {:.1f} s into sweep {}", f.duration, f.drive_time, sweeps_));
    if (f.kind == FaultKind::kHalfSweep) Start(r, t, 0.0, fmt::format("sweep {} loses half of its points", sweeps_));
    if (f.kind == FaultKind::kDroppedScans && f.device == DeviceId::kArmLaser) {
      scans_to_drop_[i] = f.count;
      Start(r, t, 0.0, fmt::format("{} consecutive arm laser scans lost in sweep {}", f.count, sweeps_));
    }
  }
}

}  // namespace ifab::sim
