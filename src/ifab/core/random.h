#pragma once
/// \file
/// Seeded random streams. Everything stochastic takes a RandomStream, so a run is reproducible
/// from its seed. Independent sub-streams are derived by name (e.g. "lrf.base"), so adding a
/// new noise source does not shift the numbers drawn by the others.

#include <cstdint>
#include <random>
#include <string_view>

namespace ifab {

/// A standard normal sample from `engine` by the ziggurat method (random.cc).
double ZigguratStandardNormal(std::mt19937_64& engine);

class RandomStream {
 public:
  explicit RandomStream(std::uint64_t seed = 0) : seed_(seed), engine_(Mix(seed)) {}

  /// An independent stream derived from this one's seed and a name (not from its state).
  RandomStream Derive(std::string_view name) const { return RandomStream(Mix(seed_ ^ Hash(name))); }
  RandomStream Derive(std::uint64_t index) const { return RandomStream(Mix(seed_ + 0x9E3779B97F4A7C15ULL * (index + 1))); }

  std::uint64_t seed() const { return seed_; }

  /// Standard normal sample times sigma.
  double Normal(double sigma = 1.0) { return sigma * normal_(engine_); }
  /// The same distribution as Normal, drawn by the ziggurat method (Marsaglia & Tsang 2000):
  /// one engine draw and a table look-up for ~99 % of samples, where Normal's polar method
  /// (libstdc++) takes a log, a sqrt and two or more draws per pair. A different sequence from
  /// Normal's: for the hot per-beam draws of the simulated lasers, so the other streams (the
  /// as-built world, the planner) keep their numbers.
  double NormalZiggurat(double sigma = 1.0) { return sigma * ZigguratStandardNormal(engine_); }
  /// Uniform in [lo, hi).
  double Uniform(double lo = 0.0, double hi = 1.0) { return lo + (hi - lo) * uniform_(engine_); }
  /// True with probability p.
  bool Bernoulli(double p) { return uniform_(engine_) < p; }
  /// Uniform integer in [lo, hi].
  int UniformInt(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(engine_); }

  std::mt19937_64& engine() { return engine_; }

 private:
  // SplitMix64 finaliser: spreads nearby seeds over the whole state space.
  static std::uint64_t Mix(std::uint64_t z) {
    z += 0x9E3779B97F4A7C15ULL;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  static std::uint64_t Hash(std::string_view s) {  // FNV-1a
    std::uint64_t h = 0xcbf29ce484222325ULL;
    for (char c : s) h = (h ^ static_cast<unsigned char>(c)) * 0x100000001b3ULL;
    return h;
  }

  std::uint64_t seed_;
  std::mt19937_64 engine_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
};

}  // namespace ifab
