// The one copy of the small statistics every layer reports: median, percentiles and a
// distribution summary. It lives in toolkit/core, the lowest layer, because the mesh report
// (toolkit), the benchmarks (bench/) and the experiments (analysis/) all need the same
// definitions: a p50 printed by `ptc info` and one in a benchmark table mean the same thing.
//
// Percentiles interpolate linearly between order statistics (type 7 of Hyndman & Fan 1996, the
// default of numpy and R): p of n sorted values v is v[i] + f (v[i+1] - v[i]) with
// i + f = p (n - 1); the median of an even count is the mean of the two middle values.
// NaN values are not allowed (they have no order); callers drop them first.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

namespace ptc {

/// Distribution summary of a sample. For an empty sample count = 0 and all values are 0.
struct Summary {
  std::size_t count = 0;
  double min = 0, mean = 0, p5 = 0, p50 = 0, p95 = 0, max = 0;
};

/// Summary of the values (copies and sorts them; O(n log n)). The mean is summed in long double.
[[nodiscard]] Summary summarize(std::span<const double> values);

/// Percentile p in [0, 1] of values already sorted ascending (0 for none).
[[nodiscard]] double percentile_sorted(std::span<const double> sorted, double p);

/// Percentile p in [0, 1] of the values (copies and sorts them; 0 for none).
[[nodiscard]] double percentile(std::vector<double> values, double p);

/// Median (percentile 0.5): the mean of the two middle values for an even count; 0 for none.
[[nodiscard]] double median(std::vector<double> values);

/// Ranks 1..n of the values, ties sharing the mean of their ranks ("fractional" ranking).
[[nodiscard]] std::vector<double> fractional_ranks(std::span<const double> values);

/// Pearson's correlation coefficient of x and y (equal sizes, std::invalid_argument otherwise);
/// NaN for fewer than two pairs or when either has zero variance.
[[nodiscard]] double pearson(std::span<const double> x, std::span<const double> y);

/// Spearman's rank correlation: Pearson's coefficient of the fractional ranks (ties handled as
/// averages, as scipy.stats.spearmanr does). NaN as for pearson().
[[nodiscard]] double spearman(std::span<const double> x, std::span<const double> y);

}  // namespace ptc
