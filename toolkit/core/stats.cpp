#include "toolkit/core/stats.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace ptc {

double percentile_sorted(std::span<const double> v, double p) {
  if (v.empty()) return 0.0;
  const double pos = p * static_cast<double>(v.size() - 1);
  const auto i = static_cast<std::size_t>(pos);
  const double f = pos - static_cast<double>(i);
  if (i + 1 >= v.size() || f == 0.0 || v[i] == v[i + 1]) return v[i];  // (two equal infinities: not inf - inf)
  const double d = v[i + 1] - v[i];
  if (std::isfinite(d)) return v[i] + f * d;
  return (1.0 - f) * v[i] + f * v[i + 1];  // an infinite end, or a difference beyond double's range
}

double percentile(std::vector<double> values, double p) {
  std::sort(values.begin(), values.end());
  return percentile_sorted(values, p);
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  if (n == 0) return 0.0;
  if (n % 2) return values[n / 2];
  const double a = values[n / 2 - 1], b = values[n / 2];
  if (a == b) return a;  // (two equal infinities: their sum is fine, but keep every equal pair exact)
  const double sum = a + b;
  return std::isfinite(sum) ? 0.5 * sum : 0.5 * a + 0.5 * b;  // (two values near DBL_MAX: no overflow)
}

std::vector<double> fractional_ranks(std::span<const double> values) {
  const std::size_t n = values.size();
  std::vector<std::size_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = i;
  // std::sort with the index as tie-break (the order a stable sort gives; libstdc++ 12's
  // stable_sort buffer trips AddressSanitizer's alloc-dealloc check).
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return values[a] < values[b] || (values[a] == values[b] && a < b); });
  std::vector<double> rank(n);
  for (std::size_t i = 0; i < n;) {
    std::size_t j = i + 1;
    while (j < n && values[order[j]] == values[order[i]]) ++j;
    const double r = 0.5 * (double(i + 1) + double(j));  // mean of ranks i+1 .. j
    for (std::size_t k = i; k < j; ++k) rank[order[k]] = r;
    i = j;
  }
  return rank;
}

double pearson(std::span<const double> x, std::span<const double> y) {
  if (x.size() != y.size()) throw std::invalid_argument("pearson: x and y differ in size");
  const std::size_t n = x.size();
  if (n < 2) return std::numeric_limits<double>::quiet_NaN();
  long double mx = 0, my = 0;
  for (std::size_t i = 0; i < n; ++i) mx += x[i], my += y[i];
  mx /= static_cast<long double>(n), my /= static_cast<long double>(n);
  long double sxy = 0, sxx = 0, syy = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const long double dx = x[i] - mx, dy = y[i] - my;
    sxy += dx * dy, sxx += dx * dx, syy += dy * dy;
  }
  if (sxx == 0 || syy == 0) return std::numeric_limits<double>::quiet_NaN();
  return static_cast<double>(sxy / std::sqrt(sxx * syy));
}

double spearman(std::span<const double> x, std::span<const double> y) {
  if (x.size() != y.size()) throw std::invalid_argument("spearman: x and y differ in size");
  const std::vector<double> rx = fractional_ranks(x), ry = fractional_ranks(y);
  return pearson(rx, ry);
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
