// The method's per-frame rebuild (Garanzha 2009): a BVH over cluster boxes whose leaves hold
// whole clusters, with the clusters' triangles in SIMD blocks laid out once per clustering (see
// trace_scene.h for the per-frame loop). Also the method's precomputation: the order in which
// the scene keeps the clusters (cluster_visit_order) and the vertex renumbering that lets the
// per-frame conversion and box pass run fused over the input (cluster_vertex_order).
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "bvh/aligned.h"
#include "bvh/leaf_tables.h"
#include "bvh/scene_config.h"
#include "bvh/scene_frame.h"
#include "bvh/triangle_scene.h"
#include "bvh/vertex_order.h"
#include "bvh/wide_bvh.h"

namespace ptc::bvh {

/// A clustering as the BVH layer sees it: cluster c is the triangles
/// triangle_order[triangle_offsets[c] .. triangle_offsets[c+1]) and, for the per-frame box, the
/// vertices vertices[vertex_offsets[c] .. vertex_offsets[c+1]) (when vertex_offsets is empty
/// the boxes are made from the triangles' corners instead). Spans are copied by ClusterScene.
struct ClusterView {
  std::span<const std::uint32_t> triangle_order, triangle_offsets, vertices, vertex_offsets;
};
/// The view of any clustering type with these four members (e.g. ptc::Clustering).
template <class C>
[[nodiscard]] ClusterView view_of(const C& c) {
  return {c.triangle_order, c.triangle_offsets, c.vertices, c.vertex_offsets};
}

/// The order in which a ClusterScene keeps the clusters of `clusters` on `mesh`: the primitive
/// order of the plain binned SAH BVH over the clusters' rest-pose boxes (those of the per-frame
/// pass at the rest pose; cfg's frame and build settings, one cluster per leaf). It depends on
/// positions, not on the vertex numbering.
/// Throws std::invalid_argument like ClusterScene.
[[nodiscard]] std::vector<std::uint32_t> cluster_visit_order(const Mesh& mesh, const ClusterView& clusters,
                                                             const SceneConfig& cfg);

/// The vertex renumbering (to_old) of the method's precomputation: cluster_vertex_order
/// (vertex_order.h) over the clusters' vertex lists (their triangles' corners when the view has
/// none) in cluster_visit_order. A ClusterScene with the same cfg over renumber_vertices(mesh,
/// to_old) and the clustering renamed with it takes the fused per-frame pass (fused_vertex_pass()).
[[nodiscard]] std::vector<std::uint32_t> cluster_vertex_order(const Mesh& mesh, const ClusterView& clusters,
                                                              std::span<const std::size_t> part_offsets,
                                                              const SceneConfig& cfg);

/// Cluster BVH: one box per cluster (from its vertex list), weights = cluster sizes. Blocks are
/// laid out once per clustering, cluster by cluster, and only refilled per frame. Within a
/// cluster: Linear packs the triangles in Morton order of their rest-pose centroids (the
/// paper's leaves, tested linearly four at a time); BlockTree builds a binned SAH tree (leaves
/// of at most 4 triangles, one block each) over the cluster's rest-pose triangles and lays the
/// blocks out in its leaf order, a fixed-topology tree refitted every frame (a two-level
/// variant: the per-frame build still only sees cluster boxes).
class ClusterScene {
 public:
  /// Throws std::invalid_argument when the clustering does not cover the mesh's triangles once
  /// each (sizes and offsets are checked, not connectivity), and for BlockTree leaves with
  /// cfg.build.max_leaf_size > 1 (a leaf of several clusters would bypass their block trees).
  /// The scene is at the mesh's positions; with cfg.built_once it stays there (no per-frame state).
  ClusterScene(const Mesh& mesh, const ClusterView& clusters, const SceneConfig& cfg = cluster_scene_defaults());
  /// A frame: the positions of the mesh's vertices. std::logic_error for a scene built once
  /// (SceneConfig::built_once), std::invalid_argument for a wrong count or a non-finite position.
  void update(std::span<const Vec3> positions);

