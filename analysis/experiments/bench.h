// The side-by-side benchmark against Embree (`ptc bench`, bench/peer_bench): in one process, on
// the same mesh, the same trace frame and the same primary rays, over the frames of a scene,
// every acceleration configuration of analysis/loop/accel.h (ours_triangles, ours_clusters,
// embree_medium, embree_low, embree_refit) updates to the frame's positions and traces, through
// the one frame loop (analysis/loop/frame_loop.h). Every configuration sees the whole
// (combined) mesh as one geometry, static parts included: the static/dynamic split is
// `ptc trace`'s; the benchmark measures the per-frame structures. A static scene is given its
// stand-in motion by the caller (toolkit/anim/scene.h deform_scene).
//
// Per frame and configuration: update_ms, build_ms and every stage (analysis/loop UpdateTimes),
// trace_ms (closest hit, counters off), hits, and the agreement of the closest triangle with
// ours_triangles of the same frame (analysis/metrics/hit_agreement.h). With a light (the
// default of `ptc bench`): shadow rays towards it (render/rays.h trace_shadows, any hit), one
// batch per frame made from ours_triangles' primary hits and traced by every configuration
// (rtcOccluded1 for Embree; with packets rtcOccludedN, by default timed with both context
// flags and the faster counted: EmbreeShadowHint), shadow_ms timed alone, and the points lit differently from
// ours_triangles counted; the whole frame is update + build + primary trace + shadow trace.
// Medians skip the first frame (first-touch page faults, caches, Embree's lazy initialisation)
// when there is more than one. Threads: oneTBB is limited to `threads` for the whole run
// (builds and traces), Embree's device gets "threads=N"; set_affinity is never used.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "analysis/loop/accel.h"
#include "analysis/metrics/hit_agreement.h"
#include "analysis/schema/table.h"
#include "bvh/vertex_order.h"
#include "render/camera.h"
#include "toolkit/clustering/cluster.h"
#include "toolkit/anim/scene.h"
#include "toolkit/clustering/clustering.h"

