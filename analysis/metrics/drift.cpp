#include "analysis/metrics/drift.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace ptc {
namespace {

double ratio(double now, double ref) {
  return ref != 0 ? now / ref : std::numeric_limits<double>::quiet_NaN();
}

Summary finite_summary(const std::vector<ClusterDrift>& d, double ClusterDrift::*field) {
  std::vector<double> v;
  v.reserve(d.size());
  for (const ClusterDrift& x : d)
    if (std::isfinite(x.*field)) v.push_back(x.*field);
  return summarize(v);
}

}  // namespace

std::vector<ClusterDrift> cluster_drift(const std::vector<ClusterRow>& reference, const std::vector<ClusterRow>& current) {
  if (reference.size() != current.size())
    throw std::invalid_argument("cluster_drift: " + std::to_string(reference.size()) + " clusters against " +
                                std::to_string(current.size()));
  std::vector<ClusterDrift> out(reference.size());
  for (std::size_t k = 0; k < reference.size(); ++k) {
    const ClusterRow &a = reference[k], &b = current[k];
    if (a.m.triangles != b.m.triangles || a.m.vertices != b.m.vertices)
      throw std::invalid_argument("cluster_drift: cluster " + std::to_string(k) + " is not the same cluster in both frames");
    ClusterDrift& d = out[k];
    d.cluster = static_cast<std::uint32_t>(k);
    d.reg_delta = b.m.reg - a.m.reg;
    d.acc_delta = b.acc - a.acc;
    d.sphere_radius_ratio = ratio(b.m.sphere.radius, a.m.sphere.radius);
    d.box_area_ratio = ratio(b.m.box.surface_area(), a.m.box.surface_area());
  }
  return out;
}

DriftSummary summarize_drift(const std::vector<ClusterDrift>& d, std::size_t worst) {
  DriftSummary s;
  s.reg_delta = finite_summary(d, &ClusterDrift::reg_delta);
  s.acc_delta = finite_summary(d, &ClusterDrift::acc_delta);
  s.sphere_radius_ratio = finite_summary(d, &ClusterDrift::sphere_radius_ratio);
  s.box_area_ratio = finite_summary(d, &ClusterDrift::box_area_ratio);
  std::vector<std::pair<double, std::uint32_t>> by;
  for (const ClusterDrift& x : d)
    if (std::isfinite(x.box_area_ratio) && x.box_area_ratio > 0) by.emplace_back(std::abs(std::log(x.box_area_ratio)), x.cluster);
  const std::size_t n = std::min(worst, by.size());
  std::partial_sort(by.begin(), by.begin() + std::ptrdiff_t(n), by.end(),
                    [](const auto& a, const auto& b) { return a.first > b.first || (a.first == b.first && a.second < b.second); });
  for (std::size_t i = 0; i < n; ++i) s.worst_box_area.push_back(by[i].second);
  return s;
}

}  // namespace ptc
