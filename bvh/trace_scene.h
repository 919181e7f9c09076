// What the tracer reads: a 4-wide BVH whose leaves refer to SIMD blocks of triangles, in one of
// two flavours that share every line of traversal code:
//   - TriangleScene: a BVH over triangle boxes (the standard per-frame rebuild);
//   - ClusterScene: a BVH over cluster boxes (Garanzha 2009): a leaf holds whole clusters, whose
//     triangles are either tested linearly four at a time (ClusterLeaf::Linear, the paper's
//     method) or through a small fixed-topology tree per cluster over its blocks of four
//     triangles, built once per clustering and refitted every frame (ClusterLeaf::BlockTree:
//     a two-level variant; the per-frame build still only sees cluster boxes).
// Per frame (method.md, "The per-frame loop"): update(positions) converts the positions into
// the trace frame, recomputes the boxes (for a mesh renumbered once with cluster_vertex_order(),
// both in one pass over the input, see ClusterScene::fused_vertex_pass()), builds the SAH BVH, refreshes the leaf data (and, for
// BlockTree, refits the per-cluster trees); the time of every stage is kept.
//
// Precision: everything is in single precision in a *trace frame* centred at `origin` (double),
// see box.h. Rays come in world coordinates (double origins) and are moved into the frame.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "bvh/aligned.h"
#include "bvh/box.h"
#include "bvh/sah_builder.h"
#include "bvh/stage_clock.h"
#include "bvh/wide_bvh.h"
#include "toolkit/mesh/mesh.h"

