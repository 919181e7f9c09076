// The side-by-side benchmark against Embree (issue 5): in one process, on the same mesh, the same
// trace frame and the same primary rays, over F animated frames (a scene's positions, or the
// stand-in deformation of analysis/trace_deform.h), five configurations update their
// acceleration structure to the frame's positions and trace. Every configuration sees the whole
// (combined) mesh as one geometry, static parts included: the static/dynamic split is
// `ptc trace`'s (analysis/scene_trace.h); the benchmark measures the per-frame structures.
//
//   ours_triangles  our binned-SAH BVH over triangle boxes, rebuilt per frame (the reference)
//   ours_clusters   our BVH over cluster boxes (Garanzha 2009): cluster boxes updated, BVH built
//   embree_medium   Embree static scene, RTC_BUILD_QUALITY_MEDIUM, rebuilt per frame
//   embree_low      Embree dynamic scene, RTC_BUILD_QUALITY_LOW, rebuilt per frame
//   embree_refit    Embree dynamic scene, geometry quality REFIT: refitted per frame
//
// Per frame and configuration: update_ms (ours: positions into the trace frame + primitive
// boxes; Embree: vertex buffer), build_ms (ours: SAH build + collapse + leaf data + block-tree
// refit; Embree: rtcCommitScene), trace_ms (closest hit, counters off), hits, and mismatches of
// the closest triangle against ours_triangles of the same frame: a hit against a miss, or another
// triangle at a t differing by more than tie_rel (relative); another triangle within tie_rel is
// a tie (rays through shared edges and vertices), counted separately.
// Medians skip frame 0 (first-touch page faults, caches, Embree's lazy initialisation) when there
// is more than one frame. Threads: oneTBB is limited to `threads` for the whole run (builds and
// traces), Embree's device gets "threads=N"; set_affinity is never used.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "analysis/csv.h"
#include "analysis/trace_camera.h"
#include "analysis/trace_deform.h"
#include "bvh/trace_scene.h"
#include "toolkit/clustering/clustering.h"
#include "toolkit/mesh/mesh.h"

