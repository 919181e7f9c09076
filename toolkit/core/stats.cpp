#include "toolkit/core/stats.h"

#include <algorithm>

namespace ptc {

double percentile_sorted(std::span<const double> v, double p) {
  if (v.empty()) return 0.0;
  const double pos = p * static_cast<double>(v.size() - 1);
  const auto i = static_cast<std::size_t>(pos);
  const double f = pos - static_cast<double>(i);
  return i + 1 < v.size() ? v[i] + f * (v[i + 1] - v[i]) : v[i];
}

double percentile(std::vector<double> values, double p) {
  std::sort(values.begin(), values.end());
  return percentile_sorted(values, p);
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  if (n == 0) return 0.0;
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

Summary summarize(std::span<const double> values) {
  Summary s;
  s.count = values.size();
  if (values.empty()) return s;
  std::vector<double> v(values.begin(), values.end());
  std::sort(v.begin(), v.end());
  s.min = v.front();
  s.max = v.back();
  long double sum = 0;  // long double: the mean of 1M areas stays exact to ~1e-16
  for (double x : v) sum += x;
  s.mean = static_cast<double>(sum / static_cast<long double>(v.size()));
  s.p5 = percentile_sorted(v, 0.05);
  s.p50 = percentile_sorted(v, 0.5);
  s.p95 = percentile_sorted(v, 0.95);
  return s;
}

}  // namespace ptc
