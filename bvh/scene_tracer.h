// Tracing a scene whose static parts keep their BVH (issue 6, "Scenes": static meshes keep their
// BVH across frames, only moving meshes are updated; per-frame state is positions only).
//
// A SceneTracer holds up to two BVHs over sub-meshes of the scene's combined mesh
// (toolkit/anim/scene.h: parts' triangles concatenated in part order):
//   - the static parts' triangles in a TriangleScene built once, never updated;
//   - the moving parts' triangles in a TriangleScene or (given a clustering of the combined
//     mesh) a ClusterScene, updated per frame from positions only.
// With a clustering and every part static the one BVH is a ClusterScene built once
// (SceneConfig::built_once: no per-frame state).
// Static and moving parts may interleave in part order: each sub-mesh keeps its triangles in
// combined order, and an id map turns a sub-mesh triangle id back into the combined id (monotone,
// so the (t, id) order inside a sub-mesh is the combined order). A ray is traced through both and
// the results merged (the second traversal only up to the first one's hit, and for any-hit only
// the rays the first did not stop): closest hit = the smaller (t, combined triangle id) pair, which is what
// one BVH over the combined mesh returns (the tracer's closest hit is the smallest (t, id) pair
// whatever the tree); any hit = a hit in either. Both BVHs use the same trace frame (origin), so
// their float vertices and rays are bit-identical to those of a BVH over the whole mesh.
// When every part is static there is one BVH, built once; when none is, one BVH updated per frame.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "bvh/tracer.h"
#include "bvh/trace_scene.h"
#include "toolkit/anim/scene.h"
#include "toolkit/clustering/clustering.h"

namespace ptc::bvh {

/// Which triangles and vertices of a combined mesh belong to which part, and which parts move.
struct PartLayout {
  std::vector<std::size_t> vertex_offsets{0}, triangle_offsets{0};  ///< part_count + 1 entries each
  std::vector<bool> is_static;                                       ///< part_count entries
  [[nodiscard]] std::size_t part_count() const { return is_static.size(); }
  [[nodiscard]] static PartLayout of(const Scene& scene);
  /// One static part covering the whole mesh (a mesh file).
  [[nodiscard]] static PartLayout single(const Mesh& mesh, bool is_static);
};

struct SceneTracerConfig {
  const Clustering* clusters = nullptr;  ///< of the combined mesh: the moving BVH is a cluster BVH
  ClusterLeaf cluster_leaf = ClusterLeaf::Linear;
  std::uint32_t cluster_group_size = cluster_scene_defaults().cluster_group_size;  ///< SceneConfig (0: plain build)
  GroupTrees group_trees = cluster_scene_defaults().group_trees;                    ///< SceneConfig
  /// Every part static, with clusters: the one cluster BVH is built once (SceneConfig::built_once)
  /// with this group size instead. 0, the default: the plain build, whose tree is the rest tree
  /// (the groups make a per-frame rebuild cheap, and this BVH is never rebuilt).
  std::uint32_t still_cluster_group_size = 0;
  /// SceneConfig::min_cluster_groups (0: groups of exactly up to cluster_group_size clusters).
  std::uint32_t min_cluster_groups = cluster_scene_defaults().min_cluster_groups;
  std::optional<Vec3> origin;  ///< trace frame; default: centre of the first frame's bounds
  /// The moving cluster BVH's SceneConfig::fallback_swelling (0, the default: never).
  double cluster_fallback = 0.0;
  /// The moving cluster BVH's SceneConfig::refit_growth: its triangle fallback's refit limit (0,
  /// the default: rebuilt every frame).
  double fallback_refit = 0.0;
  /// The moving cluster BVH's SceneConfig::fallback_area_weights (the plain SAH by default).
  std::array<float, 3> fallback_area_weights = {1.0f, 1.0f, 1.0f};
  /// The moving cluster BVH's SceneConfig::fallback_area_eye (none by default).
  std::optional<Vec3> fallback_area_eye;
};

/// The configuration of the cluster BVH a SceneTracer with `cfg` builds, in the trace frame
/// around `origin` (cfg.origin when given, else the first frame's bounds' centre): what
/// cluster_vertex_order needs to renumber the vertices for it.
[[nodiscard]] SceneConfig cluster_config(const SceneTracerConfig& cfg, const Vec3& origin);

/// The method's precomputation on a scene (ptc bench, ptc trace --vertex-order clusters): to_old
/// = cluster_vertex_order over the scene's rest mesh, its parts and `clusters` (cfg: the cluster
/// BVH's configuration), then `clusters` (in place) and the scene's sources renamed with it.
/// Returns to_old, for whatever else the caller holds in the old numbering.
std::vector<std::uint32_t> renumber_by_clusters(Scene& scene, Clustering& clusters, const SceneConfig& cfg);

class SceneTracer {
 public:
  /// `first` = the combined mesh at the first traced frame (topology + positions). Builds every
  /// BVH over those positions. Throws std::invalid_argument when the layout does not cover the
  /// mesh, a part's triangle uses a vertex outside the part, or a cluster mixes static and
  /// moving triangles (InputError cannot arise: read_clusters makes clusters edge-connected and
  /// parts share no vertex).
  SceneTracer(const Mesh& first, const PartLayout& parts, const SceneTracerConfig& cfg = {});
  SceneTracer(const SceneTracer&) = delete;
  SceneTracer& operator=(const SceneTracer&) = delete;

