// What the experiments of `ptc experiment` (issue 12: sweep, compare, drift, accuracy) share:
//
//  - work items: every experiment is a list of named items (a MaxCount value, a configuration,
//    a clustering, an approximation), measured independently of each other over the same
//    frames, rays and trace frame. A shard K/N runs the items i with i % N == K - 1, so a study
//    splits over processes and machines deterministically, and `ptc merge` joins the shards'
//    rows back in item order (docs/experiments.md).
//  - configurations: a named acceleration structure of analysis/loop/accel.h, with the
//    clustering it is built over (made from a ClusterConfig, or given);
//  - the study loop: one pass over the frames; per frame the scene's positions are made once
//    and every configuration of the shard updates to them (in its own vertex order) and is
//    measured by the experiment's callback;
//  - the passes: primary rays of one camera (closest hit) and shadow rays towards one light
//    (any hit), timed; optionally ambient-occlusion rays; optionally per-ray counters (an
//    untimed second trace, so the timed one runs without them).
//
// Work items are never merged into one run's timing: each configuration is timed on its own
// update and trace. The first frame of the loop is marked `warmup` (first touch of memory,
// Embree's lazy initialisation): summaries leave it out when there is more than one frame.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "analysis/loop/accel.h"
#include "render/camera.h"
#include "render/rays.h"
#include "toolkit/anim/scene.h"
#include "toolkit/clustering/cluster.h"

