#include "analysis/metrics/frame_stats.h"

#include "toolkit/mesh/mesh.h"

#include <algorithm>
#include <limits>

#include "toolkit/geometry/triangle.h"

namespace ptc {

namespace {
// A triangle's area by the toolkit's rule (docs/mesh_policy.md): 0 for a degenerate triangle,
// including a near-degenerate one (its sine below 1e-12: toolkit/geometry/triangle.h), whose
// area is rounding; else half the cross product's length.
double area_by_rule(const Vec3& a, const Vec3& b, const Vec3& c) {
  if (triangle_geometry(a, b, c).normal == Vec3::Zero()) return 0.0;
  return 0.5 * (b - a).cross(c - a).norm();
}
}  // namespace

std::vector<double> triangle_areas(std::span<const Tri> triangles, std::span<const Vec3> positions) {
  std::vector<double> a(triangles.size());
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const Tri& f = triangles[t];
    a[t] = area_by_rule(positions[f[0]], positions[f[1]], positions[f[2]]);
  }
  return a;
}

FrameStats frame_stats(std::int64_t frame, std::span<const Tri> triangles, std::span<const Vec3> positions,
                       std::span<const double> first_areas) {
  FrameStats s;
  s.frame = frame;
  s.bounds = referenced_bounds(triangles, positions);  // (as ptc info's: the vertices triangles use)
  double lo = std::numeric_limits<double>::infinity(), hi = -lo, sum = 0;
  std::size_t counted = 0;
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const Tri& f = triangles[t];
    const double a = area_by_rule(positions[f[0]], positions[f[1]], positions[f[2]]);
    s.total_area += a;
    if (!(first_areas[t] > 0)) {
      ++s.degenerate_at_first;
      continue;
    }
    const double r = a / first_areas[t];
    lo = std::min(lo, r);
    hi = std::max(hi, r);
    sum += r;
    ++counted;
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  s.area_ratio_min = counted ? lo : nan;
  s.area_ratio_max = counted ? hi : nan;
  s.area_ratio_mean = counted ? sum / double(counted) : nan;
  return s;
}

Table frame_stats_table(const std::vector<FrameStats>& stats) {
  return tabulate(Schema{"ptc-animate-stats", 1}, stats, [](const FrameStats& s, Columns& col) {
    col("frame", s.frame);
    col("bbox_min_x", s.bounds.lo.x());
    col("bbox_min_y", s.bounds.lo.y());
    col("bbox_min_z", s.bounds.lo.z());
    col("bbox_max_x", s.bounds.hi.x());
    col("bbox_max_y", s.bounds.hi.y());
    col("bbox_max_z", s.bounds.hi.z());
    col("bbox_diagonal", s.bounds.extent().norm());
    col("total_area", s.total_area);
    col("area_ratio_min", s.area_ratio_min);
    col("area_ratio_mean", s.area_ratio_mean);
    col("area_ratio_max", s.area_ratio_max);
    col("degenerate_at_first", s.degenerate_at_first);
  });
}

}  // namespace ptc