  /// A frame: the combined positions (only the moving parts' ranges are read). Updates the moving
  /// BVH; a no-op when every part is static. std::invalid_argument for a wrong size.
  void update(std::span<const Vec3> combined_positions);

  /// Traces the rays through both BVHs and merges (see the file comment); triangle ids are
  /// combined ids; counters (when asked) are the sums over both traversals.
  TraceTotals trace(const RayBatch& rays, HitBatch& hits, const TraceOptions& opt) const;

  [[nodiscard]] const Vec3& origin() const { return origin_; }
  [[nodiscard]] bool split() const { return static_ != nullptr && moving_any(); }
  [[nodiscard]] bool all_static() const { return all_static_; }
  [[nodiscard]] std::size_t static_triangles() const { return static_n_; }
  [[nodiscard]] std::size_t moving_triangles() const { return moving_n_; }
  [[nodiscard]] bool moving_is_clusters() const { return bool(moving_cs_); }
  /// Whether the last update traced the moving cluster BVH's frame on its triangle fallback
  /// (SceneTracerConfig::cluster_fallback), and that BVH's swelling (NaN without one).
  [[nodiscard]] bool moving_fallback_active() const { return moving_cs_ && moving_cs_->fallback_active(); }
  /// Whether that fallback kept its tree and refitted it for the last update
  /// (SceneTracerConfig::fallback_refit; false when the frame was not traced on it).
  [[nodiscard]] bool moving_fallback_refitted() const {
    return moving_fallback_active() && moving_cs_->fallback_scene()->refitted();
  }
  [[nodiscard]] double moving_swelling() const {
    return moving_cs_ ? moving_cs_->swelling() : std::numeric_limits<double>::quiet_NaN();
  }
  /// The cluster BVH's group size (ClusterScene::group_size; 0: the plain build or no cluster BVH).
  [[nodiscard]] std::uint32_t cluster_group_size() const;
  /// Construction time of the static BVH (all parts static: of the one BVH), milliseconds.
  [[nodiscard]] double static_build_ms() const { return static_build_ms_; }
  /// Construction time of the moving BVH (including its first build), milliseconds.
  [[nodiscard]] double moving_setup_ms() const { return moving_setup_ms_; }
  /// Stage times of the last update() of the moving BVH (zero before the first / all static).
  [[nodiscard]] const StageTimes& moving_times() const { return moving_times_; }
  /// The BVH data (tests): static_data() requires a static part, moving_data() a moving one.
  [[nodiscard]] const TraceData& static_data() const { return static_->data(); }
  [[nodiscard]] const TraceData& moving_data() const;

 private:
  [[nodiscard]] bool moving_any() const { return moving_ts_ || moving_cs_; }
  Vec3 origin_ = Vec3::Zero();
  std::unique_ptr<TriangleScene> static_;
  std::unique_ptr<TriangleScene> moving_ts_;
  std::unique_ptr<ClusterScene> moving_cs_;
  std::vector<std::uint32_t> static_ids_, moving_ids_;  // sub-mesh triangle -> combined triangle (split only)
  std::size_t static_n_ = 0, moving_n_ = 0;             // triangles of each BVH
  struct Range {
    std::size_t first, count;  // combined vertices [first, first + count)
  };
  std::vector<Range> moving_vertex_ranges_;
  std::size_t combined_vertices_ = 0;
  bool all_static_ = false;
  std::vector<Vec3> moving_pos_;
  mutable HitBatch scratch_;
  mutable RayBatch scratch_rays_;
  double static_build_ms_ = 0, moving_setup_ms_ = 0;
  StageTimes moving_times_;
};

}  // namespace ptc::bvh