  /// What the last frame is traced on: the cluster BVH's data, or on a frame traced on the
  /// triangle fallback (fallback_active()) the triangle BVH's.
  [[nodiscard]] const TraceData& data() const { return fallback_active_ ? fallback_->data() : f_.data; }
  /// The cluster BVH's trace data, whether or not the frame is traced on it.
  [[nodiscard]] const TraceData& cluster_data() const { return f_.data; }
  /// How far the clusters have come apart at the last update: the sum of the cluster boxes' half
  /// surface areas (xy + yz + zx) over the sum of the triangles' areas at the positions the scene
  /// was made with (both in the trace frame). A compact cluster on a surface has a box about as
  /// large as its triangles (2-3 for the built-in meshes' clusters of 17-32 triangles); the
  /// value grows as a cluster's triangles move apart, and with it the boxes a ray enters and the
  /// triangles it tests. Triangles that keep their size (bending, rigid pieces) keep the
  /// denominator; a mesh that grows as a whole raises the value with it. NaN for a mesh of
  /// zero area and for a scene built once (SceneConfig::built_once). With the fallback on, the
  /// update computes it (in build_ms) and this returns that value; off, it is computed here, a pass
  /// over the cluster boxes outside the update.
  [[nodiscard]] double swelling() const;
  /// Whether the last frame is traced on the triangle fallback (SceneConfig::fallback_swelling).
  [[nodiscard]] bool fallback_active() const { return fallback_active_; }
  /// The triangle fallback's scene (null until a frame first needs it).
  [[nodiscard]] const TriangleScene* fallback_scene() const { return fallback_.get(); }
  /// The last update's binary tree: over the clusters (primitive i = scene cluster i), or with
  /// GroupTrees::Refit over the groups (primitive g = group g of group_offsets()).
  [[nodiscard]] const Bvh& bvh() const { return f_.bvh; }
  /// The last update's binary tree over the clusters: bvh() itself, or with GroupTrees::Refit the
  /// top tree over the groups with every group's leaf replaced by that group's fixed tree, boxes
  /// and cost recomputed from boxes() (for reports and tests: it is not made per frame).
  [[nodiscard]] Bvh cluster_tree() const;
  /// The SAH cost of cluster_tree() (bvh().cost for the plain and the rebuilt two-level build).
  [[nodiscard]] double sah_cost() const;
  /// Per-cluster data (boxes, weights, the primitive ids of cluster_tree(), and of bvh() without
  /// fixed group trees) is in the scene's own cluster order: scene cluster i is the clustering's
  /// cluster cluster_ids()[i] (cluster_visit_order).
  [[nodiscard]] const std::vector<std::uint32_t>& cluster_ids() const { return cluster_ids_; }
  [[nodiscard]] std::span<const Box3f> boxes() const { return f_.boxes; }
  [[nodiscard]] const std::vector<std::uint32_t>& weights() const { return weights_; }
  /// The two-level build's groups (BuildInput::groups, in scene cluster order); empty: plain build.
  [[nodiscard]] const std::vector<std::uint32_t>& group_offsets() const { return group_offsets_; }
  /// The two-level build's group size, cluster_group_size_used: at most this many clusters a
  /// group (0: the plain build, also when that size makes one group only).
  [[nodiscard]] std::uint32_t group_size() const { return group_size_; }
  [[nodiscard]] const StageTimes& times() const { return f_.times; }
  /// The clusters' linear-leaf bytes as LeafFormatChoice::Auto estimates them (estimate_leaf_bytes),
  /// whatever the format used (data().format).
  [[nodiscard]] const LeafBytes& leaf_bytes_estimate() const { return leaf_estimate_; }
  /// 8-wide nodes kept from frame to frame (the block trees, then the fixed group trees): nodes
  /// [0, subtree_nodes()) of data().wide8.nodes; only their boxes change per frame.
  [[nodiscard]] std::size_t subtree_nodes() const { return sub8_count_; }
  /// Whether the positions arrive in the clusters' vertex order (the mesh was renumbered with
  /// cluster_vertex_order()): the conversion then reads the input once, in order. For clusters
  /// whose vertex lists are their triangles' corners (as a Clustering's are) it streams alone
  /// (vertices_ms) and the fill of the leaf data takes the cluster boxes from the corners it
  /// writes (boxes_ms = 0, leaf_data_ms = both; the same boxes, bit for bit, without a second
  /// read of the vertices the clusters share), then the tree is built, at any thread count (at
  /// two threads this beat the fill beside the tree's build: docs/tracing.md, thirty-second
  /// session). Other lists: the conversion is fused into the box stage (StageTimes::vertices_ms =
  /// 0, boxes_ms = both), and on more than one thread the leaf data is filled beside the tree's
  /// build. Otherwise (not renumbered) the conversion gathers the positions in that order
  /// (vertices_ms) before the boxes. False for a scene built once (SceneConfig::built_once), which
  /// has no per-frame pass.
  [[nodiscard]] bool fused_vertex_pass() const { return runs_.has_value(); }