namespace ptc::bvh {

/// Four triangles in structure-of-arrays form: v[corner][axis][lane], 144 bytes. Unused lanes
/// hold NaN corners, which every comparison of the kernel rejects.
struct alignas(16) TriBlock {
  float v[3][3][4];
};

/// Triangles in consecutive blocks [first_block, first_block + block_count) holding
/// triangle_count triangles (padding lanes may be in any block).
struct LeafRange {
  std::uint32_t first_block = 0;
  std::uint32_t block_count = 0;
  std::uint32_t triangle_count = 0;
};

/// Marker of "no triangle" (padding lanes, misses).
inline constexpr std::uint32_t kNoTriangle = 0xffffffffu;

/// Flag in WideNode::count of a leaf child that refers to several ranges (see TraceData).
inline constexpr std::uint32_t kIndirectLeaf = 0x80000000u;

/// The flat data of a scene, as traversal sees it. Traversal starts at wide.root. A leaf child
/// of a wide node is either
///   direct   (count < kIndirectLeaf): `count` triangles packed in the ceil(count / 4) blocks
///            starting at block `child` (padding only in the last block);
///   indirect (count & kIndirectLeaf): the ranges ranges[child .. child + (count & ~kIndirectLeaf)).
/// Triangle scenes have direct leaves only; cluster scenes direct leaves for single clusters (or
/// single blocks) and indirect ones for leaves of several clusters.
struct TraceData {
  WideBvh wide;
  std::vector<LeafRange> ranges;
  AlignedVector<TriBlock> blocks;
  AlignedVector<std::uint32_t> triangle_ids;  ///< 4 per block: mesh triangle id or kNoTriangle
  Vec3 origin = Vec3::Zero();                 ///< the trace frame
};

/// Checks of the flat data (tests call it on every scene): every node reachable from the root
/// exactly once (a tree), every leaf child's ranges inside `ranges` and blocks inside `blocks`,
/// every mesh triangle id 0 .. triangle_count-1 in exactly one used lane (padding lanes:
/// kNoTriangle and NaN corners), every inner child box containing its node's child boxes
/// (equal to their union when `exact_unions`), every leaf child box containing its triangles'
/// float corners. One line per violation (empty = valid).
[[nodiscard]] std::vector<std::string> validate(const TraceData& data, std::size_t triangle_count,
                                                bool exact_unions = true);

/// Times of the last update's stages, milliseconds (wall-clock unless SceneConfig::clock says otherwise).
struct StageTimes {
  double vertices_ms = 0;   ///< positions into the trace frame (float); 0 when fused into boxes_ms
  double boxes_ms = 0;      ///< primitive boxes and centroids (ClusterScene::fused_vertex_pass(): and the conversion)
  double build_ms = 0;      ///< binned SAH build
  double collapse_ms = 0;   ///< binary -> 4-wide, and (clusters) linking
  double leaf_data_ms = 0;  ///< SoA triangle blocks
  double refit_ms = 0;      ///< ClusterLeaf::BlockTree: refit of the per-cluster trees
  [[nodiscard]] double total_ms() const {
    return vertices_ms + boxes_ms + build_ms + collapse_ms + leaf_data_ms + refit_ms;
  }
};

/// How a cluster leaf's triangles are tested (see the file comment).
enum class ClusterLeaf { Linear, BlockTree };
[[nodiscard]] const char* to_string(ClusterLeaf l);

struct SceneConfig {
  BuildConfig build{};  ///< builder settings (max_leaf_size counts primitives: triangles or clusters)
  std::optional<Vec3> origin;  ///< trace frame; default: centre of the first frame's vertex bounds
  ClusterLeaf cluster_leaf = ClusterLeaf::Linear;  ///< ClusterScene only (Linear: the paper's leaves, and the faster with Acc clusters, bench/bvh_bench.cpp)
  StageClock clock = StageClock::Wall;  ///< clock of the StageTimes (see stage_clock.h)
  /// ClusterScene only: two-level build (BuildInput::groups). The groups are fixed once per
  /// clustering: the maximal subtrees of at most this many clusters of the rest-pose BVH; per
  /// frame the top is built over the groups' boxes and each group over its clusters' boxes.
  /// 0 (or 1): the plain build over all cluster boxes (the paper's).
  std::uint32_t cluster_group_size = 0;
};

/// Default build settings of a triangle scene: SAH traversal 1, intersection 0.3 (a 4-wide node
/// test costs about three triangle tests of a 4-wide block; measured best on armadillo x2, see
/// bench/bvh_bench.cpp), leaves of up to 8 triangles.
[[nodiscard]] SceneConfig triangle_scene_defaults();
/// Default build settings of a cluster scene: the same SAH constants, one cluster per leaf
/// (leaves of several clusters cost the sum of their triangles and are rarely chosen), and the
/// two-level build over groups of at most 8 clusters (cluster_group_size; measured on 27.6k Acc
/// clusters of armadillo x2: build 3.6 -> 1.9 ms, SAH cost +2.6%, trace speed within 1-5%).
[[nodiscard]] SceneConfig cluster_scene_defaults();

/// Triangle BVH: one box per triangle; a leaf is a range of triangles whose blocks are laid out
/// in leaf order (each leaf starts a new block).
class TriangleScene {
 public:
  /// Keeps the topology (shared, not copied) and builds the first frame.
  explicit TriangleScene(const Mesh& mesh, const SceneConfig& cfg = triangle_scene_defaults());
  /// One frame: new positions (same vertex count).
  void update(std::span<const Vec3> positions);

  [[nodiscard]] const TraceData& data() const { return data_; }
  [[nodiscard]] const Bvh& bvh() const { return bvh_; }
  [[nodiscard]] const std::vector<Box3f>& boxes() const { return boxes_; }
  [[nodiscard]] const StageTimes& times() const { return times_; }

 private:
  std::shared_ptr<const std::vector<Tri>> tris_;
  SceneConfig cfg_;
  std::vector<Vec3f> fpos_;
  std::vector<Box3f> boxes_;
  std::vector<Vec3f> centroids_;
  Bvh bvh_;
  BuildWorkspace ws_;  // the builder's scratch, kept between frames
  TraceData data_;
  StageTimes times_;
};

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
/// order of the plain binned SAH BVH over the clusters' rest-pose boxes (cfg's frame and build
/// settings, one cluster per leaf). It depends on positions, not on the vertex numbering.
/// Throws std::invalid_argument like ClusterScene.
[[nodiscard]] std::vector<std::uint32_t> cluster_visit_order(const Mesh& mesh, const ClusterView& clusters,
                                                             const SceneConfig& cfg);

/// The vertex renumbering (to_old) of the method's precomputation: cluster_vertex_order (box.h)
/// over the clusters' vertex lists (their triangles' corners when the view has none) in
/// cluster_visit_order. A ClusterScene with the same cfg over renumber_vertices(mesh, to_old)
/// and the clustering renamed with it takes the fused per-frame pass (fused_vertex_pass()).
[[nodiscard]] std::vector<std::uint32_t> cluster_vertex_order(const Mesh& mesh, const ClusterView& clusters,
                                                              std::span<const std::size_t> part_offsets,
                                                              const SceneConfig& cfg);

/// Cluster BVH: one box per cluster (from its vertex list), weights = cluster sizes. Blocks are
/// laid out once per clustering, cluster by cluster, and only refilled per frame. Within a
/// cluster: Linear packs the triangles in Morton order of their rest-pose centroids; BlockTree
/// builds a binned SAH tree (leaves of at most 4 triangles, one block each) over the
/// cluster's rest-pose triangles and lays the blocks out in its leaf order.
class ClusterScene {
 public:
  /// Throws std::invalid_argument when the clustering does not cover the mesh's triangles once
  /// each (sizes and offsets are checked, not connectivity).
  ClusterScene(const Mesh& mesh, const ClusterView& clusters, const SceneConfig& cfg = cluster_scene_defaults());
  void update(std::span<const Vec3> positions);