namespace ptc {

/// Per-frame positions of a scene (toolkit/anim/scene.h): fills `out` (the mesh's vertex count)
/// with the positions at scene frame `frame`.
using FramePositions = std::function<void(std::int64_t frame, std::span<Vec3> out)>;

struct PeerBenchConfig {
  int frames = 5;                         ///< animated frames (>= 1): first_frame .. first_frame + frames - 1
  std::int64_t first_frame = 0;           ///< scene frame of the first benchmark frame (>= 0)
  /// Where the frames come from: a scene's positions; empty = the stand-in `deformation` of the
  /// mesh's positions (frame 0 of the deformation is the rest pose).
  FramePositions positions;
  int width = 1024, height = 1024;        ///< primary rays of the default camera (1..16384 each)
  CameraSpec camera;                      ///< optional overrides of the default camera
  unsigned threads = 1;                   ///< oneTBB and Embree threads (>= 1; 1 = one-thread figures)
  Deformation deformation = Deformation::Twist;
  std::uint32_t max_count = 50;           ///< clustering when none is given: growth / Acc, MaxCount = MaxSize = this
  bvh::ClusterLeaf cluster_leaf = bvh::ClusterLeaf::Linear;
  /// Two-level build of the cluster BVH over groups of at most this many clusters
  /// (bvh::SceneConfig::cluster_group_size); 0: the plain build over all cluster boxes.
  std::uint32_t cluster_group_size = bvh::cluster_scene_defaults().cluster_group_size;
  double tie_rel = 1e-5;                  ///< relative t tolerance of a tie
  /// Vertex order of the benchmark mesh. true (default): renumbered once, after clustering, with
  /// bvh::cluster_vertex_order (every cluster's own vertices consecutive), so that the cluster
  /// path converts and boxes in one pass over the positions (ClusterScene::fused_vertex_pass);
  /// every configuration sees the same renumbered mesh and positions, triangle ids unchanged.
  /// false: the input order (the cluster path gathers the positions per frame).
  bool cluster_vertex_order = true;
  /// With `positions` and cluster_vertex_order: renumbers the caller's frame source once (e.g.
  /// Scene::renumber_vertices), so that `positions` writes in the new order; required then.
  std::function<void(std::span<const std::uint32_t> to_old)> renumber_positions;
  /// Vertex ranges (parts, ascending from 0 to the vertex count) that the renumbering keeps in
  /// place (a scene's parts: Scene::vertex_offsets()); empty = one part.
  std::vector<std::size_t> part_offsets;
};

/// The configurations, in the order they run within a frame.
[[nodiscard]] const std::vector<std::string>& peer_bench_configs();

struct BenchRow {
  int frame = 0;                 ///< benchmark frame 0 .. frames - 1
  std::int64_t scene_frame = 0;  ///< first_frame + frame
  std::string config;
  double update_ms = 0, build_ms = 0, frame_ms = 0;  ///< frame_ms: wall time of the whole update call
  double source_ms = 0;  ///< producing the frame's positions (scene or stand-in deformation), once per frame, untimed in the configurations
  double trace_ms = 0, mrays_per_s = 0;
  std::uint64_t rays = 0, hits = 0;
  std::uint64_t mismatches = 0;  ///< hit_miss + other_triangle
  std::uint64_t hit_miss = 0, other_triangle = 0, ties = 0;
};

struct BenchSummary {
  std::string config;
  double update_ms = 0, build_ms = 0, update_build_ms = 0, trace_ms = 0, mrays_per_s = 0;  ///< medians
  std::uint64_t mismatches = 0, ties = 0;  ///< sums over all frames (frame 0 included)
};

struct PeerBenchResult {
  std::vector<BenchRow> rows;          ///< frame-major, configurations in peer_bench_configs() order
  std::vector<BenchSummary> summary;   ///< one per configuration
  std::size_t triangles = 0, vertices = 0, clusters = 0, rays = 0;
  int median_first_frame = 0;          ///< medians over frames [median_first_frame, frames)
  double cluster_ms = 0;               ///< clustering (0 when clusters were given)
  double cluster_scene_setup_ms = 0;   ///< ClusterScene construction (per-clustering layout, once)
  std::string clustering;              ///< how the clusters were made
  std::string vertex_order;            ///< "clusters" (renumbered once) or "input"
  bool fused_vertex_pass = false;      ///< the cluster scene converts and boxes in one pass (no gather)
  std::uint32_t cluster_group_size = 0;  ///< the cluster BVH's two-level build (0: plain)
  double renumber_ms = 0;              ///< the renumbering (mesh, clustering, frame source), once
};

/// Runs the benchmark. `clusters`: a clustering of `mesh` (validated by the caller), or nullptr
/// to compute growth / Acc with MaxCount = MaxSize = cfg.max_count (timed as cluster_ms).
/// Throws std::invalid_argument for a bad configuration, std::runtime_error when Embree fails.
[[nodiscard]] PeerBenchResult run_peer_bench(const Mesh& mesh, const Clustering* clusters, const PeerBenchConfig& cfg);

/// Median of values (mean of the middle two for an even count; 0 for none).
[[nodiscard]] double median(std::vector<double> v);

/// Medians over frames >= first_frame per configuration (order of first appearance) and
/// mismatch sums over all frames: the summary of run_peer_bench, recomputable from rows.
[[nodiscard]] std::vector<BenchSummary> summarize(const std::vector<BenchRow>& rows, int first_frame);

/// bench.csv: one row per frame and configuration (schema ptc-bench/1, docs/tracing.md).
[[nodiscard]] CsvTable bench_csv(const PeerBenchResult& r);
/// summary.csv: medians per configuration and ratios against each Embree mode.
[[nodiscard]] CsvTable bench_summary_csv(const PeerBenchResult& r);
/// The printed tables: medians, then ratios against each Embree mode (> 1: the row is faster).
[[nodiscard]] std::string bench_table(const PeerBenchResult& r);

}  // namespace ptc
