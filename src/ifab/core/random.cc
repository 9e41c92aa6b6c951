#include "ifab/core/random.h"

#include <cmath>
#include <cstdint>

namespace ifab {
namespace {

// Ziggurat for the standard normal (Marsaglia & Tsang, "The ziggurat method for generating
// random variables", J. Stat. Softw. 5(8), 2000), over the half density f(x) = exp(-x^2 / 2):
// kLayers strips of equal area v. Strip 0 is the rectangle [0, x_1] x [0, f(x_1)] plus the tail
// beyond r = x_1 (its pseudo-width x_0 = v / f(r)); strip i >= 1 spans heights [f(x_i),
// f(x_{i+1})] and widths [0, x_i]; x_kLayers = 0 (the mode). A point drawn uniformly in a
// uniformly chosen strip is accepted when it lies under f, so the sample is exactly normal; the
// tables only decide how often the cheap test suffices.
constexpr int kLayers = 256;

double Density(double x) { return std::exp(-0.5 * x * x); }

struct Ziggurat {
  double r{0.0};
  double x[kLayers + 1]{};
  double f[kLayers + 1]{};

  // The strips for base edge r; returns how far the top strip's area misses v (0 when r is
  // right): negative when the strips end below the mode (r too large), positive when they reach
  // it early (r too small).
  double Build(double r_try) {
    const double v = r_try * Density(r_try) + std::sqrt(0.5 * M_PI) * std::erfc(r_try / std::sqrt(2.0));
    x[1] = r_try;
    for (int i = 1; i + 1 < kLayers; ++i) {
      const double y = Density(x[i]) + v / x[i];
      if (y >= 1.0) return 1.0;
      x[i + 1] = std::sqrt(-2.0 * std::log(y));
    }
    x[0] = v / Density(r_try);
    x[kLayers] = 0.0;
    for (int i = 0; i <= kLayers; ++i) f[i] = Density(x[i]);
    return Density(x[kLayers - 1]) + v / x[kLayers - 1] - 1.0;
  }

  // r by bisection, so the strips close at the mode to rounding (no published constant needed;
  // r = 3.6541528853610088 for 256 strips).
  Ziggurat() {
    double lo = 3.0, hi = 4.5;
    for (int it = 0; it < 200 && hi - lo > 1e-15; ++it) {
      const double mid = 0.5 * (lo + hi);
      (Build(mid) > 0.0 ? lo : hi) = mid;
    }
    r = hi;
    Build(r);
  }
};

// Uniform in [0, 1) from the top 53 bits.
double Unit(std::uint64_t bits) { return static_cast<double>(bits >> 11) * 0x1.0p-53; }

}  // namespace

double ZigguratStandardNormal(std::mt19937_64& engine) {
  static const Ziggurat z;  // built on first use (safe from other files' static initialisers)
  for (;;) {
    // One draw gives the strip (bits 0-7), the sign (bit 8) and the abscissa (bits 11-63).
    const std::uint64_t bits = engine();
    const int i = static_cast<int>(bits & 0xff);
    const double sign = (bits & 0x100) != 0 ? -1.0 : 1.0;
    const double x = Unit(bits) * z.x[i];
    if (x < z.x[i + 1]) return sign * x;  // inside the strip's part that lies under f
    if (i == 0) {
      // The tail beyond r (Marsaglia 1964): exact, by rejection from an exponential.
      double a = 0.0, b = 0.0;
      do {
        a = -std::log(1.0 - Unit(engine())) / z.r;
        b = -std::log(1.0 - Unit(engine()));
      } while (b + b < a * a);
      return sign * (z.r + a);
    }
    // The wedge: a uniform height in the strip, accepted under f.
    if (z.f[i] + Unit(engine()) * (z.f[i + 1] - z.f[i]) < Density(x)) return sign * x;
  }
}

}  // namespace ifab
