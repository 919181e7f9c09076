// The acceleration configurations that the frame loop updates and traces, behind one interface,
// so that every experiment (bench today; sweep, compare, drift next) compares them the same way:
//
//   ours_triangles  our binned-SAH BVH over triangle boxes, rebuilt per frame (the reference)
//   ours_clusters   our BVH over cluster boxes (Garanzha 2009): cluster boxes updated, BVH built
//   embree_medium   Embree static scene, RTC_BUILD_QUALITY_MEDIUM, rebuilt per frame
//   embree_low      Embree dynamic scene, RTC_BUILD_QUALITY_LOW, rebuilt per frame
//   embree_refit    Embree dynamic scene, geometry quality REFIT: refitted per frame
//   scene           `ptc trace`'s: the static parts' triangle BVH built once + the moving parts'
//                   triangle or cluster BVH updated per frame (bvh/scene_tracer.h)
//
// Every configuration sees the same mesh, trace frame (origin) and rays; update() takes the
// whole mesh's positions of a frame and leaves a traceable structure (the span that per-frame
// comparisons count on both sides: positions in, traceable structure out).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string_view>

#include "bvh/scene_tracer.h"
#include "bvh/trace_scene.h"
#include "bvh/tracer.h"
#include "toolkit/clustering/clustering.h"
#include "toolkit/mesh/mesh.h"