  [[nodiscard]] const TraceData& data() const { return data_; }
  [[nodiscard]] const Bvh& bvh() const { return bvh_; }
  /// Per-cluster data (boxes, weights, the BVH's primitive ids) is in the scene's own cluster
  /// order: scene cluster i is the clustering's cluster cluster_ids()[i] (cluster_visit_order).
  [[nodiscard]] const std::vector<std::uint32_t>& cluster_ids() const { return cluster_ids_; }
  [[nodiscard]] const std::vector<Box3f>& boxes() const { return boxes_; }
  [[nodiscard]] const std::vector<std::uint32_t>& weights() const { return weights_; }
  /// The two-level build's groups (BuildInput::groups, in scene cluster order); empty: plain build.
  [[nodiscard]] const std::vector<std::uint32_t>& group_offsets() const { return group_offsets_; }
  [[nodiscard]] const StageTimes& times() const { return times_; }
  [[nodiscard]] std::size_t subtree_nodes() const { return sub_nodes_.size(); }
  /// Whether the positions arrive in the clusters' vertex order (the mesh was renumbered with
  /// cluster_vertex_order()): the conversion is then fused into the box stage (StageTimes::
  /// vertices_ms = 0, boxes_ms = both) and reads the input once, in order; otherwise the
  /// conversion gathers the positions in that order (vertices_ms) before the boxes.
  [[nodiscard]] bool fused_vertex_pass() const { return runs_.has_value(); }

 private:
  void refit_subtrees();
  std::shared_ptr<const std::vector<Tri>> tris_;
  SceneConfig cfg_;
  std::vector<std::uint32_t> cluster_ids_;  // scene cluster -> the clustering's cluster
  std::vector<std::uint32_t> order_, offsets_, vertices_, vertex_offsets_;  // in the scene's cluster order
  std::vector<std::uint32_t> weights_;
  std::vector<std::uint32_t> group_offsets_;  // SceneConfig::cluster_group_size: runs of clusters
  std::vector<LeafRange> cluster_ranges_;  // blocks of cluster c (fixed layout)
  // BlockTree: the per-cluster trees (child indices relative to the start of sub_nodes_, which
  // become absolute because the subtrees occupy nodes [0, sub_nodes_.size()) of every frame).
  AlignedVector<WideNode> sub_nodes_;
  std::vector<std::uint32_t> sub_root_;  // per cluster: subtree root, or kNoTriangle (one block)
  std::uint32_t sub_depth_ = 0;
  std::vector<Box3f> block_boxes_;  // exact box of every block, from the last fill
  GroupVertexOrder vorder_;  // gather mode: vertices renumbered in first-touch order over the clusters (fpos_ is in it)
  std::optional<GroupRuns> runs_;  // fused mode (the input is in that order already): fpos_ in input order
  AlignedVector<std::uint32_t> corners_;  // per block [corner][lane] renumbered vertex indices (V: NaN sentinel)
  std::vector<Vec3f> fpos_;
  std::vector<Box3f> boxes_;
  std::vector<Vec3f> centroids_;
  Bvh bvh_;
  BuildWorkspace ws_;  // the builder's scratch, kept between frames
  TraceData data_;
  StageTimes times_;
};

}  // namespace ptc::bvh