 private:
  void update_clusters(std::span<const Vec3> positions);
  void update_fallback(std::span<const Vec3> positions);
  // The triangle fallback's configuration: fallback_scene_defaults() in this scene's trace frame,
  // with its refit limit and area weights or point (SceneConfig::fallback_area_*).
  [[nodiscard]] SceneConfig fallback_config() const;
  void layout_linear(AlignedVector<std::uint32_t>& lane_ids);
  void layout_block_trees(AlignedVector<std::uint32_t>& lane_ids);
  void set_vertex_order(const Mesh& mesh, std::span<const std::uint32_t> lane_ids);
  void fill_corners(std::span<const Tri> tris, std::span<const std::uint32_t> lane_ids, std::uint32_t sentinel,
                    const std::uint32_t* to_new);
  void layout_tables(const Mesh& mesh, AlignedVector<std::uint32_t>& lane_ids);
  void rest_boxes(std::span<const Box3f> boxes, std::span<const Vec3f> centres);
  void only_frame();
  /// boxes_from_fill: the cluster boxes are made by the fill of the blocks (update() on one
  /// thread), which then runs before the tree instead of beside it.
  void build_frame(bool boxes_from_fill = false);
  [[nodiscard]] bool use_tables(bool corner_lists);
  [[nodiscard]] bool overlap_possible() const;
  [[nodiscard]] bool lists_are_corners(std::size_t vertex_count, std::span<const std::uint32_t> lane_ids) const;
  [[nodiscard]] std::span<const Tri> triangles() const {
    return tris_ ? std::span<const Tri>(*tris_) : std::span<const Tri>();
  }
  void layout_group_trees();
  void append_group_tree(std::size_t g, const WideBvh& w);
  void collapse_top8();
  void refit8(std::size_t begin, std::size_t end, bool block_trees);
  void layout_wide8();
  void refit_group_trees();
  [[nodiscard]] std::pair<std::uint32_t, std::uint32_t> cluster_slot(std::uint32_t c) const;
  [[nodiscard]] std::pair<std::uint32_t, std::uint32_t> cluster_slot8(std::uint32_t c) const;
  std::shared_ptr<const std::vector<Tri>> tris_;
  SceneConfig cfg_;
  std::vector<std::uint32_t> cluster_ids_;  // scene cluster -> the clustering's cluster
  std::vector<std::uint32_t> order_, offsets_, vertices_, vertex_offsets_;  // in the scene's cluster order (set-up only: freed)
  std::vector<std::uint32_t> weights_;
  std::uint32_t group_size_ = 0;              // cluster_group_size_used
  std::vector<std::uint32_t> group_offsets_;  // groups of at most group_size_ clusters: runs of clusters
  std::vector<LeafRange> cluster_ranges_;  // blocks of cluster c (fixed layout)
  // BlockTree: the per-cluster trees (child indices relative to the start of sub_nodes_, which
  // become absolute because the subtrees occupy nodes [0, sub_count_) of every frame).
  AlignedVector<WideNode> sub_nodes_;  // (read by layout_wide8, then released; sub_count_ stays)
  std::uint32_t sub_count_ = 0;        // fixed 4-wide nodes [0, sub_count_) = sub_nodes_ until then
  std::vector<std::uint32_t> sub_root_;  // per cluster: subtree root, or kNoTriangle (one block)
  // GroupTrees::Refit: sub_nodes_[block_nodes_ ..) are the groups' fixed trees (after the block
  // trees), whose 8-wide nodes are refitted from the cluster boxes; the per-frame build sees one
  // record per group.
  bool refit_groups_ = false;
  bool rest_is_frame_tree_ = false;  // built once, plain build: f_.bvh is the rest tree (no build in build_frame)
  std::uint32_t block_nodes_ = 0;
  // The 8-wide nodes of the fixed subtrees, which the tracer walks (layout_wide8): their structure is
  // fixed, refit8 writes their boxes. Nodes [0, group8_begin_) are the block trees', then the
  // groups' trees'. link8_ maps a 4-wide subtree root to its 8-wide one.
  AlignedVector<WideNode8> sub8_;  // (moved into data().wide8.nodes by layout_wide8; sub8_count_ stays)
  std::size_t sub8_count_ = 0, group8_begin_ = 0;
  std::vector<std::uint32_t> link8_;
  // Per fixed 8-wide slot 8 d + j, the box record it takes its box from per frame (layout_wide8).
  std::vector<std::uint32_t> src8_;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> multi_src_;  // per leaf of several clusters: group_leaf_clusters_ range
  std::vector<Box3f> multi_boxes_;  // [0] empty; [k + 1] the union of multi_src_[k]'s clusters' boxes
  AlignedVector<float> box8_;  // per fixed 8-wide node, refit8's union of its slots (a Box3f: lo x y z hi x y z)
  std::uint32_t sub_depth8_ = 0, group_depth8_ = 0;
  std::vector<Bvh> group_bvh_;             // per group: its rest-pose tree over its clusters (local ids)
  std::vector<std::pair<std::uint32_t, std::uint32_t>> group_slot8_;  // per group: its (child, count) as an 8-wide slot
  std::vector<std::uint32_t> group_root_;  // per group: the 4-wide root of its tree (link8_: the 8-wide one), or kNoTriangle (one cluster)
  struct GroupSlots {  // per node of a group's tree: the scene clusters whose boxes a child slot unites
    std::uint32_t first[4], count[4];      // into group_leaf_clusters_; count 0: an inner child (or empty)
  };
  std::vector<GroupSlots> group_slots_;  // (set-up only: layout_wide8 turns them into src8_, then they are released)
  std::vector<std::uint32_t> group_leaf_clusters_;
  std::vector<LeafRange> group_ranges_;     // the indirect leaves of the groups' trees (fixed)
  std::vector<std::uint32_t> group_weights_;
  BuildConfig group_top_build_;             // the per-frame build over the groups: the scene's, one group a leaf
  AlignedVector<Box3f> group_boxes_;
  AlignedVector<Vec3f> group_centres_;
  struct Top8Item {  // an inner binary node to become 8-wide node node8, with its 4-wide children
    std::uint32_t bin, node8, depth;
    std::uint32_t kids[4];
    int nk;
  };
  std::vector<Top8Item> top8_stack_;  // collapse_top8's work stack (kept: no allocation per frame)
  std::vector<Box3f> block_boxes_;  // exact box of every block, from the last fill (none kept when built once)
  GroupVertexOrder vorder_;  // gather mode: vertices renumbered in first-touch order over the clusters (f_.fpos is in it)
  std::optional<GroupRuns> runs_;  // fused mode (the input is in that order already): f_.fpos in input order
  bool lists_are_corners_ = false;  // fused mode: the clusters' vertex lists are their corners (lists_are_corners)
  AlignedVector<std::uint32_t> corners_;  // per block [corner][lane] renumbered vertex indices (V: NaN sentinel; none with tables)
  TableLayout tables_;  // LeafFormat::Tables: the groups per cluster and their slots' vertex indices
  LeafBytes leaf_estimate_;  // leaf_bytes_estimate()
  SceneFrame f_;
  double triangle_area_ = 0;  // the triangles' areas at the scene's first positions, in the trace frame (swelling())
  double swelling_ = std::numeric_limits<double>::quiet_NaN();  // the last update's, when it needed it (else NaN)
  bool fallback_active_ = false;
  std::unique_ptr<TriangleScene> fallback_;  // made at the first frame traced on it
};

}  // namespace ptc::bvh
