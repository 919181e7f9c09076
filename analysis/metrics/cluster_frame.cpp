#include "analysis/metrics/cluster_frame.h"

#include <algorithm>
#include <array>
#include <optional>
#include <stdexcept>

#include "analysis/metrics/drift.h"
#include "analysis/metrics/meshlet_stats.h"
#include "analysis/metrics/sah_share.h"
#include "bvh/cluster_scene.h"
#include "bvh/sah_cost.h"

namespace ptc {
namespace {

constexpr std::array<ClusterMetricInfo, 18> kInfos = {{
    {"triangles", false, 0, "triangles in the cluster", true},
    {"vertices", false, 0, "distinct vertices of the cluster", true},
    {"connectivity", false, 0, "triangles / vertices"},
    {"reg", false, 0, "regularity AreaP / AreaC"},
    {"acc", false, 0, "Acc = reg - regBound * sizeBound"},
    {"reg_delta", true, 0, "reg minus reg at the reference frame"},
    {"acc_delta", true, 0, "Acc minus Acc at the reference frame"},
    {"sphere_radius", false, 0, "radius of the bounding sphere"},
    {"sphere_radius_ratio", true, 1, "sphere radius / its radius at the reference frame"},
    {"sphere_radius_ratio_prev", true, 1, "sphere radius / its radius at the previous frame"},
    {"box_area", false, 0, "surface area of the cluster's box"},
    {"box_area_ratio", true, 1, "box area / box area at the reference frame"},
    {"box_area_ratio_prev", true, 1, "box area / box area at the previous frame"},
    {"p_hit", false, 0, "SAH hit probability of the surface in its box"},
    {"sah_share", false, 0, "share of the cluster BVH's SAH cost"},
    {"boundary_vertices", false, 0, "vertices on the cluster's border", true},
    {"components", false, 0, "vertex-connected components of the cluster", true},
    {"not_full", false, 0, "1: fewer vertices than MaxCount (meshoptimizer's meshlet not full)", true, true},
}};

}  // namespace

std::span<const ClusterMetricInfo> cluster_metric_infos() { return kInfos; }

std::optional<ClusterMetricInfo> find_cluster_metric(std::string_view name) {
  for (const auto& i : kInfos)
    if (i.name == name) return i;
  return std::nullopt;
}

std::string cluster_metric_names() {
  std::string s;
  for (const auto& i : kInfos) s += (s.empty() ? "" : ", ") + std::string(i.name);
  return s;
}

const std::vector<double>& ClusterFrameMetrics::of(std::string_view name) const {
  for (std::size_t i = 0; i < kInfos.size(); ++i)
    if (kInfos[i].name == name) return values.at(i);
  throw std::invalid_argument("no cluster metric '" + std::string(name) + "'");
}

ClusterFrameMetrics cluster_frame_metrics(const Mesh& mesh, const Clustering& clustering, const ClusterConfig& cfg,
                                          const std::vector<ClusterRow>& reference, const std::vector<ClusterRow>& previous,
                                          std::span<const Tri> adjacency, bvh::ClusterScene* tree) {
  ClusterFrameMetrics out;
  out.rows = cluster_rows(mesh, clustering, cfg, std::nullopt, adjacency);
  const std::size_t n = out.rows.size();
  const std::vector<ClusterDrift> dr = cluster_drift(reference.empty() ? out.rows : reference, out.rows);
  const std::vector<ClusterDrift> dp = cluster_drift(previous.empty() ? out.rows : previous, out.rows);

  std::vector<double> share(n, 0.0);
  if (n > 0) {
    std::optional<bvh::ClusterScene> own;
    if (!tree) {
      bvh::SceneConfig sc = bvh::cluster_scene_defaults();
      sc.leaf_format = bvh::LeafFormatChoice::Blocks;  // (only the tree is read: no table layout)
      own.emplace(mesh, bvh::view_of(clustering), sc);
      own->update(mesh.positions());
    }
    const bvh::ClusterScene& cs = tree ? *tree : *own;
    // (the tree over the clusters: bvh() is over the groups with fixed group trees)
    const SahShares s = sah_shares(cs.cluster_tree(), cs.boxes(), cs.weights(), bvh::cluster_scene_defaults().build.cost);
    for (std::size_t i = 0; i < cs.cluster_ids().size(); ++i) share[cs.cluster_ids()[i]] = s.share[i];
  }
  std::uint32_t max_vertices = cfg.max_count;
  if (max_vertices == 0)
    for (const auto& r : out.rows) max_vertices = std::max<std::uint32_t>(max_vertices, static_cast<std::uint32_t>(r.m.vertices));
  const std::vector<MeshletShape> shapes =
      meshlet_shapes(clustering, mesh.triangles(), mesh.vertex_count(), std::max<std::uint32_t>(max_vertices, 1));

  out.values.assign(kInfos.size(), std::vector<double>(n));
  for (std::size_t k = 0; k < n; ++k) {
    const ClusterRow& r = out.rows[k];
    const double v[] = {double(r.m.triangles),
                        double(r.m.vertices),
                        r.m.connectivity,
                        r.m.reg,
                        r.acc,
                        dr[k].reg_delta,
                        dr[k].acc_delta,
                        r.m.sphere.radius,
                        dr[k].sphere_radius_ratio,
                        dp[k].sphere_radius_ratio,
                        r.m.box.surface_area(),
                        dr[k].box_area_ratio,
                        dp[k].box_area_ratio,
                        r.m.p_hit,
                        share[k],
                        double(shapes[k].boundary_vertices),
                        double(shapes[k].components),
                        shapes[k].not_full ? 1.0 : 0.0};
    static_assert(sizeof(v) / sizeof(v[0]) == kInfos.size());
    for (std::size_t i = 0; i < kInfos.size(); ++i) out.values[i][k] = v[i];
  }
  return out;
}

std::unique_ptr<bvh::ClusterScene> cluster_bvh_at_rest(const Mesh& rest, const Clustering& clustering) {
  bvh::SceneConfig cfg = bvh::cluster_scene_defaults();
  cfg.origin = rest.referenced_bounds().center();  // the study's trace frame (study_rays)
  cfg.leaf_format = bvh::LeafFormatChoice::Blocks;  // (its tree and boxes are read, and the set-up of blocks is the shorter)
  return std::make_unique<bvh::ClusterScene>(rest, bvh::view_of(clustering), cfg);
}

}  // namespace ptc
