// Every per-cluster metric of one animation frame, by name, for the pictures and the ParaView
// export of viz/ (issue 13): the columns of the drift study's clusters_frames.csv (docs/
// experiments.md), computed from the frame's positions with the same functions (cluster_rows,
// cluster_drift, sah_shares over the cluster BVH of the frame, meshlet_shapes), so a picture and
// the study's table agree value for value.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "analysis/metrics/cluster_table.h"

namespace ptc::bvh {
class ClusterScene;
}

namespace ptc {

/// How a metric is drawn: sequential (0 or its minimum .. its maximum) or diverging about a centre
/// (signed changes about 0, ratios about 1), with the range symmetric about the centre.
struct ClusterMetricInfo {
  std::string_view name;
  bool diverging = false;
  double centre = 0;
  std::string_view meaning;  ///< one line for legends and docs
  bool integer = false;      ///< whole-number values (a legend without fractions)
  bool flag = false;         ///< 0 or 1: drawn on 0 .. 1 whatever a frame's values
};

/// The metrics, in clusters_frames.csv's column order: triangles, vertices, connectivity, reg,
/// acc, reg_delta, acc_delta, sphere_radius, sphere_radius_ratio, sphere_radius_ratio_prev,
/// box_area, box_area_ratio, box_area_ratio_prev, p_hit, sah_share, boundary_vertices, components,
/// not_full (0 or 1).
[[nodiscard]] std::span<const ClusterMetricInfo> cluster_metric_infos();
/// The metric called `name`, or nullopt.
[[nodiscard]] std::optional<ClusterMetricInfo> find_cluster_metric(std::string_view name);
/// "triangles, vertices, ..." (for error messages and --help).
[[nodiscard]] std::string cluster_metric_names();

/// Values per metric (outer: cluster_metric_infos() order) and cluster id.
struct ClusterFrameMetrics {
  std::vector<std::vector<double>> values;
  std::vector<ClusterRow> rows;  ///< this frame's rows (the next frame's `previous`)
  [[nodiscard]] const std::vector<double>& of(std::string_view name) const;
};

/// The metrics of `clustering` at `mesh`'s positions. `reference`: the rows of the reference
/// frame (the scene's first frame) and `previous` those of the frame before; either empty means
/// "this frame" (ratios 1, deltas 0). `max_vertices` for meshlet_shapes: the largest cluster's
/// vertex count when 0. Throws std::invalid_argument when reference / previous are of another
/// clustering (cluster_drift). `adjacency`: the rest pose's adjacency triangles of a clustering
/// made by coincident corners (cluster_rows). `tree`: the cluster BVH whose SAH shares are
/// reported, already updated to `mesh`'s positions; the drift study's is set up once at the rest
/// pose in the study's trace frame and updated every frame (cluster_bvh_at_rest), so a caller
/// drawing the study's values passes one made that way. nullptr: one set up at this frame (its
/// cluster order and fixed group trees then come from this frame, not the rest pose).
[[nodiscard]] ClusterFrameMetrics cluster_frame_metrics(const Mesh& mesh, const Clustering& clustering, const ClusterConfig& cfg,
                                                        const std::vector<ClusterRow>& reference,
                                                        const std::vector<ClusterRow>& previous,
                                                        std::span<const Tri> adjacency = {},
                                                        bvh::ClusterScene* tree = nullptr);

/// The cluster BVH the drift study measures SAH shares on: the default cluster scene set up at
/// `rest` in the trace frame centred on rest's box (the study's), to be updated to each frame.
[[nodiscard]] std::unique_ptr<bvh::ClusterScene> cluster_bvh_at_rest(const Mesh& rest, const Clustering& clustering);

}  // namespace ptc