namespace ptc::study {

/// Shard K/N (index = K - 1): the items i with i % count == index.
struct Shard {
  std::uint32_t index = 0, count = 1;
  [[nodiscard]] bool has(std::size_t item) const { return item % count == index; }
  [[nodiscard]] bool whole() const { return count == 1; }
  /// "K/N".
  [[nodiscard]] std::string str() const { return std::to_string(index + 1) + "/" + std::to_string(count); }
};

/// The clustering configurations of the studies, by name (the paper's method and its baselines):
///   acc_growth       growth with Acc (Garanzha 2009)
///   acc_contraction  dual-graph contraction with Acc (Garanzha 2009)
///   naive            contraction with the Naive objective ("SAH clusters")
///   gwh01            contraction with GWH01's cost (Garland, Willmott, Heckbert 2001)
///   meshopt          meshoptimizer's meshlet builder
///   sah_split        the top-down SAH split
/// and "given": the clustering of a `ptc cluster` output (--clusters DIR).
inline constexpr const char* kClusteringNames[] = {"acc_growth", "acc_contraction", "naive",
                                                   "gwh01",      "meshopt",         "sah_split"};
/// The ClusterConfig of a clustering name: `base` (the user's parameters: MaxCount, MaxSize,
/// sphere, ...) with the method and objective of the name; nullopt for an unknown name.
[[nodiscard]] std::optional<ClusterConfig> clustering_config(std::string_view name, const ClusterConfig& base);

/// One configuration of a study.
struct ConfigSpec {
  std::string name;                     ///< the row label ("acc_growth", "standard", "embree_low", ...)
  loop::AccelKind kind = loop::AccelKind::OursClusters;
  std::optional<ClusterConfig> cluster;  ///< how the clusters are made (ours_clusters without `given`)
  const Clustering* given = nullptr;     ///< or the given clustering (ours_clusters)
  /// The adjacency `given` was made with (its manifest; read with adjacency_on).
  ClusterAdjacency given_adjacency = ClusterAdjacency::Auto;
};

/// What every study shares.
struct StudySetup {
  FrameRange frames{0, 0};
  int width = 256, height = 256;     ///< primary rays
  CameraSpec camera;                 ///< resolved by the caller (flags > scene > framing)
  Vec3 light = Vec3::Zero();         ///< shadow rays' point light (resolved by the caller)
  unsigned threads = 1;              ///< oneTBB and Embree threads for the whole run
  bvh::ClusterLeaf cluster_leaf = bvh::ClusterLeaf::Linear;
  std::uint32_t cluster_group_size = bvh::cluster_scene_defaults().cluster_group_size;
  std::uint32_t min_cluster_groups = bvh::cluster_scene_defaults().min_cluster_groups;  ///< bvh::SceneConfig's
  bvh::GroupTrees group_trees = bvh::cluster_scene_defaults().group_trees;
  bvh::VertexOrder vertex_order = bvh::VertexOrder::Clusters;
  Shard shard;
  /// Called with the fraction done (0..1) between frames and configurations.
  std::function<void(double)> progress;
};

/// A configuration made ready: its clustering, the mesh in its vertex order and its structure.
struct Prepared {
  ConfigSpec spec;
  Clustering clustering;               ///< in `mesh`'s vertex numbering (empty without clusters)
  bool has_clusters = false;
  std::vector<std::uint32_t> to_old;   ///< mesh vertex i = scene vertex to_old[i] (empty: the scene's order)
  /// The scene's topology in this configuration's vertex order, at the positions of the frame
  /// the study loop is at (the rest pose after prepare()).
  Mesh mesh;
  /// With clusters made by coincident corners (cluster.h ClusterAdjacency): the rest pose's
  /// adjacency triangles in `mesh`'s vertex order (the metrics count distinct rest positions);
  /// empty otherwise.
  std::vector<Tri> adjacency;
  std::unique_ptr<loop::Accel> accel;
  double cluster_ms = 0;               ///< making the clustering (0 when given)
  double setup_ms = 0;                 ///< renumbering and building the structure, once
  bvh::HitBatch hits;                  ///< the primary hits of the last trace_passes (kept: no allocation in the timed trace)
  bool rays_checked = false;           ///< the study's primary rays passed accel->check_rays (the same every frame)
};

/// Clusters (when the configuration has them), renumbers (VertexOrder::Clusters) and builds
/// the structure over `rest` (the scene's rest mesh), in the trace frame `setup.origin`.
/// Throws std::invalid_argument for a configuration cluster_mesh refuses.
[[nodiscard]] Prepared prepare(const Mesh& rest, const ConfigSpec& spec, const StudySetup& setup,
                               const loop::AccelSetup& accel_setup);

/// The primary rays and the trace frame every configuration of a study shares.
struct StudyRays {
  bvh::PinholeCamera camera;
  bvh::RayBatch primary;
  Vec3 origin = Vec3::Zero();  ///< the trace frame: the rest pose's bounds' centre
};
[[nodiscard]] StudyRays study_rays(const Mesh& rest, const StudySetup& setup);

/// What every structure of a study is built with: the trace frame `origin` (StudyRays::origin)
/// and the setup's cluster BVH settings, its linear leaves in blocks (bvh::LeafFormatChoice::
/// Blocks, the paper's layout: the studies compare clusterings and sizes, and auto would switch
/// to the vertex tables part of the way along a sweep; docs/experiments.md). No clustering.
[[nodiscard]] loop::AccelSetup accel_setup(const StudySetup& setup, const Vec3& origin);

/// Totals of the passes of one configuration and frame.
struct Passes {
  PassStats primary, shadow, ao;
};
struct PassOptions {
  bool shadows = true;
  int ao_samples = 0;      ///< 0: no AO pass
  bool counters = false;   ///< per-ray counters: an untimed second trace of every pass
  unsigned threads = 1;
};
/// Traces the passes on `p` at its current positions (`p.mesh`). With counters, the
/// returned counts are those of the counted trace and the times those of the timed one.
[[nodiscard]] Passes trace_passes(Prepared& p, const StudyRays& rays, const Vec3& light, const PassOptions& opt);

/// What the study loop reports per frame and configuration.
struct StudyFrame {
  int index = 0;             ///< 0 .. frames - 1
  std::int64_t frame = 0;    ///< the scene frame
  bool warmup = false;       ///< the loop's first frame when it has more than one
  loop::UpdateTimes times;   ///< the configuration's own update and build
};

/// The one frame loop (analysis/loop/frame_loop.h) over setup.frames: per frame the scene's
/// positions once, then for every prepared configuration (in order) its positions in its vertex
/// order (untimed), update() (timed by the structure itself) and measure(frame, configuration
/// index). oneTBB is limited to setup.threads for the whole loop. Ctrl-C stops it between steps.
void run_study(Scene& scene, std::vector<Prepared>& configs, const StudySetup& setup,
               const std::function<void(const StudyFrame&, std::size_t, Prepared&)>& measure);

}  // namespace ptc::study
