// Per-frame shape statistics of an animation against its first frame (ptc animate --stats,
// schema ptc-animate-stats/1): bounds, total area and per-triangle area ratios.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "analysis/schema/table.h"
#include "toolkit/core/types.h"

namespace ptc {

/// Per-frame shape statistics of `positions` against the first frame's (same topology).
struct FrameStats {
  std::int64_t frame = 0;
  Box3 bounds;  ///< of the vertices some triangle uses (Mesh::referenced_bounds)
  double total_area = 0;
  double area_ratio_min = 0, area_ratio_mean = 0, area_ratio_max = 0;  ///< NaN when no triangle counts
  std::size_t degenerate_at_first = 0;
};
/// first_areas: per-triangle areas of the reference frame (triangle_areas()).
[[nodiscard]] FrameStats frame_stats(std::int64_t frame, std::span<const Tri> triangles, std::span<const Vec3> positions,
                                     std::span<const double> first_areas);
[[nodiscard]] std::vector<double> triangle_areas(std::span<const Tri> triangles, std::span<const Vec3> positions);

/// stats.csv (schema ptc-animate-stats/1): one row per frame.
[[nodiscard]] Table frame_stats_table(const std::vector<FrameStats>& stats);

}  // namespace ptc
