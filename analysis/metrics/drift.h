// Drift of cluster quality over an animation (issue 12): keyed per-cluster differences of the
// metrics of analysis/metrics/cluster_table.h between a reference frame (frame 0, or the previous
// frame) and the current one, and their per-frame summary. Pure functions over ClusterRow
// vectors of the same clustering (rows are keyed by cluster id = position).
//
// Rotation-invariant quantities (reg, Acc, the sphere radius) do not drift under rigid motion,
// up to the rounding of the positions and of the sphere; the box area does (an axis-aligned box
// of rotated points), as the rotated box predicts.
#pragma once

#include <cstdint>
#include <vector>

#include "analysis/metrics/cluster_table.h"
#include "toolkit/core/stats.h"

namespace ptc {

struct ClusterDrift {
  std::uint32_t cluster = 0;
  double reg_delta = 0, acc_delta = 0;                 ///< current - reference
  double sphere_radius_ratio = 1, box_area_ratio = 1;  ///< current / reference; NaN when the reference is 0
};

/// One entry per cluster. std::invalid_argument when the two frames have different cluster
/// counts or a cluster's triangle or vertex count differs (another clustering).
[[nodiscard]] std::vector<ClusterDrift> cluster_drift(const std::vector<ClusterRow>& reference,
                                                      const std::vector<ClusterRow>& current);

struct DriftSummary {
  Summary reg_delta, acc_delta, sphere_radius_ratio, box_area_ratio;  ///< over clusters (NaNs left out)
  /// The clusters whose box area changed most (largest |log box_area_ratio|), worst first.
  std::vector<std::uint32_t> worst_box_area;
};

/// Summaries of a frame's drift; `worst` = how many worst clusters to name.
[[nodiscard]] DriftSummary summarize_drift(const std::vector<ClusterDrift>& drift, std::size_t worst = 5);

}  // namespace ptc
