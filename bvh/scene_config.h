// What both scenes (triangle_scene.h, cluster_scene.h) are configured with, their defaults, the
// rule that fixes their trace frame, and the times of their per-frame stages.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string_view>

#include "bvh/box.h"
#include "bvh/build_config.h"
#include "bvh/stage_clock.h"
#include "bvh/trace_data.h"
#include "toolkit/mesh/mesh.h"

namespace ptc::bvh {

/// Times of the last update's stages, milliseconds (wall-clock unless SceneConfig::clock says otherwise).
struct StageTimes {
  /// positions into the trace frame (float); 0 when fused into boxes_ms
  double vertices_ms = 0;
  /// primitive boxes and centroids (ClusterScene::fused_vertex_pass(): and the conversion, on
  /// more than one thread); 0 when the fill of the blocks makes them (leaf_data_ms)
  double boxes_ms = 0;
  double build_ms = 0;      ///< SAH build (binned, or the sweep: SceneConfig::builder; GroupTrees::Refit: and the groups' refit; a ClusterScene's update with the triangle fallback on: and its swelling sum)
  double collapse_ms = 0;   ///< binary -> 4-wide, (clusters) linking, and the 8-wide regroup (regroup_to_8)
  /// SoA triangle blocks (ClusterScene::fused_vertex_pass() on one thread: and the cluster boxes,
  /// taken from the blocks' corners as they are written)
  double leaf_data_ms = 0;
  double refit_ms = 0;      ///< ClusterLeaf::BlockTree: refit of the per-cluster trees; a TriangleScene with refit_growth: its wide trees' refit and cost
  /// Time during which two of the stages above ran at once (a ClusterScene on more than one
  /// thread writes the leaf data while it builds and links the tree); 0 otherwise.
  double overlap_ms = 0;
  /// ClusterScene on a frame traced on its triangle fallback (SceneConfig::fallback_swelling):
  /// the whole update of that triangle BVH (made at the first such frame); 0 otherwise.
  double fallback_ms = 0;
  /// The update's wall time: the stages, less what they shared.
  [[nodiscard]] double total_ms() const {
    return vertices_ms + boxes_ms + build_ms + collapse_ms + leaf_data_ms + refit_ms - overlap_ms + fallback_ms;
  }
};

/// How a cluster leaf's triangles are tested (see cluster_scene.h).
enum class ClusterLeaf { Linear, BlockTree };
/// "linear", "block-tree" (the spelling of the command line, manifests and docs).
[[nodiscard]] const char* to_string(ClusterLeaf l);
[[nodiscard]] std::optional<ClusterLeaf> parse_cluster_leaf(std::string_view s);

/// "blocks", "tables" (LeafFormat, trace_data.h).
[[nodiscard]] const char* to_string(LeafFormat f);
[[nodiscard]] std::optional<LeafFormat> parse_leaf_format(std::string_view s);

/// Which LeafFormat a cluster scene's linear leaves use (SceneConfig::leaf_format): one of the
/// two, or Auto, the scene's own choice from its clusters (ClusterScene, tables_suit in
/// leaf_tables.h): the vertex tables when the clusters share enough vertices for them to be
/// clearly smaller than the blocks, blocks otherwise (triangle soups, small clusters, block
/// trees) and for a scene built once (whose rays alone count; the blocks' are as fast or faster).
enum class LeafFormatChoice : std::uint8_t { Auto, Blocks, Tables };
/// "auto", "blocks", "tables".
[[nodiscard]] const char* to_string(LeafFormatChoice f);
/// Auto picks the tables when their estimated bytes (LeafBytes) are at most this share of the
/// blocks'. On the built-in scenes at the bench's clusters (MaxCount 32): the cloth 0.71,
/// the armadillo's 0.76, the epileptic 0.99 and the faerie 1.11 (their meshes split vertices at
/// seams), the explode scene's triangle soup 1.63.
inline constexpr double kAutoTablesMaxShare = 0.85;
[[nodiscard]] std::optional<LeafFormatChoice> parse_leaf_format_choice(std::string_view s);

/// What the two-level build (SceneConfig::cluster_group_size) does inside a group per frame:
/// Rebuild builds a binned SAH tree over the group's cluster boxes every frame; Refit keeps the
/// tree built over the group's rest-pose boxes (a fixed 4-wide subtree, as the block trees of
/// ClusterLeaf::BlockTree) and only recomputes its boxes, so the per-frame build and collapse
/// see one record per group (docs/tracing.md, "Fixed group trees").
enum class GroupTrees { Rebuild, Refit };
/// "rebuild", "refit".
[[nodiscard]] const char* to_string(GroupTrees g);
[[nodiscard]] std::optional<GroupTrees> parse_group_trees(std::string_view s);

/// How the commands build a cluster scene's triangle fallback (`--fallback-sah`): for rays from
/// the camera's eye (Eye: SceneConfig::fallback_area_eye), for the primary rays' mean directions
/// (Directions: fallback_area_weights from direction_area_weights), or with the plain SAH.
enum class FallbackSah : std::uint8_t { Eye, Directions, Plain };
/// "eye", "directions", "plain".
[[nodiscard]] const char* to_string(FallbackSah s);
[[nodiscard]] std::optional<FallbackSah> parse_fallback_sah(std::string_view s);

/// Which SAH builder a scene runs per frame: Binned (Wald 2007, the per-frame one) or Sweep (the
/// exact full sweep, sah_builder.h: the quality reference, for accuracy studies; it has no
/// two-level build, so a cluster scene refuses it with cluster_group_size > 1).
enum class SahBuilder { Binned, Sweep };
/// "binned", "sweep".
[[nodiscard]] const char* to_string(SahBuilder b);

/// The swelling above which the commands trace a cluster scene's frame on a triangle BVH
/// (SceneConfig::fallback_swelling, `--cluster-fallback auto`). ClusterScene::swelling() is
/// about 2-3 for clusters of 17-32 triangles on the built-in meshes at rest and stays there
/// under their bending, draping and skinning (the cloth 2.0-2.1, the twist 3.0-3.6); on the
/// explode scene it grows fast (5.1 at frame 1, 30 at frame 5, 95 at frame 10, 344 at frame
/// 20). There, with 1024 x 1024 primary rays and their shadow rays at two threads,
/// the cluster BVH's whole frame passed the per-frame triangle BVH's between swellings 64 and
/// 79 (docs/tracing.md, "Swollen clusters and the triangle fallback").
inline constexpr double kAutoFallbackSwelling = 64.0;

/// The refit limit of the triangle fallback (SceneConfig::refit_growth, `--fallback-refit auto`).
/// On the explode scene, where the fallback runs, one frame of refit raises the 8-wide tree's
/// cost by 16% at frame 12 and 8.5% at frame 40, two frames by 46% and 25%: the tree is kept one
/// frame in two there. 0.1 kept it less often from frame 24 on, 0.15 to 0.25 alike
/// (docs/tracing.md, "The fallback keeps its tree a frame").
inline constexpr double kAutoFallbackRefitGrowth = 0.2;

struct SceneConfig {
  BuildConfig build{};  ///< builder settings (max_leaf_size counts primitives: triangles or clusters)
  std::optional<Vec3> origin;  ///< trace frame; default: centre of the first frame's vertex bounds
  /// The trace frame's scale (a power of two, as trace_frame_scale gives); default:
  /// trace_frame_scale of the first frame (a scene that must share another's frame sets it).
  std::optional<double> scale = std::nullopt;
  ClusterLeaf cluster_leaf = ClusterLeaf::Linear;  ///< ClusterScene only (Linear: the paper's leaves, and the faster with Acc clusters, bench/bvh_bench.cpp)
  StageClock clock = StageClock::Wall;  ///< clock of the StageTimes (see stage_clock.h)
  /// ClusterScene with ClusterLeaf::Linear only: how the leaves hold their triangles (blocks of
  /// four, or the per-group vertex tables; docs/tracing.md, "Vertex tables in the walk"), or
  /// Auto: the scene picks (LeafFormatChoice; the format used is data().format). The hits are
  /// the same bits either way; a triangle scene and block trees always use blocks.
  LeafFormatChoice leaf_format = LeafFormatChoice::Auto;
  /// ClusterScene only: two-level build (BuildInput::groups). The groups are fixed once per
  /// clustering: the maximal subtrees of at most this many clusters of the rest-pose BVH; per
  /// frame the top is built over the groups' boxes and each group's tree rebuilt over its
  /// clusters' boxes or refitted (group_trees).
  /// 0 (or 1): the plain build over all cluster boxes (the paper's).
  std::uint32_t cluster_group_size = 0;
  /// ClusterScene only: with the two-level build, groups are made no larger than needed for at
  /// least this many groups, so a small scene keeps most of its tree rebuilt per frame (the
  /// fixed group trees cost node visits, the per-frame build over few clusters little time):
  /// cluster_group_size_used. 0: groups of at most cluster_group_size clusters, whatever the
  /// scene's size (the commands' explicit --cluster-groups N).
  std::uint32_t min_cluster_groups = 0;
  GroupTrees group_trees = GroupTrees::Refit;  ///< ClusterScene with groups only (see GroupTrees)
  SahBuilder builder = SahBuilder::Binned;  ///< the per-frame SAH builder (see SahBuilder)
  /// ClusterScene only: built once, at the positions it is made with, and never updated (a
  /// static scene's one BVH, SceneTracer). It then keeps no per-frame state: no corner indices,
  /// no vertex order, no frame positions or block boxes after its one fill (at 13.3M triangles
  /// 160 MB, 50 MB and 80 MB, and their set-up time); its trace data is the same bytes as the
  /// first frame of a scene made with built_once = false, except that with the plain build its
  /// tree is the rest tree (no second build), which may list the two clusters of a node of two
  /// the other way round (docs/tracing.md, "A still scene"). update() throws std::logic_error;
  /// fused_vertex_pass() is false, and times() has vertices_ms 0 (the conversion is part of
  /// the constructor's layout).
  bool built_once = false;
  /// ClusterScene only: on a frame whose clusters have come apart, swelling() above this, trace a
  /// BVH over the frame's triangles instead (a TriangleScene with triangle_scene_defaults()'s
  /// build and this scene's trace frame, made at the first such frame and rebuilt on each; its
  /// time is StageTimes::fallback_ms). The cluster BVH is still updated every frame, so its
  /// accessors (bvh(), boxes(), sah_cost(), cluster_data()) describe it; data() is what the
  /// frame is traced on. 0 (the default, the method as published): never. See
  /// kAutoFallbackSwelling.
  double fallback_swelling = 0.0;
  /// TriangleScene: keep the tree of the last build and only refit it to a new frame (the
  /// blocks refilled in place, the boxes recomputed) while its SAH cost stays at most (1 + x)
  /// times the cost it had right after that build; rebuild otherwise (the rebuild criterion of
  /// Lauterbach et al. 2006, "RT-DEFORM"). The cost is the 8-wide tree's, as the tracer walks it
  /// (wide_sah_cost). A frame whose extrapolated growth (the square of the tree's age) would pass
  /// the limit rebuilds without trying; after a refit that fails at its first frame the next
  /// attempts wait 1, 2, 4, then 8 rebuilds. The age counts the scene's updates, not scene
  /// frames (a cluster scene's fallback is updated only on the frames traced on it; the cost
  /// check holds whatever the gap). ClusterScene: its triangle fallback's value. 0 (the
  /// default): rebuild every frame. See kAutoFallbackRefitGrowth.
  double refit_growth = 0.0;
  /// ClusterScene only: the area weights its triangle fallback is built with
  /// (BuildConfig::area_weights). (1, 1, 1), the default: the plain SAH. The commands give the
  /// weights of their primary rays with `--fallback-sah directions`, their default (direction_area_weights), a
  /// tree for the camera's rays: on the explode scene they crossed 12-14% fewer nodes
  /// (docs/tracing.md, "The fallback built for the camera's rays").
  std::array<float, 3> fallback_area_weights = {1.0f, 1.0f, 1.0f};
  /// ClusterScene only: the point its triangle fallback's rays leave from (world coordinates;
  /// BuildConfig::area_eye in the trace frame), which then replaces fallback_area_weights; none
  /// by default. The commands give the camera's eye with `--fallback-sah eye`: on the explode
  /// scene a further 8-9% fewer nodes a primary ray than the mean directions, but a dearer
  /// update and slower shadow rays (docs/tracing.md, "The fallback built for the camera's eye").
  /// Must be finite.
  std::optional<Vec3> fallback_area_eye;
};

/// Default build settings of a triangle scene: SAH traversal 1, intersection 0.3 (a 4-wide node
/// test costs about three triangle tests of a 4-wide block; measured best on armadillo x2, see
/// bench/bvh_bench.cpp), leaves of up to 8 triangles.
[[nodiscard]] SceneConfig triangle_scene_defaults();
/// The build settings of a cluster scene's triangle fallback (SceneConfig::fallback_swelling):
/// triangle_scene_defaults() with intersection cost 0.1. The fallback runs on clusters whose
/// triangles have flown apart, a sparse cloud of triangles, where larger leaves cost the rays
/// little and spare nodes: on the explode scene's frames 12-19, 24-31 and 46-53 at two threads
/// the update fell by 17-20% and the shadow rays by 12-14% against 0.3, the primary rays alike
/// (docs/tracing.md, "The fallback keeps its tree a frame").
[[nodiscard]] SceneConfig fallback_scene_defaults();
/// Default build settings of a cluster scene: the same SAH constants, one cluster per leaf
/// (leaves of several clusters cost the sum of their triangles and are rarely chosen), and the
/// two-level build over groups of at most 32 clusters (cluster_group_size; groups of 8 measured
/// first on 27.6k Acc clusters of armadillo x2: build 3.6 -> 1.9 ms, SAH cost +2.6%, trace speed
/// within 1-5%; 16 against 8: update 0.3-0.8 ms less, nodes a ray +0.3-1%; 32 against 16 on the
/// built-in scenes: update 0.3-1.4 ms less, nodes a primary ray -1.9% to +0.7%, docs/tracing.md), each
/// group's tree fixed at the rest pose and refitted (GroupTrees::Refit: build and collapse
/// 3.0 -> 1.0 ms, nodes per ray +1-8%; docs/tracing.md, "Fixed group trees").
[[nodiscard]] SceneConfig cluster_scene_defaults();

/// The group size a ClusterScene with `cfg` uses over `clusters` clusters: cfg.cluster_group_size,
/// but with cfg.min_cluster_groups = M > 0 at most clusters / M; 0 (the plain build) when that is
/// 1 or less (with the defaults, 32 clusters a group from 32,768 clusters up, fewer below, and the
/// plain build under 2,048 clusters).
[[nodiscard]] std::uint32_t cluster_group_size_used(std::size_t clusters, const SceneConfig& cfg);

/// The trace frame of a scene over `mesh`: cfg.origin, or the centre of the bounds of the vertices
/// its triangles use (Mesh::referenced_bounds; the world origin for a mesh without triangles). A scene's rest positions and origin must be finite (they fix
/// the trace frame, the layout and, for clusters, the rest-pose tree): std::invalid_argument
/// naming the first bad vertex otherwise.
[[nodiscard]] Vec3 trace_frame_origin(const Mesh& mesh, const SceneConfig& cfg);

/// The trace frame's scale (box.h, FrameMap) for `mesh` around `origin`: 1 when the largest
/// |p - origin| coordinate E of the positions its triangles use lies in [2^-8, 2^16] (or E = 0), else the
/// power of two that brings E into [0.5, 1). In single precision the watertight test's
/// products grow like E^2 t (t: the ray parameter, about E for unit directions): unscaled, a
/// mesh of 1e13 units overflowed them and its rays missed, and one of 1e-15 units underflowed.
/// Throws std::invalid_argument for E beyond 2^100 (about 1.3e30) or below 2^-100 (about
/// 7.9e-31): the directions scaled with the frame would leave the float range there.
[[nodiscard]] double trace_frame_scale(const Mesh& mesh, const Vec3& origin);

/// The trace frame of a scene over `mesh`: trace_frame_origin and trace_frame_scale together.
[[nodiscard]] FrameMap trace_frame(const Mesh& mesh, const SceneConfig& cfg);


}  // namespace ptc::bvh
