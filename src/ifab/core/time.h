#pragma once
/// \file
/// Time stamps. All times are seconds as double, on a named clock: host time unless a variable
/// says otherwise (`t_device`). Stamped<T> pairs a value with its time; a StampedSeries holds
/// samples in increasing time and interpolates between them (the arm pose at each laser point's
/// time, eq. 6).

#include <algorithm>
#include <optional>
#include <vector>

#include "ifab/core/error.h"

namespace ifab {

using Seconds = double;

template <typename T>
struct Stamped {
  Seconds t{0.0};
  T value{};
};

/// Index i such that times[i] <= t < times[i+1], and the fraction of the way; nullopt outside.
template <typename T>
std::optional<std::pair<std::size_t, double>> Bracket(const std::vector<Stamped<T>>& series,
                                                      Seconds t) {
  if (series.size() < 2 || t < series.front().t || t > series.back().t) return std::nullopt;
  auto it = std::upper_bound(series.begin(), series.end(), t,
                             [](Seconds v, const Stamped<T>& s) { return v < s.t; });
  std::size_t i = static_cast<std::size_t>(std::distance(series.begin(), it));
  i = (i == 0) ? 0 : i - 1;
  if (i + 1 >= series.size()) i = series.size() - 2;
  const double dt = series[i + 1].t - series[i].t;
  const double s = dt > 0.0 ? (t - series[i].t) / dt : 0.0;
  return std::make_pair(i, std::clamp(s, 0.0, 1.0));
}

/// Value at time t, linearly interpolated by `interp(a, b, s)`; nullopt outside the series.
template <typename T, typename Interp>
std::optional<T> InterpolateAt(const std::vector<Stamped<T>>& series, Seconds t, Interp interp) {
  const auto b = Bracket(series, t);
  if (!b) return std::nullopt;
  return interp(series[b->first].value, series[b->first + 1].value, b->second);
}

}  // namespace ifab