namespace ptc {

/// MaxCount = MaxSize of the bench's own clustering when neither the user nor the scene gives one
/// (docs/tracing.md, "The bench's cluster size").
inline constexpr std::uint32_t kBenchDefaultMaxCount = 32;

/// Embree's shadow packets' context flag (`ptc bench --embree-shadow-hint`): Best times each
/// frame's shadow rays with both flags and counts the faster (the other's time is kept), since
/// neither is faster on every scene (docs/tracing.md, "Embree's shadow packets"); Coherent or
/// Incoherent: that flag alone. Primary packets always take the coherent flag (a camera's rows).
enum class EmbreeShadowHint : std::uint8_t { Best, Coherent, Incoherent };
[[nodiscard]] const char* to_string(EmbreeShadowHint h);
[[nodiscard]] std::optional<EmbreeShadowHint> parse_embree_shadow_hint(std::string_view s);

struct PeerBenchConfig {
  FrameRange frames{0, 4};                ///< scene frames (the first is left out of the medians)
  int width = 1024, height = 1024;        ///< primary rays of the camera (1..16384 each)
  CameraSpec camera;                      ///< the camera (unset fields: framing the rest pose)
  /// The camera itself when the caller made it from `camera` (ptc bench does, for the light):
  /// not made again (framing walks every triangle of the rest mesh).
  std::optional<bvh::PinholeCamera> made_camera;
  unsigned threads = 1;                   ///< oneTBB and Embree threads (>= 1; 1 = one-thread figures)
  /// Clustering when none is given: growth / Acc, MaxCount = MaxSize = this (ptc bench sets it
  /// from --max-count, else the scene's own cluster size, else kBenchDefaultMaxCount). 32, not the
  /// paper's 50: the paper leaves MaxCount free, to be chosen per implementation for speed, and 32
  /// gave this tracer the fastest whole frames over the built-in 832k scenes on their first frames
  /// (docs/tracing.md, "The bench's cluster size"); the draped cloth is faster at its own 28
  /// ("The cloth's own cluster size").
  std::uint32_t max_count = kBenchDefaultMaxCount;
  ClusterAdjacency adjacency = ClusterAdjacency::Auto;  ///< and its adjacency (cluster.h)
  bvh::ClusterLeaf cluster_leaf = bvh::ClusterLeaf::Linear;
  /// How the cluster BVH's linear leaves hold their triangles (bvh::LeafFormatChoice; the format
  /// used is PeerBenchResult::cluster_leaves.format).
  bvh::LeafFormatChoice leaf_format = bvh::LeafFormatChoice::Auto;
  /// Two-level build of the cluster BVH over groups of at most this many clusters; 0: plain.
  std::uint32_t cluster_group_size = bvh::cluster_scene_defaults().cluster_group_size;
  /// bvh::SceneConfig::min_cluster_groups (0: groups of exactly up to cluster_group_size; the
  /// command's --cluster-groups N given).
  std::uint32_t min_cluster_groups = bvh::cluster_scene_defaults().min_cluster_groups;
  /// With groups: each group's tree rebuilt per frame, or fixed and refitted (bvh::GroupTrees).
  bvh::GroupTrees group_trees = bvh::cluster_scene_defaults().group_trees;
  TieRule tie;                            ///< what counts as a tie in the hit agreement
  /// Vertex order of the benchmark mesh. Clusters (default): the scene is renumbered once, after
  /// clustering, with bvh::cluster_vertex_order (every cluster's own vertices consecutive, parts
  /// kept in place), so that the cluster path converts and boxes in one pass over the positions
  /// (ClusterScene::fused_vertex_pass); every configuration sees the same renumbered mesh,
  /// triangle ids unchanged. Input: the file's order (the cluster path gathers per frame).
  bvh::VertexOrder vertex_order = bvh::VertexOrder::Clusters;
  /// Point light (world) of the shadow pass; nullopt: primary rays only (the whole frame is then
  /// update + build + primary trace).
  std::optional<Vec3> light;
  /// Trace primary and shadow rays in packets: ours with bvh::TraceOptions::packets (8 rays, one
  /// per AVX2 lane), Embree with rtcIntersectN / rtcOccludedN (N = embree_packet_width), the
  /// coherent flag for primary rays and embree_shadow_hint's for shadow rays. Off: single rays
  /// on both sides (rtcIntersect1 / rtcOccluded1).
  bool packets = false;
  int embree_packet_width = 8;  ///< Embree's packets with `packets`: 4, 8 or 16 rays (rtcIntersect4/8/16)
  EmbreeShadowHint embree_shadow_hint = EmbreeShadowHint::Best;  ///< with `packets` and a light
  /// The shadow batch's order (`ptc bench --shadow-order`): the primary hits' pixel order, or the
  /// Morton order of the hit points (render/rays.h morton_order), made once per frame for every
  /// configuration alike; its time is BenchRow::shadow_order_ms, counted in every whole frame.
  bool shadow_morton = false;
  /// Our tracer's instruction-set variant (bvh::TraceOptions::isa; Auto: see bvh/tracer.h).
  /// Embree keeps its own choice.
  bvh::TraceIsa isa = bvh::TraceIsa::Auto;
  /// ours_clusters traces a frame on a triangle BVH when the clusters' swelling exceeds this
  /// (bvh::SceneConfig::fallback_swelling; `ptc bench --cluster-fallback`); 0: never.
  double cluster_fallback = bvh::kAutoFallbackSwelling;
  /// ours_clusters: the triangle fallback's refit limit (bvh::SceneConfig::refit_growth; `ptc
  /// bench --fallback-refit`); 0: rebuilt every frame.
  double fallback_refit = bvh::kAutoFallbackRefitGrowth;
  /// ours_clusters: the triangle fallback built for the primary rays' mean directions
  /// (Directions, `ptc bench --fallback-sah directions`, the default: their
  /// bvh::direction_area_weights), for rays from the camera's eye (Eye:
  /// bvh::SceneConfig::fallback_area_eye), or with the plain SAH.
  bvh::FallbackSah fallback_sah = bvh::FallbackSah::Directions;
};

struct BenchRow {
  int frame = 0;                 ///< benchmark frame 0 .. frames - 1
  std::int64_t scene_frame = 0;  ///< the scene frame
  std::string config;
  loop::UpdateTimes times;       ///< update_ms, build_ms and the stages
  double frame_ms = 0;           ///< wall time of the whole update call
  double source_ms = 0;          ///< producing the frame's positions, once per frame, outside the configurations
  double trace_ms = 0, mrays_per_s = 0;
  std::uint64_t rays = 0, hits = 0;
  HitAgreement agreement;        ///< against ours_triangles of the same frame (zero for itself)
  /// Shadow pass (zero without a light): rays (surface points facing the light), occluded rays,
  /// trace time, and points whose lit/unlit differs from ours_triangles' of the same frame (with
  /// EmbreeShadowHint::Best, the larger count of the two flags' passes).
  std::uint64_t shadow_rays = 0, shadow_occluded = 0, shadow_mismatches = 0;
  double shadow_ms = 0;
  /// Embree's shadow packets: the context flag of shadow_ms ("coherent" or "incoherent"; empty
  /// for ours, single rays and without a light), and with EmbreeShadowHint::Best the other
  /// flag's time (NaN otherwise).
  std::string shadow_hint;
  double shadow_other_ms = std::numeric_limits<double>::quiet_NaN();
  /// With PeerBenchConfig::shadow_morton: the frame's Morton ordering of the shadow batch, made
  /// once and the same in every configuration's row (0 otherwise).
  double shadow_order_ms = 0;
  /// update_ms + build_ms + trace_ms + shadow_order_ms + shadow_ms.
  [[nodiscard]] double whole_frame_ms() const {
    return times.update_ms + times.build_ms + trace_ms + shadow_order_ms + shadow_ms;
  }
  /// Per-ray traversal counters of ours (an untimed second trace with counters on: the timed one
  /// runs without them); NaN for Embree, which has none.
  double nodes_per_ray = 0, triangles_per_ray = 0;
  double sah_cost = 0;           ///< SAH cost of our binary BVH (NaN for Embree)
  /// ours_clusters: bvh::ClusterScene::swelling() (NaN for the others), and whether the frame
  /// was traced on the triangle fallback (0 for the others).
  double swelling = 0;
  int fallback = 0;
  /// ours_clusters on a frame traced on the triangle fallback: 1 when the fallback kept its tree
  /// and refitted it (bvh::TriangleScene::refitted()), 0 when it was rebuilt; 0 for the others.
  int fallback_refit = 0;
  double rss_mb = 0, peak_rss_mb = 0;  ///< resident and peak resident memory after the row's trace
};

struct BenchSummary {
  std::string config;
  double update_ms = 0, build_ms = 0, update_build_ms = 0, trace_ms = 0, mrays_per_s = 0;  ///< medians
  double shadow_ms = 0, whole_frame_ms = 0;  ///< medians (the whole frame's of the per-frame sums)
  std::uint64_t mismatches = 0, ties = 0;  ///< sums over all frames (the first included)
  std::uint64_t shadow_mismatches = 0;     ///< sum over all frames
};

struct PeerBenchResult {
  std::vector<BenchRow> rows;          ///< frame-major, configurations in loop::kAllAccelKinds order
  std::vector<BenchSummary> summary;   ///< one per configuration
  std::size_t triangles = 0, vertices = 0, clusters = 0, rays = 0;
  int median_first_frame = 0;          ///< medians over benchmark frames [median_first_frame, frames)
  double cluster_ms = 0;               ///< clustering (0 when clusters were given)
  double cluster_scene_setup_ms = 0;   ///< ClusterScene construction (per-clustering layout, once)
  std::string clustering;              ///< how the clusters were made
  std::string vertex_order;            ///< "clusters" (renumbered once) or "input"
  bool fused_vertex_pass = false;      ///< the cluster scene converts and boxes in one pass (no gather)
  bvh::LeafShape cluster_leaves;       ///< how full the cluster BVH's leaves are (bvh::leaf_shape)
  bvh::LeafBytes cluster_leaf_estimate;  ///< both formats' bytes as LeafFormatChoice::Auto estimates them
  std::uint32_t cluster_group_size = 0;  ///< the cluster BVH's two-level build (0: plain)
  bvh::GroupTrees group_trees = bvh::GroupTrees::Rebuild;  ///< and what it does inside a group
  double renumber_ms = 0;              ///< the renumbering (mesh, clustering, frame source), once
  bool shadows = false;                ///< a shadow pass was traced (cfg.light)
  bool packets = false;                ///< rays were traced in packets (cfg.packets)
  int embree_packet_width = 8;         ///< and Embree's packet width
  EmbreeShadowHint embree_shadow_hint = EmbreeShadowHint::Best;  ///< and its shadow packets' flag (cfg's)
  bool shadow_morton = false;          ///< the shadow batch in Morton order (cfg's)
  bvh::TraceIsa isa = bvh::TraceIsa::Auto;  ///< our tracer's variant that ran (resolved)
  double cluster_fallback = 0;         ///< the fallback's threshold (cfg.cluster_fallback; 0: off)
  double fallback_refit = 0;           ///< the fallback's refit limit (cfg.fallback_refit; 0: rebuilt every frame)
  /// how the fallback was built (cfg.fallback_sah with the fallback on, else Plain), and with
  /// what: its area weights (the primary rays' with Directions; else 1, 1, 1) and its rays'
  /// point (the camera's eye with Eye; else none)
  bvh::FallbackSah fallback_sah = bvh::FallbackSah::Plain;
  std::array<float, 3> fallback_area_weights = {1.0f, 1.0f, 1.0f};
  std::optional<Vec3> fallback_area_eye;
};

/// The per-frame ratio of a peer's whole frame to a configuration's (> 1: the configuration is
/// faster), over the frames of the medians on which both have a row with a finite whole frame
/// above 0 ms: the lowest, its frame (benchmark frame and scene frame; the first such when
/// several tie) and the highest. NaN and frames -1 when no frame has both.
struct FrameRatioRange {
  double lowest = std::numeric_limits<double>::quiet_NaN(), highest = std::numeric_limits<double>::quiet_NaN();
  int lowest_frame = -1;                ///< benchmark frame of the lowest
  std::int64_t lowest_scene_frame = -1;  ///< and its scene frame
};
[[nodiscard]] FrameRatioRange whole_frame_ratio_range(const PeerBenchResult& r, std::string_view config,
                                                      std::string_view peer);

/// Runs the benchmark over scene frames cfg.frames. `clusters`: a clustering of scene.rest()
/// (validated by the caller; taken over, renumbered with the vertices without a copy), or
/// nullopt to compute growth / Acc with MaxCount = MaxSize = cfg.max_count (timed as
/// cluster_ms). With VertexOrder::Clusters the scene is renumbered in place
/// (Scene::renumber_vertices). Throws std::invalid_argument for a bad configuration,
/// std::runtime_error when Embree fails.
[[nodiscard]] PeerBenchResult run_peer_bench(Scene& scene, std::optional<Clustering> clusters, const PeerBenchConfig& cfg);

/// Medians over benchmark frames >= first_frame per configuration (order of first appearance)
/// and mismatch sums over all frames: the summary of run_peer_bench, recomputable from rows.
[[nodiscard]] std::vector<BenchSummary> summarize(const std::vector<BenchRow>& rows, int first_frame);

/// bench.csv (schema ptc-bench/8, docs/tracing.md): one row per frame and configuration.
[[nodiscard]] Table bench_table(const PeerBenchResult& r);
/// summary.csv (schema ptc-bench-summary/3): medians per configuration and ratios against each Embree mode.
[[nodiscard]] Table bench_summary_table(const PeerBenchResult& r);
/// The printed tables: the whole frame against each Embree mode first, then the medians, then
/// the ratios of each part (> 1: the row is faster).
[[nodiscard]] std::string bench_text(const PeerBenchResult& r);

}  // namespace ptc