namespace ptc::loop {

enum class AccelKind { OursTriangles, OursClusters, EmbreeMedium, EmbreeLow, EmbreeRefit };
/// "ours_triangles", "ours_clusters", "embree_medium", "embree_low", "embree_refit".
[[nodiscard]] std::string_view to_string(AccelKind k);
[[nodiscard]] std::optional<AccelKind> parse_accel_kind(std::string_view s);
inline constexpr AccelKind kAllAccelKinds[] = {AccelKind::OursTriangles, AccelKind::OursClusters,
                                               AccelKind::EmbreeMedium, AccelKind::EmbreeLow, AccelKind::EmbreeRefit};
[[nodiscard]] bool is_embree(AccelKind k);

/// The last update of a configuration, milliseconds.
struct UpdateTimes {
  double update_ms = 0;    ///< ours: positions into the trace frame + primitive boxes; Embree: vertex buffer
  double build_ms = 0;     ///< ours: SAH build + collapse + leaf data (+ block-tree refit) - overlap (wall time) + a cluster scene's triangle fallback; Embree: rtcCommitScene
  bvh::StageTimes stages;  ///< ours: each stage; Embree: zero (its commit is one call)
};

class Accel {
 public:
  virtual ~Accel() = default;
  [[nodiscard]] virtual std::string_view name() const = 0;
  /// One frame: the whole mesh's positions (the mesh's vertex count).
  virtual void update(std::span<const Vec3> positions) = 0;
  [[nodiscard]] virtual UpdateTimes last_update() const = 0;
  /// Traces the batch (closest or any hit by opt.mode; Embree ignores opt.counters and opt.isa).
  virtual bvh::TraceTotals trace(const bvh::RayBatch& rays, bvh::HitBatch& hits, const bvh::TraceOptions& opt) const = 0;
  /// Throws std::invalid_argument for rays the structure cannot take (Embree: origins beyond its
  /// range, bvh::EmbreeScene::check_rays); ours take any. Callers run it before their timed trace.
  virtual void check_rays(const bvh::RayBatch& rays) const { (void)rays; }
  /// The trace frame (ray offsets are measured in it).
  [[nodiscard]] virtual Vec3 origin() const = 0;
  /// SAH cost of the binary BVH of the last update (bvh/sah_cost.h); nullopt where the
  /// structure is not ours (Embree) or not one tree (the static + moving scene).
  [[nodiscard]] virtual std::optional<double> sah_cost() const { return std::nullopt; }
};

struct AccelSetup {
  Vec3 origin = Vec3::Zero();            ///< the trace frame shared by every configuration
  const Clustering* clusters = nullptr;  ///< ours_clusters: a clustering of the mesh (required)
  bvh::ClusterLeaf cluster_leaf = bvh::ClusterLeaf::Linear;
  /// ours_clusters with linear leaves: blocks, per-group vertex tables or the scene's choice
  /// (bvh::LeafFormatChoice).
  bvh::LeafFormatChoice leaf_format = bvh::LeafFormatChoice::Auto;
  /// ours_clusters: two-level build over groups of at most this many clusters (0: plain build).
  std::uint32_t cluster_group_size = bvh::cluster_scene_defaults().cluster_group_size;
  /// ours_clusters: bvh::SceneConfig::min_cluster_groups (0: groups of exactly up to cluster_group_size).
  std::uint32_t min_cluster_groups = bvh::cluster_scene_defaults().min_cluster_groups;
  /// ours_clusters with groups: the groups' trees rebuilt or refitted per frame (bvh::GroupTrees).
  bvh::GroupTrees group_trees = bvh::cluster_scene_defaults().group_trees;
  unsigned threads = 1;                  ///< Embree's device threads (ours: the caller's oneTBB limit)
  /// Embree's packet width when a trace asks for packets (TraceOptions::packets): 4, 8 or 16.
  int embree_packet_width = 8;
  bvh::StageClock clock = bvh::StageClock::Wall;   ///< clock of every configuration's stage times
  std::optional<bvh::BuildConfig> triangle_build;  ///< ours_triangles' builder (default: triangle_scene_defaults())
  std::optional<bvh::BuildConfig> cluster_build;   ///< ours_clusters' builder (default: cluster_scene_defaults())
  /// The SAH builder of ours_triangles and ours_clusters (Sweep: the exact reference, without
  /// the two-level build; accuracy studies).
  bvh::SahBuilder builder = bvh::SahBuilder::Binned;
  /// ours_clusters: bvh::SceneConfig::fallback_swelling (0: the cluster BVH on every frame).
  double cluster_fallback = 0.0;
  /// ours_clusters: bvh::SceneConfig::refit_growth, the triangle fallback's refit limit (0: rebuilt
  /// every frame).
  double fallback_refit = 0.0;
  /// ours_clusters: bvh::SceneConfig::fallback_area_weights (the plain SAH by default).
  std::array<float, 3> fallback_area_weights = {1.0f, 1.0f, 1.0f};
  /// ours_clusters: bvh::SceneConfig::fallback_area_eye (none by default).
  std::optional<Vec3> fallback_area_eye;
};

/// The cluster scene settings of ours_clusters under `setup` (the method's precomputation, such
/// as bvh::cluster_vertex_order, must use the same).
[[nodiscard]] bvh::SceneConfig cluster_scene_config(const AccelSetup& setup);

/// Builds the configuration over `mesh` at its current positions. std::invalid_argument for
/// ours_clusters without clusters; std::runtime_error when Embree fails.
[[nodiscard]] std::unique_ptr<Accel> make_accel(AccelKind kind, const Mesh& mesh, const AccelSetup& setup);

/// The ClusterScene inside an ours_clusters configuration (nullptr for any other).
[[nodiscard]] const bvh::ClusterScene* cluster_scene_of(const Accel& a);
/// The TriangleScene inside an ours_triangles configuration (nullptr for any other).
[[nodiscard]] const bvh::TriangleScene* triangle_scene_of(const Accel& a);

/// `ptc trace`'s configuration: bvh::SceneTracer (static parts built once, moving parts updated).
class SceneAccel final : public Accel {
 public:
  SceneAccel(const Mesh& first, const bvh::PartLayout& parts, const bvh::SceneTracerConfig& cfg)
      : tracer_(first, parts, cfg) {}
  [[nodiscard]] std::string_view name() const override { return "scene"; }
  void update(std::span<const Vec3> positions) override { tracer_.update(positions); }
  [[nodiscard]] UpdateTimes last_update() const override;
  bvh::TraceTotals trace(const bvh::RayBatch& rays, bvh::HitBatch& hits, const bvh::TraceOptions& opt) const override {
    return tracer_.trace(rays, hits, opt);
  }
  [[nodiscard]] Vec3 origin() const override { return tracer_.origin(); }
  [[nodiscard]] const bvh::SceneTracer& tracer() const { return tracer_; }

 private:
  bvh::SceneTracer tracer_;
};

/// (update_ms, build_ms) of a scene's stage times: update = conversion + boxes, build = the rest.
[[nodiscard]] UpdateTimes update_times_of(const bvh::StageTimes& t);

}  // namespace ptc::loop
