#include "ifab/sync/clock_sync.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "ifab/core/config.h"
#include "ifab/core/random.h"

namespace ifab {
namespace {

// A device clock: host time = offset + rate * device + 0.5 * drift * device^2 (a crystal whose
// rate drifts slowly).
struct SyntheticClock {
  double offset{12.345};
  double rate{1.0 + 50e-6};
  double drift{0.0};  // [1/s]
  double Host(double device) const { return offset + rate * device + 0.5 * drift * device * device; }
};

// Positive delays of the host's pulse time stamps: a floor, exponential jitter and a share of
// pulses that arrive very late (a busy acquisition system).
double Delay(RandomStream& rng, double late_share = 0.05) {
  double d = 50e-6 - 500e-6 * std::log(1.0 - rng.Uniform());
  if (rng.Bernoulli(late_share)) d += rng.Uniform(5e-3, 50e-3);
  return d;
}

TEST(ClockSync, RecoversOffsetAndSkewDespiteLateObservations) {
  const SyntheticClock clock;
  for (std::uint64_t seed = 0; seed < 20; ++seed) {
    RandomStream rng(seed);
    ClockSync sync;
    // Pulses at 40 Hz for 30 s of device time.
    for (int k = 0; k < 1200; ++k) {
      const double device = 100.0 + k * 0.025;
      sync.AddPair(device, clock.Host(device) + Delay(rng));
    }
    const ClockMapping m = *sync.Mapping();
    EXPECT_NEAR(m.Skew(), 50e-6, 5e-6) << "seed " << seed;
    // The one-way estimate maps to the earliest possible arrival: within the delay floor plus a
    // little of the jitter of the least delayed pulses.
    for (double device : {100.0, 115.0, 130.0}) {
      const double err = *sync.ToHost(device) - clock.Host(device);
      EXPECT_GT(err, 0.0) << "seed " << seed;
      EXPECT_LT(err, 50e-6 + 40e-6) << "seed " << seed;
    }
  }
}

// The hull is kept incrementally for pairs in order and rebuilt otherwise: both give one answer.
TEST(ClockSync, SameMapInAnyArrivalOrderAndAcrossWindowTrims) {
  const SyntheticClock clock;
  RandomStream rng(7);
  std::vector<std::pair<double, double>> pairs;
  for (int k = 0; k < 4000; ++k) {
    const double device = 1e6 + k * 0.0025;  // 400 Hz, epoch-sized times
    pairs.emplace_back(device, clock.Host(device) + Delay(rng));
  }
  ClockSyncOptions o;
  o.max_early = 0.0;  // judge nothing: both see the same pairs
  o.max_late = 0.0;
  ClockSync in_order(o), shuffled(o);
  for (const auto& [d, h] : pairs) in_order.AddPair(d, h);
  std::vector<std::pair<double, double>> mixed = pairs;
  for (std::size_t i = 0; i + 1 < mixed.size(); i += 7) std::swap(mixed[i], mixed[i + 1]);
  for (const auto& [d, h] : mixed) shuffled.AddPair(d, h);
  EXPECT_NEAR(*in_order.ToHost(1e6 + 5.0), *shuffled.ToHost(1e6 + 5.0), 1e-9);
  EXPECT_NEAR(in_order.Mapping()->rate, shuffled.Mapping()->rate, 1e-9);
  // A short window trims in batches; the map still follows the clock.
  o.window = 2.0;
  ClockSync windowed(o);
  for (const auto& [d, h] : pairs) {
    windowed.AddPair(d, h);
    if (d > 1e6 + 1.0) {  // after 1 s of pairs
      EXPECT_NEAR(*windowed.ToHost(d) - clock.Host(d), 0.0, 2e-4);
    }
  }
  EXPECT_LE(windowed.size(), 2.2 / 0.0025 + 1);
}

TEST(ClockSync, BeatsLeastSquaresByTheMeanDelay) {
  const SyntheticClock clock;
  RandomStream rng(7);
  ClockSync sync;
  std::vector<std::pair<double, double>> pairs;
  for (int k = 0; k < 400; ++k) {
    const double device = k * 0.025;
    pairs.emplace_back(device, clock.Host(device) + Delay(rng, 0.1));
    sync.AddPair(pairs.back().first, pairs.back().second);
  }
  // Ordinary least squares line through the same pairs (what one gets ignoring the delay sign).
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (auto [x, y] : pairs) { sx += x; sy += y; sxx += x * x; sxy += x * y; }
  const double n = static_cast<double>(pairs.size());
  const double b = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  const double a = (sy - b * sx) / n;
  const double device = 5.0;
  const double err_ls = std::abs(a + b * device - clock.Host(device));
  const double err_hull = std::abs(*sync.ToHost(device) - clock.Host(device));
  EXPECT_GT(err_ls, 1e-3);
  EXPECT_LT(err_hull, 1e-4);
}

TEST(ClockSync, TracksADriftingSkewOverItsWindow) {
  SyntheticClock clock;
  clock.drift = 2e-8;  // the rate changes by 2e-8 per second: 36 ppm over 30 min
  RandomStream rng(3);
  ClockSyncOptions options;
  options.window = 30.0;
  ClockSync sync(options);
  double worst = 0.0;
  for (int k = 0; k < 40 * 1800; ++k) {
    const double device = k * 0.025;
    sync.AddPair(device, clock.Host(device) + Delay(rng));
    if (k % 400 == 399) worst = std::max(worst, std::abs(*sync.ToHost(device) - clock.Host(device)));
  }
  // Curvature over a 30 s window: drift W^2 / 8 ~ 2 us, plus the delay floor.
  EXPECT_LT(worst, 150e-6);
}

TEST(ClockSync, RejectsMismatchedPulsesAndRestartsAfterAClockJump) {
  const SyntheticClock clock;
  RandomStream rng(11);
  ClockSync sync;
  for (int k = 0; k < 400; ++k) {
    const double device = k * 0.025;
    double host = clock.Host(device) + Delay(rng);
    if (k % 50 == 25) host -= 0.025;  // pulse matched with the next packet: 25 ms early
    sync.AddPair(device, host);
  }
  EXPECT_GE(sync.rejected(), 6);
  EXPECT_LT(std::abs(*sync.ToHost(5.0) - clock.Host(5.0)), 1e-4);

  // The device restarts its clock: device times jump back by 9 s. Pairs look far too early,
  // and after a run of rejections the estimator starts over on the new clock.
  SyntheticClock restarted = clock;
  restarted.offset += 9.0;
  for (int k = 0; k < 400; ++k) {
    const double device = 1.0 + k * 0.025;
    sync.AddPair(device, restarted.Host(device) + Delay(rng, 0.0));
  }
  EXPECT_EQ(sync.restarts(), 1);
  EXPECT_LT(std::abs(*sync.ToHost(10.0) - restarted.Host(10.0)), 1e-4);
}

TEST(ClockSync, KeepsPrecisionWithEpochTimes) {
  SyntheticClock clock;
  clock.offset = 1.7e9;
  RandomStream rng(5);
  ClockSyncOptions options;
  options.latency = 50e-6;  // the known delay floor
  ClockSync sync(options);
  for (int k = 0; k < 800; ++k) {
    const double device = 3.0e5 + k * 0.025;
    sync.AddPair(device, clock.Host(device) + Delay(rng));
  }
  EXPECT_NEAR(*sync.ToHost(3.0e5 + 10.0), clock.Host(3.0e5 + 10.0), 40e-6);
}

TEST(ClockSync, OnePairGivesOffsetOnly) {
  ClockSync sync;
  EXPECT_FALSE(sync.Mapping().has_value());
  sync.AddPair(10.0, 110.0);
  EXPECT_NEAR(*sync.ToHost(12.0), 112.0, 1e-12);
  EXPECT_NEAR(sync.Mapping()->Skew(), 0.0, 1e-15);
}

TEST(DeviceClockSync, MatchesPacketsAndPulsesBySequenceInAnyOrder) {
  const SyntheticClock clock;
  RandomStream rng(2);
  DeviceClockSync device_sync;
  std::vector<Stamp> stamps;
  for (std::uint64_t k = 0; k < 200; ++k) {
    Stamp s;
    s.sequence = k;
    s.t_device = k * 0.025;
    s.t_host_received = clock.Host(s.t_device) + 0.01;
    stamps.push_back(s);
  }
  for (std::uint64_t k = 0; k < 200; ++k) {
    const SyncPulse pulse{DeviceId::kArmLaser, k, clock.Host(stamps[k].t_device) + Delay(rng, 0.0)};
    if (k % 2 == 0) {  // pulse first, then packet
      device_sync.AddPulse(pulse);
      device_sync.AddPacket(stamps[k]);
    } else if (k % 7 != 0) {  // some pulses are lost
      device_sync.AddPacket(stamps[k]);
      device_sync.AddPulse(pulse);
    } else {
      device_sync.AddPacket(stamps[k]);
    }
  }
  EXPECT_GT(device_sync.clock().size(), 150u);
  Stamp s = stamps[120];
  ASSERT_TRUE(device_sync.Apply(s));
  EXPECT_NEAR(s.t, clock.Host(s.t_device), 1e-4);
}

TEST(ClockSyncOptions, ReadsAndValidatesConfig) {
  const auto o = ClockSyncOptions::FromConfig(ConfigNode::FromString("{window: 10, latency: 0.0001}"));
  EXPECT_EQ(o.window, 10.0);
  EXPECT_EQ(o.latency, 0.0001);
  EXPECT_THROW(ClockSyncOptions::FromConfig(ConfigNode::FromString("{window: -1}")), InputError);
  EXPECT_THROW(ClockSyncOptions::FromConfig(ConfigNode::FromString("{windw: 1}")), InputError);
}

// Packets of a device with 50 ppm skew, a 4 ms mean transport delay, sent at 40 Hz in bursts
// (a sweep of 5 s), silent for `silence` s between bursts; its clock jumps by `jump` s just
// before burst `jump_burst`. Returns the step reported, and at which packet of that burst.
struct StepSeen {
  Seconds step{0.0};
  int burst{-1}, packet{-1};
};
StepSeen RunBursts(double silence, double jump, int jump_burst, int late_packet = -1) {
  ClockStepDetector d(0.25);
  RandomStream rng(5);
  Seconds t = 100.0, jumped = 0.0;
  for (int b = 0; b < 4; ++b) {
    if (b == jump_burst) jumped = jump;
    for (int k = 0; k < 200; ++k, t += 0.025) {
      Stamp s;
      s.t_device = 1e6 + (1 + 50e-6) * t + jumped;
      s.t_host_received = t + 0.001 + -0.004 * std::log(1.0 - rng.Uniform());
      if (b == 1 && k == late_packet) s.t_host_received += 0.4;  // one packet stuck in a buffer
      if (const Seconds step = d.Add(s, -50e-6, 2 * 0.002 / 60); step != 0.0) return {step, b, k};
    }
    t += silence;
  }
  return {};
}

TEST(ClockStepDetector, SeesAJumpOnADeviceSilentForMinutesAtItsSecondPacket) {
  for (const double jump : {0.5, -0.5, 2.0}) {
    const StepSeen s = RunBursts(300.0, jump, 2);
    EXPECT_EQ(s.burst, 2) << jump;
    EXPECT_EQ(s.packet, 1) << jump;
    EXPECT_NEAR(s.step, jump, 0.02) << jump;
  }
}

TEST(ClockStepDetector, IgnoresSkewOverSilenceAndALatePacket) {
  EXPECT_EQ(RunBursts(300.0, 0.0, -1).burst, -1);       // 50 ppm over 5 min: 15 ms of drift
  EXPECT_EQ(RunBursts(1.0, 0.0, -1, 17).burst, -1);     // one packet 0.4 s late
}

}  // namespace
}  // namespace ifab
